"""The offline partners: who stands in for the person when no human node runs.

A partner is a callable ``partner(state, subtasks) -> command in [-1, 1]`` on the human's
degree of freedom, where ``state`` has the PhysicsState attributes and ``subtasks`` are the
ids the session assigns to the partner; one with ``start_episode(episode)`` is told each
episode before it starts, and one with ``takes_time`` true is also given ``now``, the state's
time on the session clock (s, its stamp), as the human node's core gives it to the simulated
person (fatigue and rest run on it). The in-process loop asks it as the human side
(``hrc_engine.loop.PartnerSide``) at the human's rate: the period's state and each slice state.

* :class:`ScriptedPartner`: not a model of a person but a deterministic, reproducible PD
  controller with which learners can be compared;
* :class:`SimulatedHumanPartner`: ``hrc_joystick_node``'s simulated human, one person or a new
  person of the population around a profile every N episodes (population training);
* :class:`ClonedPartner`: a human model cloned from recordings;
* :class:`MixturePartner`: a new partner drawn from specifications every N episodes.

A partner is named by a short string (the command lines take them as they are):

* ``profile:NAME`` -- the simulated-human profile NAME itself (one person, whose practice,
  fatigue and adaptation carry over between the episodes of an evaluation);
* ``person:NAME:K`` -- person K of the population around NAME
  (``hrc_joystick_node.population.sample_person(profile, K)``);
* ``population:NAME`` -- a new person of NAME's population at every episode (the training
  distribution of an agent trained with ``--population-every 1``; drawn with evaluation seeds
  no training uses);
* ``model:PATH`` -- a human model cloned from recordings (``hrc_joystick_node.human_model``);
* ``mixture:SPEC+SPEC+...`` -- a new partner drawn from the specs at every episode
  (:class:`MixturePartner`; the training distribution of ``hrc partners train --kinds
  mixture``).

Profiles come from the installed ``params/sim_human.yaml`` unless a profiles file is given.

The scripted partner's control laws:

* translation: ``u = -(kp * S_x + kd * dS_x/dt)`` when it holds ``slider`` (else 0): the slider
  moves the ball only through (g + a) sin P_z, too weakly to hold the ball with it;
* rotation: ``u = -(kp * (P_z - P_ref) + kd * dP_z/dt) + feed-forward``, where ``P_ref = 0``
  when it holds ``pendulum`` and, when it also holds ``ball``, ``P_ref = kb * B_y + kbv * dB_y/dt``
  (tilt the east end up while the ball is east of the middle, so the ball rolls back) and the
  feed-forward cancels the ball's torque on the beam (m_b g B_y cos P_z).
"""

from dataclasses import dataclass
import math
import pathlib
import typing

from hrc_common.contract import check_dof, SimLimits
from hrc_common.params import ParameterError
from hrc_joystick_node.human_model import ClonedHuman
from hrc_joystick_node.human_profile import load_profile
from hrc_joystick_node.population import sample_person
from hrc_joystick_node.sim_human import SimulatedHuman
import numpy as np


@dataclass
class PDGains:
    """Gains of the scripted partner, in normalized command per SI unit."""

    slider_kp: float = 20.0       # 1/m: a 5 cm offset commands full force
    slider_kd: float = 2.0        # s/m (larger gains chatter at the 5 Hz control rate)
    pendulum_kp: float = 6.0      # 1/rad
    pendulum_kd: float = 0.5      # s/rad (more derivative rings at the 5 Hz control rate)
    ball_kp: float = 0.8          # rad/m: desired tilt per m of ball offset
    ball_kd: float = 0.4          # rad*s/m
    max_reference: float = 0.25   # rad: |P_ref| limit


class ScriptedPartner:
    """PD partner on ``dof``; deterministic unless ``noise`` (std of the command) is set."""

    def __init__(self, dof: str, gains: PDGains = None, max_torque: float = 0.5,
                 ball_mass: float = 0.05, gravity: float = 9.81, noise: float = 0.0,
                 seed: int = 0):
        self.dof = check_dof(dof)
        self.gains = gains or PDGains()
        self.max_torque = max_torque
        self.ball_weight = ball_mass * gravity   # N: the ball's pull on the beam
        self.noise = noise
        self.rng = np.random.default_rng(seed)

    def __call__(self, state, subtasks) -> float:
        """Return the command in [-1, 1] for ``state`` given the partner's subtasks."""
        g = self.gains
        command = 0.0
        if self.dof == 'translation':
            if 'slider' in subtasks:
                command = -(g.slider_kp * state.slider_position
                            + g.slider_kd * state.slider_velocity)
        else:
            reference = 0.0
            feed_forward = 0.0
            if 'ball' in subtasks:
                reference = g.ball_kp * state.ball_position + g.ball_kd * state.ball_velocity
                reference = max(-g.max_reference, min(g.max_reference, reference))
                # The ball east of the middle presses the east end down: push it back up.
                feed_forward = self.ball_weight * state.ball_position \
                    * math.cos(state.pendulum_angle) / self.max_torque
            if 'pendulum' in subtasks or 'ball' in subtasks:
                command = -(g.pendulum_kp * (state.pendulum_angle - reference)
                            + g.pendulum_kd * state.pendulum_angular_velocity) + feed_forward
        if self.noise > 0:
            command += float(self.rng.normal(0.0, self.noise))
        return float(min(1.0, max(-1.0, command)))


