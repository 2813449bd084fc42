"""The messages of the graph as plain values (no rclpy), for the bags the engine writes.

Each function returns the mapping of one message as the node that publishes it in the graph
fills it in (sim: TaskState; agent: WrenchStamped, AgentStep, EpisodeSummary, SessionStatus;
human: HumanAction, WrenchStamped), so a bag of the engine holds the same fields as a bag of
the graph. ``hrc_bag.session_writer`` encodes them to CDR.
"""

from hrc_common.contract import DOF_INDEX, episode_kind, InputSource, Phase
# Wrench values live with the sim's command rules; wrench_on is used here and re-exported.
from hrc_sim_node.commands import HUMAN, ROBOT, Wrench, wrench_on  # noqa: F401
from hrc_sim_node.protocol import stamp_fields

FRAME = 'world'
SOURCE_SIMULATED = int(InputSource.SIMULATED)
SOURCE_NONE = int(InputSource.NONE)


def header(stamp: int) -> dict:
    """Return a std_msgs/Header for a stamp in ns (frame 'world')."""
    sec, nanosec = stamp_fields(stamp)
    return {'stamp': {'sec': sec, 'nanosec': nanosec}, 'frame_id': FRAME}


def wrench_stamped(stamp: int, wrench: Wrench) -> dict:
    """Return a geometry_msgs/WrenchStamped."""
    return {'header': header(stamp),
            'wrench': {'force': vars(wrench.force), 'torque': vars(wrench.torque)}}


def task_state(state, episode: int, stamp: int, missing: dict, slice_index: int = 0,
               human_applied=()) -> dict:
    """Return the TaskState the sim publishes for a PhysicsState."""
    return {'header': header(stamp), 'episode': episode, 'step': state.step,
            'slider_position': state.slider_position,
            'slider_velocity': state.slider_velocity,
            'pendulum_angle': state.pendulum_angle,
            'pendulum_angular_velocity': state.pendulum_angular_velocity,
            'ball_position': state.ball_position, 'ball_velocity': state.ball_velocity,
            'applied_force': state.applied_force, 'applied_torque': state.applied_torque,
            'robot_command_missing': bool(missing.get(ROBOT, False)),
            'human_command_missing': bool(missing.get(HUMAN, False)),
            'slice': int(slice_index),
            'human_applied': [float(value) for value in human_applied],
            'terminated': bool(state.terminated), 'truncated': bool(state.truncated)}


def human_action(stamp: int, episode: int, step: int, answer) -> dict:
    """Return the HumanAction of one answer (a HumanAnswer)."""
    return {'header': header(stamp), 'episode': episode, 'step': step,
            'command': answer.command, 'dof': DOF_INDEX[answer.dof],
            'source': answer.source, 'source_detail': answer.detail,
            'engaged': answer.engaged}


def agent_step(record, stamp: int) -> dict:
    """Return the AgentStep of a completed StepRecord (stamp of the state acted on)."""
    return {'header': header(stamp), 'episode': record.episode, 'step': record.step,
            'observation_human_action': record.observed_human_action,
            'action': record.action, 'wrench': record.wrench,
            'subtask_ids': list(record.subtask_ids),
            'reward_components': [float(value) for value in record.reward_components],
            'reward': record.reward, 'value_estimate': record.value,
            'log_prob': record.log_prob, 'deterministic': record.deterministic}


def episode_summary(core, result, stamp: int) -> dict:
    """Return the EpisodeSummary of a finished episode (stamp of its final state)."""
    return {'header': header(stamp), 'session_id': core.session_id,
            'case_id': core.case_id, 'episode': result.episode,
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
            'human_effort': result.human_effort, 'converged': result.converged}


def session_status(core, text: str, wall_ns: int) -> dict:
    """Return the SessionStatus the agent publishes (header stamp: wall time)."""
    step = core.training_step
    sec, nanosec = stamp_fields(wall_ns)
    return {'header': {'stamp': {'sec': sec, 'nanosec': nanosec}, 'frame_id': ''},
            'session_id': core.session_id, 'case_id': core.case_id,
            'strategy': core.strategy, 'training_step': step.index,
            'training_step_count': core.training_step_count,
            'robot_dof': DOF_INDEX[core.robot_dof], 'human_dof': DOF_INDEX[core.human_dof],
            'human_involved': core.human_involved,
            'robot_subtasks': list(core.robot_subtasks),
            'human_subtasks': list(core.human_subtasks), 'episode': core.episode,
            'total_episodes': core.total_episodes,
            'human_involved_episodes': core.human_involved_episodes,
            'phase': int(Phase.from_label(core.phase)), 'message': text}
