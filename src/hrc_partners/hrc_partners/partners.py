"""Partner specifications and the offline evaluation of a frozen agent with a partner (no ROS).

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
  (:class:`MixturePartner`; the training distribution of ``train_partners_agents --kinds
  mixture``).

Profiles come from the installed ``params/sim_human.yaml`` unless a profiles file is given.
Partners are callables for :func:`hrc_agent_node.offline.run_session` (``partner(state,
subtasks) -> command`` with ``start_episode(episode)``).
"""

from dataclasses import dataclass, fields
import pathlib
import typing

from hrc_agent_node.agent_core import AgentCore
from hrc_agent_node.checkpoint import load_into, read_checkpoint
from hrc_agent_node.config import AgentParams
from hrc_agent_node.offline import run_session
from hrc_agent_node.partners import person_period, person_seed, SimulatedHumanPartner
from hrc_common.contract import SimLimits
from hrc_common.params import from_dict, ParameterError, with_overrides
from hrc_joystick_node.human_model import ClonedHuman
from hrc_joystick_node.population import sample_person
from hrc_joystick_node.human_profile import load_profile
from hrc_sim_node.physics import PhysicsParams, SliderPendulumBall
import numpy

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
    control step, ``ClonedHuman``). ``period`` ``human`` (the default): it acts on the
    period's state and holds that command over the period's slices, as the engine's and the
    graph's human core run a model (``hrc_joystick_node.human_core``) and as a person's stick
    stays where it is between the robot's steps. ``control``: it acts at every call, as before
    issue 22's leftovers were fixed (its history then spanned a tenth of the time it was
    trained on at human_period 0.02 s); the same numbers when human_period = control_period.
    """

    def __init__(self, path, dof: str, limits: SimLimits, period: str = 'human'):
        person_period(limits, period)          # refuses an unknown period now
        self.human = ClonedHuman(path, dof, control_period=limits.control_period)
        # calls of the offline loop per new command of the model (1: a new one at every call)
        self.calls_per_command = limits.human_slices if period == 'human' else 1
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


def make_partner(spec: PartnerSpec, dof: str, seed: int, limits: SimLimits, profiles_file=None,
                 period: str = 'human'):
    """Return the offline partner of ``spec`` on ``dof`` (``seed``: its evaluation seed).

    ``limits``: the sim's. ``period``: how often a simulated person acts
    (``hrc_agent_node.partners.PERSON_PERIODS``); a cloned model acts at the control period,
    the rate its recordings were cut at, unless ``control`` asks for the old numbers
    (:class:`ClonedPartner`).
    """
    if spec.kind == 'model':
        return ClonedPartner(spec.path, dof, limits, period)
    if spec.kind == 'mixture':
        return MixturePartner(spec.parts, dof, seed + EVALUATION_SEED_OFFSET, limits, 1,
                              profiles_file, period)
    profile = load_profile(spec.name, profiles_file)
    seconds = person_period(limits, period)
    if spec.kind == 'person':
        return SimulatedHumanPartner(sample_person(profile, spec.person), dof, seed, seconds)
    if spec.kind == 'population':
        return SimulatedHumanPartner(profile, dof, seed + EVALUATION_SEED_OFFSET, seconds,
                                     population_every=1)
    return SimulatedHumanPartner(profile, dof, seed, seconds)


def evaluation_core(checkpoint, seed: int, episodes: int, overrides: dict = None):
    """Return an AgentCore that evaluates ``checkpoint``'s frozen policy (``episodes``, seed)."""
    config = read_checkpoint(checkpoint)['config']
    settings = dict(seed=int(seed), evaluation_only=True, resume_from=str(checkpoint),
                    evaluation_episodes=int(episodes), checkpoint_dir='', torch_threads=1)
    settings.update(overrides or {})
    # Checkpoints written before the sim's limits left AgentParams still hold max_force and
    # max_torque among their params: those are the sim's now (run_session gives them).
    known = {field.name for field in fields(AgentParams)}
    trained = from_dict(AgentParams, {name: value for name, value in config['params'].items()
                                      if name in known})
    core = AgentCore(with_overrides(trained, **settings))
    load_into(core, checkpoint, resume=False)
    return core


def evaluate(checkpoint, spec: PartnerSpec, seed: int, episodes: int,
             physics_overrides: dict = None, profiles_file=None) -> float:
    """Return the mean total error of ``checkpoint``'s frozen policy with ``spec`` (one seed)."""
    physics = with_overrides(PhysicsParams(), **(physics_overrides or {}))
    core = evaluation_core(checkpoint, seed, episodes)
    partner = make_partner(spec, core.human_dof, seed, SimLimits.of(physics), profiles_file)
    with SliderPendulumBall(physics) as sim:
        return float(run_session(core, sim, partner)['evaluation']['total_error'])


class MixturePartner:
    """Population training over partner specifications: profiles, populations and clones.

    Every ``every`` episodes a new partner is drawn uniformly from ``specs`` (numpy, seeded by
    ``seed`` and the draw index): ``population:NAME`` gives a new person of that population
    at each draw, ``person:``/``profile:`` that person, ``model:`` the cloned model. The
    offline loop tells it each episode (``start_episode``). ``period``: how often a simulated
    person acts (``hrc_agent_node.partners.PERSON_PERIODS``).
    """

    def __init__(self, specs, dof: str, seed: int, limits: SimLimits, every: int = 1,
                 profiles_file=None, period: str = 'human'):
        if every < 1:
            raise ValueError(f'every must be >= 1, got {every}')
        person_period(limits, period)          # refuses an unknown period now
        self.period = period
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
            rng = numpy.random.default_rng([self.seed, draw, 15])
            self.spec = self.specs[int(rng.integers(len(self.specs)))]
            seed = person_seed(self.seed, draw)
            if self.spec.kind == 'population':
                person = sample_person(load_profile(self.spec.name, self.profiles_file), seed)
                self.partner = SimulatedHumanPartner(person, self.dof, seed,
                                                     person_period(self.limits, self.period))
            else:
                self.partner = make_partner(self.spec, self.dof, seed, self.limits,
                                            self.profiles_file, self.period)
            self.drawn.append((draw, self.spec.text))
        self.partner.start_episode(int(episode))

    def __call__(self, state, subtasks) -> float:
        """Return the current partner's command."""
        if self.partner is None:
            raise RuntimeError('call start_episode() before the first command')
        return self.partner(state, subtasks)
