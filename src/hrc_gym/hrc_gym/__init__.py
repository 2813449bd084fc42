"""The slider-pendulum-ball task as Gymnasium and PettingZoo environments (see docs/gym.md).

Importing the package registers ``hrc/SliderPendulumBall-v0`` with Gymnasium, so
``gymnasium.make('hrc/SliderPendulumBall-v0', case=2, training_step=0, preset='tuned')`` works
after ``import hrc_gym``. The PettingZoo parallel environment is :func:`parallel_env`.
"""

import gymnasium

ENV_ID = 'hrc/SliderPendulumBall-v0'

if ENV_ID not in gymnasium.registry:
    gymnasium.register(id=ENV_ID, entry_point='hrc_gym.env:SliderPendulumBallEnv')


def parallel_env(**kwargs):
    """Return the PettingZoo parallel environment of both actors (hrc_gym.parallel)."""
    from hrc_gym.parallel import SliderPendulumBallParallelEnv  # lazy: pettingzoo, only this API

    return SliderPendulumBallParallelEnv(**kwargs)
