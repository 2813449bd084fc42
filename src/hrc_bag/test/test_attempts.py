"""Every attempt of an episode filed as itself: a dropped attempt and its re-run after a resume.

The recorder core is fed what a live session sends when the joystick is unplugged mid-episode
(the agent stops: the episode's states end without a final state or a summary), the operator
resumes, and the agent re-runs the episode from step 0. Each attempt must get its own file,
named in metadata.yaml and in the files' ``hrc_episode`` records, and the report must take the
person's time and the errors from the same attempt (the one that finished) and say so.
"""


from hrc_msgs.msg import EpisodeSummary, HumanAction, SessionStatus, TaskState
import pytest
from std_msgs.msg import String
import yaml

from hrc_bag import bag_reader, recording
from hrc_bag.format import EPISODE_RECORD, index_named_file_stem, TopicDescription
from hrc_bag.recorder_params import RecorderParams
from hrc_bag.recording import ATTEMPTS_KEY, EpisodeRecorder
from hrc_bag.report.loading import load_session
from hrc_bag.report.metrics import human_time
from hrc_testing.bag_traffic import ManualClock, RecorderFeeder

PROFILE = {'history': 'keep_last', 'depth': 10, 'reliability': 'reliable',
           'durability': 'volatile'}
DROPPED_STEPS = 5       # states of the attempt the unplug cut short (steps 0..4)
RERUN_STEPS = 10        # the re-run, to its final state (steps 0..9)
PERIOD_NS = 200_000_000  # 0.2 s control period, in the stamps


Clock = ManualClock


class Session(RecorderFeeder):
    """Feeds the recorder as the node would (increasing log times), an episode at a time."""

    def episode(self, episode, steps, final, summary, human=True):
        for step in range(steps):
            state = TaskState(episode=episode, step=step,
                              truncated=final and step == steps - 1)
            state.header.stamp.sec, state.header.stamp.nanosec = divmod(step * PERIOD_NS,
                                                                        1_000_000_000)
            self.send('/hrc/state', state)
            if human and not state.truncated:
                action = HumanAction(episode=episode, step=step, engaged=True, command=0.1,
                                     source=HumanAction.SOURCE_DEVICE)
                action.header.stamp = state.header.stamp
                self.send('/hrc/human/action', action)
        if summary:
            self.send('/hrc/episode', EpisodeSummary(episode=episode, session_id='s',
                                                     human_involved=human,
                                                     ball_error=0.01 * (episode + 1)))


def recorder_in(tmp_path, clock):
    params = RecorderParams(output_dir=str(tmp_path), session_id='s', close_grace=0.0,
                            summary_timeout=3.0)
    return EpisodeRecorder(params, lambda topic, type_name: TopicDescription(
        type_name, (PROFILE,), 'RIHS01_' + '0' * 64), clock=clock)


def states(path):
    return sum(message.topic == '/hrc/state' for message in bag_reader.scan_file(path).messages)


@pytest.mark.parametrize('first_file', ['open', 'closed'])
def test_an_unplugged_episode_and_its_rerun_are_each_filed_as_themselves(tmp_path, first_file):
    """Unplug, resume, re-run: the files, their records, metadata.yaml and the report.

    ``open``: the re-run starts while the dropped attempt's file is still open; ``closed``:
    the session said "aborted" (the agent stopped), so its file closed before the re-run.
    """
    clock = Clock()
    recorder = recorder_in(tmp_path, clock)
    feed = Session(recorder)
    feed.send('/hrc/session', SessionStatus(session_id='s', case_id=2, phase=1))
    feed.episode(0, RERUN_STEPS, final=True, summary=True)
    feed.episode(1, DROPPED_STEPS, final=False, summary=False)       # the joystick is unplugged
    if first_file == 'closed':
        feed.send('/hrc/session', SessionStatus(session_id='s', case_id=2,
                                                phase=SessionStatus.PHASE_ABORTED))
        clock.now += 0.1
        recorder.tick()
        assert 1 not in recorder.open_files
    clock.now += 1.0
    feed.send('/hrc/session', SessionStatus(session_id='s', case_id=2, phase=1))  # resumed
    feed.episode(1, RERUN_STEPS, final=True, summary=True)            # the re-run, complete
    clock.now += 0.1
    recorder.tick()
    feed.send('/hrc/session', SessionStatus(session_id='s', case_id=2,
                                            phase=SessionStatus.PHASE_DONE))
    recorder.close()

    folder = tmp_path / 's'
    dropped, rerun = folder / 's_episode0002.mcap', folder / 's_episode0002_attempt2.mcap'
    assert {path.name for path in folder.glob('*.mcap')} - {'s_end.mcap'} == {
        's_episode0001.mcap', 's_episode0002.mcap', 's_episode0002_attempt2.mcap'}
    if (folder / 's_end.mcap').exists():            # never the re-run's states
        assert states(folder / 's_end.mcap') == 0
    assert (states(dropped), states(rerun)) == (DROPPED_STEPS, RERUN_STEPS)
    # The hrc_episode records: which attempt, how far it went, and the files of the episode.
    records = [bag_reader.scan_file(path).metadata[EPISODE_RECORD] for path in (dropped,
                                                                                 rerun)]
    assert [(r['attempt'], r['last_step'], r['finished']) for r in records] == [
        ('1', str(DROPPED_STEPS - 1), 'false'), ('2', str(RERUN_STEPS - 1), 'true')]
    assert records[1]['attempt_files'] == 's_episode0002.mcap,s_episode0002_attempt2.mcap'
    assert yaml.safe_load(records[0]['human_steps']) == {'device': DROPPED_STEPS}
    assert yaml.safe_load(records[1]['human_steps']) == {'device': RERUN_STEPS - 1}
    # metadata.yaml lists both attempts, and says they are attempts of one episode.
    metadata = bag_reader.read_bag_metadata_yaml(folder)
    assert {'s_episode0002.mcap', 's_episode0002_attempt2.mcap'} <= set(
        metadata['relative_file_paths'])
    assert yaml.safe_load(metadata['custom_data'][ATTEMPTS_KEY]) == {
        1: ['s_episode0002.mcap', 's_episode0002_attempt2.mcap']}

    # The report: time and errors of the same (finished) attempt, and it says which.
    session = load_session(folder)
    assert [s.episode for s in session.summaries] == [0, 1]
    assert session.files_by_episode[1] == [rerun]
    assert session.attempts == {1: [dropped, rerun]}
    assert session.human_inputs[1]['attempt'] == '2'
    assert human_time(session)['device']['engaged_steps'] == 2 * (RERUN_STEPS - 1)
    assert human_time(session)['device']['episodes'] == 2
    assert any('episode 2 was recorded 2 times (s_episode0002.mcap: 5 steps, dropped, '
               's_episode0002_attempt2.mcap: 10 steps, finished): its time and errors are from '
               's_episode0002_attempt2.mcap (the attempt that finished)' in notice
               for notice in session.notices), session.notices


