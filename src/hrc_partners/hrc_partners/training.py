"""Train the agents that cross-play compares: one simulated person vs a population (offline).

    hrc partners train --out runs/partners --case 2 --seeds 0 1 \
        --episodes 250 --profile paper

For each seed, trains a case agent with the simulated human ``--profile`` itself (``one``) and
with a new person of its population every episode (``population``), in one process
(hrc_engine.offline: the engine's loop with a partner, no ROS, one torch thread). Each agent is
saved as ``<out>/<kind>-s<seed>.pt`` (the agent node's checkpoint format) with
``<kind>-s<seed>.json``: its training partner as a cross-play partner specification
(``profile:paper`` or ``population:paper``), episodes, convergence, wall seconds.
"""

import json
import pathlib
import sys

from hrc_agent_node.agent_core import AgentCore
from hrc_agent_node.checkpoint import save_checkpoint
from hrc_agent_node.config import AgentParams
from hrc_common.contract import SimLimits
from hrc_common.params import with_overrides
from hrc_engine.offline import run_session
from hrc_engine.partners import MixturePartner, parse_spec, SimulatedHumanPartner, spec_problem
from hrc_joystick_node.human_profile import load_profile
from hrc_sim_node.physics import PhysicsParams, SliderPendulumBall
from hrc_partners.training_args import build_parser


def training_partner(core, seed: int, limits: SimLimits, profile: str, population_every: int,
                     profiles_file=None, mixture=None) -> tuple:
    """Return (the partner :func:`train_agent` trains ``core`` with, its specification text).

    A simulated person acts at the sim's human period, as the offline loop calls it.
    """
    if mixture:
        trained_with = 'mixture:' + '+'.join(mixture)
        return (MixturePartner(parse_spec(trained_with).parts, core.human_dof, seed, limits,
                               max(1, population_every), profiles_file), trained_with)
    partner = SimulatedHumanPartner(load_profile(profile, profiles_file), core.human_dof,
                                    seed, limits.human_step, population_every)
    return partner, f'population:{profile}' if population_every else f'profile:{profile}'


def train_agent(case: int, seed: int, episodes: int, profile: str, population_every: int,
                preset: str, checkpoint, profiles_file=None, mixture=None) -> dict:
    """Train one agent offline, save its checkpoint; return its summary (JSON-able).

    ``mixture``: partner specifications to draw from every ``population_every`` episodes
    (hrc_engine.partners.MixturePartner) instead of the ``profile`` or its population.
    """
    physics = PhysicsParams()
    limits = SimLimits.of(physics)
    core = AgentCore(with_overrides(
        AgentParams(), case=case, seed=seed, preset=preset, max_training_episodes=episodes,
        evaluation_episodes=0, checkpoint_dir='', torch_threads=1), limits=limits)
    partner, trained_with = training_partner(core, seed, limits, profile, population_every,
                                             profiles_file, mixture)
    with SliderPendulumBall(physics) as sim:
        summary = run_session(core, sim, partner)
    save_checkpoint(core, checkpoint)
    return {'checkpoint': str(checkpoint), 'case': case, 'seed': seed, 'preset': preset,
            'training_partner': trained_with, 'population_every': population_every,
            'training_episodes': summary['training_episodes'],
            'human_involved_episodes': summary['human_involved_episodes'],
            'converged': summary['converged'], 'wall_seconds': summary['wall_seconds']}


def main(argv=None) -> int:
    """Train one-person and population agents per seed; print one JSON line per agent."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.episodes < 1 or args.population_every < 1:
        print('train_partners_agents: --episodes and --population-every must be >= 1',
              file=sys.stderr)
        return 2
    if 'mixture' in args.kinds:
        problems = [problem for problem in map(spec_problem, args.mixture) if problem]
        if not args.mixture or problems:
            for problem in problems or ['--kinds mixture needs --mixture SPEC...']:
                print(f'train_partners_agents: {problem}', file=sys.stderr)
            return 2
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    for seed in args.seeds:
        for kind in args.kinds:
            every = args.population_every if kind != 'one' else 0
            stem = out / f'c{args.case}-{kind}-s{seed}'
            summary = train_agent(args.case, seed, args.episodes, args.profile, every,
                                  args.preset, stem.with_suffix('.pt'),
                                  mixture=args.mixture if kind == 'mixture' else None)
            stem.with_suffix('.json').write_text(json.dumps(summary, indent=2) + '\n')
            print(json.dumps(summary), flush=True)
    return 0


if __name__ == '__main__':
    sys.exit(main())
