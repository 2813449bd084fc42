"""The human side of an in-process session: the human node's pure core, driven by calls.

It answers exactly as the human node does with ``input: sim``: both run
:class:`hrc_joystick_node.human_core.HumanCore` (roles from the session, involvement, the
simulated human reset at each new episode or when a step does not follow the last one, its
fatigue on the state stamps, person N of the population when ``human.person`` is N); the wrench
is the command times the sim's ``max_force``/``max_torque``, and the simulated human runs on the
sim's control period (``SimLimits``, given by the session as the node reads them from the sim).
"""

from hrc_engine.loop import HumanAnswer
from hrc_joystick_node.human_core import core_from_parameters


class SimulatedHumanSide:
    """The human node's core (``input: sim``), driven by calls instead of messages."""

    def __init__(self, core):
        self.core = core            # a HumanCore with the sim's limits set

    @classmethod
    def from_parameters(cls, parameters: dict, limits) -> 'SimulatedHumanSide':
        """Return the side of the human node's parameters (a dict) and the sim's limits."""
        if parameters.get('input', 'sim') not in ('sim', 'model', 'script'):
            raise ValueError(f"the in-process engine runs the simulated human, a cloned model "
                             f"or a scripted stick only (human.input 'sim', 'model' or "
                             f"'script'), got "
                             f"{parameters.get('input')!r}")
        return cls(core_from_parameters(parameters, limits))

    def start_episode(self, episode: int) -> None:
        """Nothing to do: the core resets the simulated human at each new episode itself."""

    def on_session(self, dof: str, involved: bool, subtasks) -> None:
        """Take the roles a SessionStatus announces."""
        self.core.on_session(dof, involved, list(subtasks))

    @property
    def answers_states(self) -> bool:
        """Return True while the human answers states (involved; HumanCore.answers_states)."""
        return self.core.answers_states

    def answer(self, episode: int, state, stamp_ns: int, slice_index: int = 0) -> HumanAnswer:
        """Return the answer to a non-final (slice) state of ``episode`` stamped ``stamp_ns``."""
        answer = self.core.answer(episode, state.step, stamp_ns, state,
                                  slice_index=slice_index)
        return HumanAnswer(answer.command, answer.wrench, answer.dof, answer.source_code,
                           answer.detail, answer.engaged)
