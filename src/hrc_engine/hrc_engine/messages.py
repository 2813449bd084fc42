"""The messages of the graph as plain values (no rclpy), for the bags the engine writes.

Each function returns the mapping of one message as the node that publishes it in the graph
fills it in (sim: TaskState; agent: WrenchStamped, AgentStep, EpisodeSummary, SessionStatus;
human: HumanAction, WrenchStamped), so a bag of the engine holds the same fields as a bag of
the graph. ``hrc_bag.session_writer`` encodes them to CDR.
"""

from hrc_agent_node.agent_messages import (agent_step_fields, episode_summary_fields,
                                          session_status_fields)
from hrc_common.contract import DOF_INDEX, InputSource
# Wrench values live with the sim's command rules; wrench_on is used here and re-exported.
from hrc_sim_node.body_geometry import JOINT_NAMES, joint_values
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


def joint_state(state, stamp: int) -> dict:
    """Return the JointState the sim publishes with a period's state."""
    positions, velocities = joint_values(state)
    return {'header': header(stamp), 'name': list(JOINT_NAMES),
            'position': [float(value) for value in positions],
            'velocity': [float(value) for value in velocities], 'effort': []}


def human_action(stamp: int, episode: int, step: int, answer) -> dict:
    """Return the HumanAction of one answer (a HumanAnswer)."""
    return {'header': header(stamp), 'episode': episode, 'step': step,
            'command': answer.command, 'dof': DOF_INDEX[answer.dof],
            'source': answer.source, 'source_detail': answer.detail,
            'engaged': answer.engaged}


def agent_step(record, stamp: int) -> dict:
    """Return the AgentStep of a completed StepRecord (stamp of the state acted on)."""
    return {'header': header(stamp), **agent_step_fields(record)}


def episode_summary(core, result, stamp: int) -> dict:
    """Return the EpisodeSummary of a finished episode (stamp of its final state)."""
    return {'header': header(stamp), **episode_summary_fields(core, result)}


def session_status(core, text: str, wall_ns: int) -> dict:
    """Return the SessionStatus the agent publishes (header stamp: wall time)."""
    sec, nanosec = stamp_fields(wall_ns)
    return {'header': {'stamp': {'sec': sec, 'nanosec': nanosec}, 'frame_id': ''},
            **session_status_fields(core, text)}
