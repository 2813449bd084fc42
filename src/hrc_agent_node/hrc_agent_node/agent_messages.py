"""The fields of the agent's messages, from the core's records (pure, no rclpy).

One place for what the agent publishes: the agent node builds its ROS messages from these
(``AgentStep(**agent_step_fields(record))``, then the header) and the in-process engine writes
the same fields into its bags (``hrc_engine.messages``), so the two cannot drift apart.
"""

from hrc_common.contract import DOF_INDEX, episode_kind, Phase


def agent_step_fields(record) -> dict:
    """Return the AgentStep fields (no header) of a completed StepRecord."""
    return {'episode': record.episode, 'step': record.step,
            'observation_human_action': record.observed_human_action,
            'action': record.action, 'wrench': record.wrench,
            'subtask_ids': list(record.subtask_ids),
            'reward_components': [float(value) for value in record.reward_components],
            'reward': record.reward, 'value_estimate': record.value,
            'log_prob': record.log_prob, 'deterministic': record.deterministic}


def episode_summary_fields(core, result) -> dict:
    """Return the EpisodeSummary fields (no header) of a finished episode.

    Judging episodes are not Table II evaluation: they count with the training episodes
    (``kind`` tells them apart; their AgentStep messages are deterministic).
    """
    return {'session_id': core.session_id, 'case_id': core.case_id, 'episode': result.episode,
            'training_step': result.training_step, 'human_involved': result.human_involved,
            'evaluation': result.evaluation,
            'kind': int(episode_kind(evaluation=result.evaluation, judging=result.judging,
                                     practice=getattr(result, 'practice', False))),
            'steps': result.steps,
            'terminated': result.terminated, 'truncated': result.truncated,
            'episode_return': result.episode_return,
            'slider_error': float(result.errors.get('slider', 0.0)),
            'pendulum_error': float(result.errors.get('pendulum', 0.0)),
            'ball_error': float(result.errors.get('ball', 0.0)),
            'total_error': result.total_error, 'robot_effort': result.robot_effort,
            'human_effort': result.human_effort, 'converged': result.converged,
            'robot_reversals': float(result.robot_reversals),
            'human_reversals': float(result.human_reversals),
            'commands_missing': int(result.commands_missing)}


def session_status_fields(core, text: str) -> dict:
    """Return the SessionStatus fields (no header) of the session now, with ``text``."""
    step = core.training_step
    return {'session_id': core.session_id, 'case_id': core.case_id,
            'strategy': core.strategy, 'training_step': step.index,
            'training_step_count': core.training_step_count,
            'robot_dof': DOF_INDEX[core.robot_dof], 'human_dof': DOF_INDEX[core.human_dof],
            'human_involved': core.human_involved,
            'robot_subtasks': list(core.robot_subtasks),
            'human_subtasks': list(core.human_subtasks), 'episode': core.episode,
            'total_episodes': core.total_episodes,
            'human_involved_episodes': core.human_involved_episodes,
            'phase': int(Phase.from_label(core.phase)), 'message': text}
