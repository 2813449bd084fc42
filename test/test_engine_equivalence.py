"""The in-process engine and the node graph in lockstep run the same session.

The same short session (case 5: robot and human together from the start, the human at its own
rate, the sim's default human_period, answering ten slice states per step; a PPO update after
the second episode, so the evaluation episode runs the updated policy) is run twice: by the
session runner (sim, agent, human and recorder as separate processes over DDS) and by
``inprocess_session``. Both bags are read back with rosbags and compared episode by episode:
every state, both commands, the human's action, the agent's step record (action, reward,
value, log-probability) and the episode summary must be bit-identical. What may differ is
listed and checked apart: log times and the SessionStatus header stamps are wall clock, and
the ``hrc_session`` record says which writer wrote the file.

Why case 5: in a case whose roles change at an episode boundary (case 3's evaluation gives the
human the ball as well), the graph's human node may answer the new episode's first state
before it has handled the SessionStatus announcing the change (both wait in its executor, and
rclpy serves the state subscription first, created first): the graph then differs from itself
from run to run, not from the engine, which always applies the announcement first.
"""

import bisect
import collections
import subprocess

import pytest

from hrc_agent_node.checkpoint import read_checkpoint
from hrc_common.executables import executable_path

# The main session: the default learning configuration (SAC), learning from its 10th
# transition on (every step after that runs its gradient steps inside the step).
ARGS = ['--case', '5', '--episodes', '2', '--eval-episodes', '1', '--session-id', 'same',
        '--set', 'sim.episode_duration=8.0', '--set', 'agent.sac_learning_starts=10']
# Every test here reads a session of the shared `sessions` fixture, which talks DDS (the domains
# are reserved inside it, so conftest.py cannot tell from the tests' fixtures).
pytestmark = pytest.mark.dds
STEPS = 40
PERIOD_NS = 200_000_000
SLICES = 10          # the sim's default human_period 0.02 s: the human answers 10 times a step
HUMAN_TOPICS = ('/hrc/human/cmd_wrench', '/hrc/human/action')
TOPICS = ('/hrc/state', '/hrc/robot/cmd_wrench', *HUMAN_TOPICS, '/hrc/agent/step',
          '/hrc/episode')


def fields_of(message):
    """Return a rosbags message as nested plain values (floats compared exactly)."""
    if hasattr(message, '__dataclass_fields__'):
        return {name: fields_of(getattr(message, name)) for name in message.__dataclass_fields__
                if not name.isupper() and not name.startswith('_')}
    if isinstance(message, (list, tuple)) or type(message).__name__ == 'ndarray':
        return [fields_of(item) for item in message]
    return message


def stamp_ns(stamp) -> int:
    return stamp.sec * 1_000_000_000 + stamp.nanosec


def by_episode(bag):
    """Return {topic: {episode: [message fields]}} (commands by the episode of their stamp).

    A command answers a state (its stamp) or, at the human's rate, a slice state within the
    period that follows a state (stamp up to one control period later).
    """
    states = sorted((stamp_ns(state.header.stamp), state.episode) for state in bag['/hrc/state'])
    stamps = [stamp for stamp, _ in states]
    grouped = {topic: collections.defaultdict(list) for topic in TOPICS}
    for topic in TOPICS:
        for message in bag[topic]:
            episode = getattr(message, 'episode', None)
            if episode is None:
                stamp = stamp_ns(message.header.stamp)
                index = bisect.bisect_right(stamps, stamp) - 1
                assert index >= 0 and stamp - stamps[index] < PERIOD_NS, (topic, stamp)
                episode = states[index][1]
            grouped[topic][episode].append(fields_of(message))
    return grouped


