"""The sim's step protocol as a pure core: plain values and a clock in, decisions out (no ROS).

The sim node and the in-process engine (``hrc_engine``) both drive a :class:`StepProtocol`;
the node only turns messages into calls and the decisions into physics steps, messages and
timers. The rules (docs/architecture.md, "The step protocol"):

* Stamps are simulation time in integer nanoseconds since the session started: 0 for the
  first state, then one control period more for every state published (resets included), so
  a stamp names one state of the session.
* A command answers a state by carrying its stamp. From each actor only its degree of freedom
  is read (:func:`hrc_sim_node.commands.read_command`: non-finite refused, beyond the limit
  clamped where the limit is owned, here; off-axis components ignored and reported).
* ``lockstep``: the step is taken as soon as every actor in ``expected_actors`` answered the
  awaited state (:meth:`StepProtocol.on_command` returns the :class:`StepOrder`), or at the
  ``lockstep_timeout`` (:meth:`StepProtocol.on_timeout`: the missing commands count as zero
  and are reported); with no expected actor the sim runs free (:meth:`StepProtocol.free_run`).
  A command with another stamp is stale: ignored, counted, reported.
* The human counts only while involved (:attr:`StepProtocol.awaits_human`): a human who sits
  out a training step is neither awaited (lockstep) nor missing (realtime), and sends nothing.
* ``realtime``: a wall timer calls :meth:`StepProtocol.on_tick` every control period; each
  actor's kept command is applied unless older than ``command_timeout`` (wall s). The kept
  command is the one answering the newest state of the running episode, not the latest
  arrival: a command whose stamp names no state of the episode is stale, and one answering an
  older state than the kept one does not replace it (a flood from another publisher with
  wrong stamps cannot push the actor's real command out).
* The clock mode can change at an episode boundary only (:meth:`StepProtocol.set_mode`, the
  node calls it from a reset that asks for it: ``ResetEpisode.clock_mode``).
* Counters (refused, clamped, off-axis, stale, missing, ...) are kept per episode and for the
  whole session; an episode abandoned by a reset in its middle still yields its counters.
* Episode indices are uint32 in the messages: :data:`MAX_EPISODE` is the last usable one.
"""

from collections import Counter
from dataclasses import dataclass, field
import typing

from hrc_common.contract import DOFS, NS_PER_S, other_dof, ROTATION, SimLimits, TRANSLATION
from hrc_sim_node.commands import ACTORS, Command, HUMAN, read_command, ROBOT
from hrc_sim_node.physics_params import PhysicsParams
from hrc_sim_node.sim_params import CLOCK_MODES, LOCKSTEP, REALTIME

_PHYSICS_DEFAULTS = PhysicsParams()

# Episode indices travel as uint32 (TaskState.episode, ResetEpisode.episode).
MAX_EPISODE = 2 ** 32 - 1
# Stamps of the running episode remembered for realtime matching (an episode has 200 states).
REALTIME_STAMPS_KEPT = 100_000


class ProtocolError(ValueError):
    """A request the protocol cannot follow (unknown clock mode, episode index out of range)."""


def stamp_ns(sec: int, nanosec: int) -> int:
    """Return the stamp (ns) of a builtin_interfaces/Time's fields; -1 if it is malformed."""
    if not 0 <= nanosec < NS_PER_S or sec < 0:
        return -1
    return int(sec) * NS_PER_S + int(nanosec)


def stamp_fields(nanoseconds: int) -> tuple:
    """Return (sec, nanosec) of a stamp in nanoseconds."""
    return nanoseconds // NS_PER_S, nanoseconds % NS_PER_S


def per_dof(values: dict, dof_of: dict) -> dict:
    """Return {translation: x, rotation: y}: each actor's value on its degree of freedom.

    ``values`` maps actor -> value (N, N*m, or normalized: the unit is the caller's); actors
    absent count as zero. Both the sim and offline loops dispatch through this one function.
    """
    wrench = {TRANSLATION: 0.0, ROTATION: 0.0}
    for actor, value in values.items():
        wrench[dof_of[actor]] += value
    return wrench


