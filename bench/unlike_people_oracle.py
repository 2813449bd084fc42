#!/usr/bin/env python3
"""How well can any robot of a strategy do with a person unlike the study's.

The partners-first robustness target compares a robot's error with people unlike its training
population (``hrc_partners.partners_first.unlike_people``: slower, heavier-handed, lapsing,
timid) to its error with the person it trained for. This bench asks what that ratio would be
for a robot that *did* train with the unlike person: each session of the paper's task-first
strategy (case 2: the robot rotates, case 1: it translates) is run offline, in one process,
with the default learning configuration (params/learning/sac.yaml) and the unlike
person as the session's person, then its frozen policy is evaluated with that same person twice:
in the session's own final evaluation (the person as the session left them: practised, maybe
tired) and offline with the person met afresh, as ``bench/partners_first.py`` evaluates the
partners-first robots (so its ratios compare with that bench's). The error with person N of the
``paper`` population (``person``) is the reference. A ratio well
above 2x here means the team itself is worse with that person, whoever the robot trained with:
the robustness target cannot be met for that trait by any policy this learner finds.

    python bench/unlike_people_oracle.py --cases 2 --seeds 0 1 2 3 4 --parallel 2

Prints one table per case: per person (the session's, then each unlike one) the sessions that
converged, the person's (human-involved) episodes and the final evaluation's total error,
median [min, max] over the seeds, and the median of the per-seed error ratios to ``person``.
"""

import argparse
import json
import multiprocessing
import pathlib
import statistics
import sys
import tempfile

import torch
import yaml

from hrc_agent_node.config import AgentParams
from hrc_agent_node.agent_core import AgentCore
from hrc_agent_node.checkpoint import save_checkpoint
from hrc_agent_node.strategies import session_case
from hrc_common.contract import SimLimits
from hrc_common.params import with_overrides
from hrc_common.paths import params_dir
from hrc_common.session_plan import DEFAULT_LEARNING, load_learning
from hrc_engine.offline import run_session
from hrc_joystick_node.human_profile import load_profile
from hrc_joystick_node.population import sample_person
from hrc_partners.partners_first import UNLIKE_TRAITS, unlike_people
from hrc_sim_node.physics import PhysicsParams, SliderPendulumBall

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from partners_first import (EVALUATION_FIRST_EPISODE, evaluate, offline_partner,  # noqa: E402
                            spread)

PEOPLE = ('person',) + tuple(UNLIKE_TRAITS)


def study_settings() -> dict:
    """Return the default learning configuration's AgentParams fields (the episode cap apart)."""
    settings = load_learning(params_dir(), DEFAULT_LEARNING)
    settings.pop('max_training_episodes', None)    # each task gives its own
    return settings


def run_one(task: dict) -> dict:
    """Train one session offline with ``task['who']`` as the person; return its numbers."""
    torch.set_num_threads(1)
    partner = task_partner(task)
    physics = PhysicsParams()
    limits = SimLimits.of(physics)
    params = with_overrides(AgentParams(), case=task['case'], seed=task['seed'],
                            max_training_episodes=task['episodes'],
                            evaluation_episodes=task['evaluation_episodes'],
                            checkpoint_dir='', torch_threads=1,
                            **dict(study_settings(), **task['overrides']))
    core = AgentCore(params, limits=limits)
    with SliderPendulumBall(physics) as sim:
        summary = run_session(core, sim, offline_partner(partner, core.human_dof,
                                                         task['seed'], limits))
    with tempfile.TemporaryDirectory(prefix='oracle-') as scratch:
        # kept in task['keep_in'] when given (its policy can be evaluated again without
        # training it again), else in a scratch folder
        folder = pathlib.Path(task.get('keep_in') or scratch)
        checkpoint = folder / f"case{task['case']}-seed{task['seed']}-{task['who']}.pt"
        save_checkpoint(core, checkpoint)
        # As bench/partners_first.py evaluates the partners-first robots: the frozen policy
        # with the same person met afresh (new to the task), offline.
        fresh = evaluate(checkpoint, partner, task['seed'], task['evaluation_episodes'])
    if task.get('keep_in'):
        task = dict(task, checkpoint=str(checkpoint))
    return dict(task, converged=bool(summary['converged']), fresh_error=fresh,
                evaluated_from=EVALUATION_FIRST_EPISODE,
                human=int(summary['human_involved_episodes']),
                total=int(summary['training_episodes']),
                error=float(summary['evaluation']['total_error']),
                seconds=float(summary['wall_seconds']))


def task_partner(task: dict):
    """Return the partner ``task['who']``: a person's ``HumanProfile``, or a clone's model files.

    ``task['clones']`` ({name: {dof: model file}}, optional) names the cloned people; any other
    name is person ``seed`` of the profile or one of the people unlike them.
    """
    clones = task.get('clones') or {}
    if task['who'] in clones:
        return clones[task['who']]
    person = sample_person(load_profile(task['profile']), task['seed'])
    return dict(person=person, **unlike_people(person))[task['who']]


def parse_sets(items, option: str) -> tuple:
    """Return ({name: value}, problems) of NAME=VALUE items (agent.NAME accepted, YAML values)."""
    overrides, problems = {}, []
    for item in items:
        name, equals, value = item.partition('=')
        if not equals:
            problems.append(f'{option} {item!r}: expected NAME=VALUE')
            continue
        overrides[name.removeprefix('agent.')] = yaml.safe_load(value)
    return overrides, problems


