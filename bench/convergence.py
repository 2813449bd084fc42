"""Episodes to convergence per case against the scripted PD partner (offline loop, no ROS).

    python bench/convergence.py --presets paper tuned --cases 1 2 3 4 5 6 \
        --seed 0 --episodes 300

Prints one row per (preset, case): training episodes when each training step ended (its
condition met), human-involved episodes, whether training converged, the evaluation metrics of
the final policy (Table II: mean errors, efforts) and the wall time. Default parameters
(Table I PPO, params/task_tree.yaml tolerances, windows 3) unless --set overrides them.
"""

import argparse
import json
import multiprocessing
import sys

import yaml

from hrc_agent_node.agent_core import AgentCore
from hrc_agent_node.config import AgentParams
from hrc_common.cases import paper_case_ids
from hrc_common.params import with_overrides
from hrc_engine.offline import make_partner, run_session
from hrc_sim_node.physics import PhysicsParams, SliderPendulumBall


def run_one(job):
    """Run one offline session; return its summary."""
    preset, case, seed, episodes, evaluation, overrides = job

    physics = PhysicsParams()
    params = with_overrides(AgentParams(), case=case, seed=seed, preset=preset,
                            max_training_episodes=episodes, evaluation_episodes=evaluation,
                            checkpoint_dir='', **overrides)
    core = AgentCore(params)
    with SliderPendulumBall(physics) as sim:
        return run_session(core, sim, make_partner(core, seed=seed))


def main(argv=None) -> int:
    """Run the grid (one process per core) and print a table and JSON lines."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--presets', nargs='+', default=['paper', 'tuned'])
    parser.add_argument('--cases', nargs='+', type=int, default=list(paper_case_ids()))
    parser.add_argument('--seed', type=int, default=0)
    parser.add_argument('--episodes', type=int, default=300, help='max training episodes')
    parser.add_argument('--evaluation-episodes', type=int, default=5)
    parser.add_argument('--processes', type=int, default=2)
    parser.add_argument('--set', nargs='*', default=[], metavar='NAME=VALUE')
    args = parser.parse_args(argv)
    overrides = {name: yaml.safe_load(value)
                 for name, value in (item.split('=', 1) for item in args.set)}
    jobs = [(preset, case, args.seed, args.episodes, args.evaluation_episodes, overrides)
            for preset in args.presets for case in args.cases]
    with multiprocessing.get_context('spawn').Pool(args.processes) as pool:
        summaries = pool.map(run_one, jobs)
    print(f'{"preset":7} {"case":>4} {"step ends (episodes)":>22} {"human":>5} {"total":>5} '
          f'{"conv":>5} {"slider m":>9} {"pend rad":>9} {"ball m":>9} {"robot eff":>9} '
          f'{"human eff":>9} {"wall s":>7}')
    for summary in summaries:
        evaluation = summary['evaluation']
        ends = ','.join(str(value) for value in summary['episodes_to_step_end'].values()) or '-'
        print(f'{summary["preset"]:7} {summary["case"]:>4} {ends:>22} '
              f'{summary["human_involved_episodes"]:>5} {summary["training_episodes"]:>5} '
              f'{str(summary["converged"]):>5} {evaluation.get("slider_error", 0):9.4f} '
              f'{evaluation.get("pendulum_error", 0):9.4f} {evaluation.get("ball_error", 0):9.4f} '
              f'{evaluation.get("robot_effort", 0):9.4f} {evaluation.get("human_effort", 0):9.4f} '
              f'{summary["wall_seconds"]:7.1f}')
    for summary in summaries:
        print(json.dumps(summary))
    return 0


if __name__ == '__main__':
    sys.exit(main())