def roles(robot_dof: str) -> dict:
    """Return {robot: its dof, human: the other}."""
    return {ROBOT: robot_dof, HUMAN: other_dof(robot_dof)}


@dataclass
class StepOrder:
    """A decision to advance the physics one control period with this wrench."""

    force: float                         # N on the slider (translation)
    torque: float                        # N*m on the pendulum (rotation)
    missing: dict                        # expected actor -> its command counted as zero
    reason: str                          # 'answered' | 'timeout' | 'tick' | 'free_run'
    ignored: list = field(default_factory=list)   # (actor, value) not applied: not involved
    slices: int = 1                      # human slices of the period this order covers
    final: bool = True                   # this order completes the control period
    human_value: float = 0.0             # the human's applied command (N or N*m) in it

    @property
    def absent(self) -> list:
        """Return the actors whose command is missing."""
        return [actor for actor, is_missing in self.missing.items() if is_missing]


@dataclass
class CommandResult:
    """What the protocol made of one received command."""

    actor: str
    kind: str                    # 'between_episodes' | 'stale' | 'refused' | 'accepted'
    stamp: int                   # ns as received (-1 malformed)
    awaited: typing.Optional[int] = None   # ns of the state awaited (lockstep) or newest
    command: typing.Optional[Command] = None
    dof: str = ''
    limit: float = 0.0
    order: typing.Optional[StepOrder] = None   # lockstep: the step this command completed


@dataclass
class ProtocolSettings:
    """What the protocol needs of the sim's parameters (fields of SimParams by these names)."""

    mode: str = LOCKSTEP
    expected_actors: tuple = (ROBOT, HUMAN)
    lockstep_timeout: float = 1.0          # wall s
    command_timeout: float = 0.5           # wall s
    # The sim's limits; a bare ProtocolSettings() (tests) has the physics' defaults, never a
    # copy of their numbers (ProtocolSettings.of(sim_params) is what the sim uses).
    control_period: float = _PHYSICS_DEFAULTS.control_period   # s of simulation time per state
    max_force: float = _PHYSICS_DEFAULTS.max_force             # N
    max_torque: float = _PHYSICS_DEFAULTS.max_torque           # N*m
    robot_dof: str = TRANSLATION
    human_period: typing.Optional[float] = None   # s: the human's command is applied this
    #                                         often; None: once a period (the sim passes its own)

    @classmethod
    def of(cls, params) -> 'ProtocolSettings':
        """Return the settings carried by ``params`` (a SimParams or alike)."""
        return cls(params.mode, tuple(params.expected_actors), params.lockstep_timeout,
                   params.command_timeout, params.control_period, params.max_force,
                   params.max_torque, params.robot_dof,
                   getattr(params, 'human_period', params.control_period))

    @property
    def human_slices(self) -> int:
        """Human slices per control period (1: the human acts once a period).

        The one rule is ``SimLimits.human_slices`` (hrc_common.contract).
        """
        return SimLimits.of(self).human_slices


