#!/usr/bin/env python3
"""Held-out partners: a robot scored against the robot trained for each partner (the oracle).

The protocol (in the manner of ZSC-Eval's best-response-relative score, for continuous
control): the held-out partners are the people unlike the training population
(``hrc_partners.partners_first.unlike_people`` of person N of the profile: slower,
heavier-handed, lapsing, timid; each one trait outside the population's spread) and person N
itself. For each, the **oracle** is a robot of the paper's task-first strategy trained with that
very partner (``bench/unlike_people_oracle.py --json``: case 2 when the robot rotates, case 1
when it translates), its frozen policy evaluated with the partner met afresh. The robot under
test (a partners-first robot of case 8 or 7, trained with the simulated population and never
with the partner: the final checkpoints of ``hrc experiment --checkpoints``) is scored twice:

* **met first**: its frozen policy with the partner met afresh (the partner's first
  ``--episodes`` episodes), its total error over the oracle's;
* **after adapting**: a session with the partner that starts from the robot's policy and
  learns from each of ``--adapt`` of the partner's episodes (``adapting``: the last step, no
  judging; SAC learns inside the episodes), then its policy evaluated as met first is (the
  partner met afresh, the same episodes: the three errors are paired): its error over the
  oracle's. The person's minutes are those episodes at 40 s. ``--adapt-set
  start_from_judged=true --adapt-set judging_interval=0`` adapts by the paper's rule instead (a
  returning person's start: the first episode judges the inherited policy, and a policy the
  judge passes learns no more).

``--train-oracles`` trains the oracles the scores need that the ``--oracles`` file lacks
(``bench/unlike_people_oracle.py``'s sessions, up to ``--oracle-episodes`` each; a capped one
takes 5-14 minutes on 2 shared cores) and adds each to the file as it finishes, so one command
runs the whole protocol and a second run reuses them; each oracle's policy is kept beside the
file (``<oracles>-checkpoints/``). Without ``--oracles`` the reference is
each robot's own error with the session's person met afresh (the robustness ratio of
``bench/partners_first.py``).

Medians over seeds with a 95% percentile bootstrap interval (seeded); the verdict is on the
median ratio, the worst seed beside it. Every run folder is one robot (its learning
configuration is read from its checkpoints)::

    hrc experiment --cases 7 8 --seeds 5 --checkpoints --learning sac --name pf-sac ...
    hrc experiment --cases 7 8 --seeds 5 --checkpoints --learning partner_aware --name pf-pa ...
    python bench/held_out_partners.py runs/pf-sac runs/pf-pa --oracles oracles.json \
        --train-oracles --oracle-episodes 100 --out x.md
"""

import argparse
import json
import multiprocessing
import pathlib
import statistics
import sys
import tempfile

import numpy
import torch

from hrc_agent_node.agent_core import AgentCore
from hrc_agent_node.checkpoint import load_session_start, read_checkpoint, save_checkpoint
from hrc_agent_node.config import AgentParams
from hrc_common.cases import case_table
from hrc_common.contract import SimLimits
from hrc_common.params import from_dict, ParameterError, with_overrides
from hrc_common.session_plan import adapting_agent_parameters
from hrc_engine.offline import run_session
from hrc_joystick_node.human_model import load_human_model
from hrc_partners.partners_first import UNLIKE_TRAITS
from hrc_sim_node.physics import PhysicsParams, SliderPendulumBall
from hrc_study.statistics import bootstrap_interval

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from partners_first import (EVALUATION_FIRST_EPISODE, evaluate, offline_partner,  # noqa: E402
                            sessions)
from unlike_people_oracle import oracle_task, parse_sets, run_one, task_partner  # noqa: E402

ORACLE_CASE = {8: 2, 7: 1}          # the same role assignment in the paper's task first
FIRST_TARGET, ADAPTED_TARGET = 2.0, 1.5
EPISODE_MINUTES = 40.0 / 60.0


