"""The report on recorded sessions: Table II values and intervals, CSV, PNG figures, the CLI."""

import csv
import io
import math
import struct
import subprocess

from hrc_common.executables import executable_path
import numpy
import pytest

from hrc_bag import report
from hrc_testing.bag_traffic import record_in_process, strategy_plan

CASES = {1: 'responsibility_guided', 2: 'responsibility_guided', 4: 'level_guided',
         5: 'learn_together'}
SEEDS = (1, 2)


@pytest.fixture(scope='module')
def bags(tmp_path_factory):
    """Record 4 cases x 2 seeds (training episodes vary with the seed) in-process."""
    folder = tmp_path_factory.mktemp('report_bags')
    published = {}
    for case, strategy in CASES.items():
        for seed in SEEDS:
            plan = strategy_plan(strategy, seed, 1, 1)
            session = record_in_process(folder, f'case{case}_seed{seed}', case, strategy, seed,
                                        plan, steps=12)
            published[(case, seed)] = session.published.by_topic['/hrc/episode']
    return folder, published


@pytest.fixture(scope='module')
def written(bags, tmp_path_factory):
    """Run the report once on every session; return (result, records, output folder)."""
    out = tmp_path_factory.mktemp('report')
    records = report.load_records([bags[0]], log=lambda text: None)
    return report.write_report(records, out, resamples=500), records, out


def expected_values(summaries) -> dict:
    training = [summary for summary in summaries if not summary.evaluation]
    evaluation = [summary for summary in summaries if summary.evaluation]
    involved = sum(summary.human_involved for summary in training)
    values = {'human_involved_episodes': involved, 'total_episodes': len(training),
              'percentage': 100.0 * involved / len(training)}
    for key in ('slider_error', 'pendulum_error', 'ball_error', 'total_error', 'human_effort',
                'robot_effort'):
        values[key] = numpy.mean([getattr(summary, key) for summary in evaluation])
    return values


def png_size(path) -> tuple:
    data = path.read_bytes()
    assert data[:8] == b'\x89PNG\r\n\x1a\n', f'{path} is not a PNG'
    assert data[12:16] == b'IHDR' and data[-8:-4] == b'IEND'
    return struct.unpack('>II', data[16:24])


def test_table2_values_are_the_mean_and_interval_over_seeds(bags, written):
    folder, published = bags
    result, _, _ = written
    intervals = result['intervals']
    assert list(intervals) == sorted(CASES)
    for case in CASES:
        per_seed = [expected_values(published[(case, seed)]) for seed in SEEDS]
        for key, values in ((key, [entry[key] for entry in per_seed]) for key in per_seed[0]):
            interval = intervals[case][key]
            assert interval.count == 2
            assert interval.estimate == pytest.approx(numpy.mean(values), rel=1e-12), (case, key)
            if len(set(values)) == 1:
                assert interval.low == interval.high == interval.estimate
            else:
                assert 0.0 <= interval.low <= interval.estimate <= interval.high, (case, key)
    # responsibility-guided: the human joins in step 2 only; the others: always involved
    assert intervals[1]['human_involved_episodes'].estimate == 1.0
    assert intervals[1]['total_episodes'].estimate == 2.5
    assert intervals[4]['percentage'].estimate == 100.0
    groups = result['groups']
    assert (groups[1][0].robot_dof, groups[2][0].robot_dof) == ('translation', 'rotation')


