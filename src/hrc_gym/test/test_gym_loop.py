"""The Gymnasium environment's step is the engine's loop's step (``hrc_engine.loop``).

The environment with the simulated person inside and a loop of its own with the same physics,
protocol and human side, driven by the same robot commands, reach the same states.
"""

import numpy as np

from hrc_engine.loop import EpisodeLoop
from hrc_gym.env import derived_seed, SliderPendulumBallEnv
from hrc_gym.task import make_human
from hrc_sim_node.commands import wrench_on
from hrc_sim_node.physics import SliderPendulumBall


def test_the_gym_environments_step_is_the_loops_step():
    env = SliderPendulumBallEnv(case=4, training_step=-1, human='paper')
    commands = np.random.default_rng(1).uniform(-1.0, 1.0, 25)
    try:
        env.reset(seed=7)
        task = env.task
        episode_seed = int(np.random.default_rng(7).integers(2 ** 31 - 1))
        gym = [env.step([command])[4]['human_action'] for command in commands]
        gym_states = [env.state]
        params = task.physics.params
    finally:
        env.close()
    # the same episode on a loop of its own: the same physics, protocol and human
    human = make_human('paper', task.dofs['human'], derived_seed(7, 1), task.limits, True,
                       task.subtasks['human'])
    with SliderPendulumBall(params) as physics:
        loop = EpisodeLoop.on_physics(physics, human, task.dofs['robot'])
        loop.set_roles(task.dofs['robot'], task.dofs['human'], True, task.subtasks['human'])
        loop.start(0, episode_seed)
        own = []
        for command in commands:
            answer = loop.answer()
            own.append(answer.command)
            advanced = loop.step(wrench_on(task.dofs['robot'],
                                           command * task.limits.full_scale(task.dofs['robot'])),
                                 answer)
    assert gym == own and any(gym)
    assert vars(gym_states[0]) == vars(advanced.state)
