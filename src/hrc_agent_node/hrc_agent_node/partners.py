"""Partners of the offline loop: a scripted PD controller, and the simulated human (a population).

``ScriptedPartner`` is not a model of a person (``hrc_joystick_node``'s simulated human is,
wrapped by ``SimulatedHumanPartner``, which can also draw a new person from the population
around a profile every N episodes: population training): a deterministic,
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

from hrc_common.contract import check_dof, SimLimits
from hrc_joystick_node.population import sample_person
from hrc_joystick_node.sim_human import SimulatedHuman
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
        self.dof = check_dof(dof)
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


def person_seed(session_seed: int, draw: int) -> int:
    """Return the population seed of the ``draw``-th person of a session (31-bit)."""
    return int(np.random.SeedSequence([int(session_seed), int(draw), 0x9E3779B9])
               .generate_state(1)[0] & 0x7FFFFFFF)


# How often an offline simulated person is told it acts (the SimulatedHuman's control_period):
# `human` = the sim's human_period (SimLimits.human_step), as the engine's and the graph's
# person act (hrc_joystick_node.human_core); `control` = the control period, which the offline
# tools (hrc_partners, the benches) used before (issue 22): with the sim's human_period 0.02 s
# the offline loop calls the person every 0.02 s, so a person built for 0.2 s calls ran its
# delays, lags, slew limits, integrator and lapses 10x fast. Same numbers when human_period =
# control_period. Defined here, next to the offline person, so every layer above (hrc_partners,
# the benches) chooses an offline person's rate in this one place.
PERSON_PERIODS = ('human', 'control')


def person_period(limits: SimLimits, period: str = 'human') -> float:
    """Return the s between a simulated person's calls for ``period`` (PERSON_PERIODS)."""
    if period not in PERSON_PERIODS:
        raise ValueError(f'person period {period!r} is not one of {PERSON_PERIODS}')
    return limits.human_step if period == 'human' else limits.control_period


class SimulatedHumanPartner:
    """``hrc_joystick_node``'s simulated human as an offline partner, alone or as a population.

    ``control_period``: the sim's (``SimLimits.control_period``), the s between calls; no default.

    ``population_every`` 0: one person, the profile itself, for the whole session (fatigue,
    practice and adaptation carry over between episodes). N > 0: population training, a new
    person drawn with ``sample_person(profile, person_seed(seed, episode // N))`` every N
    episodes (1: every episode), each new to the task. Every episode kind (training, judging,
    evaluation) meets the person the rule gives, so judging and evaluation measure the team
    with the training distribution. Call :meth:`start_episode` before each episode (the
    offline loop does).
    """

    def __init__(self, profile, dof: str, seed: int, control_period: float,
                 population_every: int = 0):
        if population_every < 0:
            raise ValueError(f'population_every must be >= 0, got {population_every}')
        self.profile = profile
        self.dof = dof
        self.seed = int(seed)
        self.control_period = float(control_period)
        self.population_every = int(population_every)
        self.draw = None          # index of the person drawn (None: the profile itself)
        self.person = None        # the HumanProfile of the current person
        self.human = None         # their SimulatedHuman

    def start_episode(self, episode: int) -> None:
        """Meet the person of ``episode`` (draw a new one when the rule says so); reset."""
        draw = int(episode) // self.population_every if self.population_every else None
        if self.human is None or draw != self.draw:
            self.draw = draw
            self.person = self.profile if draw is None else \
                sample_person(self.profile, person_seed(self.seed, draw))
            seed = self.seed if draw is None else person_seed(self.seed, draw)
            self.human = SimulatedHuman(self.person, self.dof, seed=seed,
                                        control_period=self.control_period)
        self.human.reset(int(episode))

    def __call__(self, state, subtasks) -> float:
        """Return the person's stick command in [-1, 1] for ``state``."""
        if self.human is None:
            raise RuntimeError('call start_episode() before the first command')
        return float(self.human.act(state, list(subtasks)))
