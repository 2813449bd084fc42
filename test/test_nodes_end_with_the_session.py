"""Nodes started by hand end with their session: after the agent's "done" they exit 0 on their own.

The README's hand-started graph (sim, human, recorder, agent as separate ``ros2 run``
processes): once the agent is done, the sim, the human node and the recorder exit 0 with a
line that says why, and the recorder's bags are complete. With ``exit_after_session: false``
(what ``hrc session`` gives the nodes it stops itself) a second recorder stays up.
"""


def test_hand_started_nodes_exit_when_the_agent_is_done(start_node, tmp_path, read_rosbag):
    sim = start_node('hrc_sim_node', 'sim_node', parameters={
        'mode': 'lockstep', 'episode_duration': 2.0, 'marker_rate': 0.0})
    human = start_node('hrc_joystick_node', 'human_node', parameters={'input': 'sim'})
    recorder = start_node('hrc_bag', 'recorder_node', parameters={
        'output_dir': str(tmp_path / 'bags'), 'session_id': 'by-hand'})
    kept = start_node('hrc_bag', 'recorder_node', ros_args=['-r', '__node:=recorder_kept'],
                      parameters={'output_dir': str(tmp_path / 'kept'), 'session_id': 'by-hand',
                                  'exit_after_session': False})
    agent = start_node('hrc_agent_node', 'agent_node', parameters={
        'case': 5, 'seed': 1, 'max_training_episodes': 1, 'evaluation_episodes': 1,
        'horizon': 16, 'minibatch_size': 8, 'checkpoint_dir': '', 'session_id': 'by-hand',
        'wait_for_subscribers': ['recorder', 'recorder_kept', 'human']})
    assert agent.wait(timeout=180) == 0, agent.output
    for node in (sim, human, recorder):
        assert node.wait(timeout=60) == 0, node.output
        assert "session 'by-hand' is done: exiting" in node.output, node.output
    # it took the same "done" (its subscriptions as the first's) and stays up
    assert kept.process.poll() is None and 'is done: exiting' not in kept.output, kept.output
    summaries = read_rosbag(tmp_path / 'bags' / 'by-hand')['/hrc/episode']
    assert [(summary.episode, summary.evaluation) for summary in summaries] == [
        (0, False), (1, True)]
