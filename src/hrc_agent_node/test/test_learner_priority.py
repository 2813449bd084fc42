"""The background learner yields to the control thread: lower nice, short switch interval.

On the 2-core machine a PPO update inside a realtime episode would compete with the control
steps on equal terms: the learner thread lowers its own priority and shortens the
interpreter's switch interval while it runs (0 for both: neither), and the agent's defaults
carry the settings to it.
"""

import os
import sys
import threading

from hrc_agent_node.agent_core import AgentCore
from hrc_agent_node.config import AgentParams
from hrc_agent_node.learner import BackgroundLearner
from hrc_common.params import with_overrides


class RecordingAgent:
    """Records, inside the update, the learner thread's nice value and the switch interval."""

    def __init__(self):
        self.seen = {}

    def freeze_actor(self):
        pass

    def release_actor(self):
        pass

    def update(self, buffer):
        thread = threading.get_native_id()
        self.seen = {'nice': os.getpriority(os.PRIO_PROCESS, thread),
                     'switch': sys.getswitchinterval()}
        return {'buffer': buffer}


def run_one_update(learner):
    learner.start('rollout')
    return learner.wait()


def test_the_learner_thread_runs_at_lower_priority_with_a_short_switch_interval():
    caller_nice = os.getpriority(os.PRIO_PROCESS, threading.get_native_id())
    switch_before = sys.getswitchinterval()
    agent = RecordingAgent()
    stats = run_one_update(BackgroundLearner(agent, niceness=10, switch_interval=0.0005))
    assert stats == {'buffer': 'rollout'}
    assert agent.seen['nice'] == min(19, caller_nice + 10)
    assert agent.seen['switch'] == 0.0005
    # back as it was once the new weights are swapped in; the caller's own priority untouched
    assert sys.getswitchinterval() == switch_before
    assert os.getpriority(os.PRIO_PROCESS, threading.get_native_id()) == caller_nice


def test_zero_for_both_is_the_learner_as_before():
    caller_nice = os.getpriority(os.PRIO_PROCESS, threading.get_native_id())
    switch_before = sys.getswitchinterval()
    agent = RecordingAgent()
    run_one_update(BackgroundLearner(agent))
    assert agent.seen == {'nice': caller_nice, 'switch': switch_before}


def test_the_agent_gives_its_background_learner_the_parameters():
    core = AgentCore(with_overrides(AgentParams(), case=4, checkpoint_dir='', learner_niceness=7,
                                    learner_switch_interval=0.002))
    core.set_learner_mode('background')
    assert (core.learner.niceness, core.learner.switch_interval) == (7, 0.002)
    defaults = AgentParams()
    assert (defaults.learner_niceness, defaults.learner_switch_interval) == (10, 0.0005)