def adapting(adapt: int, overrides: dict) -> dict:
    """Return the adapting session's AgentParams but its start: ``overrides`` over ours.

    Ours are ``hrc session --adapt-from``'s (``adapting_agent_parameters``): the robot learns
    from every one of the partner's ``adapt`` episodes, no judging episode. Chosen by
    measurement: adapting by the paper's rule (the first episode judges, a policy the judge
    passes learns no more) never adapts to a partner with whom the inherited policy meets the
    step, however much better that partner's oracle is (docs/partners/held_out.md).
    """
    return {**adapting_agent_parameters(adapt), **overrides}


def adapted_error(task: dict, partner) -> tuple:
    """Return the errors after adapting to ``partner``, and the partner's episodes.

    (error, the partner's episodes, the session's own evaluation error). ``error`` is the
    adapted policy's evaluated as the robot met first and the oracle are (``evaluate``: the
    partner met afresh, the same evaluation episodes), so the three are paired: the session's
    own evaluation comes after its training episodes, from other starting states (with a
    practised partner).
    """
    config = read_checkpoint(task['checkpoint'])['config']
    known = AgentParams.__dataclass_fields__
    trained = from_dict(AgentParams, {name: value for name, value in config['params'].items()
                                      if name in known})
    params = with_overrides(trained, seed=task['seed'], start_from=str(task['checkpoint']),
                            resume_from='', evaluation_episodes=task['episodes'],
                            checkpoint_dir='',
                            torch_threads=1, **task['adapting'])
    physics = PhysicsParams()
    core = AgentCore(params, limits=SimLimits.of(physics))
    load_session_start(core)
    with SliderPendulumBall(physics) as sim:
        summary = run_session(core, sim, offline_partner(partner, core.human_dof, task['seed'],
                                                         SimLimits.of(physics)))
    with tempfile.TemporaryDirectory(prefix='adapted-') as scratch:
        checkpoint = pathlib.Path(scratch) / 'adapted.pt'
        save_checkpoint(core, checkpoint)
        error = evaluate(checkpoint, partner, task['seed'], task['episodes'])
    return (error, int(summary['human_involved_episodes']),
            float(summary['evaluation']['total_error']))


def score(task: dict) -> dict:
    """Score one robot with one held-out partner: met first and after adapting."""
    torch.set_num_threads(1)
    partner = task_partner(task)
    first = evaluate(task['checkpoint'], partner, task['seed'], task['episodes'])
    adapted, episodes, in_session = adapted_error(task, partner)
    return dict(task, checkpoint=str(task['checkpoint']), first=first, adapted=adapted,
                adapt_episodes=episodes, adapted_in_session=in_session)


def robot_name(checkpoint) -> str:
    """Return the robot's learning configuration in words (from its checkpoint)."""
    params = read_checkpoint(checkpoint)['config']['params']
    name = params.get('algorithm', '?')
    if params.get('partner_inference'):
        name += ' + partner model'
    if params.get('action_rate_cost'):
        name += f" + action-rate cost {params['action_rate_cost']:g}"
    return name


def interval_text(values) -> str:
    interval = bootstrap_interval(values, numpy.median)
    if numpy.isnan(interval.low):
        return f'{interval.estimate:.2f}x'
    return f'{interval.estimate:.2f}x [{interval.low:.2f}, {interval.high:.2f}]'


def own_person_references(results: list) -> dict:
    """Return {(oracle case, seed, partner): the robot's error met first with its person}.

    The reference when no oracle was trained: each robot against itself with the session's
    person (keyed as the oracles are, per robot).
    """
    partners = {r['who'] for r in results}
    return {(r['robot'], ORACLE_CASE[r['case']], r['seed'], who): r['first']
            for r in results if r['who'] == 'person' for who in partners}


def verdict(ratios, target: float) -> str:
    """Return whether the median ratio meets ``target``, with the worst seed's ratio."""
    met = 'yes' if statistics.median(ratios) <= target else '**no**'
    return f'{met} (worst {max(ratios):.2f}x)'


