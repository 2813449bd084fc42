"""The sim's side of one control step, as a pure core: step orders in, states to publish out.

The sim node and the in-process engine both advance the physics through a :class:`SimStepper`,
so the order of a control step at the human's rate is written once:

1. The period's state (step k, slice 0) is published on ``/hrc/state``; the robot and the human
   answer it (:class:`~hrc_sim_node.protocol.StepProtocol` decides when a step order is due).
2. Whole period (the human acts once a period, or sits out): the order's wrench is held for all
   ``substeps`` and the state of step k+1 follows.
3. At the human's rate (``human_period`` < ``control_period`` and the human involved): each
   order covers one human slice (``substeps_per_slice`` substeps). After slice j < slices the
   state at that moment, a *slice state* (``slice`` = j), goes to the human (lockstep: its
   answer, stamped with the slice state's stamp, completes the next order; the robot's answer
   to the period's state holds for the whole period; realtime: the wall timer ticks per slice
   with the newest commands). After the last slice the period's state k+1 follows, carrying
   ``human_applied``: the human's applied command in each part of the period.

What the robot observes as the human's action over such a period is the state's
``applied_force``/``applied_torque`` on the human's degree of freedom: the period's
time-weighted mean of the applied commands (:meth:`SliderPendulumBall.finish_period`); with one
slice it is the held command itself, exactly as before human slices existed.
"""

from dataclasses import dataclass, field
import typing

from hrc_sim_node.commands import HUMAN, ROBOT


@dataclass
class Advanced:
    """What one step order produced: a state to publish."""

    state: typing.Any             # PhysicsState: the period's new state, or the slice state
    stamp: int                    # ns: its stamp
    period_end: bool              # True: the state of the next control step (/hrc/state)
    slice: int = 0                # > 0: a slice state (the human's rate), its index
    missing: dict = field(default_factory=dict)      # period end: actor -> counted as zero
    human_applied: list = field(default_factory=list)  # period end: per part of the period

    @property
    def observed(self):
        """Return the state with its applied human commands (what a TaskState carries)."""
        return PeriodState(self.state, self.human_applied)

    @property
    def episode_over(self) -> bool:
        """Return True when this is the last state of the episode."""
        return self.period_end and bool(self.state.truncated or self.state.terminated)


class PeriodState:
    """A period's state as the actors see it in a TaskState.

    The PhysicsState's fields plus ``human_applied`` (the human's commands applied in each
    slice of the period).
    """

    __slots__ = ('_state', 'human_applied')

    def __init__(self, state, human_applied):
        self._state = state
        self.human_applied = tuple(human_applied)

    def __getattr__(self, name):
        return getattr(self._state, name)


class SimStepper:
    """Physics (``SliderPendulumBall``) and the step protocol, one control step at a time."""

    def __init__(self, physics, protocol):
        if physics.params.human_slices != protocol.slices:
            raise ValueError(f'the physics splits a period into {physics.params.human_slices} '
                             f'human slices, the protocol into {protocol.slices}')
        self.physics = physics
        self.protocol = protocol
        self._human_applied = []

    def start_episode(self, episode: int, seed=None) -> Advanced:
        """Reset the physics (``seed`` None: the next of its sequence); return state 0."""
        state = self.physics.reset(seed=seed) if seed is not None else self.physics.reset()
        self.protocol.start_episode(episode)
        self._human_applied = []
        stamp = self.protocol.next_stamp(state.step, bool(state.truncated or state.terminated))
        return Advanced(state, stamp, True)

    def apply(self, order) -> Advanced:
        """Advance the physics as ``order`` (a StepOrder) says; return the state to publish."""
        physics = self.physics
        substeps = order.slices * physics.params.substeps_per_slice
        middle = physics.advance(order.force, order.torque, substeps)
        self._human_applied.append(order.human_value)
        if not order.final:
            stamp = self.protocol.next_slice_stamp()
            return Advanced(middle, stamp, False, slice=self.protocol.slice_index)
        state = physics.finish_period()
        applied, self._human_applied = self._human_applied, []
        stamp = self.protocol.next_stamp(state.step, bool(state.truncated or state.terminated))
        return Advanced(state, stamp, True, 0, dict(order.missing), applied)

    def run_period(self, robot_wrench, human_wrench, answer_slice) -> Advanced:
        """Lockstep, in one process: the period's state answered, to the next period's state.

        ``robot_wrench``, ``human_wrench``: both actors' answers to the period's state
        (Wrench-like; the human's is not read, and may be None, while the human sits out:
        :attr:`StepProtocol.awaits_human`); ``answer_slice(advanced)`` returns the human's
        answer to a slice state (called only at the human's rate, while the human is
        involved). The robot's answer holds for the period. The in-process engine, the
        offline runner and the Gymnasium environments step through this, as the sim node and
        the human node do over DDS.
        """
        protocol = self.protocol
        stamp = protocol.awaited
        order = protocol.on_command(ROBOT, stamp, robot_wrench, 0.0).order
        if protocol.awaits_human:
            order = protocol.on_command(HUMAN, stamp, human_wrench, 0.0).order
        while True:
            if order is None:  # cannot happen: every awaited actor answered
                raise RuntimeError(f'step {protocol.step}: the protocol did not step')
            advanced = self.apply(order)
            if advanced.period_end:
                return advanced
            order = protocol.on_command(HUMAN, advanced.stamp, answer_slice(advanced),
                                        0.0).order
