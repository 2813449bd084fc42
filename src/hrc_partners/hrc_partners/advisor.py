"""Role allocation advisor: who should drive what, from a short calibration (pure, no rclpy).

The paper's future work is "task and role allocation". The two assignments of the task are:
the person drives the translation (slider) and the robot the rotation (beam and ball), or the
other way round. The calibration runs a few short episodes of each: the person on one degree
of freedom with their subtasks (their own level-2 subtask and the ball, as in the paper's whole
task), a robot holding the other with the whole task. Each episode's team error is the paper's
total error (mean over the states reached of |S_x| + |P_z| + |B_y|, m + rad + m; mu = 0 in
params/task_tree.yaml). Per assignment: the mean over the episodes with a Student-t 95 %
interval (hrc_study.statistics.mean_interval) -- the expected team error of that assignment --
and the person's own error on their level-2 subtask (their skill on that degree of freedom).

Recommendation: the assignment with the lower mean when the two intervals do not overlap,
else "no clear difference" (both listed with their intervals). Person time = episodes x
seconds plus the rests between them (the simulated human's ``rest_between_episodes``).

The robot is a trained agent (a checkpoint per assignment: a robot on rotation for "person on
translation", e.g. case 2; on translation for "person on rotation", e.g. case 1) or, only when
asked for, the deterministic scripted PD controller of hrc_engine.partners standing in
for the robot (the fast tests use it and say so).
"""

import dataclasses
from dataclasses import dataclass
import math
import typing

from hrc_common.contract import other_dof, SimLimits
from hrc_common.params import with_overrides
from hrc_engine.loop import EpisodeLoop, HumanAnswer, SOURCE_SIMULATED
from hrc_engine.offline import evaluation_core
from hrc_engine.partners import ScriptedPartner
from hrc_joystick_node.population import sample_person
from hrc_joystick_node.human_profile import load_profile
from hrc_joystick_node.sim_human import SimulatedHuman
from hrc_sim_node.commands import wrench_on
from hrc_sim_node.physics import PhysicsParams, SliderPendulumBall
from hrc_study.statistics import mean_interval
import numpy
from scipy import stats

from hrc_partners.crossplay import format_cell

DOFS = ('translation', 'rotation')
OWN_SUBTASK = {'translation': 'slider', 'rotation': 'pendulum'}
ROBOT_SUBTASKS = ['slider', 'pendulum', 'ball']


@dataclass
class CalibrationPlan:
    """How long the calibration takes."""

    episodes_per_dof: int = 5       # short episodes with the person on each degree of freedom
    seconds: float = 12.0           # s of simulation per episode
    rest_seconds: float = 5.0       # s between episodes (counted in the person's time)
    seed: int = 0                   # seeds of the episodes' initial states

    @property
    def person_seconds(self) -> float:
        """Return the person's time: every episode plus the rests between them."""
        episodes = 2 * self.episodes_per_dof
        return episodes * self.seconds + (episodes - 1) * self.rest_seconds


class ScriptedRobot:
    """The scripted PD controller standing in for a trained robot (deterministic)."""

    kind = 'scripted PD controller (stand-in for a trained robot)'

    def __init__(self, dof: str, noise: float = 0.0, seed: int = 0, max_torque: float = 0.5):
        self.controller = ScriptedPartner(dof, max_torque=max_torque, noise=noise, seed=seed)

    def start_episode(self, limits) -> None:
        """Nothing to reset (``limits``: the sim's, unused by the scripted controller)."""

    def act(self, state, human_command: float) -> float:
        """Return the robot's command in [-1, 1]."""
        return self.controller(state, ROBOT_SUBTASKS)

    def end_episode(self, state) -> None:
        """Nothing to close."""


class TrainedRobot:
    """A trained agent's frozen deterministic policy (evaluation episodes of an AgentCore)."""

    kind = 'trained agent'

    def __init__(self, checkpoint, seed: int = 0):
        self.core = evaluation_core(checkpoint, seed, episodes=10000)
        self.dof = self.core.robot_dof

    def start_episode(self, limits) -> None:
        """Open an evaluation episode of the core, which acts with the sim's ``limits``."""
        self.core.set_limits(limits)
        self.core.start_episode()

    def act(self, state, human_command: float) -> float:
        """Return the policy's command for ``state``."""
        decision = self.core.act(state, human_command if self.core.needs_human_action else None)
        return float(decision.action)

    def end_episode(self, state) -> None:
        """Close the core's episode."""
        self.core.end_episode(state)


