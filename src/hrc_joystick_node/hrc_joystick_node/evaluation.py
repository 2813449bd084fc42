"""Run the simulated human on the physics core alone (the robot doing nothing); pure, no rclpy.

Used by the tests and ``bench/sim_human_error_table.py`` to measure how well a profile holds its
own subtask next to zero action. The physics is passed in (an ``hrc_sim_node.physics``
``SliderPendulumBall``), so this module does not import it.
"""

import typing

import numpy

from hrc_common.dof import check_dof, TRANSLATION

ERROR_OF = {  # subtask id -> the state attribute whose magnitude is its error
    'slider': 'slider_position',
    'pendulum': 'pendulum_angle',
    'ball': 'ball_position',
}


class EpisodeResult(typing.NamedTuple):
    """Mean absolute error of every subtask over one episode, and the actor's effort."""

    errors: typing.Dict[str, float]  # subtask id -> mean |S_x| (m), |P_z| (rad), |B_y| (m)
    effort: float  # variance of the human's normalized command (the paper's effort)
    commands: typing.List[float]


def run_episode(physics, dof: str, seed: int, command=None) -> EpisodeResult:
    """Run one episode from ``physics.reset(seed)``; ``command(state)`` drives ``dof``.

    ``command`` None means zero action. The other degree of freedom gets zero (robot idle).
    The errors are averaged over the states reached after each step (step 1..end).
    """
    check_dof(dof)
    state = physics.reset(seed=seed)
    sums = {subtask: 0.0 for subtask in ERROR_OF}
    commands = []
    steps = 0
    while not (state.truncated or state.terminated):
        value = 0.0 if command is None else float(command(state))
        commands.append(value)
        if dof == TRANSLATION:
            state = physics.step_normalized(value, 0.0)
        else:
            state = physics.step_normalized(0.0, value)
        steps += 1
        for subtask, attribute in ERROR_OF.items():
            sums[subtask] += abs(getattr(state, attribute))
    errors = {subtask: total / steps for subtask, total in sums.items()}
    return EpisodeResult(errors, float(numpy.var(commands)), commands)


def human_episode(physics, human, episode: int, seed: int, subtasks) -> EpisodeResult:
    """Reset ``human`` for ``episode`` and let it act on ``subtasks`` for one episode."""
    human.reset(episode)
    return run_episode(physics, human.dof, seed, lambda state: human.act(state, subtasks))