def table(results: list, oracles: dict, unpaired=frozenset()) -> list:
    """Return the Markdown lines: per robot, case and partner the ratios to the reference.

    ``oracles`` None: the reference is the robot's own error with the session's person.
    ``unpaired``: the oracles' keys whose evaluation was not on the paired episodes (before
    ``EVALUATION_FIRST_EPISODE``): their reference is marked.
    """
    own = own_person_references(results) if oracles is None else None
    reference = 'oracle' if oracles is not None else "its own with the session's person"
    lines = [f"| robot | case (robot's DOF) | partner | reference error ({reference}) | "
             'met first: error, / reference | '
             f'median <= {FIRST_TARGET:g}x | after adapting: error, / reference | '
             f'median <= {ADAPTED_TARGET:g}x | after adapting / met first | '
             "the partner's episodes (minutes) |", '|---|---|---|---|---|---|---|---|---|---|']
    keys = sorted({(r['robot'], r['case'], r['who']) for r in results})
    for robot, case, who in keys:
        rows = [r for r in results if (r['robot'], r['case'], r['who']) == (robot, case, who)]
        pairs = [(r, oracles.get((ORACLE_CASE[case], r['seed'], who)) if own is None
                  else own.get((robot, ORACLE_CASE[case], r['seed'], who))) for r in rows]
        pairs = [(r, o) for r, o in pairs if o]
        if not pairs:
            continue
        first = [r['first'] / o for r, o in pairs]
        adapted = [r['adapted'] / o for r, o in pairs]
        # 1.00 exactly: the judge kept the robot's policy (paired evaluations, same episodes)
        change = [r['adapted'] / r['first'] for r, _ in pairs]
        episodes = statistics.median(r['adapt_episodes'] for r, _ in pairs)
        dof = case_table()[case].robot_dof
        marked = ' (unpaired)' if any((ORACLE_CASE[case], r['seed'], who) in unpaired
                                      for r, _ in pairs) else ''
        lines.append(
            f'| {robot} | {case} ({dof}) | {who} | '
            f'{statistics.median(o for _, o in pairs):.4f}{marked} | '
            f"{statistics.median(r['first'] for r, _ in pairs):.4f}, {interval_text(first)} | "
            f'{verdict(first, FIRST_TARGET)} | '
            f"{statistics.median(r['adapted'] for r, _ in pairs):.4f}, {interval_text(adapted)} | "
            f'{verdict(adapted, ADAPTED_TARGET)} | {interval_text(change)} | '
            f'{episodes:g} ({episodes * EPISODE_MINUTES:.1f}) |')
    return lines


def parse_arguments(argv) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('runs', type=pathlib.Path, nargs='*',
                        help='<runs-dir>/<experiment>: partners-first robots, one folder each')
    parser.add_argument('--oracles', type=pathlib.Path,
                        help='the oracles: bench/unlike_people_oracle.py --json output (cases 2 '
                        "and 1); without: each robot's errors over its own with the session's "
                        'person (the robustness ratio of bench/partners_first.py)')
    parser.add_argument('--train-oracles', action='store_true',
                        help='train the oracles the scores need that --oracles lacks (up to '
                        "--oracle-episodes of the partner's episodes each) and add them to it")
    parser.add_argument('--oracle-episodes', type=int, default=300,
                        help="an oracle's training episodes at most (default 300)")
    parser.add_argument('--episodes', type=int, default=3, help='evaluation episodes')
    parser.add_argument('--adapt', type=int, default=3, help="the partner's episodes at most")
    parser.add_argument('--adapt-set', action='append', default=[], metavar='NAME=VALUE',
                        help='an AgentParams override of the adapting session, over the '
                        "robot's own configuration (repeatable; shown with the robot's name)")
    parser.add_argument('--clone', action='append', default=[], metavar='NAME=MODEL',
                        help='a cloned person as a held-out partner too (bench/held_out_clones.py'
                        "; repeatable: one model per degree of freedom, 'clone:NAME' in the "
                        "table; a case runs when the clone has the partner's DOF)")
    parser.add_argument('--partners', nargs='+', metavar='NAME',
                        help='only these partners (e.g. clone:novice; default: every one)')
    parser.add_argument('--profile', default='paper')
    parser.add_argument('--seeds', type=int, nargs='*', default=None,
                        help='only these seeds (default: every seed of the runs)')
    parser.add_argument('--parallel', type=int, default=2)
    parser.add_argument('--out', type=pathlib.Path, help='write the table here (Markdown)')
    parser.add_argument('--json', type=pathlib.Path, help='write every score here too')
    parser.add_argument('--scores', type=pathlib.Path,
                        help='the --json of an earlier run: make the table from its scores')
    return parser.parse_args(argv)