def test_markdown_csv_and_figures_are_written(bags, written):
    folder, published = bags
    _, _, tmp_path = written
    markdown = (tmp_path / 'table2.md').read_text()
    lines = [line for line in markdown.splitlines() if line.startswith('| ')]
    assert len(lines) == 1 + len(CASES) + 1          # Table II, then the person's time header
    assert 'human-involved episodes' in lines[0] and 'robot effort' in lines[0]
    case4 = next(line for line in lines if line.startswith('| 4 |'))
    assert '| human first | rotation | 2 | ' in case4 and '| 100 [100, 100] |' in case4
    assert 'Learning configuration: unrecorded (8 sessions).' in markdown
    with open(tmp_path / 'table2.csv') as stream:
        table = list(csv.DictReader(stream))
    assert [int(row['case_id']) for row in table] == [1, 2, 4, 5]
    expected = numpy.mean([expected_values(published[(2, seed)])['ball_error']
                           for seed in SEEDS])
    assert float(table[1]['ball_error_mean']) == pytest.approx(expected)
    # How each case's sessions ended: a training that stopped at its cap is not a success.
    assert lines[0].rstrip().endswith(
        '| converged / at the cap / unfinished | robots that chatter |')
    for line, row in zip(lines[1:1 + len(CASES)], table):
        case = int(row['case_id'])
        converged = sum(any(summary.converged and not summary.evaluation
                            for summary in published[(case, seed)]) for seed in SEEDS)
        # no robot of these summaries reversed (their reversals are 0 per second)
        assert line.rstrip().endswith(f'| {converged} / {len(SEEDS) - converged} / 0 | '
                                      f'0 / {len(SEEDS)} |'), line
        assert (int(row['sessions_converged']), int(row['sessions_at_cap']),
                int(row['sessions_unfinished'])) == (converged, len(SEEDS) - converged, 0)
    assert float(table[1]['ball_error_low']) <= expected <= float(table[1]['ball_error_high'])
    sessions = list(csv.DictReader(io.StringIO((tmp_path / 'sessions.csv').read_text())))
    assert len(sessions) == len(CASES) * len(SEEDS)
    assert {row['seed'] for row in sessions} == {'1', '2'}
    assert {row['learning'] for row in sessions} == {'unrecorded'}
    for name, minimum in (('fig5_training.png', (1000, 400)), ('fig6_actions.png', (900, 400)),
                          ('fig7_three_factor.png', (500, 500))):
        width, height = png_size(tmp_path / name)
        assert width >= minimum[0] and height >= minimum[1], name
        assert (tmp_path / name).stat().st_size > 20_000, name   # not an empty canvas


def test_figure_data(bags, written):
    from hrc_bag.report.curves import first_human_episode, return_band
    from hrc_bag.report.metrics import factor_score, final_trace, three_factors

    _, records, _ = written
    case1 = next(record for record in records if record.session_id == 'case1_seed2')
    band = return_band([case1])
    assert band.episodes == [1, 2, 3] and band.stops == [3]
    assert band.median == band.low == band.high          # one session: its own curve
    assert first_human_episode(case1) == 3
    trace = final_trace(case1, seconds=2.0)
    assert trace['episode'] == 3                                 # first evaluation episode
    assert [time for time, _ in trace['robot']] == pytest.approx(
        [0.2 * step for step in range(10)])
    factors = {entry['strategy']: entry for entry in three_factors(records, resamples=200)}
    assert factors['responsibility_guided']['human_involved_episodes'].estimate == 1.0
    assert factors['learn_together']['total_episodes'].estimate == 2.5
    assert factors['learn_together']['sessions'] == 2
    assert factor_score(0.0, 10.0) == 1.0
    assert factor_score(10.0, 10.0) == pytest.approx(0.2)
    assert math.isnan(factor_score(math.nan, 1.0))