def drop_episode_0(recorder):
    """Record episode 0 cut short (no final state, no summary), then stop the recorder."""
    Session(recorder).episode(0, DROPPED_STEPS, final=False, summary=False)
    recorder.close()


def rerun_episode_0(recorder, clock):
    """Record episode 0 again to its end with a later recorder (a resumed session)."""
    feed = Session(recorder)
    feed.log_time += 10_000_000_000
    feed.episode(0, RERUN_STEPS, final=True, summary=True)
    clock.now += 0.1
    recorder.tick()
    recorder.close()


def test_a_later_recorder_of_a_resumed_session_continues_the_attempt_count(tmp_path):
    """An operator abort and ``--resume-from``: a new recorder re-runs the aborted episode."""
    clock = Clock()
    drop_episode_0(recorder_in(tmp_path, clock))
    rerun_episode_0(recorder_in(tmp_path, clock), clock)
    folder = tmp_path / 's'
    rerun = folder / 's_episode0001_attempt2.mcap'
    assert states(rerun) == RERUN_STEPS
    assert bag_reader.scan_file(rerun).metadata[EPISODE_RECORD]['attempt'] == '2'
    assert bag_reader.session_files(folder) == [folder / 's_episode0001.mcap', rerun]
    assert load_session(folder).files_by_episode[0] == [rerun]


def test_a_repeated_first_state_is_not_a_new_attempt(tmp_path):
    """Step 0 twice before any later step (a re-sent first state) stays one attempt."""
    clock = Clock()
    recorder = recorder_in(tmp_path, clock)
    feed = Session(recorder)
    feed.send('/hrc/state', TaskState(episode=0, step=0))
    feed.episode(0, RERUN_STEPS, final=True, summary=True, human=False)
    recorder.close()
    assert sorted(path.name for path in (tmp_path / 's').glob('*.mcap')) == ['s_episode0001.mcap']


def test_a_session_begun_with_index_names_resumes_as_the_next_attempt(tmp_path, monkeypatch):
    """A folder from before hrc 1.0 (``s_ep0000.mcap`` for episode 1) resumed: attempt 2 follows.

    The first recorder writes the old names; the second, after a resume, must find that file
    as the episode's first attempt, so the re-run is ``s_episode0001_attempt2.mcap`` and the
    report reads the re-run as the attempt that finished.
    """
    clock = Clock()
    with monkeypatch.context() as patch:
        patch.setattr(recording, 'episode_file_stem', index_named_file_stem)
        drop_episode_0(recorder_in(tmp_path, clock))
    folder = tmp_path / 's'
    assert sorted(path.name for path in folder.glob('*.mcap')) == ['s_ep0000.mcap']
    rerun_episode_0(recorder_in(tmp_path, clock), clock)
    rerun = folder / 's_episode0001_attempt2.mcap'
    assert bag_reader.session_files(folder) == [folder / 's_ep0000.mcap', rerun]
    assert bag_reader.scan_file(rerun).metadata[EPISODE_RECORD]['attempt_files'] == (
        's_ep0000.mcap,s_episode0001_attempt2.mcap')
    assert load_session(folder).files_by_episode[0] == [rerun]


def test_the_robot_description_opens_every_episode_file_once(tmp_path):
    """The URDF, published once (latched) before the first episode, starts each file once.

    A viewer opens one file; without the repetition only the first file showed the system.
    """
    clock = Clock()
    recorder = recorder_in(tmp_path, clock)
    feed = Session(recorder)
    feed.send('/robot_description', String(data='<robot name="slider_pendulum_ball"/>'))
    for episode in range(3):
        feed.episode(episode, RERUN_STEPS, final=True, summary=True)
        clock.now += 0.1
        recorder.tick()
    recorder.close()
    files = bag_reader.session_files(tmp_path / 's')
    assert [path.name for path in files][:3] == [
        's_episode0001.mcap', 's_episode0002.mcap', 's_episode0003.mcap']
    for path in files[:3]:
        found = [message for message in bag_reader.scan_file(path).messages
                 if message.topic == '/robot_description']
        assert len(found) == 1, path.name