def argument_problems(args, adapt_overrides: dict) -> list:
    """Return every reason the arguments cannot run (all at once)."""
    problems = []
    if not args.runs and not args.scores:
        problems.append('give run folders or --scores')
    if args.train_oracles and args.oracles is None:
        problems.append('--train-oracles: give --oracles FILE to keep them in')
    if args.oracles is not None and not args.train_oracles and not args.oracles.is_file():
        problems.append(f'--oracles {args.oracles}: no such file (--train-oracles makes it)')
    if min(args.episodes, args.adapt, args.oracle_episodes, args.parallel) < 1:
        problems.append('--episodes, --adapt, --oracle-episodes and --parallel must be >= 1')
    try:
        with_overrides(AgentParams(), **adapt_overrides)
    except (ValueError, TypeError) as error:
        problems.append(f'--adapt-set: {error}')
    return problems


def parse_clones(items) -> tuple:
    """Return ({'clone:NAME': {dof: model file}}, problems) of NAME=MODEL items."""
    clones, problems = {}, []
    for item in items:
        name, equals, path = item.partition('=')
        if not equals or not name:
            problems.append(f'--clone {item!r}: expected NAME=MODEL')
            continue
        try:
            dof = load_human_model(path)[0]['dof']
        except ParameterError as error:
            problems.append(f'--clone {item}: {error}')
            continue
        models = clones.setdefault(f'clone:{name}', {})
        if dof in models:
            problems.append(f'--clone {item}: {name} has a {dof} model already ({models[dof]})')
        models[dof] = path
    return clones, problems


def adapting_name(overrides: dict) -> str:
    """Return ', adapting with a=1 b=2' ('' without overrides) for the robot's name."""
    if not overrides:
        return ''
    return ', adapting with ' + ' '.join(f'{name}={value}' for name, value in
                                         sorted(overrides.items()))


def partners_of(case: int, clones: dict) -> list:
    """Return the held-out partners of ``case``: the people, then the clones of its DOF."""
    return ['person', *UNLIKE_TRAITS,
            *(name for name, models in clones.items() if case_table()[case].human_dof in models)]


def scoring_tasks(args, adapt_overrides: dict, clones: dict) -> list:
    """Return one task per robot and held-out partner."""
    return [dict(robot=robot_name(entry['checkpoint']) + adapting_name(adapt_overrides),
                 case=entry['case'], seed=entry['seed'], checkpoint=entry['checkpoint'],
                 who=who, profile=args.profile, episodes=args.episodes, adapt=args.adapt,
                 adapt_overrides=adapt_overrides, adapting=adapting(args.adapt, adapt_overrides),
                 clones=clones)
            for run in args.runs for entry in sessions(run) if entry['case'] in ORACLE_CASE
            and (args.seeds is None or entry['seed'] in args.seeds)
            for who in partners_of(entry['case'], clones)
            if args.partners is None or who in args.partners]


