"""SAC's gradient steps in a learner thread in realtime episodes (sac_background).

The control step only stores the transition and acts; the thread takes the owed steps, and
what it has not done by the episode's end runs in update(): no step is lost or done twice.
Deterministic: the thread is held on an event while the control steps run, so the test does
not depend on how fast the machine is.
"""

import threading
from hrc_agent_node.agent_core import AgentCore
from hrc_agent_node.config import AgentParams
from hrc_common.contract import SimLimits
from hrc_common.params import with_overrides
from hrc_testing.hand_states import hand_state

LIMITS = SimLimits(control_period=0.2, max_force=2.0, max_torque=0.5)
STEPS = 12
UPDATES_PER_STEP = 2


def state(step, final=False):
    return hand_state(step, final, slider_position=0.01 * step, pendulum_angle=0.1,
                      ball_position=0.02)


def make_core():
    return AgentCore(with_overrides(
        AgentParams(), case=1, seed=3, preset='tuned', algorithm='sac', checkpoint_dir='',
        sac_hidden_size=8, sac_batch_size=4, sac_updates_per_step=UPDATES_PER_STEP,
        sac_learning_starts=1, max_training_episodes=10, evaluation_episodes=0,
        judging_interval=100), limits=LIMITS)


def run_episode(core):
    core.start_episode()
    for step in range(STEPS):
        core.act(state(step))
    core.end_episode(state(STEPS, final=True))
    return core.update() if core.phase == 'updating' else None


def test_the_control_step_stores_and_acts_while_the_thread_learns():
    core = make_core()
    sac = core.policy_learner
    core.set_learner_mode('background')
    assert core.learner_mode == 'background' and sac.background is not None
    # hold the learner thread before its first step: the control steps must not learn
    held, learning = threading.Event(), sac.learn_one_owed

    def held_learning():
        held.wait(60)
        return learning()

    sac.learn_one_owed = held_learning
    core.start_episode()
    for step in range(STEPS):
        core.act(state(step))
    assert sac.gradient_steps == 0
    assert sac.pending_updates == STEPS - 1     # every transition but the first stored (owed)
    core.end_episode(state(STEPS, final=True))
    held.set()                                   # the thread goes on; update() takes the rest
    stats = core.update()
    # every owed transition learned once: by the thread or by update(), none lost or twice
    assert sac.pending_updates == 0
    assert sac.gradient_steps == STEPS * UPDATES_PER_STEP
    assert stats['gradient_steps'] == STEPS * UPDATES_PER_STEP
    core.set_learner_mode('synchronous')
    assert sac.background is None and core.learner_mode == 'synchronous'


def test_background_and_synchronous_learning_take_the_same_gradient_steps():
    synchronous, background = make_core(), make_core()
    background.set_learner_mode('background')
    for core in (synchronous, background):
        for _ in range(2):
            run_episode(core)
    background.set_learner_mode('synchronous')
    assert background.policy_learner.gradient_steps == \
        synchronous.policy_learner.gradient_steps == 2 * STEPS * UPDATES_PER_STEP