class PersonSide:
    """The calibrated person as the human side of the engine's loop (``hrc_engine.loop``).

    ``person``: ``act(state, subtasks, now)`` (a SimulatedHuman built for the sim's human
    period); asked at every state the human answers (the period's and, at the human's rate,
    each slice state), on the calibration's clock: ``clock_start`` (s, rests between episodes
    included) plus the state's time in the episode (its stamp) and one human step, the moment
    the person's command applies.
    """

    def __init__(self, person, limits: SimLimits, clock_start: float):
        self.person = person
        self.limits = limits
        self.clock_start = float(clock_start)
        self.dof, self.subtasks = 'rotation', []
        self.answers_states = True
        self._first_stamp = None

    def on_session(self, dof: str, involved: bool, subtasks) -> None:
        """Take the roles of the assignment."""
        self.dof, self.subtasks = dof, list(subtasks)

    def start_episode(self, episode: int) -> None:
        """Start the episode's clock at its first state."""
        self._first_stamp = None

    def answer(self, episode: int, state, stamp_ns: int, slice_index: int = 0) -> HumanAnswer:
        """Return the person's answer to a (slice) state."""
        if self._first_stamp is None:
            self._first_stamp = stamp_ns
        now = self.clock_start + (stamp_ns - self._first_stamp) * 1e-9 + self.limits.human_step
        command = float(self.person.act(state, self.subtasks, now=now))
        return HumanAnswer(command, command * self.limits.full_scale(self.dof), self.dof,
                           SOURCE_SIMULATED, 'calibrated person', True)


def team_episode(sim, robot, person, person_dof: str, seed: int, clock_start: float) -> tuple:
    """Run one episode; return (team total error, the person's own-subtask error).

    Through the engine's loop on ``sim``: the person (:class:`PersonSide`) answers each state
    at the human's rate; the robot acts on the period's state with the person's answer.
    """
    limits = SimLimits.of(sim.params)
    robot_dof = other_dof(person_dof)
    loop = EpisodeLoop.on_physics(sim, PersonSide(person, limits, clock_start), robot_dof)
    loop.set_roles(robot_dof, person_dof, True, [OWN_SUBTASK[person_dof], 'ball'])
    robot.start_episode(limits)
    advanced = loop.start(0, int(seed))
    team, own, steps = 0.0, 0.0, 0
    while not advanced.episode_over:
        state = advanced.state
        team += abs(state.slider_position) + abs(state.pendulum_angle) + abs(state.ball_position)
        own += abs(getattr(state, 'slider_position' if person_dof == 'translation'
                           else 'pendulum_angle'))
        steps += 1
        answer = loop.answer()
        command = min(1.0, max(-1.0, robot.act(advanced.observed, answer.command)))
        advanced = loop.step(wrench_on(robot_dof, command * limits.full_scale(robot_dof)),
                             answer)
    robot.end_episode(advanced.observed)
    return team / max(steps, 1), own / max(steps, 1)


@dataclass
class Assignment:
    """The measured team with the person on one degree of freedom."""

    person_dof: str
    robot: str                      # what drove the other degree of freedom
    team_errors: typing.List[float]  # per episode
    own_errors: typing.List[float]   # per episode, the person's level-2 subtask (m or rad)

    def team(self):
        """Return the expected team error (hrc_study Interval)."""
        return mean_interval(self.team_errors)

    def skill(self):
        """Return the person's own-subtask error on this degree of freedom (Interval)."""
        return mean_interval(self.own_errors)


@dataclass
class Advice:
    """The recommendation and what it rests on."""

    assignments: typing.Dict[str, Assignment]   # by the person's degree of freedom
    recommended: str                            # person's dof, or '' for no clear difference
    person_seconds: float

    def difference(self) -> str:
        """Return 'translation - rotation d [low, high]' (paired t, 95 %)."""
        difference, low, high = difference_interval(
            self.assignments[DOFS[0]].team_errors, self.assignments[DOFS[1]].team_errors)
        return f'translation - rotation {difference:+.4f} [{low:+.4f}, {high:+.4f}]'

    def describe(self) -> str:
        """Return the recommendation as readable lines."""
        lines = []
        for dof, assignment in self.assignments.items():
            unit = 'm' if dof == 'translation' else 'rad'
            lines.append(f'person on {dof:11} (robot on {other_dof(dof)}, {assignment.robot}): '
                         f"expected team error {format_cell(assignment.team())}; person's "
                         f'{OWN_SUBTASK[dof]} error {format_cell(assignment.skill())} {unit} '
                         f'({len(assignment.team_errors)} episodes)')
        if self.recommended:
            lines.append(f'recommendation: the person drives the {self.recommended}, the robot '
                         f'the {other_dof(self.recommended)} (difference {self.difference()})')
        else:
            lines.append(f'recommendation: no clear difference (difference {self.difference()}'
                         f'); either assignment, or calibrate longer')
        lines.append(f"calibration: {self.person_seconds:.0f} s of the person's time")
        return '\n'.join(lines)