def test_cli_writes_the_report_and_refuses_an_empty_folder(bags, tmp_path):
    folder, _ = bags
    command = [str(executable_path('hrc_bringup', 'hrc')), 'bag', 'report']
    done = subprocess.run(command + [str(folder / 'case5_seed1'), '--out', str(tmp_path / 'a')],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert '| 5 | together | translation | 1 |' in done.stdout
    assert (tmp_path / 'a' / 'fig7_three_factor.png').is_file()
    empty = tmp_path / 'empty'
    empty.mkdir()
    done = subprocess.run(command + [str(empty), '--out', str(tmp_path / 'b')],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 1
    assert 'no session with episode summaries' in done.stderr


def test_human_time_is_counted_by_input_source(bags, written):
    folder, _ = bags
    together = report.load_session(folder / 'case5_seed1')       # 3 episodes with the human
    assert report.human_time(together) == {'simulated': {
        'seconds': pytest.approx(3 * 11 * 0.2), 'engaged_steps': 33, 'steps': 33,
        'episodes': 3}}
    alone_first = report.load_session(folder / 'case1_seed1')    # the first one without him
    assert report.human_time(alone_first)['simulated']['engaged_steps'] == 22
    assert report.human_time(alone_first)['simulated']['seconds'] == pytest.approx(4.4)
    text = (written[2] / 'human_time.md').read_text()
    assert '| case5_seed1 | 5 | simulated | 6.6 | 33 | 33 | 3 |' in text


BAD_METADATA = {'binary': b'\xff\xfe\x00binary', 'not YAML': b'key: [unclosed\n',
                'a list': b'- a\n- b\n', 'a string': b'just words\n',
                # beyond hrc_common.bounded_yaml's depth (yaml.safe_load recursed out)
                'nested 20,000 deep': b'[' * 20000 + b']' * 20000}


@pytest.mark.parametrize('kind', sorted(BAD_METADATA))
def test_an_unusable_metadata_yaml_falls_back_to_the_mcap_files(bags, tmp_path, kind):
    import shutil
    folder = tmp_path / 'case2_seed1'
    shutil.copytree(bags[0] / 'case2_seed1', folder)
    expected = report.load_session(bags[0] / 'case2_seed1')
    (folder / 'metadata.yaml').write_bytes(BAD_METADATA[kind])
    notices = []
    sessions = report.load_sessions([folder], log=notices.append)
    assert [summary.episode for summary in sessions[0].summaries] == [
        summary.episode for summary in expected.summaries]
    assert sessions[0].case_id == 2
    assert len(notices) == 1 and 'using the MCAP files of the folder' in notices[0], notices


def test_the_cli_refuses_files_that_are_not_mcap_with_the_reason(bags, tmp_path):
    import os
    command = [str(executable_path('hrc_bringup', 'hrc')),
               'bag', 'report', '--out', str(tmp_path / 'out')]
    empty = tmp_path / 'empty.mcap'
    empty.write_bytes(b'')
    text = tmp_path / 'text.mcap'
    text.write_text('not a bag\n')
    fifo = tmp_path / 'fifo.mcap'
    os.mkfifo(fifo)
    done = subprocess.run(command + [str(empty), str(text), str(fifo)], capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 1, done.stderr
    assert 'Traceback' not in done.stderr
    assert f'{empty}: is empty, not an MCAP file' in done.stderr
    assert f'{text}: is not an MCAP file' in done.stderr    # every reason at once
    assert f'{fifo}: is a FIFO, not an MCAP file' in done.stderr
    # in a session folder: every bad file is named at once
    import shutil
    folder = tmp_path / 'case4_seed2'
    shutil.copytree(bags[0] / 'case4_seed2', folder)
    (folder / 'zz_broken.mcap').write_text('garbage')
    (folder / 'zz_empty.mcap').write_bytes(b'')
    done = subprocess.run(command + [str(folder)], capture_output=True, text=True, timeout=120)
    assert done.returncode == 1
    assert 'zz_broken.mcap: is not an MCAP file' in done.stderr
    assert 'zz_empty.mcap: is empty' in done.stderr
    done = subprocess.run(command + [str(fifo)], capture_output=True, text=True, timeout=60)
    assert done.returncode == 1 and 'is a FIFO, not an MCAP file' in done.stderr


def _without_schema_text(source, target):
    """Copy the MCAP file ``source`` to ``target`` with every schema's text left out."""
    _copy_mcap(source, target, keep_schemas=False)


def _copy_mcap(source, target, keep_schemas=True, transform=None):
    """Copy the MCAP file ``source`` to ``target``; ``transform(topic, data)`` edits messages."""
    from mcap.reader import make_reader
    from mcap.writer import Writer
    with open(source, 'rb') as stream:
        reader = make_reader(stream)
        summary = reader.get_summary()
        metadata = list(reader.iter_metadata())
        messages = list(reader.iter_messages())
    with open(target, 'wb') as stream:
        writer = Writer(stream)
        writer.start(profile='ros2', library='another writer')
        schemas = {schema.id: writer.register_schema(schema.name, schema.encoding,
                                                     schema.data if keep_schemas else b'')
                   for schema in summary.schemas.values()}
        channels = {channel.id: writer.register_channel(
            channel.topic, channel.message_encoding, schemas[channel.schema_id],
            channel.metadata) for channel in summary.channels.values()}
        for record in metadata:
            writer.add_metadata(record.name, record.metadata)
        for _, channel, message in messages:
            data = transform(channel.topic, message.data) if transform else message.data
            writer.add_message(channels[channel.id], message.log_time, data,
                               message.publish_time, message.sequence)
        writer.finish()


def test_a_bag_without_schema_texts_is_read_with_the_installed_definitions(bags, tmp_path):
    source = bags[0] / 'case2_seed1'
    folder = tmp_path / 'case2_seed1'
    folder.mkdir()
    for file in source.glob('*.mcap'):
        _without_schema_text(file, folder / file.name)
    expected = report.load_session(source)
    session = report.load_session(folder)
    assert expected_values(session.summaries) == expected_values(expected.summaries)
    assert [(summary.episode, summary.total_error) for summary in session.summaries] == [
        (summary.episode, summary.total_error) for summary in expected.summaries]
    assert session.summaries and session.case_id == expected.case_id == 2
    assert ('/hrc/episode (hrc_msgs/msg/EpisodeSummary): the bag holds no schema of the type: '
            'decoded with the installed definition') in session.notices, session.notices


def test_a_type_without_schema_text_nor_installed_definition_is_refused():
    from hrc_bag.bag_reader import BagError, BagMessage, MessageDecoder
    message = BagMessage('/foreign', 'foreign_msgs/msg/Thing', b'\x00\x01\x00\x00', 0, 0, 0)
    with pytest.raises(BagError, match=r'/foreign \(foreign_msgs/msg/Thing\): the bag holds no '
                                       'schema of the type and none is installed'):
        MessageDecoder().decode(message)


def test_a_session_rewritten_by_rosbags_gives_the_same_numbers_and_says_how(bags, tmp_path):
    from rosbags.rosbag2 import Reader, StoragePlugin, Writer
    source = bags[0] / 'case5_seed1'
    target = tmp_path / 'rewritten'
    with Reader(source) as reader, Writer(target, version=9,
                                          storage_plugin=StoragePlugin.MCAP) as writer:
        connections = {}
        for connection in reader.connections:       # one per topic: each file repeats them
            if connection.topic not in connections:
                connections[connection.topic] = writer.add_connection(
                    connection.topic, connection.msgtype, msgdef=connection.msgdef.data,
                    rihs01=connection.digest or 'RIHS01_' + '0' * 64,
                    offered_qos_profiles=connection.ext.offered_qos_profiles)
        for connection, stamp, data in reader.messages():
            writer.write(connections[connection.topic], stamp, data)
    assert len(list(target.glob('*.mcap'))) == 1            # every episode in one file
    original, rewritten = report.load_session(source), report.load_session(target)
    assert report.human_time(original) == report.human_time(rewritten) != {}
    assert expected_values(rewritten.summaries) == expected_values(original.summaries)
    assert ("no file holds an hrc episode record (written by another tool?): the person's "
            'time is counted from the HumanAction messages') in rewritten.notices
    assert not any('hrc episode record' in notice for notice in original.notices)


def test_a_summary_that_contradicts_itself_is_repaired_and_said(bags, tmp_path):
    from hrc_msgs.msg import EpisodeSummary
    from rclpy.serialization import deserialize_message, serialize_message

    def hostile(topic, data):
        if topic != '/hrc/episode':
            return data
        summary = deserialize_message(data, EpisodeSummary)
        summary.total_error = 99.0              # not the sum of its three errors
        summary.robot_effort = float('nan')
        return serialize_message(summary)

    source = bags[0] / 'case5_seed1'
    folder = tmp_path / 'case5_seed1'
    folder.mkdir()
    for file in source.glob('*.mcap'):
        _copy_mcap(file, folder / file.name, transform=hostile)
    expected = report.load_session(source)
    session = report.load_session(folder)
    assert [summary.total_error for summary in session.summaries] == pytest.approx([
        summary.total_error for summary in expected.summaries], rel=1e-12)
    assert all(math.isnan(summary.robot_effort) for summary in session.summaries)
    number = session.summaries[0].episode + 1       # people read episode numbers from 1
    assert (f'episode {number}: its summary total_error 99 is not the sum of its errors '
            f'({expected.summaries[0].total_error:g}): the sum is used') in session.notices
    assert f'episode {number}: its summary robot_effort nan is not a finite number >= ' \
        '0: left out' in session.notices
    from hrc_bag.report.records import measures
    records = report.load_records([folder], log=lambda text: None)
    assert math.isnan(measures(records[0])['robot_effort'])
    assert measures(records[0])['total_error'] < 99


def test_an_episode_with_missing_commands_is_counted_in_its_file_and_said(tmp_path):
    """A frozen actor's episode counted as normal: nothing in the bag or the report said so."""
    plan = strategy_plan('learn_together', 2, 0, 1)
    record_in_process(tmp_path, 'frozen', 5, 'learn_together', 1, plan, steps=8,
                      missing={1: ((2, 3, 4), (4,))})
    session = report.load_session(tmp_path / 'frozen')
    records = {episode: session.human_inputs[episode] for episode in (0, 1)}
    assert [records[0]['robot_commands_missing'], records[0]['human_commands_missing']] == \
        ['0', '0']
    assert [records[1]['states'], records[1]['robot_commands_missing'],
            records[1]['human_commands_missing']] == ['8', '3', '1']
    assert ("episode 2: of its 8 states, 3 went without the robot's command and 1 without the "
            "person's (each applied as zero): not a normal episode") in session.notices
    assert not any(notice.startswith('episode 1:') for notice in session.notices)


def test_episodes_the_recorder_missed_are_said(tmp_path):
    """A stalled recorder lost episodes 2-3 of 4 and the report showed 2 episodes silently."""
    plan = strategy_plan('learn_together', 3, 0, 1)
    record_in_process(tmp_path, 'stalled', 5, 'learn_together', 1, plan, steps=6)
    folder = tmp_path / 'stalled'
    (folder / 'metadata.yaml').unlink()             # as if the recorder never wrote them
    for index in (1, 2):
        (folder / f'stalled_episode{index + 1:04d}.mcap').unlink()
    session = report.load_session(folder)
    assert [summary.episode for summary in session.summaries] == [0, 3]
    assert ('episodes 2, 3 have no file in the bags (the recorder missed them: stalled or '
            'stopped)') in session.notices, session.notices
    (folder / 'stalled_episode0001.mcap').unlink()   # not recorded at all: a pre-training, say
    assert not any('no file in the bags' in notice
                   for notice in report.load_session(folder).notices)


def test_an_episode_with_fewer_states_than_steps_is_said():
    from types import SimpleNamespace

    from hrc_bag.report.loading import recording_gaps
    files = {0: ['a'], 1: ['b']}
    summaries = {0: SimpleNamespace(steps=200), 1: SimpleNamespace(steps=200)}
    assert recording_gaps(files, summaries, {0: {'states': '201'}, 1: {'states': '201'}}) == []
    assert recording_gaps(files, summaries, {0: {'states': '201'}, 1: {'states': '57'}}) == [
        'episode 2: the bags hold 57 of its 200+ states (the recorder missed the others)']
    # a recording without /hrc/state says nothing about states
    assert recording_gaps(files, summaries, {0: {'states': '0'}, 1: {}}) == []
