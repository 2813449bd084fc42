"""With updates inside episodes, the lockstep graph and the in-process engine stay bit-identical.

The session of test/test_engine_equivalence.py (case 5, 40-step episodes) under ``update_rule:
horizon_or_episode_end`` with horizon 30: the first episode's rollout is cut at step 30, the
update runs before the action for that state (in the agent node and in the engine alike), the
rest of the episode acts with the new weights and updates again at its end. Every message of
both bags must be equal (the comparison of test_engine_equivalence.py).
"""

import importlib.util
import pathlib
import subprocess

import pytest

from hrc_agent_node.checkpoint import read_checkpoint
from hrc_common.testing import executable_path

REPOSITORY = pathlib.Path(__file__).resolve().parents[3]


def equivalence_module():
    """Return test/test_engine_equivalence.py (its message comparison), loaded from its path."""
    path = REPOSITORY / 'test' / 'test_engine_equivalence.py'
    spec = importlib.util.spec_from_file_location('engine_equivalence', path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


ARGS = ['--case', '5', '--episodes', '2', '--eval-episodes', '1', '--session-id', 'same',
        '--set', 'sim.episode_duration=8.0', '--set', 'agent.horizon=30',
        '--set', 'agent.minibatch_size=16', '--set', 'agent.update_rule=horizon_or_episode_end']


@pytest.mark.slow
def test_updates_inside_episodes_keep_the_graph_and_the_engine_identical(
        tmp_path, ros_domain_id, read_rosbag):
    equivalence = equivalence_module()
    graph_dir, engine_dir = tmp_path / 'graph', tmp_path / 'engine'
    graph = subprocess.run(
        [str(executable_path('hrc_bringup', 'session')), '--domain-id', str(ros_domain_id),
         '--bags-dir', str(graph_dir / 'bags'), '--runs-dir', str(graph_dir / 'runs'),
         '--no-report', *ARGS], capture_output=True, text=True, timeout=300)
    assert graph.returncode == 0, graph.stdout + graph.stderr
    engine = subprocess.run(
        [str(executable_path('hrc_engine', 'inprocess_session')),
         '--bags-dir', str(engine_dir / 'bags'), '--runs-dir', str(engine_dir / 'runs'),
         *ARGS], capture_output=True, text=True, timeout=300)
    assert engine.returncode == 0, engine.stdout + engine.stderr
    graph_messages = equivalence.by_episode(read_rosbag(graph_dir / 'bags' / 'same'))
    engine_messages = equivalence.by_episode(read_rosbag(engine_dir / 'bags' / 'same'))
    # Episode 0 is a training episode with the update inside (step 30): the robot's values
    # before and after it come from different weights in both.
    steps = graph_messages['/hrc/agent/step'][0]
    assert len(steps) == 40 and not steps[0]['deterministic']
    # Two updates each: inside episode 0 (step 30) and at its end (10 samples); the earlier
    # rule would have made one, at the end.
    for run_dir in (graph_dir, engine_dir):
        final = read_checkpoint(run_dir / 'runs' / 'checkpoints' / 'same' / 'final.pt')
        assert final['core']['ppo']['updates'] == 2, run_dir
    for topic in equivalence.TOPICS:
        assert sorted(graph_messages[topic]) == [0, 1, 2], topic
        for episode in (0, 1, 2):
            assert engine_messages[topic][episode] == graph_messages[topic][episode], \
                (topic, episode)