def difference_interval(first, second, confidence: float = 0.95) -> tuple:
    """Return (mean difference first - second, low, high), a t interval.

    Paired (the t interval of the per-pair differences) when both have the same length: the
    calibration runs its episodes in pairs with the same initial state, one of each
    assignment; Welch's interval otherwise.
    """
    a, b = numpy.asarray(first, dtype=float), numpy.asarray(second, dtype=float)
    if len(a) == len(b) and len(a) >= 2:
        differences = a - b
        spread = float(differences.std(ddof=1)) / math.sqrt(len(a))
        half = float(stats.t.ppf(0.5 + confidence / 2, len(a) - 1)) * spread
        mean = float(differences.mean())
        return mean, mean - half, mean + half
    if len(a) < 2 or len(b) < 2:
        return float(a.mean() - b.mean()), math.nan, math.nan
    va, vb = a.var(ddof=1) / len(a), b.var(ddof=1) / len(b)
    difference = float(a.mean() - b.mean())
    scale = math.sqrt(va + vb)
    if scale == 0:
        return difference, difference, difference
    freedom = (va + vb) ** 2 / (va ** 2 / (len(a) - 1) + vb ** 2 / (len(b) - 1))
    half = float(stats.t.ppf(0.5 + confidence / 2, freedom)) * scale
    return difference, difference - half, difference + half


def recommend(assignments: typing.Dict[str, Assignment]) -> str:
    """Return the person's dof of the clearly better assignment, or '' (no clear difference).

    Clear: the paired 95 % t interval of the difference of the two team errors excludes 0.
    """
    _, low, high = difference_interval(assignments[DOFS[0]].team_errors,
                                       assignments[DOFS[1]].team_errors)
    if math.isnan(low) or low <= 0 <= high:
        return ''
    return DOFS[0] if high < 0 else DOFS[1]


def calibrate(person_for, robots: typing.Dict[str, object], plan: CalibrationPlan,
              physics_overrides: dict = None) -> Advice:
    """Run the calibration and return the advice.

    ``person_for(dof, limits)``: the person driving ``dof`` (``reset(episode)``, ``act(state,
    subtasks, now)``: a SimulatedHuman or a ClonedHuman), given the sim's
    :class:`~hrc_common.contract.SimLimits` (its control period); ``robots[person_dof]``: the robot
    that holds the other degree of freedom. Episodes alternate between the assignments (a
    person's practice and fatigue do not favour one of them).
    """
    physics = with_overrides(PhysicsParams(), episode_duration=float(plan.seconds),
                             **(physics_overrides or {}))
    people = {dof: person_for(dof, SimLimits.of(physics)) for dof in DOFS}
    results = {dof: Assignment(dof, robots[dof].kind, [], []) for dof in DOFS}
    clock = 0.0
    with SliderPendulumBall(physics) as sim:
        for episode in range(plan.episodes_per_dof):
            for index, dof in enumerate(DOFS if episode % 2 == 0 else DOFS[::-1]):
                number = 2 * episode + index
                people[dof].reset(number)
                team, own = team_episode(sim, robots[dof], people[dof], dof,
                                         plan.seed * 1000 + episode, clock)
                results[dof].team_errors.append(team)
                results[dof].own_errors.append(own)
                clock += plan.seconds + plan.rest_seconds
    return Advice(results, recommend(results), plan.person_seconds)


def simulated_person(profile, seed: int):
    """Return ``person_for(dof, limits)`` for a simulated person (one seed, both dofs)."""
    return lambda dof, limits: SimulatedHuman(profile, dof, seed=seed,
                                              control_period=limits.human_step)


def weaken(person, dof: str, factor: float):
    """Return ``person`` ``factor`` times worse at judging ``dof``'s quantity.

    Perception noise, per-episode bias and the error at which the stick is pushed fully are
    multiplied by ``factor`` for the slider (translation) or the beam angle (rotation).
    """
    name = OWN_SUBTASK[dof]
    return dataclasses.replace(person, **{
        f'{name}_{field}': getattr(person, f'{name}_{field}') * float(factor)
        for field in ('noise', 'bias', 'full_scale')})


def asymmetric_person(base, seed: int, weak_dof: str, factor: float):
    """Return person ``seed`` of ``base``'s population, ``factor`` times worse at ``weak_dof``.

    Known asymmetric skill, everything else as the person of ``base`` (e.g. of
    ``paper_symmetric``).
    """
    return weaken(sample_person(base, seed), weak_dof, factor)