class StepProtocol:
    """The sim's side of the step protocol for one session (see the module docstring)."""

    def __init__(self, settings: ProtocolSettings):
        if settings.mode not in CLOCK_MODES:
            raise ProtocolError(f'clock mode {settings.mode!r} is not one of {CLOCK_MODES}')
        if settings.robot_dof not in DOFS:
            raise ProtocolError(f'robot_dof {settings.robot_dof!r} is not one of {DOFS}')
        self.settings = settings
        self.mode = settings.mode
        self.expected = tuple(settings.expected_actors)
        self.period_ns = int(round(settings.control_period * NS_PER_S))
        self.slices = settings.human_slices
        self.slice_ns = self.period_ns // self.slices
        if self.slice_ns * self.slices != self.period_ns:
            raise ProtocolError(f'control_period {settings.control_period} s does not split '
                                f'into {self.slices} human slices of whole nanoseconds')
        self.limits = SimLimits.of(settings)   # once: read_command runs for every command
        self.dof_of = roles(settings.robot_dof)
        self.human_involved = True
        self.episode = 0
        self.active = False                  # an episode is running (false while holding)
        self.step = 0                        # step of the last published state
        self.sim_time_ns = None              # stamp of the last published state
        self.awaited = None                  # stamp the commands must answer (None: none)
        self.counters = Counter()            # this episode's events
        self.totals = Counter()              # the session's events (every episode)
        self.finished_episodes = 0
        self._answers = {}                   # lockstep: actor -> Command for the awaited state
        # actor -> stale commands since the awaited state was published: a lockstep timeout
        # with many of them means a flood may have pushed the matching one out of the queue
        self.stale_while_waiting = Counter()
        self._kept = {}                      # realtime: actor -> (Command, receipt s, stamp)
        self._episode_first_stamp = None     # realtime: stamps of this episode start here
        self._slice = 0                      # human slices of the running period applied
        self._period = {}                    # actor -> Command held over the period (lockstep)
        self._period_missing = {}            # actor -> missing in any slice of the period
        self.slice_stamp_ns = None           # stamp of the newest slice state (None: none)

    # -- episodes ----------------------------------------------------------------------------
    def set_mode(self, mode: str) -> bool:
        """Switch the clock mode between episodes; return True when it changed."""
        if mode not in CLOCK_MODES:
            raise ProtocolError(f'clock mode {mode!r} is not one of {CLOCK_MODES}')
        if self.active:
            raise ProtocolError(f'the clock mode changes between episodes only (episode '
                                f'{self.episode} is running at step {self.step})')
        changed = mode != self.mode
        self.mode = mode
        return changed

    def set_roles(self, robot_dof: str, human_involved: bool) -> bool:
        """Take the roles a session announces; return True when something changed."""
        new = roles(robot_dof)
        changed = new != self.dof_of or bool(human_involved) != self.human_involved
        self.dof_of = new
        self.human_involved = bool(human_involved)
        return changed

    def start_episode(self, episode: int) -> typing.Optional[Counter]:
        """Begin ``episode``; return the counters of an episode it abandons (else None).

        The caller publishes the first state right after (:meth:`next_stamp`).
        """
        if not 0 <= int(episode) <= MAX_EPISODE:
            raise ProtocolError(f'episode index {episode} is outside 0..{MAX_EPISODE} '
                                f'(uint32)')
        abandoned = Counter(self.counters) if self.active else None
        self.episode = int(episode)
        self.active = True
        self.step = 0
        self.counters = Counter()
        self._answers = {}
        self.stale_while_waiting = Counter()
        self._kept = {}
        self._episode_first_stamp = None
        self._start_period()
        return abandoned

    def _start_period(self) -> None:
        self._slice = 0
        self._period = {}
        self._period_missing = {}
        self.slice_stamp_ns = None

    def next_episode(self) -> typing.Optional[int]:
        """Return the index after the current episode, None when uint32 is exhausted."""
        return self.episode + 1 if self.episode < MAX_EPISODE else None

    def next_stamp(self, step: int, final: bool) -> int:
        """Return the stamp (ns) of the state of ``step`` about to be published; arm the wait."""
        self.sim_time_ns = 0 if self.sim_time_ns is None else self.sim_time_ns + self.period_ns
        self.step = int(step)
        self._answers = {}
        self.stale_while_waiting = Counter()
        self._start_period()
        if self._episode_first_stamp is None:
            self._episode_first_stamp = self.sim_time_ns
        self.awaited = None if final else self.sim_time_ns
        if final:
            self.active = False
            self.finished_episodes += 1
        return self.sim_time_ns

    @property
    def sliced(self) -> bool:
        """Return True when the running period is applied slice by slice (human's rate).

        Lockstep: only while the human is involved and expected (a human who sits out, or a
        graph that does not wait for the human, steps whole periods, as before human slices);
        realtime: whenever the period has several slices (the wall timer ticks per slice).
        """
        if self.slices == 1:
            return False
        if self.mode == REALTIME:
            return True
        return self.human_involved and HUMAN in self.expected

    @property
    def slice_index(self) -> int:
        """Return the index of the slice the running period is at (0: its start)."""
        return self._slice

    def next_slice_stamp(self) -> int:
        """Return the stamp (ns) of the slice state about to be published; arm its wait.

        Lockstep: the human's command answering it is awaited next (the robot's answer to the
        period's state holds for the whole period). Realtime: the human's commands may answer
        it from now on.
        """
        if not self.active or not 0 < self._slice < self.slices:
            raise ProtocolError(f'no slice state is due (slice {self._slice} of '
                                f'{self.slices}, episode running: {self.active})')
        stamp = self.sim_time_ns + self._slice * self.slice_ns
        self.slice_stamp_ns = stamp
        self.awaited = stamp
        self._answers = {}
        self.stale_while_waiting = Counter()
        return stamp

    def hold(self) -> None:
        """Stop the running episode at once (operator abort): nothing more is applied."""
        self.active = False
        self.awaited = None
        self._answers = {}
        self._kept = {}

    @property
    def waiting(self) -> bool:
        """Return True while a state awaits its commands."""
        return self.active and self.awaited is not None

    # -- commands ----------------------------------------------------------------------------
    def _count(self, name: str) -> None:
        self.counters[name] += 1
        self.totals[name] += 1

    def is_answer(self, stamp: int) -> bool:
        """Return True when a command stamped ``stamp`` (ns) would be read, not stale.

        Lockstep: the stamp of the awaited state; realtime: of any state of the episode.
        (The node checks this before it decodes a command: a flood of stale ones costs little.)
        """
        if not self.active:
            return False
        if self.mode == LOCKSTEP:
            return stamp == self.awaited
        newest = self.sim_time_ns if self.slice_stamp_ns is None else self.slice_stamp_ns
        return (self._episode_first_stamp is not None
                and self._episode_first_stamp <= stamp <= newest
                and (stamp - self._episode_first_stamp) % self.slice_ns == 0)

    def on_command(self, actor: str, stamp: int, wrench, now: float) -> CommandResult:
        """Read one command of ``actor`` (a Wrench-like object) stamped ``stamp`` (ns).

        ``now`` is a monotonic wall time (s), used in realtime for the command's age. The
        wrench is not read when the command is stale (it may be None then).
        """
        if not self.active:
            self._count(actor + '_between_episodes')
            return CommandResult(actor, 'between_episodes', stamp)
        awaited = self.awaited if self.mode == LOCKSTEP else (
            self.sim_time_ns if self.slice_stamp_ns is None else self.slice_stamp_ns)
        if not self.is_answer(stamp):
            self._count(actor + '_stale')
            self.stale_while_waiting[actor] += 1
            return CommandResult(actor, 'stale', stamp, awaited)
        dof = self.dof_of[actor]
        limit = self.limits.full_scale(dof)
        command = read_command(wrench, dof, limit)
        result = CommandResult(actor, 'accepted', stamp, awaited, command, dof, limit)
        if not command.accepted:
            result.kind = 'refused'
            self._count(actor + '_refused')
        else:
            if command.clamped:
                self._count(actor + '_clamped')
            if command.off_axis:
                self._count(actor + '_off_axis')
        if self.mode == REALTIME:
            kept = self._kept.get(actor)
            if kept is None or stamp >= kept[2]:
                self._kept[actor] = (command, now, stamp)
            else:
                self._count(actor + '_superseded')
            return result
        if actor in self._answers:
            self._count(actor + '_duplicate')   # the first answer to a state stands
            return result
        self._answers[actor] = command
        result.order = self._order_if_answered()
        return result

    def _order_if_answered(self) -> typing.Optional[StepOrder]:
        """Return the step when every actor awaited now has answered the awaited state."""
        awaited_actors = self.awaited_actors()
        if not all(actor in self._answers for actor in awaited_actors):
            return None
        missing = {actor: not self._answers[actor].accepted for actor in awaited_actors}
        return self._order(self._answers, missing, 'answered')

    @property
    def awaits_human(self) -> bool:
        """Return True when the human's commands are awaited (lockstep) or expected (realtime).

        Only while the human is involved: a human who sits out a training step has nothing
        applied, so their answers would carry nothing; the human node does not send them then
        (they were two of a lockstep step's five messages in the robot-alone episodes).
        """
        return self.human_involved and HUMAN in self.expected

    def expected_now(self) -> tuple:
        """Return the expected actors whose commands count now (the human: awaits_human)."""
        if self.awaits_human:
            return self.expected
        return tuple(actor for actor in self.expected if actor != HUMAN)

    def awaited_actors(self) -> tuple:
        """Return the actors whose answer the awaited (slice) state needs (lockstep).

        Empty: nothing is awaited (no expected actor, or only a human who sits out): the sim
        runs free (:meth:`free_run`).
        """
        if self._slice == 0:
            return self.expected_now()
        return (HUMAN,)    # a slice state: the robot's answer holds for the whole period

    def on_timeout(self) -> typing.Optional[StepOrder]:
        """Lockstep: the wait for the awaited state's commands timed out; step without them."""
        if self.mode != LOCKSTEP or not self.waiting:
            return None
        missing = {actor: actor not in self._answers or not self._answers[actor].accepted
                   for actor in self.awaited_actors()}
        return self._order(self._answers, missing, 'timeout')

    def on_roles_changed(self) -> typing.Optional[StepOrder]:
        """Lockstep, a role change during a wait: the step if the awaited actors have answered.

        A late announcement (its acknowledgement wait timed out) can change who is awaited
        after the state went out: when every actor awaited now has answered, the step is due.
        """
        if self.mode != LOCKSTEP or not self.waiting or not self.awaited_actors():
            return None     # awaiting nobody: the free-run timer steps
        return self._order_if_answered()

    def free_run(self) -> typing.Optional[StepOrder]:
        """Lockstep awaiting no actor: step with what arrived (nothing is missing)."""
        if self.mode != LOCKSTEP or self.awaited_actors() or not self.waiting:
            return None
        return self._order(self._answers, {}, 'free_run')

    def on_tick(self, now: float) -> typing.Optional[StepOrder]:
        """Realtime: one control period of wall time passed; step with the fresh commands."""
        if self.mode != REALTIME or not self.waiting:
            return None
        commands, missing = {}, {}
        expected = self.expected_now()
        for actor in ACTORS:
            command, received, _ = self._kept.get(actor, (None, None, None))
            fresh = (command is not None and command.accepted
                     and now - received <= self.settings.command_timeout)
            if fresh:
                commands[actor] = command
            if actor in expected:
                missing[actor] = not fresh
        return self._order(commands, missing, 'tick')

    def _order(self, commands: dict, missing: dict, reason: str) -> StepOrder:
        """Count the missing commands and sum the applied ones per degree of freedom.

        Whole period (one slice, or not :attr:`sliced`): as before human slices. Sliced:
        lockstep takes the robot's answer to the period's state for every slice and the
        human's answer to each slice state; realtime takes the kept commands at each tick.
        A period's ``*_missing`` counter counts once however many of its slices missed.
        """
        sliced = self.sliced
        if sliced and self.mode == LOCKSTEP and self._slice > 0:
            commands = dict(self._period, **{HUMAN: commands.get(HUMAN)})
            missing = dict(self._period_missing, **{
                HUMAN: self._period_missing.get(HUMAN, False) or missing.get(HUMAN, False)})
        elif sliced and self.mode == LOCKSTEP:
            self._period = {actor: command for actor, command in commands.items()
                            if actor != HUMAN}
        applied, ignored = {}, []
        for actor, command in commands.items():
            if command is None or not command.accepted:
                continue
            if actor == HUMAN and not self.human_involved:
                if command.value != 0.0:
                    self._count('human_not_involved')
                    ignored.append((actor, command.value))
                continue
            applied[actor] = command.value
        if sliced:
            if self.mode == REALTIME:
                missing = {actor: self._period_missing.get(actor, False) or is_missing
                           for actor, is_missing in missing.items()}
            self._period_missing = dict(missing)
            self._slice += 1
            final = self._slice >= self.slices
        else:
            final = True
        if final:
            for actor, is_missing in missing.items():
                if is_missing:
                    self._count(actor + '_missing')
        wrench = per_dof(applied, self.dof_of)
        self.awaited = None                  # the next (slice) state arms the next wait
        return StepOrder(wrench[TRANSLATION], wrench[ROTATION], missing, reason, ignored,
                         slices=1 if sliced else self.slices, final=final,
                         human_value=applied.get(HUMAN, 0.0))