def person_seed(session_seed: int, draw: int) -> int:
    """Return the population seed of the ``draw``-th person of a session (31-bit)."""
    return int(np.random.SeedSequence([int(session_seed), int(draw), 0x9E3779B9])
               .generate_state(1)[0] & 0x7FFFFFFF)


class SimulatedHumanPartner:
    """``hrc_joystick_node``'s simulated human as an offline partner, alone or as a population.

    ``control_period``: the s between calls, the sim's human period (``SimLimits.human_step``:
    the loop asks the person at every state the human answers); no default.

    ``population_every`` 0: one person, the profile itself, for the whole session (fatigue,
    practice and adaptation carry over between episodes). N > 0: population training, a new
    person drawn with ``sample_person(profile, person_seed(seed, episode // N))`` every N
    episodes (1: every episode), each new to the task. Every episode kind (training, judging,
    evaluation) meets the person the rule gives, so judging and evaluation measure the team
    with the training distribution. Call :meth:`start_episode` before each episode (the
    offline loop does).
    """

    def __init__(self, profile, dof: str, seed: int, control_period: float,
                 population_every: int = 0):
        if population_every < 0:
            raise ValueError(f'population_every must be >= 0, got {population_every}')
        self.profile = profile
        self.dof = dof
        self.seed = int(seed)
        self.control_period = float(control_period)
        self.population_every = int(population_every)
        self.draw = None          # index of the person drawn (None: the profile itself)
        self.person = None        # the HumanProfile of the current person
        self.human = None         # their SimulatedHuman

    def start_episode(self, episode: int) -> None:
        """Meet the person of ``episode`` (draw a new one when the rule says so); reset."""
        draw = int(episode) // self.population_every if self.population_every else None
        if self.human is None or draw != self.draw:
            self.draw = draw
            self.person = self.profile if draw is None else \
                sample_person(self.profile, person_seed(self.seed, draw))
            seed = self.seed if draw is None else person_seed(self.seed, draw)
            self.human = SimulatedHuman(self.person, self.dof, seed=seed,
                                        control_period=self.control_period)
        self.human.reset(int(episode))

    takes_time = True

    def __call__(self, state, subtasks, now=None) -> float:
        """Return the person's stick command in [-1, 1] for ``state`` (``now``: its time, s)."""
        if self.human is None:
            raise RuntimeError('call start_episode() before the first command')
        return float(self.human.act(state, list(subtasks), now=now))


KINDS = ('profile', 'person', 'population', 'model', 'mixture')
EVALUATION_SEED_OFFSET = 5000   # evaluation person draws: seeds no training session uses


@dataclass(frozen=True)
class PartnerSpec:
    """A parsed partner specification."""

    text: str                       # as given, e.g. 'person:paper:100000'
    kind: str                       # one of KINDS
    name: str = ''                  # profile name (profile, person, population)
    person: int = -1                # person index (person)
    path: str = ''                  # model file (model)
    parts: tuple = ()               # the specs of a mixture


def spec_problem(text: str) -> typing.Optional[str]:
    """Return why ``text`` is not a partner specification, or None."""
    kind, _, rest = str(text).partition(':')
    if kind not in KINDS or not rest:
        return (f'partner {text!r}: expected profile:NAME, person:NAME:K, population:NAME, '
                f'model:PATH or mixture:SPEC+SPEC')
    if kind == 'mixture':
        problems = [spec_problem(part) for part in rest.split('+')]
        nested = [part for part in rest.split('+') if part.startswith('mixture:')]
        problems = [problem for problem in problems if problem]
        problems += [f'partner {text!r}: a mixture of mixtures' for _ in nested[:1]]
        return '; '.join(problems) or None
    if kind == 'person':
        name, _, index = rest.rpartition(':')
        if not name or not index.isdigit():
            return f'partner {text!r}: expected person:NAME:K with K an integer >= 0'
    if kind == 'model' and not pathlib.Path(rest).is_file():
        return f'partner {text!r}: no such model file {rest}'
    return None


def parse_spec(text: str) -> PartnerSpec:
    """Return the PartnerSpec of ``text``; ParameterError if it is not one."""
    problem = spec_problem(text)
    if problem:
        raise ParameterError(problem)
    kind, _, rest = text.partition(':')
    if kind == 'person':
        name, _, index = rest.rpartition(':')
        return PartnerSpec(text, kind, name=name, person=int(index))
    if kind == 'model':
        return PartnerSpec(text, kind, path=rest)
    if kind == 'mixture':
        return PartnerSpec(text, kind, parts=tuple(parse_spec(part) for part in rest.split('+')))
    return PartnerSpec(text, kind, name=rest)


