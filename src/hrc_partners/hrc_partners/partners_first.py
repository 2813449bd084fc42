"""Partners first (cases 7 and 8): train with simulated people before the person joins. Pure.

The ``partners_first`` strategy (``params/cases.yaml``) has three steps: the robot alone, the
team task with a population of simulated people, the team task with the person. The first
two need no person, so they run here, in one process (``hrc_engine.offline``: the engine's
loop with a partner as the human, the same cores as the engine and the nodes), in minutes;
:func:`pretrain` returns the checkpoint in which the strategy stands at
the person's step. The session with the person (the in-process engine, the experiment runner
or the graph session) then starts from that checkpoint (agent ``resume_from``): its first
episode judges the pre-trained policy with the person (the step's ``judge_first``), and the
person's step can end after ``convergence_window`` episodes.
A population step that has not met its condition after ``POPULATION_BUDGET`` episodes ends
anyway (``AgentCore.skip_step``; ``PretrainResult.population_met`` says so): the population,
with its slow and noisy people, may be a harder partner than the person.

**The population (modelling choice).** Set in the ``population`` block of the
``partners_first`` strategy (``params/cases.yaml``, :class:`PopulationSettings`); by default
:func:`default_population`: persons
``POPULATION_FIRST_PERSON`` .. + ``persons_per_profile`` - 1 of the populations around the
``paper``, ``novice`` and ``skilled`` profiles (``hrc_joystick_node.population.sample_person``),
one drawn at random for every episode (``hrc_engine.partners.MixturePartner``). Three
profiles so that the robot meets slow and fast, noisy and precise people; person numbers from
1000 on so that no training person is a person the experiment runner gives a session (its
seed: person 0, 1, ... of the profile) nor the profile's own mean person (``person: -1``).
The session's person is checked against the population: :func:`pretrain` refuses a
population that holds it (:func:`person_spec_of` names it as a partner specification).
The training people act at the sim's ``human_period``, as the session's person does.

By hand (then start the session with the person as the last line says)::

    python -m hrc_partners.partners_first --case 8 --seed 0 --set agent.preset=tuned ...
"""

import argparse
from dataclasses import asdict, dataclass, field, replace
import json
import pathlib
import sys
import time

from hrc_common import bounded_yaml

from hrc_agent_node.agent_core import AgentCore
from hrc_agent_node.checkpoint import save_checkpoint
from hrc_agent_node.config import AgentParams, CASES_FILE_NAME, share_file
from hrc_agent_node.strategies import pretrains_with_population
from hrc_common.contract import Phase, SimLimits
from hrc_common.params import from_dict, param, ParameterError, validate, with_overrides
from hrc_common.paths import params_dir as default_params_dir
from hrc_common.session_plan import compose, new_session_id, parse_overrides, SessionSettings
from hrc_engine.loop import run_agent_session
from hrc_engine.offline import partner_loop
from hrc_engine.partners import MixturePartner, parse_specs
from hrc_sim_node.physics import physics_params_of, PhysicsParams, SliderPendulumBall
from hrc_sim_node.sim_params import SimParams

POPULATION_PROFILES = ('paper', 'novice', 'skilled')
# People unlike the population, each one trait of a person pushed outside the population's
# spread (modelling choices; the population's reaction delay varies by ~15 %, its full scales by
# ~20 %, its lapses by ~50 %): {name: {field: factor on the person's value}}.
UNLIKE_TRAITS = {
    'slower': {'reaction_delay': 2.5, 'neuromuscular_time': 2.5},      # 0.2 s -> 0.5 s
    'heavier_handed': {'slider_full_scale': 0.4, 'pendulum_full_scale': 0.4,  # 2.5x the gain
                       'motor_noise': 2.0},
    'lapsing': {'lapse_probability': 7.5, 'lapse_duration': 2.5},       # 7.5x the lapses
    'timid': {'slider_full_scale': 2.5, 'pendulum_full_scale': 2.5, 'max_rate': 0.4},
}
POPULATION_FIRST_PERSON = 1000      # person numbers below it are left to the sessions' people
PERSONS_PER_PROFILE = 8
# Population episodes after which the population step ends even if unmet (modelling choice:
# a population with slow and noisy people may be harder than the person; measured, case 8's
# population step met its condition after 14-29 episodes, case 7's not in 266).
POPULATION_BUDGET = 60


