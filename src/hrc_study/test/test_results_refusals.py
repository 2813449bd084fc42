"""``hrc results`` refuses to pool sessions that are not seeds of one experiment (exit 2).

It pooled practice-only sessions, sessions where nobody acted as the person, sessions of other
episode limits and repeats of one case with one person as "N seeds" of a profile, and wrote
into the repository's docs/ when no --out was given. An --out it cannot write is one line; an
error inside the statistics is hrc's own and keeps its traceback.
"""

from hrc_msgs.msg import EpisodeSummary
from hrc_testing.bag_traffic import record_in_process, strategy_plan
import pytest

from hrc_study import results_args, results_cli


def config(session_id: str, seed: int, limit: int) -> dict:
    return {'session_id': session_id, 'case': 5, 'strategy': 'learn_together',
            'roles': {'robot': 'translation', 'human': 'rotation'}, 'seeds': {'session': seed},
            'parameters': {'agent': {'max_training_episodes': limit}}}


def record(folder, session_id, seed, plan, limit=100):
    record_in_process(folder, session_id, 5, 'learn_together', seed, plan, steps=6,
                      session_config=config(session_id, seed, limit))


@pytest.fixture
def mixed(tmp_path):
    folder = tmp_path / 'bags'
    together = strategy_plan('learn_together', 2, 0, 1)
    record(folder, 'seed1', 1, together)
    record(folder, 'seed1-again', 1, together)                 # a repeat, not a seed
    record(folder, 'seed2-short', 2, together, limit=2)         # another episode limit
    record(folder, 'seed3-alone', 3, [(0, False, False), (0, False, True)])   # nobody acted
    practice = EpisodeSummary.KIND_PRACTICE
    record(folder, 'seed4-practice', 4, [(0, True, False, practice)] * 2)
    return folder


def test_sessions_that_are_not_seeds_of_one_experiment_are_refused(mixed, tmp_path, capsys):
    out = tmp_path / 'results'
    assert results_cli.main([str(mixed), '--out', str(out)]) == 2
    err = capsys.readouterr().err
    for reason in ["the sessions differ in the person's input (who acted as the person): "
                   'simulated (4: seed1, seed1-again, seed2-short, ...); nobody (1: seed3-alone)',
                   'the sessions differ in their episode limits: at most 100 training episodes '
                   '(4: seed1, seed1-again, seed3-alone, ...); at most 2 training episodes (1: '
                   'seed2-short)',
                   'practice only (no training episode): seed4-practice',
                   'case 5 with profile paper seed 1 is there 2 times (seed1, seed1-again)',
                   'give sessions that agree, or --pool-configurations to pool them anyway']:
        assert f'hrc_results: {reason}' in err, err
    assert 'Traceback' not in err and not out.exists()


def test_they_are_pooled_when_asked(mixed, tmp_path):
    out = tmp_path / 'results'
    assert results_cli.main([str(mixed), '--out', str(out), '--pool-configurations']) == 0
    assert (out / 'results.md').is_file()


def test_without_out_nothing_goes_into_the_repositorys_docs():
    assert results_args.build_parser().parse_args(['bags']).out == 'results'


def test_an_out_that_cannot_be_written_is_one_line_without_a_traceback(mixed, tmp_path, capsys):
    taken = tmp_path / 'taken'
    taken.write_text('a file, not a folder')
    arguments = [str(mixed), '--out', str(taken), '--pool-configurations']
    assert results_cli.main(arguments) == 1
    err = capsys.readouterr().err
    assert f'hrc_results: cannot write the results to {taken}: ' in err
    assert 'Traceback' not in err


def test_an_error_inside_the_statistics_keeps_its_traceback(mixed, tmp_path, monkeypatch):
    """A defect of hrc (here a ValueError raised inside) is not passed off as a user mistake."""
    def failing(*args, **kwargs):
        raise ValueError('each sample in `data` must contain two or more observations')

    monkeypatch.setattr(results_cli, 'write_results', failing)
    with pytest.raises(ValueError, match='two or more observations'):
        results_cli.main([str(mixed), '--out', str(tmp_path / 'out'), '--pool-configurations'])
