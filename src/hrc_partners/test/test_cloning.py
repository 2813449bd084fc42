"""Cloning a person from the engine's real bags: held-out error, slow vs fast, input model."""

import json

import pytest

from hrc_partners import clone_cli, cloning, synthetic
from hrc_partners.recordings import load_demonstrations


def _clone(capsys, paths, held_out, out):
    code = clone_cli.main(paths + ['--held-out', held_out, '--out', str(out), '--epochs', '300',
                                   '--json'])
    assert code == 0
    return json.loads(capsys.readouterr().out)


@pytest.mark.slow
def test_clones_of_a_slow_and_a_fast_person(tmp_path, capsys):
    profiles = synthetic.fast_and_slow(tmp_path / 'people.yaml')
    folders = synthetic.record_sessions(tmp_path / 'bags', tmp_path / 'runs', profiles,
                                        ['fast', 'slow'], [0, 1], episodes=2, seconds=12.0)
    demonstrations = load_demonstrations(folders, log=lambda line: None)
    assert [item.session_id for item in demonstrations] == [
        'fast-seed0', 'fast-seed1', 'slow-seed0', 'slow-seed1']
    assert all(item.dof == 'rotation' and item.steps == 2 * 60 for item in demonstrations)
    assert demonstrations[0].sources == ['fast']           # the simulated human's detail

    reports = {}
    for person in ('fast', 'slow'):
        paths = [folder for folder in folders if f'/{person}-' in folder]
        reports[person] = _clone(capsys, paths, f'{person}-seed1', tmp_path / f'{person}.pt')
        report = reports[person]
        # split by session: the held-out session is not among the training ones
        assert report['training_sessions'] == [f'{person}-seed0']
        assert report['held_out_sessions'] == [f'{person}-seed1']
        held = report['held_out']
        assert held['rmse'] < 0.4 * held['zero_command_rmse'], held
        # the clone answers about as late as the person it was cloned from
        assert abs(held['clone_lag_s'] - held['person_lag_s']) < 0.2, held
    # reaction delays 0.1 s and 0.6 s: the slow clone is measurably slower
    assert reports['slow']['held_out']['clone_lag_s'] \
        > reports['fast']['held_out']['clone_lag_s'] + 0.3, reports

    # the two clones on the same held-out states: the slow one lags too
    from hrc_joystick_node.human_model import load_human_model
    traces = [trace for item in demonstrations if item.session_id.endswith('seed1')
              for trace in item.episodes]
    lags = {}
    for person in ('fast', 'slow'):
        config, network = load_human_model(tmp_path / f'{person}.pt')
        assert config['dof'] == 'rotation' and config['control_period'] == 0.2
        commands = [cloning.predict(network, trace, config['history_steps'])
                    for trace in traces]
        lags[person] = cloning.response_lag(traces, commands, 'rotation', 0.2)
    assert lags['slow'] > lags['fast'] + 0.2, lags


def test_a_clone_drives_the_human_side_of_the_engine(tmp_path, capsys):
    profiles = synthetic.fast_and_slow(tmp_path / 'people.yaml')
    folders = synthetic.record_sessions(tmp_path / 'bags', tmp_path / 'runs', profiles,
                                        ['fast'], [0, 1], episodes=1, seconds=8.0)
    _clone(capsys, folders, 'fast-seed1', tmp_path / 'fast.pt')
    folder = synthetic.record_with_model(tmp_path / 'bags', tmp_path / 'runs',
                                         tmp_path / 'fast.pt', seed=3, episodes=1, seconds=4.0)
    [driven] = load_demonstrations([folder], log=lambda line: None)
    assert driven.sources == [f'model {tmp_path / "fast.pt"}']
    assert driven.steps == 20


def test_bad_input_exits_2_with_every_reason(tmp_path, capsys):
    code = clone_cli.main([str(tmp_path / 'none'), '--out', str(tmp_path / 'no' / 'x.pt'),
                           '--epochs', '0'])
    assert code == 2
    error = capsys.readouterr().err
    assert 'no such session folder' in error and '--epochs' in error and '--out' in error
    assert 'Traceback' not in error


def test_features_match_what_the_cloned_human_sees():
    import numpy

    states = numpy.arange(18, dtype=float).reshape(3, 6)
    rows = cloning.features(states, ['pendulum', 'T1_1'], history_steps=2)
    # step 0: history filled with the first state; newest first; subtask flags last
    assert rows[0].tolist() == states[0].tolist() + states[0].tolist() + [0, 1, 1]
    assert rows[2].tolist() == states[2].tolist() + states[1].tolist() + [0, 1, 1]


def test_a_clone_learns_every_command_the_sim_applied_at_the_human_rate(tmp_path, capsys):
    import numpy

    profiles = synthetic.fast_and_slow(tmp_path / 'people.yaml')
    folders = synthetic.record_sessions(tmp_path / 'bags', tmp_path / 'runs', profiles,
                                        ['fast'], [0, 1], episodes=1, seconds=8.0,
                                        human_period=0.02)
    demonstrations = load_demonstrations(folders, log=lambda line: None)
    assert [item.steps for item in demonstrations] == [40, 40]
    for trace in (trace for item in demonstrations for trace in item.episodes):
        driven = numpy.flatnonzero(trace.driving)
        # ten slices a period; the first is the HumanAction's command (another message), the
        # rest are what the person did later in the period, and they differ from it
        assert all(len(trace.applied[step]) == 10 for step in driven)
        first = numpy.array([trace.applied[step][0] for step in driven])
        assert numpy.allclose(first, trace.commands[driven], atol=1e-12)
        spread = [numpy.ptp(trace.applied[step]) for step in driven]
        assert max(spread) > 0.05, spread
    inputs, targets = cloning.dataset(demonstrations[:1], 6, 'applied')
    command_inputs, _ = cloning.dataset(demonstrations[:1], 6, 'command')
    assert len(targets) == len(inputs) == 10 * 40 and len(command_inputs) == 40

    # The command line learns from them by default and says so; the held-out error counts
    # every applied command (40 held-out steps x 10 slices).
    report = _clone(capsys, folders, 'fast-seed1', tmp_path / 'applied.pt')
    assert report['targets'] == 'applied' and report['held_out']['steps'] == 400
    assert report['held_out']['rmse'] < 0.5 * report['held_out']['zero_command_rmse'], report


def test_one_command_a_period_learns_exactly_what_it_learned_before(tmp_path):
    import numpy

    profiles = synthetic.fast_and_slow(tmp_path / 'people.yaml')
    folders = synthetic.record_sessions(tmp_path / 'bags', tmp_path / 'runs', profiles,
                                        ['fast'], [0], episodes=1, seconds=4.0)
    demonstrations = load_demonstrations(folders, log=lambda line: None)
    applied = cloning.dataset(demonstrations, 6, 'applied')
    command = cloning.dataset(demonstrations, 6, 'command')
    assert all(numpy.array_equal(a, b) for a, b in zip(applied, command))
    assert len(command[1]) == 20