def run_both(tmp_path, domain_id: int, args: list, read_rosbag, env=None) -> tuple:
    """Run the session of ``args`` through the graph and the engine; return both bags."""
    graph_dir, engine_dir = tmp_path / 'graph', tmp_path / 'engine'
    graph = subprocess.run(
        [str(executable_path('hrc_bringup', 'hrc')), 'session', '--domain-id', str(domain_id),
         '--bags-dir', str(graph_dir / 'bags'), '--runs-dir', str(graph_dir / 'runs'),
         '--no-report', *args], capture_output=True, text=True, timeout=300, env=env)
    assert graph.returncode == 0, graph.stdout + graph.stderr
    engine = subprocess.run(
        [str(executable_path('hrc_bringup', 'hrc')), 'session', '--engine', 'inprocess',
         '--bags-dir', str(engine_dir / 'bags'), '--runs-dir', str(engine_dir / 'runs'),
         *args], capture_output=True, text=True, timeout=300, env=env)
    assert engine.returncode == 0, engine.stdout + engine.stderr
    return read_rosbag(graph_dir / 'bags' / 'same'), read_rosbag(engine_dir / 'bags' / 'same')


def assert_same(graph_bag, engine_bag, episodes) -> dict:
    """Assert every message of TOPICS equal episode by episode; return the graph's grouped."""
    graph_messages, engine_messages = by_episode(graph_bag), by_episode(engine_bag)
    # A human who sits out a training step sends nothing: the human's topics have the
    # episodes where the human is involved only, in both.
    involved = [episode for episode in episodes
                if graph_messages['/hrc/episode'][episode][0]['human_involved']]
    for topic in TOPICS:
        wanted = involved if topic in HUMAN_TOPICS else list(episodes)
        assert sorted(graph_messages[topic]) == wanted, topic
        assert sorted(engine_messages[topic]) == wanted, topic
        for episode in episodes:
            expected, got = graph_messages[topic][episode], engine_messages[topic][episode]
            assert len(got) == len(expected), (topic, episode, len(got), len(expected))
            for index, (one, other) in enumerate(zip(expected, got)):
                assert one == other, f'{topic} episode {episode} message {index}: graph ' \
                    f'{one} != engine {other}'

    # SessionStatus: the same sequence of announcements apart from the wall-clock stamp.
    def announcements(bag):
        return [{name: value for name, value in fields_of(status).items() if name != 'header'}
                for status in bag['/hrc/session']]
    assert announcements(engine_bag) == announcements(graph_bag)
    return graph_messages


def test_the_engine_and_the_lockstep_graph_give_the_same_session(sessions):
    graph_bag, engine_bag, _ = outcome_of(sessions, 'main')
    graph_messages = assert_same(graph_bag, engine_bag, (0, 1, 2))
    assert len(graph_messages['/hrc/state'][2]) == STEPS + 1
    # The human acted at its own rate: a wrench for each slice of every step, the applied
    # ones in each period's state.
    for episode in (0, 1, 2):
        assert len(graph_messages['/hrc/human/cmd_wrench'][episode]) == STEPS * SLICES
        assert all(len(state['human_applied']) == SLICES
                   for state in graph_messages['/hrc/state'][episode][1:])
    assert graph_messages['/hrc/episode'][2][0]['evaluation']


OTHER_CASES = (1, 2, 3, 4, 6)
# The other cases with the paper's learner (PPO: an update after each episode)
SHORT = ['--episodes', '2', '--eval-episodes', '1', '--session-id', 'same', '--learning', 'ppo',
         '--set', 'sim.episode_duration=2.0', '--set', 'agent.horizon=16', '--set',
         'agent.minibatch_size=8']   # 10 steps an episode
UPDATE_INSIDE_ARGS = ['--case', '5', '--episodes', '2', '--eval-episodes', '1', '--session-id',
                      'same', '--set', 'sim.episode_duration=8.0', '--set', 'agent.horizon=30',
                      '--set', 'agent.minibatch_size=16', '--learning', 'ppo']
# The scripted stick: its position changes every 0.06 s (inside control periods), the enable
# button let go on every ninth change.
STICK_SCRIPT = '\n'.join(['time,axis,enable'] + [
    f'{index * 0.06:.2f},{((index * 7) % 21 - 10) / 10.0:.1f},{int(index % 9 != 4)}'
    for index in range(40)]) + '\n'
