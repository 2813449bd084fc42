"""The slider-pendulum-ball simulation: PyBullet physics core and the sim node."""
