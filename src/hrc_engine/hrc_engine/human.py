"""The human side of an in-process session: the simulated human answering each state.

It answers as the human node does with ``input: sim`` (hrc_joystick_node/human_node.py): the
session gives the degree of freedom, the involvement and the subtasks; a state is answered
with the simulated human's command when the human is involved (reset at each new episode, or
when a step does not follow the last one), with zero and ``engaged`` false when not; the
wrench is the command times the sim's ``max_force``/``max_torque``.
"""

from dataclasses import dataclass
import typing

from hrc_common.contract import TRANSLATION
from hrc_joystick_node.population import person_or_profile
from hrc_joystick_node.sim_human import (BALL, default_profiles_path, load_profiles,
                                         normalize_subtasks, OWN_SUBTASK, SimulatedHuman)

from hrc_engine.messages import SOURCE_NONE, SOURCE_SIMULATED


class StateView(typing.NamedTuple):
    """The state attributes the simulated human reads (time: s since the episode's reset)."""

    step: int
    time: float
    slider_position: float
    slider_velocity: float
    pendulum_angle: float
    pendulum_angular_velocity: float
    ball_position: float
    ball_velocity: float


@dataclass(frozen=True)
class HumanAnswer:
    """The human's answer to one state."""

    command: float          # normalized, [-1, 1]
    wrench: float           # N or N*m on ``dof``
    dof: str
    source: int             # HumanAction.SOURCE_*
    detail: str
    engaged: bool


class SimulatedHumanSide:
    """The human node's simulated-human path, driven by calls instead of messages."""

    def __init__(self, parameters: dict):
        self.parameters = parameters
        if parameters.get('input', 'sim') != 'sim':
            raise ValueError(f"the in-process engine runs the simulated human only (human.input "
                             f"'sim'), got {parameters.get('input')!r}")
        path = parameters.get('profiles_file') or default_profiles_path()
        profiles = load_profiles(path)
        name = parameters['profile']
        if name not in profiles:
            raise ValueError(f'human.profile: {name!r} is not in {path} '
                             f'(known: {sorted(profiles)})')
        # person N of the population around the profile (-1: the profile), as the human node
        self.profile = person_or_profile(profiles[name], int(parameters.get('person', -1)))
        self.control_period = float(parameters['control_period'])
        self.seed = int(parameters['seed'])
        self.dof = parameters['dof']
        self.involved = bool(parameters['involved'])
        self.subtasks = [OWN_SUBTASK[self.dof]] + ([BALL] if parameters['hold_ball'] else [])
        self.sim_human = self._new_sim_human(self.dof)
        self._episode = None
        self._step = None

    def _new_sim_human(self, dof: str) -> SimulatedHuman:
        return SimulatedHuman(self.profile, dof, seed=self.seed,
                              control_period=self.control_period)

    def on_session(self, dof: str, involved: bool, subtasks) -> None:
        """Take the roles a SessionStatus announces."""
        if dof != self.dof:
            self.sim_human = self._new_sim_human(dof)
            self._episode = None
        self.dof, self.involved = dof, bool(involved)
        self.subtasks, _ = normalize_subtasks(list(subtasks))

    def answer(self, episode: int, state) -> HumanAnswer:
        """Return the answer to a non-final state of ``episode``."""
        if not self.involved:
            return HumanAnswer(0.0, 0.0, self.dof, SOURCE_NONE,
                               'not involved in this training step (input: sim)', False)
        if episode != self._episode or self._step is None or state.step <= self._step:
            self.sim_human.reset(episode)
            self._episode = episode
        self._step = state.step
        view = StateView(state.step, state.step * self.control_period, state.slider_position,
                         state.slider_velocity, state.pendulum_angle,
                         state.pendulum_angular_velocity, state.ball_position,
                         state.ball_velocity)
        command = self.sim_human.act(view, self.subtasks)
        scale = self.parameters['max_force'] if self.dof == TRANSLATION \
            else self.parameters['max_torque']
        return HumanAnswer(command, command * scale, self.dof, SOURCE_SIMULATED,
                           self.parameters['profile'], True)