# Every session of this file: name -> (its arguments, the environment it adds). They all run at
# once (each graph on a domain of its own, then its engine run): a short graph session spends
# most of its wall time starting processes and discovering, not computing, so running them
# together takes far less wall time than one after another on 2 cores (CI time); lockstep
# sessions do not depend on timing, so running them together changes nothing they record.
SESSIONS = {
    'main': (ARGS, {}),
    **{f'case{case}': (['--case', str(case), *SHORT], {}) for case in OTHER_CASES},
    'update_inside': (UPDATE_INSIDE_ARGS, {}),
    # the graph's nodes on rclpy's own SingleThreadedExecutor (HRC_EXECUTOR's escape hatch)
    'scripted_stick': (['--case', '5', *SHORT, '--human', 'script', '--set',
                        'human.script_file={script}', '--set', 'human.enable_button=0'],
                       {'HRC_EXECUTOR': 'rclpy'}),
    'composed': (['--case', '5', *SHORT], {'HRC_COMPOSE': 'sim,human,recorder'}),
    # the partner-aware observation (the partner model fitted at every step)
    'partner_aware': ([*ARGS, '--learning', 'partner_aware'], {}),
    # the person who co-adapts to the robot's predictability (its internal model, every slice)
    'co_adapting': ([*ARGS, '--set', 'human.profile=paper_co_adapting'], {}),
}
CONCURRENT_SESSIONS = 5     # at most this many at once (each graph is 4-5 processes)


@pytest.fixture(scope='module')
def sessions(tmp_path_factory, rosbags_typestore):
    """Run every session of SESSIONS both ways: {name: (graph bag, engine bag, folder) or error}.

    An error is kept, not raised: the session's own test reports it.
    """
    from concurrent.futures import ThreadPoolExecutor

    from hrc_common.domains import DomainReservation
    from hrc_testing.nodes import read_bag_with_rosbags, ros_environment

    def run(name):
        args, extra_env = SESSIONS[name]
        folder = tmp_path_factory.mktemp(name)
        script = folder / 'stick.csv'
        script.write_text(STICK_SCRIPT)
        args = [arg.replace('{script}', str(script)) for arg in args]
        reservation = DomainReservation()
        try:
            env = ros_environment(reservation.domain_id)
            env.update(extra_env)
            graph_bag, engine_bag = run_both(
                folder, reservation.domain_id, args,
                lambda bag: read_bag_with_rosbags(rosbags_typestore, bag), env=env)
            return graph_bag, engine_bag, folder
        except AssertionError as error:     # reported by the session's own test
            return error
        finally:
            reservation.release()

    # Made once before the threads: pytest creates its base folder on first use, and five
    # threads doing that at once race (a module run alone failed with "case3 is not a
    # normalized and relative path").
    tmp_path_factory.getbasetemp()
    with ThreadPoolExecutor(max_workers=CONCURRENT_SESSIONS) as pool:
        return dict(zip(SESSIONS, pool.map(run, SESSIONS)))


def outcome_of(sessions, name):
    """Return (graph bag, engine bag, folder) of session ``name``, or raise its failure."""
    outcome = sessions[name]
    if isinstance(outcome, AssertionError):
        raise outcome
    return outcome


@pytest.mark.slow
@pytest.mark.parametrize('case', OTHER_CASES)
def test_every_case_is_the_same_in_the_graph_and_the_engine(sessions, case):
    """Short sessions of the other cases (10 steps an episode).

    Roles that change at an episode boundary included (cases 3 and 4 give the human the ball
    in the evaluation episode); a PPO update after the second episode.
    """
    graph_bag, engine_bag, _ = outcome_of(sessions, f'case{case}')
    graph_messages = assert_same(graph_bag, engine_bag, (0, 1, 2))
    if case in (1, 2):    # the robot learns alone first: the human sends nothing then
        assert not graph_messages['/hrc/episode'][0][0]['human_involved']
        assert not graph_messages['/hrc/human/action'][0]


@pytest.mark.slow
def test_updates_inside_episodes_keep_the_graph_and_the_engine_identical(sessions):
    """PPO with horizon 30: an update inside the first episode.

    The first episode's rollout is cut at step 30, the update runs before the action for that
    state (in the agent node and in the engine alike), the rest of the episode acts with the
    new weights and updates again at its end.
    """
    graph_bag, engine_bag, folder = outcome_of(sessions, 'update_inside')
    graph_messages = assert_same(graph_bag, engine_bag, (0, 1, 2))
    steps = graph_messages['/hrc/agent/step'][0]
    assert len(steps) == 40 and not steps[0]['deterministic']
    # Three updates each: inside episode 0 (step 30), at its end (10 samples), inside episode 1
    # (step 30; the ppo configuration judges after every 2nd training episode, so episode 1
    # trains too); training ends with episode 1 (--episodes 2), its last 10 samples dropped.
    for run_dir in (folder / 'graph', folder / 'engine'):
        final = read_checkpoint(run_dir / 'runs' / 'checkpoints' / 'same' / 'final.pt')
        assert final['core']['ppo']['updates'] == 3, run_dir