def parse_specs(texts) -> typing.List[PartnerSpec]:
    """Return the specs of ``texts``; ParameterError listing every bad one at once."""
    problems = [problem for problem in map(spec_problem, texts) if problem]
    if problems:
        raise ParameterError('; '.join(problems), problems)
    return [parse_spec(text) for text in texts]


class ClonedPartner:
    """A cloned human model as an offline partner (``start_episode`` resets its history).

    The offline loop calls a partner at the human's rate: the period's state, then each slice
    state (``limits.human_slices`` calls per control period, every ``limits.human_step`` s).
    The model was cloned from recordings cut at the control period (one state of history per
    control step, ``ClonedHuman``): it acts on the period's state and holds that command over
    the period's slices, as the engine's and the graph's human core run a model
    (``hrc_joystick_node.human_core``) and as a person's stick stays where it is between the
    robot's steps.
    """

    def __init__(self, path, dof: str, limits: SimLimits):
        self.human = ClonedHuman(path, dof, control_period=limits.control_period)
        # calls of the offline loop per new command of the model: one a control period
        self.calls_per_command = limits.human_slices
        self.calls = 0                         # calls since the episode started
        self.command = 0.0                     # the model's newest command, held in [-1, 1]

    def start_episode(self, episode: int) -> None:
        """Clear the model's state history; the next call is a period's state."""
        self.human.reset(int(episode))
        self.calls = 0

    def __call__(self, state, subtasks) -> float:
        """Return the model's stick command in [-1, 1] (held between its control steps)."""
        if self.calls % self.calls_per_command == 0:
            self.command = float(self.human.act(state, list(subtasks)))
        self.calls += 1
        return self.command


def make_partner(spec: PartnerSpec, dof: str, seed: int, limits: SimLimits, profiles_file=None):
    """Return the offline partner of ``spec`` on ``dof`` (``seed``: its evaluation seed).

    ``limits``: the sim's. A simulated person acts at the sim's human period, as the engine's
    and the graph's person; a cloned model at the control period, the rate its recordings
    were cut at (:class:`ClonedPartner`).
    """
    if spec.kind == 'model':
        return ClonedPartner(spec.path, dof, limits)
    if spec.kind == 'mixture':
        return MixturePartner(spec.parts, dof, seed + EVALUATION_SEED_OFFSET, limits, 1,
                              profiles_file)
    profile = load_profile(spec.name, profiles_file)
    seconds = limits.human_step
    if spec.kind == 'person':
        return SimulatedHumanPartner(sample_person(profile, spec.person), dof, seed, seconds)
    if spec.kind == 'population':
        return SimulatedHumanPartner(profile, dof, seed + EVALUATION_SEED_OFFSET, seconds,
                                     population_every=1)
    return SimulatedHumanPartner(profile, dof, seed, seconds)


class MixturePartner:
    """Population training over partner specifications: profiles, populations and clones.

    Every ``every`` episodes a new partner is drawn uniformly from ``specs`` (numpy, seeded by
    ``seed`` and the draw index): ``population:NAME`` gives a new person of that population
    at each draw, ``person:``/``profile:`` that person, ``model:`` the cloned model. The
    offline loop tells it each episode (``start_episode``).
    """

    def __init__(self, specs, dof: str, seed: int, limits: SimLimits, every: int = 1,
                 profiles_file=None):
        if every < 1:
            raise ValueError(f'every must be >= 1, got {every}')
        self.specs = list(specs)
        self.dof = dof
        self.seed = int(seed)
        self.limits = limits           # the sim's: its control period is each partner's
        self.every = int(every)
        self.profiles_file = profiles_file
        self.draw = None
        self.spec = None             # the PartnerSpec of the current partner
        self.partner = None
        self.drawn = []              # (draw, spec text) of every partner met, in order

    def start_episode(self, episode: int) -> None:
        """Meet the partner of ``episode`` (a new draw every ``every`` episodes)."""
        draw = int(episode) // self.every
        if draw != self.draw:
            self.draw = draw
            rng = np.random.default_rng([self.seed, draw, 15])
            self.spec = self.specs[int(rng.integers(len(self.specs)))]
            seed = person_seed(self.seed, draw)
            if self.spec.kind == 'population':
                person = sample_person(load_profile(self.spec.name, self.profiles_file), seed)
                self.partner = SimulatedHumanPartner(person, self.dof, seed,
                                                     self.limits.human_step)
            else:
                self.partner = make_partner(self.spec, self.dof, seed, self.limits,
                                            self.profiles_file)
            self.drawn.append((draw, self.spec.text))
        self.partner.start_episode(int(episode))

    takes_time = True

    def __call__(self, state, subtasks, now=None) -> float:
        """Return the current partner's command (``now``: the state's time, s)."""
        if self.partner is None:
            raise RuntimeError('call start_episode() before the first command')
        if getattr(self.partner, 'takes_time', False):
            return self.partner(state, subtasks, now=now)
        return self.partner(state, subtasks)