@dataclass
class PopulationSettings:
    """The pre-training's population (the people, the budget, the SAC schedule).

    The ``population`` block of the ``partners_first`` strategy in ``params/cases.yaml``, read
    by :func:`population_settings`.
    """

    profiles: list = param(list(POPULATION_PROFILES), 'Simulated-human profiles whose '
                           'populations the training people come from (params/sim_human.yaml)')
    persons_per_profile: int = param(PERSONS_PER_PROFILE, 'Training people per profile',
                                     low=1, high=10000)
    first_person: int = param(POPULATION_FIRST_PERSON, "Person number of each profile's first "
                              "training person (the sessions' people are 0, 1, ...)", low=0)
    budget: int = param(POPULATION_BUDGET, 'Population episodes after which the population '
                        'step ends unmet (0: no limit but max_training_episodes)', low=0)
    sac_updates_per_step: int = param(0, "SAC: critic gradient steps per transition in the "
                                      "pre-training (no person's time there: the sim's data "
                                      "is cheap, the gradient steps are ~95 % of its wall "
                                      "time); 0 = the session's agent.sac_updates_per_step",
                                      low=0, high=1000)

    def check(self) -> list:
        """Return the reasons across fields (the profiles: a non-empty list of names)."""
        if not isinstance(self.profiles, list) or not self.profiles \
                or not all(isinstance(name, str) and name for name in self.profiles):
            return [f'profiles: a non-empty list of profile names, got {self.profiles!r}']
        return []

    def population(self) -> list:
        """Return the population as partner specifications (:func:`default_population`)."""
        return default_population(tuple(self.profiles), self.persons_per_profile,
                                  self.first_person)


def population_settings(cases_file='') -> PopulationSettings:
    """Return the ``population`` block of ``partners_first`` in ``cases_file``.

    ``cases_file``: default the installed params/cases.yaml. Defaults where the block or a key
    is missing; ParameterError (a ValueError) with every reason on bad values.
    """
    document = bounded_yaml.load_file(cases_file or share_file(CASES_FILE_NAME)) or {}
    block = ((document.get('strategies') or {}).get('partners_first') or {}) \
        .get('population') or {}
    if not isinstance(block, dict):
        raise ParameterError(f'partners_first population: a mapping, got {block!r}',
                             [f'population: a mapping, got {block!r}'])
    return from_dict(PopulationSettings, block)


def default_population(profiles=POPULATION_PROFILES, persons_per_profile=PERSONS_PER_PROFILE,
                       first_person=POPULATION_FIRST_PERSON) -> list:
    """Return the default training population as partner specifications ('person:paper:1000')."""
    return [f'person:{profile}:{first_person + index}' for profile in profiles
            for index in range(int(persons_per_profile))]


def unlike_people(person) -> dict:
    """Return {name: HumanProfile}: ``person`` with each trait of :data:`UNLIKE_TRAITS` changed."""
    people = {}
    for name, factors in UNLIKE_TRAITS.items():
        changed = replace(person, description=f'{name}: {person.description}',
                          **{trait: getattr(person, trait) * factor
                             for trait, factor in factors.items()})
        problems = validate(changed)
        if problems:
            raise ValueError(f'unlike person {name}: {problems}')
        people[name] = changed
    return people


def person_spec_of(human_parameters: dict) -> str:
    """Return the session's simulated person as a partner specification.

    ``human_parameters``: the human node's parameters (``profile``, ``person``: -1 is the
    profile itself, N person N of its population; ``input: model`` a cloned model).
    """
    if human_parameters.get('input') == 'model' and human_parameters.get('model_file'):
        return f'model:{human_parameters["model_file"]}'
    profile = human_parameters.get('profile') or 'paper'
    person = int(human_parameters.get('person', -1))
    return f'profile:{profile}' if person == -1 else f'person:{profile}:{person}'