@pytest.mark.slow
def test_a_scripted_stick_gives_the_same_session_in_the_graph_and_the_engine(sessions):
    """The joystick path (deadzone, enable button, scaling) driven by a scripted stick.

    ``human.input: script``: the stick's position comes from a file in simulation time, so the
    person's kind of input runs without wall time; its changes fall inside control periods
    (every 0.06 s), so the slices of a period carry different commands.

    The graph's nodes run here on rclpy's own SingleThreadedExecutor (``HRC_EXECUTOR=rclpy``,
    the escape hatch), bit for bit as the engine; the default, ``lean``
    (hrc_common.executors.LeanExecutor), is every other test of this file.
    """
    graph_bag, engine_bag, _ = outcome_of(sessions, 'scripted_stick')
    graph_messages = assert_same(graph_bag, engine_bag, (0, 1, 2))
    actions = [action for episode in (0, 1, 2)
               for action in graph_messages['/hrc/human/action'][episode]]
    assert actions and {action['source'] for action in actions} == {3}, [
        action for action in actions[:2]]   # SOURCE_REPLAY
    # the script's changes inside a period reach the physics: periods with unequal slices
    mixed = [state for state in graph_messages['/hrc/state'][0][1:]
             if len(set(state['human_applied'])) > 1]
    assert len(mixed) >= 5, graph_messages['/hrc/state'][0][1]


def test_the_partner_aware_policy_is_the_same_in_the_graph_and_the_engine(sessions):
    """The partner model's features enter the observation in the agent node as in the engine.

    SAC with the partner_aware configuration (7 more inputs, the model refitted every step):
    the sessions are bit for bit the same, and the policy they trained has the larger input.
    """
    graph_bag, engine_bag, folder = outcome_of(sessions, 'partner_aware')
    assert_same(graph_bag, engine_bag, (0, 1, 2))
    for run_dir in (folder / 'graph', folder / 'engine'):
        final = read_checkpoint(run_dir / 'runs' / 'checkpoints' / 'same' / 'final.pt')
        assert final['config']['params']['partner_inference'] is True, run_dir
        first_layer = next(iter(final['core']['sac']['actor'].values()))
        assert first_layer.shape[1] == 7 + 7, run_dir       # state, rates, a_h + the model


def test_the_co_adapting_person_is_the_same_in_the_graph_and_the_engine(sessions):
    """The human node's co-adapting person acts as the engine's, slice by slice.

    The main session with the profile paper_co_adapting: bit for bit the same both ways, and
    not the main session's person (co-adaptation changed what the person did).
    """
    graph_bag, engine_bag, _ = outcome_of(sessions, 'co_adapting')
    co_adapting = assert_same(graph_bag, engine_bag, (0, 1, 2))
    paper = by_episode(outcome_of(sessions, 'main')[0])
    assert co_adapting['/hrc/human/action'] != paper['/hrc/human/action']


def test_sim_human_and_recorder_in_one_process_give_the_same_session(sessions):
    """``HRC_COMPOSE=sim,human,recorder`` (hrc_bringup.compose_nodes): one process, one executor.

    The sim, the human node and the recorder run as three nodes of one process on one
    LeanExecutor (the agent in its own): the session is bit for bit the engine's, and the
    recorder composed with them writes it whole. A short session (10 steps an episode).
    """
    graph_bag, engine_bag, folder = outcome_of(sessions, 'composed')
    graph_messages = assert_same(graph_bag, engine_bag, (0, 1, 2))
    assert all(len(graph_messages['/hrc/state'][episode]) == 11 for episode in (0, 1, 2))
    logs = sorted(path.name for path in (folder / 'graph' / 'runs' / 'same' / 'logs').iterdir())
    assert logs == ['agent.log', 'sim+human+recorder.log'], logs
