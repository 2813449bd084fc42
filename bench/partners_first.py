#!/usr/bin/env python3
"""Partners first (cases 7, 8) against the paper's strategy: the person's time and robustness.

Reads the final checkpoints of an experiment run with ``--checkpoints`` (in-process engine)::

    hrc experiment --cases 2 8 1 7 --seeds 3 --checkpoints \
        --name pf-3seeds --bags-dir /tmp/pf/bags --runs-dir /tmp/pf/runs --no-report
    python bench/partners_first.py /tmp/pf/runs/pf-3seeds [more runs] --episodes 3

and prints, per case, over the seeds: the person's (human-involved) episodes, all training
episodes, the population episodes, and the team's total error in the session's evaluation
(median [min, max]). Then each final policy is evaluated offline (``--episodes`` per person and
seed, one torch thread) with the session's person (person N of the ``paper`` population for
seed N, as the experiment gives it) and with four people unlike the training population
(``hrc_partners.partners_first.unlike_people``: slower, heavier-handed, lapsing, timid): the
error with each, and its ratio to the error with the session's person.
"""

import argparse
import json
import pathlib
import statistics
import sys

import torch

from hrc_agent_node.checkpoint import read_checkpoint
from hrc_common.contract import SimLimits
from hrc_engine.offline import evaluation_core, run_session
from hrc_engine.partners import ClonedPartner, SimulatedHumanPartner
from hrc_joystick_node.population import sample_person
from hrc_joystick_node.human_profile import load_profile
from hrc_partners.partners_first import unlike_people
from hrc_sim_node.physics import PhysicsParams, SliderPendulumBall


def spread(values) -> str:
    """Return 'median [min, max]' of ``values``."""
    values = list(values)
    if not values:
        return '-'
    number = '{:.0f}' if all(float(v).is_integer() for v in values) else '{:.4f}'
    return (f'{number.format(statistics.median(values))} '
            f'[{number.format(min(values))}, {number.format(max(values))}]')


def sessions(run: pathlib.Path) -> list:
    """Return one dict per session of the run that has a final checkpoint."""
    found = []
    for final in sorted(run.glob('case*-seed*/checkpoints/*/final.pt')):
        session_id = final.parent.name
        case, seed = session_id[4:].split('-seed')
        core = read_checkpoint(final)['core']
        counters = core['counters']
        results = core['evaluation_results']
        found.append({'case': int(case), 'seed': int(seed), 'checkpoint': final,
                      'human': counters['human_involved_episodes'],
                      'total': counters['total_episodes'],
                      'population': counters.get('population_episodes', 0),
                      'converged': core['progress']['finished'],
                      'error': statistics.fmean(sum(r['errors'].values()) for r in results)})
    return found


# Every policy is evaluated on the same episodes (their starting states and the partner's
# noise follow the episode index and the seed), so errors of two policies are paired. Far
# from any training episode's index.
EVALUATION_FIRST_EPISODE = 1_000_000


def offline_partner(partner, dof: str, seed: int, limits: SimLimits):
    """Return the offline loop's partner on ``dof``.

    ``partner``: a simulated person (a ``HumanProfile``: acts at the sim's human_period, as
    the engine's person) or a cloned person ({dof: model file}: acts at the control period,
    ``ClonedPartner``).
    """
    if isinstance(partner, dict):
        return ClonedPartner(partner[dof], dof, limits)
    return SimulatedHumanPartner(partner, dof, seed, limits.human_step)


def evaluate(checkpoint, partner, seed: int, episodes: int) -> float:
    """Return the mean total error of the checkpoint's frozen policy with ``partner``.

    ``partner``: as :func:`offline_partner` takes it.
    """
    physics = PhysicsParams()
    # a policy adapted from another (agent.start_from in its checkpoint) is evaluated alone
    core = evaluation_core(checkpoint, seed, episodes, {'start_from': ''})
    core.episode = EVALUATION_FIRST_EPISODE     # not the checkpoint's next episode
    with SliderPendulumBall(physics) as sim:
        return float(run_session(core, sim, offline_partner(
            partner, core.human_dof, seed, SimLimits.of(physics)))['evaluation']['total_error'])


def main(argv=None) -> int:
    """Print the tables; return 0 (2 when the run holds no final checkpoint)."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('runs', type=pathlib.Path, nargs='+',
                        help='<runs-dir>/<experiment name> (one or more)')
    parser.add_argument('--episodes', type=int, default=3,
                        help='offline evaluation episodes per person and seed (0: none)')
    parser.add_argument('--profile', default='paper', help="the sessions' profile")
    parser.add_argument('--unlike-cases', type=int, nargs='*', default=None,
                        help='cases evaluated offline (default: every case of the run)')
    parser.add_argument('--seeds', type=int, nargs='*', default=None,
                        help='only these seeds (default: every seed of the run)')
    parser.add_argument('--json', type=pathlib.Path, help='write every number here too')
    args = parser.parse_args(argv)
    torch.set_num_threads(1)
    found = [entry for run in args.runs for entry in sessions(run)
             if args.seeds is None or entry['seed'] in args.seeds]
    if not found:
        print(f'partners_first: no final checkpoint under {args.runs}', file=sys.stderr)
        return 2
    cases = sorted({entry['case'] for entry in found})
    print('| case | seeds | converged | person episodes | all episodes | population episodes '
          '| total error (evaluation) |')
    print('|---|---|---|---|---|---|---|')
    for case in cases:
        rows = [entry for entry in found if entry['case'] == case]
        print(f'| {case} | {len(rows)} | {sum(r["converged"] for r in rows)} | '
              f'{spread(r["human"] for r in rows)} | {spread(r["total"] for r in rows)} | '
              f'{spread(r["population"] for r in rows)} | {spread(r["error"] for r in rows)} |')
    if args.episodes > 0:
        base = load_profile(args.profile)
        names = ['person'] + list(unlike_people(base))
        print(f'\nOffline evaluation, {args.episodes} episodes per person and seed: total '
              "error, and its ratio to the error with the session's person")
        print('| case | ' + ' | '.join(names) + ' | worst ratio |')
        print('|---' * (len(names) + 2) + '|')
        for case in cases if args.unlike_cases is None else args.unlike_cases:
            errors = {name: [] for name in names}
            ratios = {name: [] for name in names[1:]}
            for entry in (entry for entry in found if entry['case'] == case):
                person = sample_person(base, entry['seed'])
                people = dict(person=person, **unlike_people(person))
                own = evaluate(entry['checkpoint'], person, entry['seed'], args.episodes)
                entry['offline'] = {'person': own}
                errors['person'].append(own)
                for name in names[1:]:
                    error = evaluate(entry['checkpoint'], people[name], entry['seed'],
                                     args.episodes)
                    entry['offline'][name] = error
                    errors[name].append(error)
                    ratios[name].append(error / own)
            cells = [spread(errors['person'])] + [
                f'{spread(errors[name])} ({statistics.median(ratios[name]):.2f}x)'
                for name in names[1:]]
            worst = max(max(values) for values in ratios.values())
            print(f'| {case} | ' + ' | '.join(cells) + f' | {worst:.2f}x |', flush=True)
    if args.json:
        args.json.write_text(json.dumps(
            [dict(entry, checkpoint=str(entry['checkpoint'])) for entry in found], indent=2))
    return 0


if __name__ == '__main__':
    sys.exit(main())