def oracle_task(case: int, seed: int, who: str, profile: str, episodes: int,
                evaluation_episodes: int, overrides=None, clones=None) -> dict:
    """Return the task of :func:`run_one`: case ``case`` trained with ``who`` of seed ``seed``.

    ``clones``: {name: {dof: model file}} of the cloned people (:func:`task_partner`).
    """
    return dict(case=case, seed=seed, who=who, profile=profile, episodes=episodes,
                evaluation_episodes=evaluation_episodes, overrides=dict(overrides or {}),
                clones=dict(clones or {}))


def median_ratio(rows, key: str, reference: dict) -> str:
    """Return the median over seeds of row[key] / reference[seed], as '1.23x' ('-': none)."""
    ratios = [row[key] / reference[row['seed']] for row in rows if row['seed'] in reference]
    return f'{statistics.median(ratios):.2f}x' if ratios else '-'


def main(argv=None) -> int:
    """Run the sessions, print the tables; return 0."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--cases', type=int, nargs='+', default=[2],
                        help='cases (default 2: task first, the robot rotates)')
    parser.add_argument('--seeds', type=int, nargs='+', default=[0, 1, 2, 3, 4],
                        help='seeds; seed N trains with person N of the profile (default 0-4)')
    parser.add_argument('--people', nargs='+', choices=PEOPLE, default=list(PEOPLE),
                        help='who the session trains with (default: all)')
    parser.add_argument('--profile', default='paper', help='the population (default paper)')
    parser.add_argument('--episodes', type=int, default=300, help='max training episodes')
    parser.add_argument('--evaluation-episodes', type=int, default=3)
    parser.add_argument('--set', action='append', default=[], metavar='NAME=VALUE',
                        help='an AgentParams override on top of the study settings '
                        '(repeatable; agent.NAME=VALUE is accepted too)')
    parser.add_argument('--parallel', type=int, default=2, help='sessions at once')
    parser.add_argument('--json', type=pathlib.Path, help='write every session here too')
    args = parser.parse_args(argv)
    if args.episodes < 1 or args.evaluation_episodes < 1 or args.parallel < 1:
        print('unlike_people_oracle: --episodes, --evaluation-episodes and --parallel must '
              'be >= 1', file=sys.stderr)
        return 2
    overrides, problems = parse_sets(args.set, '--set')
    for case in args.cases:
        try:
            params = with_overrides(AgentParams(), case=case,
                                    **dict(study_settings(), **overrides))
            if session_case(params)[1].has_population_steps:
                problems.append(f'case {case}: trains with a population first (cases 7, 8: '
                                'bench/partners_first.py); give a case of the paper')
        except (ValueError, TypeError) as error:
            problems.append(f'case {case}: {error}')
    try:
        load_profile(args.profile)
    except (ValueError, KeyError, OSError) as error:
        problems.append(f'--profile {args.profile}: {error}')
    if args.json is not None and not args.json.parent.is_dir():
        problems.append(f'--json {args.json}: no such folder {args.json.parent}')
    if problems:
        print('unlike_people_oracle: ' + '; '.join(problems), file=sys.stderr)
        return 2
    tasks = [oracle_task(case, seed, who, args.profile, args.episodes, args.evaluation_episodes,
                         overrides)
             for case in args.cases for seed in args.seeds for who in args.people]
    print(f'unlike_people_oracle: {len(tasks)} sessions on {args.parallel} processes; '
          f'settings {study_settings()} {overrides}', flush=True)
    with multiprocessing.get_context('spawn').Pool(args.parallel) as pool:
        results = []
        for result in pool.imap_unordered(run_one, tasks):
            results.append(result)
            if args.json:           # kept as each one finishes: a stopped run loses none
                args.json.write_text(json.dumps(results, indent=2))
            print(f"  case {result['case']} seed {result['seed']} {result['who']}: "
                  f"{result['human']} person's episodes, error {result['error']:.4f}, "
                  f"{'converged' if result['converged'] else 'not converged'}, "
                  f"{result['seconds']:.0f} s", flush=True)
    for case in args.cases:
        rows = [r for r in results if r['case'] == case]
        reference = {r['seed']: r['error'] for r in rows if r['who'] == 'person'}
        fresh_reference = {r['seed']: r['fresh_error'] for r in rows if r['who'] == 'person'}
        print(f'\nCase {case}: trained and evaluated with the same person '
              f'({len(args.seeds)} seeds)')
        print("| person | converged | person's episodes | total error, the session's evaluation "
              "| ratio to `person` | total error, the person met afresh | ratio to `person` |")
        print('|---|---|---|---|---|---|---|')
        for who in args.people:
            mine = [r for r in rows if r['who'] == who]
            print(f"| {who} | {sum(r['converged'] for r in mine)}/{len(mine)} | "
                  f"{spread(r['human'] for r in mine)} | "
                  f"{spread(r['error'] for r in mine)} | "
                  f"{median_ratio(mine, 'error', reference)} | "
                  f"{spread(r['fresh_error'] for r in mine)} | "
                  f"{median_ratio(mine, 'fresh_error', fresh_reference)} |")
    return 0


if __name__ == '__main__':
    sys.exit(main())
