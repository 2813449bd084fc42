"""A scripted partner for tests and offline baselines: a PD controller on one degree of freedom.

Not a model of a person (``hrc_joystick_node``'s simulated human is): a deterministic,
reproducible partner with which PPO runs can be compared. It has the signature every partner of
:func:`hrc_agent_node.offline.run_session` has: ``partner(state, subtasks) -> command in [-1, 1]``
where ``state`` has the PhysicsState attributes and ``subtasks`` are the ids the session assigns
to the partner.

* translation: ``u = -(kp * S_x + kd * dS_x/dt)`` when it holds ``slider`` (else 0): the slider
  moves the ball only through (g + a) sin P_z, too weakly to hold the ball with it;
* rotation: ``u = -(kp * (P_z - P_ref) + kd * dP_z/dt) + feed-forward``, where ``P_ref = 0``
  when it holds ``pendulum`` and, when it also holds ``ball``, ``P_ref = kb * B_y + kbv * dB_y/dt``
  (tilt the east end up while the ball is east of the middle, so the ball rolls back) and the
  feed-forward cancels the ball's torque on the beam (m_b g B_y cos P_z).
"""

from dataclasses import dataclass
import math

import numpy as np


@dataclass
class PDGains:
    """Gains of the scripted partner, in normalized command per SI unit."""

    slider_kp: float = 20.0       # 1/m: a 5 cm offset commands full force
    slider_kd: float = 2.0        # s/m (larger gains chatter at the 5 Hz control rate)
    pendulum_kp: float = 6.0      # 1/rad
    pendulum_kd: float = 0.5      # s/rad (more derivative rings at the 5 Hz control rate)
    ball_kp: float = 0.8          # rad/m: desired tilt per m of ball offset
    ball_kd: float = 0.4          # rad*s/m
    max_reference: float = 0.25   # rad: |P_ref| limit


class ScriptedPartner:
    """PD partner on ``dof``; deterministic unless ``noise`` (std of the command) is set."""

    def __init__(self, dof: str, gains: PDGains = None, max_torque: float = 0.5,
                 ball_mass: float = 0.05, gravity: float = 9.81, noise: float = 0.0,
                 seed: int = 0):
        if dof not in ('translation', 'rotation'):
            raise ValueError(f'unknown degree of freedom {dof!r}')
        self.dof = dof
        self.gains = gains or PDGains()
        self.max_torque = max_torque
        self.ball_weight = ball_mass * gravity   # N: the ball's pull on the beam
        self.noise = noise
        self.rng = np.random.default_rng(seed)

    def __call__(self, state, subtasks) -> float:
        """Return the command in [-1, 1] for ``state`` given the partner's subtasks."""
        g = self.gains
        command = 0.0
        if self.dof == 'translation':
            if 'slider' in subtasks:
                command = -(g.slider_kp * state.slider_position
                            + g.slider_kd * state.slider_velocity)
        else:
            reference = 0.0
            feed_forward = 0.0
            if 'ball' in subtasks:
                reference = g.ball_kp * state.ball_position + g.ball_kd * state.ball_velocity
                reference = max(-g.max_reference, min(g.max_reference, reference))
                # The ball east of the middle presses the east end down: push it back up.
                feed_forward = self.ball_weight * state.ball_position \
                    * math.cos(state.pendulum_angle) / self.max_torque
            if 'pendulum' in subtasks or 'ball' in subtasks:
                command = -(g.pendulum_kp * (state.pendulum_angle - reference)
                            + g.pendulum_kd * state.pendulum_angular_velocity) + feed_forward
        if self.noise > 0:
            command += float(self.rng.normal(0.0, self.noise))
        return float(min(1.0, max(-1.0, command)))
