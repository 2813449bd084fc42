"""bench/held_out_partners.py: its arguments, the oracles it trains, the table's verdicts.

The oracle sessions are replaced by a stand-in (no training): what is checked is which
oracles the bench asks for, what it keeps, and the ratios it prints against them.
"""

import importlib.util
import json
import pathlib
import sys

import pytest

BENCH = pathlib.Path(__file__).resolve().parents[1] / 'bench' / 'held_out_partners.py'


@pytest.fixture
def bench():
    sys.path.insert(0, str(BENCH.parent))
    try:
        spec = importlib.util.spec_from_file_location('held_out_bench', BENCH)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
    finally:
        sys.path.remove(str(BENCH.parent))
    return module


class InlinePool:
    """A process pool that runs each task here, in order (the stand-ins stay patched)."""

    def imap_unordered(self, function, tasks):
        return map(function, tasks)


def test_bad_arguments_give_every_reason_and_exit_2(bench, capsys, tmp_path):
    code = bench.main(['--train-oracles', '--adapt', '0', '--adapt-set', 'no_such=1',
                       '--adapt-set', 'broken', str(tmp_path)])
    assert code == 2
    error = capsys.readouterr().err
    for reason in ("--adapt-set 'broken': expected NAME=VALUE",
                   '--train-oracles: give --oracles FILE',
                   '--episodes, --adapt, --oracle-episodes and --parallel must be >= 1',
                   "unexpected keyword argument 'no_such'"):
        assert reason in error, error
    assert 'Traceback' not in error
    assert bench.main(['--oracles', str(tmp_path / 'none.json'), str(tmp_path)]) == 2
    assert 'no such file (--train-oracles makes it)' in capsys.readouterr().err


def test_only_the_missing_oracles_are_trained_and_each_is_kept(bench, monkeypatch, tmp_path):
    oracles = tmp_path / 'oracles.json'
    known = dict(case=2, seed=0, who='person', profile='paper', fresh_error=0.02)
    other_profile = dict(known, profile='novice', fresh_error=9.0)
    oracles.write_text(json.dumps([known, other_profile]))
    asked = []

    def train(task):
        asked.append((task['case'], task['seed'], task['who'], task['episodes']))
        return dict(task, fresh_error=0.05, human=task['episodes'])

    monkeypatch.setattr(bench, 'run_one', train)
    args = bench.parse_arguments(['--oracles', str(oracles), '--train-oracles',
                                  '--oracle-episodes', '40', 'runs'])
    rows = bench.train_missing_oracles(args, {(2, 0, 'person'), (2, 0, 'slower'),
                                              (1, 1, 'timid')}, InlinePool())
    assert sorted(asked) == [(1, 1, 'timid', 40), (2, 0, 'slower', 40)]
    assert json.loads(oracles.read_text()) == rows and len(rows) == 4


def score(robot, case, seed, who, first, adapted):
    return dict(robot=robot, case=case, seed=seed, who=who, profile='paper', first=first,
                adapted=adapted, adapt_episodes=3)


def test_the_table_divides_by_the_oracle_and_judges_the_median(bench):
    oracles = {(2, seed, 'slower'): 0.1 for seed in range(3)}
    # met first 1.5x, 1.8x, 3.0x the oracle: median 1.8x meets 2x, the worst seed does not
    results = [score('sac', 8, seed, 'slower', first, 0.1 * 1.6)
               for seed, first in enumerate((0.15, 0.18, 0.30))]
    lines = bench.table(results, oracles)
    assert 'reference error (oracle)' in lines[0]
    row = lines[2].split(' | ')
    assert row[2:4] == ['slower', '0.1000']
    assert row[4].startswith('0.1800, 1.80x')
    assert row[5] == 'yes (worst 3.00x)'
    assert row[6].startswith('0.1600, 1.60x') and row[7] == '**no** (worst 1.60x)'
    assert row[8].startswith('0.89x')    # after adapting / met first: 1.6 / 1.8
    assert row[9] == '3 (2.0) |'
    marked = bench.table(results, oracles, unpaired={(2, 1, 'slower')})[2].split(' | ')
    assert marked[3] == '0.1000 (unpaired)'


def test_the_robot_adapts_by_learning_from_every_one_of_the_budget(bench):
    # no judging start, and no judging episode falls due inside the budget
    assert bench.adapting(3, {}) == {'start_from_judged': False, 'max_training_episodes': 3,
                                     'judging_interval': 3}     # hrc session --adapt-from's
    judged = bench.adapting(3, {'start_from_judged': True, 'judging_interval': 0})
    assert judged == {'start_from_judged': True, 'max_training_episodes': 3,
                      'judging_interval': 0}                    # the paper's rule
    bench.with_overrides(bench.AgentParams(), **bench.adapting(3, {}))  # valid parameters


def test_an_adapting_override_is_named_with_the_robot(bench):
    assert bench.adapting_name({}) == ''
    assert bench.adapting_name({'sac_learning_starts': 20, 'a': 1}) == \
        ', adapting with a=1 sac_learning_starts=20'