@dataclass
class PretrainResult:
    """What :func:`pretrain` did (plain values)."""

    checkpoint: str
    case: int
    seed: int
    episodes: int                   # training and judging episodes so far (the core's total)
    population_episodes: int        # of which with a simulated person of the population
    reached_person_step: bool       # False: max_training_episodes ended training before it
    population_met: bool            # the population step met its condition (else: budget)
    person: str                     # the session's person (not in the population)
    population: list = field(default_factory=list)   # the specifications drawn from
    partners_met: list = field(default_factory=list)  # the population episodes' partners
    wall_seconds: float = 0.0
    sac_updates_per_step: int = 0   # the pre-training's SAC gradient steps (0: the session's)

    def to_plain(self) -> dict:
        """Return the result as JSON-able values."""
        return asdict(self)


def pretrain(agent_params, physics: PhysicsParams, checkpoint, person: str,
             population=None, profiles_file=None,
             population_budget: int = POPULATION_BUDGET,
             sac_updates_per_step: int = 0) -> PretrainResult:
    """Run a partners-first case up to the person's step; save and return its checkpoint.

    ``agent_params``: the session's AgentParams (case, seed, preset, learner, rules: the
    checkpoint must fit the session that resumes it). ``physics``: the sim's. ``person``: the
    session's person as a partner specification (:func:`person_spec_of`); ValueError if the
    population holds it. ``population``: partner specifications (default
    :func:`default_population`), one drawn for every episode, seeded by the session seed.
    ``population_budget``: episodes of a population step after which it ends unmet
    (``AgentCore.skip_step``; 0: no limit but ``max_training_episodes``). The training people
    act at the sim's human period. ``sac_updates_per_step`` > 0: the SAC
    learner's gradient steps per transition in the pre-training (the checkpoint's config keeps
    them, the session that resumes it uses its own); 0: the session's.
    """
    population = list(population or default_population())
    specs = parse_specs(population)
    if person in population:
        raise ValueError(f"the session's person {person} is in the training population: the "
                         'person must be new to the robot')
    started = time.perf_counter()
    limits = SimLimits.of(physics)
    if sac_updates_per_step and agent_params.algorithm == 'sac':
        agent_params = with_overrides(agent_params, sac_updates_per_step=sac_updates_per_step)
    core = AgentCore(agent_params, limits=limits)
    if not core.case.has_population_steps:
        raise ValueError(f'case {core.case_id} ({core.strategy}) has no population step')
    core.population_partner = True
    partner = MixturePartner(specs, core.human_dof, core.seed, limits, 1, profiles_file)
    met = []
    person_step = core.case.first_person_step
    population_met = True
    in_step = 0                     # episodes of the current population step
    with SliderPendulumBall(physics) as sim:
        loop = partner_loop(core, sim, partner)     # one session clock for the people
        while core.phase not in (Phase.DONE, Phase.EVALUATION) \
                and core.progress.step_index < person_step:
            step = core.progress.step_index
            population_step = core.training_step.partner == 'population'
            run_agent_session(core, loop, max_episodes=1)
            if population_step:
                met.append(partner.spec.text)
                in_step = in_step + 1 if core.progress.step_index == step else 0
                if population_budget and in_step >= population_budget \
                        and core.phase == Phase.TRAINING:
                    core.skip_step()
                    population_met, in_step = False, 0
    core.population_partner = False
    checkpoint = pathlib.Path(checkpoint)
    checkpoint.parent.mkdir(parents=True, exist_ok=True)
    save_checkpoint(core, checkpoint)
    return PretrainResult(str(checkpoint), core.case_id, core.seed, core.total_episodes,
                          core.population_episodes,
                          core.progress.step_index >= person_step
                          and core.activity_phase in (Phase.TRAINING, Phase.UPDATING),
                          population_met, person, population, met,
                          time.perf_counter() - started,
                          sac_updates_per_step if agent_params.algorithm == 'sac' else 0)


PRETRAINED_CHECKPOINT = 'pretrained.pt'    # in the session's run folder
PRETRAIN_RECORD = 'pretrain.json'