@dataclass
class Draw:
    """One simulated person of the validation, with the advice and the truth."""

    person: int                     # population seed
    weak_dof: str                   # the degree of freedom the person judges worse
    factor: float                   # how much worse
    advice: Advice                  # from the short calibration
    truth: typing.Dict[str, object]  # person's dof -> Interval of a long evaluation
    better: str                     # the truly better assignment, '' none, 'small' (see validate)

    @property
    def correct(self) -> bool:
        """Return whether the advice is right: the better one, or no clear difference."""
        if self.better == 'small':
            return self.advice.recommended in ('', self.truth_better)
        return self.advice.recommended == self.better

    @property
    def truth_better(self) -> str:
        """Return the assignment with the lower long-run mean."""
        return min(DOFS, key=lambda dof: self.truth[dof].estimate)


def validate(draws: int, plan: CalibrationPlan, truth_episodes: int = 16,
             robot_noise: float = 1.0, base_profile: str = 'paper_symmetric',
             factors=(1.0, 6.0), seed: int = 0, clear_margin: float = 0.2,
             truth_seconds: float = 0.0, profiles_file=None) -> typing.List[Draw]:
    """Run the advisor on ``draws`` simulated people with known asymmetric skills.

    Person k: ``asymmetric_person(base, 1000 * seed + k, weak dof, factor)`` with the weak
    dof and the factor drawn (numpy, ``seed``). The truth: ``truth_episodes`` episodes of each
    assignment (of ``truth_seconds``, default the calibration's length) with other initial
    states and person noise; the assignments differ clearly when
    the truth's 95 % interval of the difference excludes 0 and the difference is at least
    ``clear_margin`` of the larger error (``better`` the better one); they do not differ when
    the interval includes 0 (``better`` ''); a significant difference below the margin is
    ``small`` (either answer counts as right there). The robot on both
    sides: the scripted PD controller with command noise ``robot_noise`` standing in for a
    trained robot (a robot that is not perfect on either degree of freedom, so the person's
    skill decides).
    """
    base = load_profile(base_profile, profiles_file)
    rng = numpy.random.default_rng([seed, 15])
    robots = {dof: ScriptedRobot(other_dof(dof), noise=robot_noise, seed=seed) for dof in DOFS}
    truth_plan = CalibrationPlan(truth_episodes, truth_seconds or plan.seconds,
                                 plan.rest_seconds, plan.seed + 7)
    results = []
    for index in range(draws):
        weak = DOFS[int(rng.integers(2))]
        factor = float(rng.uniform(*factors))
        person = asymmetric_person(base, 1000 * seed + index, weak, factor)
        advice = calibrate(simulated_person(person, index), robots,
                           CalibrationPlan(plan.episodes_per_dof, plan.seconds,
                                           plan.rest_seconds, plan.seed + 100 * index))
        truth = calibrate(simulated_person(person, index + 50000), robots,
                          CalibrationPlan(truth_episodes, truth_plan.seconds,
                                          plan.rest_seconds, truth_plan.seed + 100 * index))
        difference, low, high = difference_interval(truth.assignments[DOFS[0]].team_errors,
                                                    truth.assignments[DOFS[1]].team_errors)
        larger = max(truth.assignments[dof].team().estimate for dof in DOFS)
        significant = not (math.isnan(low) or low <= 0 <= high)
        if significant and abs(difference) >= clear_margin * larger:
            better = truth.recommended
        else:
            better = '' if not significant else 'small'
        results.append(Draw(1000 * seed + index, weak, factor, advice,
                            {dof: truth.assignments[dof].team() for dof in DOFS}, better))
    return results


def validation_table(results: typing.List[Draw]) -> str:
    """Return the validation as a Markdown table and a summary line."""
    lines = ['| person | weaker at | x | advice: person on translation | person on rotation | '
             'advice | truth (long run): translation | rotation | truth | right |',
             '|---|---|---|---|---|---|---|---|---|---|']
    for draw in results:
        advice = draw.advice.assignments
        lines.append(
            f'| {draw.person} | {draw.weak_dof} | {draw.factor:.1f} | '
            f'{format_cell(advice["translation"].team())} | '
            f'{format_cell(advice["rotation"].team())} | {draw.advice.recommended or "no clear"}'
            f' | {format_cell(draw.truth["translation"])} | '
            f'{format_cell(draw.truth["rotation"])} | {draw.better or "no difference"} | '
            f'{"yes" if draw.correct else "no"} |')
    clear = [draw for draw in results if draw.better in DOFS]
    unclear = [draw for draw in results if not draw.better]
    small = [draw for draw in results if draw.better == 'small']
    lines.append('')
    lines.append(f'clear cases: {sum(draw.correct for draw in clear)} of {len(clear)} right; '
                 f'no difference: {sum(draw.correct for draw in unclear)} of {len(unclear)} '
                 f'answered "no clear difference"; small differences: '
                 f'{sum(draw.correct for draw in small)} of {len(small)} not answered wrongly')
    return '\n'.join(lines)