def train_missing_oracles(args, needed, pool, clones=None) -> list:
    """Train the oracles of ``needed`` ((case, seed, partner)) not in --oracles; return all.

    ``clones``: the cloned partners' model files ({'clone:NAME': {dof: model file}}).
    """
    rows = json.loads(args.oracles.read_text()) if args.oracles.is_file() else []
    clones = clones or {}
    # a clone's oracle counts only if it trained with the same model files
    have = {(row['case'], row['seed'], row['who']) for row in rows
            if row['profile'] == args.profile
            and (row.get('clones') or {}).get(row['who']) == clones.get(row['who'])}
    missing = sorted(set(needed) - have)
    print(f'held_out_partners: training {len(missing)} oracles ({len(have)} in '
          f'{args.oracles})', flush=True)
    kept = args.oracles.with_name(args.oracles.stem + '-checkpoints')   # the oracles' policies
    kept.mkdir(exist_ok=True)
    for row in pool.imap_unordered(run_one, [
            dict(oracle_task(case, seed, who, args.profile, args.oracle_episodes, args.episodes,
                             clones=clones), keep_in=str(kept))
            for case, seed, who in missing]):
        rows.append(row)
        args.oracles.write_text(json.dumps(rows, indent=2))   # kept as each one finishes
        print(f"  oracle case {row['case']} seed {row['seed']} {row['who']}: error "
              f"{row['fresh_error']:.4f} after {row['human']} episodes", flush=True)
    return rows


def run_pool(args, results: list, pool, clones=None) -> tuple:
    """Train the missing oracles (--train-oracles) and score the robots; return (oracles, scores).

    ``oracles`` is None when none were trained (they are read from --oracles then).
    """
    oracle_rows = None
    if args.train_oracles:
        oracle_rows = train_missing_oracles(args, {(ORACLE_CASE[r['case']], r['seed'], r['who'])
                                                   for r in results}, pool, clones)
    if not args.scores:
        print(f'held_out_partners: {len(results)} scores on {args.parallel} processes',
              flush=True)
        results = pool.map(score, results)
    return oracle_rows, results


def main(argv=None) -> int:
    args = parse_arguments(argv)
    adapt_overrides, problems = parse_sets(args.adapt_set, '--adapt-set')
    clones, clone_problems = parse_clones(args.clone)
    problems += clone_problems + argument_problems(args, adapt_overrides)
    known = set(partners_of(7, clones)) | set(partners_of(8, clones))
    unknown = sorted(set(args.partners or ()) - known)
    if unknown:
        problems.append(f'--partners: unknown {unknown} (known: {sorted(known)})')
    if problems:
        print('held_out_partners: ' + '; '.join(problems), file=sys.stderr)
        return 2
    if args.scores:
        results = json.loads(args.scores.read_text())
        for row in results:
            # named again from the checkpoint where it is here (scores of before named robots
            # otherwise); kept scores (docs/partners/) keep their names without the robots
            if pathlib.Path(row['checkpoint']).is_file():
                row['robot'] = robot_name(row['checkpoint']) + adapting_name(
                    row.get('adapt_overrides') or {})
    else:
        results = scoring_tasks(args, adapt_overrides, clones)
        if not results:
            print(f'held_out_partners: no partners-first checkpoint under {args.runs}',
                  file=sys.stderr)
            return 2
    oracle_rows = None
    if args.train_oracles or not args.scores:   # kept scores alone need no process
        with multiprocessing.get_context('spawn').Pool(args.parallel) as pool:
            oracle_rows, results = run_pool(args, results, pool, clones)
    if args.json and not args.scores:
        args.json.write_text(json.dumps(results, indent=2))
    if oracle_rows is None and args.oracles is not None:
        oracle_rows = json.loads(args.oracles.read_text())
    oracles = None if oracle_rows is None else {
        (row['case'], row['seed'], row['who']): row['fresh_error'] for row in oracle_rows
        if row['profile'] == args.profile}
    return write_table(results, oracles, args.out, unpaired_oracles(oracle_rows or []))


def unpaired_oracles(rows: list) -> set:
    """Return the keys of the oracles not evaluated on the paired episodes (older files)."""
    return {(row['case'], row['seed'], row['who']) for row in rows
            if row.get('evaluated_from') != EVALUATION_FIRST_EPISODE}


def write_table(results: list, oracles: dict, out, unpaired=frozenset()) -> int:
    """Print the table (and write it to ``out``); return 0."""
    lines = table(results, oracles, unpaired)
    print('\n'.join(lines))
    if out:
        out.write_text('\n'.join(lines) + '\n')
    return 0


if __name__ == '__main__':
    sys.exit(main())