def prepare_person_session(parameters: dict, run_dir, population=None):
    """Pre-train a partners-first session; return the agent parameters that start it, or None.

    The one hook every runner calls before it starts a session: ``parameters`` are the
    session's composed parameters ({node: {...}}: ``hrc_common.session_plan.compose``, as the
    session runner and the engine build them). For a case without a population step (1-6):
    None, nothing done. Otherwise :func:`pretrain` runs (``run_dir``/pretrained.pt, a record in
    ``run_dir``/pretrain.json) and the return value is the agent parameters to set:
    ``resume_from`` (the checkpoint) and ``max_training_episodes`` (the pre-training's episodes
    plus the session's own budget, which the person's step gets whole).
    """
    if not pretrains_with_population(parameters['agent']):
        return None
    agent = from_dict(AgentParams, dict(parameters['agent'], checkpoint_dir='',
                                        resume_from=''))
    physics = physics_params_of(from_dict(SimParams, parameters['sim']))
    settings = population_settings(agent.cases_file)
    run_dir = pathlib.Path(run_dir)
    result = pretrain(agent, physics, run_dir / PRETRAINED_CHECKPOINT,
                      person_spec_of(parameters['human']), population or settings.population(),
                      parameters['human'].get('profiles_file') or None, settings.budget,
                      settings.sac_updates_per_step)
    (run_dir / PRETRAIN_RECORD).write_text(json.dumps(result.to_plain(), indent=2) + '\n')
    return {'resume_from': result.checkpoint,
            'max_training_episodes': result.episodes + agent.max_training_episodes}


def main(argv=None) -> int:
    """Pre-train a partners-first session; print its record and the command that continues it."""
    parser = argparse.ArgumentParser(
        prog='python -m hrc_partners.partners_first',
        description='Pre-train a partners-first session (case 7 or 8): the robot alone, then a '
                    'population of simulated people, no person; then start the session with '
                    'the person from the checkpoint (the command is printed).')
    parser.add_argument('--case', type=int, default=8, help='7 or 8 (default 8)')
    parser.add_argument('--seed', type=int, default=0, help='session seed')
    parser.add_argument('--session-id', default='', help="default: the session runner's")
    parser.add_argument('--runs-dir', default='runs', help="the session runner's --runs-dir")
    parser.add_argument('--profile', default='', help="the person's simulated-human profile")
    parser.add_argument('--set', action='append', default=[], metavar='NODE.PARAM=VALUE',
                        help='parameter override, as for the session (repeatable)')
    parser.add_argument('--params-dir', default='', help='default: ./params or the installed')
    args = parser.parse_args(argv)
    try:
        settings = SessionSettings(case=args.case, seed=args.seed, session_id=args.session_id,
                                   runs_dir=args.runs_dir, human_profile=args.profile,
                                   overrides=parse_overrides(args.set))
        settings.session_id = settings.session_id or new_session_id(settings)
        params_dir = pathlib.Path(args.params_dir) if args.params_dir else default_params_dir()
        parameters = compose(settings, params_dir)
        from_dict(AgentParams, parameters['agent'])      # every bad agent value, at once
    except ValueError as error:
        print(f'partners_first: {error}', file=sys.stderr)
        return 2
    run_dir = pathlib.Path(settings.runs_dir) / settings.session_id
    try:
        start = prepare_person_session(parameters, run_dir)
    except ValueError as error:   # the cases file (its population block too), the task tree
        print(f'partners_first: {error}', file=sys.stderr)
        return 2
    if start is None:
        print(f'partners_first: case {args.case} has no population step (cases 7 and 8 do)',
              file=sys.stderr)
        return 2
    record = json.loads((run_dir / PRETRAIN_RECORD).read_text())
    print(f'partners_first: {record["episodes"]} episodes ({record["population_episodes"]} with '
          f'the population, its condition {"met" if record["population_met"] else "unmet"}) in '
          f'{record["wall_seconds"]:.0f} s; the person\'s step '
          f'{"is next" if record["reached_person_step"] else "was not reached"}')
    print(f'partners_first: {run_dir / PRETRAIN_RECORD}, {start["resume_from"]}')
    overrides = ''.join(f' --set {text}' for text in args.set)
    print(f'then: hrc session --case {args.case} --seed {args.seed} '
          f'--session-id {settings.session_id} --runs-dir {settings.runs_dir}{overrides} '
          f'--resume-from {start["resume_from"]} --episodes {start["max_training_episodes"]}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
