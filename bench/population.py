"""What population training buys with partners the agent never met (offline loop, no ROS).

    python bench/population.py --case 2 --seeds 0 1 --episodes 300 \
        --held-out 3 --evaluation-episodes 3

For each seed, trains two agents against hrc_joystick_node's simulated human (``--profile``):
``one person`` (the profile itself, the whole session) and ``population`` (a new person drawn
around the profile every ``--population-every`` episodes). Each trained policy is then
evaluated (deterministic, frozen, the last training step's setting) with the profile itself,
with the population (a new person per episode) and with ``--held-out`` people drawn with seeds
no training used (100000 + k) and with other named profiles (``--profiles``, e.g. novice:
people of another kind). Prints one row per agent: the mean total error of the evaluation
episodes with each partner, and its ratio to the agent's error with its training partner(s).

Every simulated person, in training and in evaluation, acts at the sim's human_period, as the
engine's and the graph's person (the offline loop is the engine's).
"""

import argparse
import json
import sys

from hrc_agent_node.agent_core import AgentCore
from hrc_agent_node.config import AgentParams
from hrc_common.contract import SimLimits
from hrc_common.params import with_overrides
from hrc_engine.offline import make_partner, run_session
from hrc_engine.partners import SimulatedHumanPartner
from hrc_joystick_node.population import sample_person
from hrc_joystick_node.human_profile import load_profile
from hrc_sim_node.physics import PhysicsParams, SliderPendulumBall


def train(case, seed, episodes, profile, population_every, preset):
    """Train one agent; return (its core, the training summary)."""
    physics = PhysicsParams()
    core = AgentCore(with_overrides(
        AgentParams(), case=case, seed=seed, preset=preset, max_training_episodes=episodes,
        evaluation_episodes=0, checkpoint_dir=''), limits=SimLimits.of(physics))
    partner = make_partner(core, seed=seed, kind=f'human:{profile}',
                           population_every=population_every,
                           limits=SimLimits.of(physics))
    with SliderPendulumBall(physics) as sim:
        summary = run_session(core, sim, partner)
    return core, summary


def evaluate(trained, person, population_every, seed, episodes):
    """Return the mean total error of ``trained``'s frozen policy with ``person``."""
    physics = PhysicsParams()
    params = with_overrides(trained.params, evaluation_only=True, resume_from='(in memory)',
                            evaluation_episodes=episodes)
    evaluator = AgentCore(params)
    evaluator.load_state_dict(trained.state_dict(), policy_only=True)
    partner = SimulatedHumanPartner(person, evaluator.human_dof, seed,
                                    SimLimits.of(physics).human_step,
                                    population_every)
    with SliderPendulumBall(physics) as sim:
        return run_session(evaluator, sim, partner)['evaluation']['total_error']


def main(argv=None) -> int:
    """Train and cross-evaluate; print a table and JSON lines."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--case', type=int, default=2)
    parser.add_argument('--seeds', nargs='+', type=int, default=[0])
    parser.add_argument('--episodes', type=int, default=300)
    parser.add_argument('--profile', default='paper')
    parser.add_argument('--preset', default='tuned')
    parser.add_argument('--population-every', type=int, default=1)
    parser.add_argument('--held-out', type=int, default=3)
    parser.add_argument('--evaluation-episodes', type=int, default=3)
    parser.add_argument('--profiles', nargs='*', default=[],
                        help='other named profiles to evaluate with (held out by kind)')
    args = parser.parse_args(argv)

    profile = load_profile(args.profile)
    held_out = [(f'held-out {k}', sample_person(profile, 100000 + k))
                for k in range(args.held_out)]
    held_out += [(name, load_profile(name)) for name in args.profiles]
    rows = []
    for seed in args.seeds:
        for label, every in (('one person', 0), ('population', args.population_every)):
            core, summary = train(args.case, seed, args.episodes, args.profile, every,
                                  args.preset)
            errors = {'profile': evaluate(core, profile, 0, seed, args.evaluation_episodes),
                      'population': evaluate(core, profile, 1, seed + 5000,
                                             args.evaluation_episodes)}
            for name, person in held_out:
                errors[name] = evaluate(core, person, 0, seed, args.evaluation_episodes)
            reference = errors['population' if every else 'profile']
            rows.append({'seed': seed, 'agent': label, 'episodes': summary['training_episodes'],
                         'converged': summary['converged'], 'errors': errors,
                         'ratio_to_training_partner': {name: value / reference
                                                       for name, value in errors.items()}})
            print(json.dumps(rows[-1]), flush=True)
    names = list(rows[0]['errors'])
    print(f'{"seed":>4} {"agent":11} {"episodes":>8} {"conv":>5} '
          + ' '.join(f'{name:>16}' for name in names))
    for row in rows:
        ratios = row['ratio_to_training_partner']
        cells = ' '.join(f'{row["errors"][name]:8.4f} ({ratios[name]:4.1f}x)' for name in names)
        print(f'{row["seed"]:>4} {row["agent"]:11} {row["episodes"]:>8} '
              f'{str(row["converged"]):>5} {cells}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