def test_the_published_tables_are_recomputed_from_their_kept_scores_and_oracles(bench):
    folder = pathlib.Path(__file__).resolve().parents[1] / 'docs' / 'partners'
    page = (folder / 'held_out.md').read_text().splitlines()
    for scores_kind, oracles_kind, rows in (('', '', 2 * 7), ('_judged', '', 2 * 7),
                                            ('_unpaired', '_unpaired', 3 * 2 * 5 + 2 * 2)):
        # paired: the default robot, both cases x seven partners, adapting from every episode
        # and by the paper's rule (judged); before pairing: three robots x two cases x five
        # partners, and two clones with the default robot
        scores = json.loads((folder / f'held_out{scores_kind}_scores.json').read_text())
        oracle_rows = json.loads((folder / f'held_out{oracles_kind}_oracles.json').read_text())
        oracles = {(row['case'], row['seed'], row['who']): row['fresh_error']
                   for row in oracle_rows if row['profile'] == 'paper'}
        lines = bench.table(scores, oracles, bench.unpaired_oracles(oracle_rows))
        assert len(lines) == 2 + rows
        for line in lines:
            assert line in page, line


def clone_bench():
    """Return bench/held_out_clones.py as a module."""
    spec = importlib.util.spec_from_file_location('held_out_clones',
                                                  BENCH.parent / 'held_out_clones.py')
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope='module')
def clone_models(tmp_path_factory):
    # A person recorded and cloned on both DOFs by the clone bench (small: 1 episode of each
    # of 2 sessions per DOF, 5 epochs).
    folder = tmp_path_factory.mktemp('clones')
    code = clone_bench().main(['--person', 'novice', '--sessions', '2', '--episodes', '1',
                               '--epochs', '5', '--out', str(folder)])
    assert code == 0
    return folder


def test_the_clone_bench_refuses_bad_arguments_all_at_once(capsys, tmp_path):
    code = clone_bench().main(['--person', 'nobody', '--sessions', '1', '--epochs', '0',
                        '--out', str(tmp_path / 'missing')])
    assert code == 2
    error = capsys.readouterr().err
    for reason in ('--person nobody', '--sessions must be >= 2', '--epochs must be >= 1',
                   'no such folder'):
        assert reason in error, error


def test_a_clone_is_a_held_out_partner_of_the_cases_of_its_dof(bench, clone_models, capsys):
    rotation = str(clone_models / 'novice-rotation.pt')
    translation = str(clone_models / 'novice-translation.pt')
    clones, problems = bench.parse_clones([f'novice={rotation}', f'novice={translation}'])
    assert problems == []
    assert clones == {'clone:novice': {'rotation': rotation, 'translation': translation}}
    only_rotation, _ = bench.parse_clones([f'novice={rotation}'])
    # case 7: the partner rotates (the clone's DOF); case 8: it translates (no model: no row)
    assert bench.partners_of(7, only_rotation)[-1] == 'clone:novice'
    assert 'clone:novice' not in bench.partners_of(8, only_rotation)
    task = dict(who='clone:novice', profile='paper', seed=0, clones=clones)
    assert bench.task_partner(task) == clones['clone:novice']
    limits = bench.SimLimits.of(bench.PhysicsParams())
    partner = bench.offline_partner(bench.task_partner(task), 'translation', 0, limits)
    assert type(partner).__name__ == 'ClonedPartner'
    _, problems = bench.parse_clones([f'novice={rotation}', f'novice={rotation}', 'x=/no.pt'])
    assert 'novice has a rotation model already' in problems[0]
    assert 'x=/no.pt: model_file /no.pt: cannot read' in problems[1]
    assert bench.main(['runs', '--clone', 'bare', '--partners', 'clone:novice']) == 2
    error = capsys.readouterr().err
    assert "--clone 'bare': expected NAME=MODEL" in error
    assert "--partners: unknown ['clone:novice']" in error


def test_a_clones_oracle_is_kept_only_for_the_same_model(bench, monkeypatch, tmp_path):
    oracles = tmp_path / 'oracles.json'
    old = dict(case=2, seed=0, who='clone:a', profile='paper', fresh_error=0.02,
               clones={'clone:a': {'translation': 'old.pt'}})
    oracles.write_text(json.dumps([old]))
    asked = []
    monkeypatch.setattr(bench, 'run_one', lambda task: asked.append(task['clones']) or
                        dict(task, fresh_error=0.03, human=5))
    args = bench.parse_arguments(['--oracles', str(oracles), '--train-oracles', 'runs'])
    same = {'clone:a': {'translation': 'old.pt'}}
    bench.train_missing_oracles(args, {(2, 0, 'clone:a')}, InlinePool(), same)
    assert asked == []
    other = {'clone:a': {'translation': 'new.pt'}}
    bench.train_missing_oracles(args, {(2, 0, 'clone:a')}, InlinePool(), other)
    assert asked == [other]


def test_every_policy_is_evaluated_on_the_same_episodes(bench, tmp_path):
    # One policy saved at two points of its episode count. Met first, after adapting and the
    # oracle are paired only if an evaluation does not start at the checkpoint's next episode
    # (the starting states and the person's noise follow the episode index).
    physics = bench.PhysicsParams()
    params = bench.with_overrides(bench.AgentParams(), case=2, seed=0, checkpoint_dir='',
                                  torch_threads=1)
    core = bench.AgentCore(params, limits=bench.SimLimits.of(physics))
    early, late = tmp_path / 'early.pt', tmp_path / 'late.pt'
    bench.save_checkpoint(core, early)
    core.episode = 37
    bench.save_checkpoint(core, late)
    person = bench.task_partner(dict(who='person', profile='paper', seed=0))
    assert bench.evaluate(early, person, 0, 1) == bench.evaluate(late, person, 0, 1)
