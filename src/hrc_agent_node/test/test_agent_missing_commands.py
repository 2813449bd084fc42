"""An episode in which a command came late is not counted as normal.

The sim applies zero for a command that did not arrive in time and says so in the state
(``robot_command_missing`` / ``human_command_missing``). Such a judging episode judges nothing
(the next episode judges the same policy again) and such an evaluation episode is run again;
Table II (the evaluation summary) is over the complete ones. Hand-made states (no physics),
seeded cores: deterministic.
"""

from hrc_agent_node.agent_core import AgentCore
from hrc_agent_node.config import AgentParams
from hrc_common.contract import SimLimits
from hrc_common.params import with_overrides
from hrc_testing.hand_states import hand_state

STEPS = 4
LIMITS = SimLimits(control_period=0.2, max_force=2.0, max_torque=0.5)


def state(step, final=False, missing=False):
    """Return a state every subtask of which is satisfied (a command late when ``missing``)."""
    return hand_state(step, final, robot_command_missing=missing, human_command_missing=False)


def core_of(**overrides):
    values = dict(case=5, seed=3, preset='tuned', checkpoint_dir='', algorithm='sac',
                  judging_interval=1, convergence_window=2, max_training_episodes=50,
                  evaluation_episodes=2, sac_learning_starts=1000)
    values.update(overrides)
    return AgentCore(with_overrides(AgentParams(), **values), limits=LIMITS)


def episode(core, missing_in=()):
    """Run one episode; the states of the steps in ``missing_in`` say a command came late."""
    plan = core.start_episode()
    for step in range(STEPS):
        core.act(state(step, missing=step in missing_in))
    return plan, core.end_episode(state(STEPS, final=True, missing=STEPS in missing_in))


def test_a_judging_episode_with_a_late_command_judges_nothing():
    core = core_of()
    kinds = []
    while core.phase == 'training':
        plan, result = episode(core, missing_in=(2,) if len(kinds) == 1 else ())
        kinds.append(('judging' if plan.judging else 'training', result.commands_missing,
                      result.converged))
    # training, judging with a late command (judges nothing), judging again twice in a row
    assert kinds == [('training', 0, False), ('judging', 1, False), ('judging', 0, False),
                     ('judging', 0, True)]


def test_an_evaluation_episode_with_a_late_command_is_run_again():
    core = core_of(evaluation_only=False)
    while core.phase == 'training':
        episode(core)
    evaluations = [episode(core, missing_in=(1, 3) if index == 0 else ())[1]
                   for index in range(3)]
    assert [result.commands_missing for result in evaluations] == [2, 0, 0]
    assert core.phase == 'done'                            # 2 complete ones
    summary = core.evaluation_summary()
    assert summary['episodes'] == 2 and summary['incomplete'] == 1


def test_the_evaluation_ends_when_commands_keep_coming_late():
    core = core_of()
    while core.phase == 'training':
        episode(core)
    count = 0
    while core.phase != 'done':
        episode(core, missing_in=(1,))
        count += 1
    assert count == 4                                      # twice evaluation_episodes
    assert core.evaluation_summary()['incomplete'] == 4
