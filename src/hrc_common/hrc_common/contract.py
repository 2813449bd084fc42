"""The contract between the hrc nodes, in one place. Pure: no rclpy, no message import.

Every definition two packages must agree on lives here once; everything else imports it.
The API below is stable (other packages import it by name):

Phases (``SessionStatus.phase``)
    ``Phase`` -- IntEnum whose values equal ``hrc_msgs/msg/SessionStatus`` ``PHASE_*``
    (checked by a test); ``Phase.X.label`` is the lower-case name the CLI and the display show
    ('training', ...) and also ``str(Phase.X)``; a phase compares equal to its label and to its
    code (``AgentCore.phase`` is a Phase); ``Phase.from_label(text)``;
    ``phase_label(code, default=None)`` for a raw code (an unknown code gives ``default``, or
    'phase N'); ``FINISHED_PHASES`` (done, aborted); ``ACTIVE_PHASES`` (training, updating,
    evaluation).
Human input sources (``HumanAction.source``)
    ``InputSource`` -- IntEnum whose values equal ``hrc_msgs/msg/HumanAction`` ``SOURCE_*``;
    ``InputSource.X.label`` ('device', 'joy', 'simulated', 'replay', 'none');
    ``source_label(code, default=None)``.
Episode kinds (``EpisodeSummary.kind``)
    ``EpisodeKind`` -- IntEnum whose values equal ``hrc_msgs/msg/EpisodeSummary`` ``KIND_*``
    (UNKNOWN, TRAINING, JUDGING, EVALUATION, PRACTICE); ``.label``;
    ``episode_kind(kind, evaluation, judging, practice)``: the kind, inferred from the flags
    when the code is unknown (old bags: evaluation, else training).
Degrees of freedom and the wrench axis convention
    ``TRANSLATION``, ``ROTATION``, ``DOFS`` (in ``SessionStatus.DOF_*`` order), ``DOF_INDEX``,
    ``DOF_NAME``, ``check_dof``, ``other_dof``, ``dof_name(code, default=None)``,
    ``wrench_axis``, ``wrench_value``, ``set_wrench_value``, ``off_axis_components``.
What the sim owns and the actors learn from it at run time
    ``SimLimits(control_period, max_force, max_torque)`` -- the sim's control period (s) and
    the force (N) / torque (N*m) of a full normalized command; ``full_scale(dof)``,
    ``problems()``. The sim declares them (``PhysicsParams``); the agent reads them from the
    ``/hrc/sim/reset`` response, the human node from the sim's parameter service; no other
    file repeats them.
Message types (as in bags and ``ros2 topic type``)
    ``TASK_STATE_TYPE``, ``HUMAN_ACTION_TYPE``, ``SESSION_STATUS_TYPE``,
    ``EPISODE_SUMMARY_TYPE``, ``AGENT_STEP_TYPE``, ``WRENCH_STAMPED_TYPE``.
Time
    ``NS_PER_S``, ``NS_PER_MS``, ``seconds_to_ns``, ``ns_to_seconds``.
Body colours (the paper's figure; sim URDF, markers and display)
    ``BODY_COLOURS`` {body: (r, g, b) in 0..1}, ``rgb8(colour)``.
Ids
    ``ID_PATTERN``, ``id_problem(text, what)`` -> reason or None (session ids, subject ids:
    one rule everywhere they enter), ``check_id``,
    ``make_session_id(case, seed, now, timestamped=True)`` ('case{N}-seed{S}-{YYYYmmdd-HHMMSS}',
    or 'case{N}-seed{S}' inside an experiment).
Cases
    :mod:`hrc_common.cases` (``params/cases.yaml``, the only place they are defined).
Files
    ``atomic_write(path, data, mode=0o644)``; ``PERSONAL_FILE_MODE`` (0o600) for files that
    hold a subject id or notes.
"""

from dataclasses import dataclass
import datetime
import enum
import errno
import math
import os
import re
import tempfile

# --------------------------------------------------------------------------- phases


class Phase(enum.IntEnum):
    """Session phase; values equal hrc_msgs/msg/SessionStatus PHASE_*."""

    TRAINING = 0     # episodes run, the robot explores and collects experience
    UPDATING = 1     # between episodes: the policy is being updated, the sim holds
    EVALUATION = 2   # the frozen deterministic policy is evaluated
    PAUSED = 3       # the operator paused the session at an episode boundary
    DONE = 4         # the session finished
    ABORTED = 5      # the operator or a failure aborted the session

    @property
    def label(self) -> str:
        """Return the lower-case name shown to users ('training', ...)."""
        return self.name.lower()

    # A phase equals its label ('done' == Phase.DONE), so code that still names phases by label
    # (a node, a test) keeps working against AgentCore.phase, which is a Phase. It still equals
    # its code (Phase.DONE == 4) and hashes as the code: sets and dicts of phases (and of raw
    # codes from messages) work as before; a label is not found in a set of phases.
    def __eq__(self, other):
        if isinstance(other, str):
            return other == self.label
        return int(self) == other

    def __ne__(self, other):
        return not self == other

    __hash__ = int.__hash__

    def __str__(self) -> str:
        """Return the label: logs and status lines say 'phase done', as when it was a string."""
        return self.label

    def __format__(self, spec: str) -> str:
        return format(self.label, spec)

    @classmethod
    def from_label(cls, label) -> 'Phase':
        """Return the phase named ``label`` (as ``Phase.X.label``); ValueError if unknown.

        A Phase is returned as it is (``Phase.from_label(core.phase)`` works).
        """
        if isinstance(label, cls):
            return label
        try:
            return cls[label.upper()]
        except KeyError:
            raise ValueError(f'unknown phase {label!r}: expected one of '
                             f'{[phase.label for phase in cls]}') from None


FINISHED_PHASES = frozenset({Phase.DONE, Phase.ABORTED})
ACTIVE_PHASES = frozenset({Phase.TRAINING, Phase.UPDATING, Phase.EVALUATION})


def phase_label(code: int, default: str = None) -> str:
    """Return the label of a raw phase code; ``default`` (or 'phase N') if the code is unknown."""
    try:
        return Phase(code).label
    except ValueError:
        return default if default is not None else f'phase {code}'


# --------------------------------------------------------------------------- input sources


class InputSource(enum.IntEnum):
    """Where the human's command came from; values equal hrc_msgs/msg/HumanAction SOURCE_*."""

    DEVICE = 0      # a Linux joystick device (/dev/input/jsN)
    JOY = 1         # sensor_msgs/Joy on /joy
    SIMULATED = 2   # the simulated human model
    REPLAY = 3      # republished from a recording
    NONE = 4        # no input: zero command held

    @property
    def label(self) -> str:
        """Return the lower-case name shown to users ('device', ...)."""
        return self.name.lower()


# Why the human node holds zero with source NONE on purpose, not for a lost input: the first
# words of HumanAction.source_detail (the human node writes them, the session runner's input
# guard and progress lines read them; every other NONE detail is the reason an input is lost).
HOLD_NOT_INVOLVED = 'not involved in this training step'
HOLD_ABORTED = 'session aborted by the operator'


def holds_on_purpose(detail: str) -> bool:
    """Return whether a zero answer's ``detail`` is a deliberate hold (no lost input)."""
    return detail.startswith(HOLD_NOT_INVOLVED) or detail.startswith(HOLD_ABORTED)


def source_label(code: int, default: str = None) -> str:
    """Return the label of a raw SOURCE_* code; ``default`` (or 'source N') if unknown."""
    try:
        return InputSource(code).label
    except ValueError:
        return default if default is not None else f'source {code}'


# --------------------------------------------------------------------------- episode kinds


class EpisodeKind(enum.IntEnum):
    """What an episode was for; values equal hrc_msgs/msg/EpisodeSummary KIND_*."""

    UNKNOWN = 0      # not said (bags recorded before EpisodeSummary.kind): see episode_kind
    TRAINING = 1     # the policy explores; its experience trains it
    JUDGING = 2      # deterministic episode during training that judges convergence
    EVALUATION = 3   # the frozen deterministic policy after training (Table II)
    PRACTICE = 4     # the person practises before training (not a training episode)

    @property
    def label(self) -> str:
        """Return the lower-case name shown to users ('training', ...)."""
        return self.name.lower()


def episode_kind(kind: int = EpisodeKind.UNKNOWN, evaluation: bool = False,
                 judging: bool = False, practice: bool = False) -> EpisodeKind:
    """Return the kind of an episode: ``kind`` when known, else inferred from the flags.

    Inference (an unknown code, or a summary without the field): practice, then judging, then
    evaluation when their flag is set, else training. Bags recorded before the field existed
    only have ``evaluation``; there, a judging episode recorded as evaluation reads as
    evaluation (hrc_study's final-block rule separates those).
    """
    try:
        known = EpisodeKind(int(kind))
    except (TypeError, ValueError):
        known = EpisodeKind.UNKNOWN
    if known is not EpisodeKind.UNKNOWN:
        return known
    if practice:
        return EpisodeKind.PRACTICE
    if judging:
        return EpisodeKind.JUDGING
    return EpisodeKind.EVALUATION if evaluation else EpisodeKind.TRAINING


# --------------------------------------------------------------------------- degrees of freedom
# World frame ("world"): x points toward the viewer (the pendulum's joint axis), y points east
# along the horizontal pendulum, z points up along the rod. Hence:
# * translation: force.z (N) pushes the slider up the rod (+ = up);
# * rotation: torque.x (N*m) turns the pendulum about its joint axis; + raises the east end
#   (counter-clockwise as the viewer sees it) and increases P_z.
# Every other wrench component is off-axis: the sim ignores it and reports it.

TRANSLATION = 'translation'
ROTATION = 'rotation'
DOFS = (TRANSLATION, ROTATION)   # in HumanAction/SessionStatus DOF_* order
DOF_INDEX = {name: index for index, name in enumerate(DOFS)}
DOF_NAME = dict(enumerate(DOFS))
_WRENCH_AXES = {TRANSLATION: ('force', 'z'), ROTATION: ('torque', 'x')}


def check_dof(dof: str) -> str:
    """Return ``dof`` or raise ValueError naming the allowed values."""
    if dof not in DOFS:
        raise ValueError(f'unknown degree of freedom {dof!r}: expected one of {DOFS}')
    return dof


def other_dof(dof: str) -> str:
    """Return the degree of freedom that is not ``dof``."""
    check_dof(dof)
    return ROTATION if dof == TRANSLATION else TRANSLATION


def dof_name(code: int, default: str = None) -> str:
    """Return the name of a DOF_* code; ``default`` (or 'dof N') if the code is unknown."""
    return DOF_NAME.get(code, default if default is not None else f'dof {code}')


def wrench_axis(dof: str) -> tuple:
    """Return (part, axis) of the WrenchStamped component that drives ``dof``."""
    return _WRENCH_AXES[check_dof(dof)]


def wrench_value(wrench, dof: str) -> float:
    """Return the component of a geometry_msgs/Wrench that drives ``dof``."""
    part, axis = wrench_axis(dof)
    return float(getattr(getattr(wrench, part), axis))


def set_wrench_value(wrench, dof: str, value: float) -> None:
    """Set the component of ``wrench`` that drives ``dof`` to ``value``."""
    part, axis = wrench_axis(dof)
    setattr(getattr(wrench, part), axis, float(value))


def off_axis_components(wrench, dof: str) -> dict:
    """Return {'force.x': value, ...} of the non-zero components that do not drive ``dof``."""
    driving = '.'.join(wrench_axis(dof))
    found = {}
    for part in ('force', 'torque'):
        vector = getattr(wrench, part)
        for axis in 'xyz':
            name = f'{part}.{axis}'
            value = float(getattr(vector, axis))
            if name != driving and value != 0.0:
                found[name] = value
    return found


# --------------------------------------------------------------------------- realtime timing
# The interpreter's thread switch interval (s) for realtime control: a thread that holds the GIL
# (the agent's learner thread in a PPO update) is asked to hand it over after this long instead
# of Python's default 5 ms, which the control thread would otherwise wait for. Used by the
# realtime-priority option of every node (hrc_common.realtime) and as the default of the agent's
# learner_switch_interval (hrc_agent_node.config).
REALTIME_SWITCH_INTERVAL_S = 0.0005


# --------------------------------------------------------------------------- sim limits

@dataclass(frozen=True)
class SimLimits:
    """The sim's timing and actuator limits, which every actor must use as the sim does.

    A normalized command of 1 on translation is ``max_force`` N on the slider, on rotation
    ``max_torque`` N*m on the hinge; the sim clamps to these, once (``hrc_sim_node.commands``).
    """

    control_period: float   # s of simulation time per control step
    max_force: float        # N, full-scale force on the slider
    max_torque: float       # N*m, full-scale torque on the pendulum's hinge
    human_period: float = 0.0   # s: the human's command is applied this often; 0 = unknown
    #                             (the reset response does not carry it: the robot needs none)

    NAMES = ('control_period', 'max_force', 'max_torque')   # as the sim's parameters
    OPTIONAL_NAMES = ('human_period',)   # the sim's, not in every source

    @classmethod
    def of(cls, source) -> 'SimLimits':
        """Return the limits of an object with these fields (SimParams, a reset response)."""
        optional = {}
        for name in cls.OPTIONAL_NAMES:   # a source without one: the field's default
            default = cls.__dataclass_fields__[name].default
            optional[name] = type(default)(getattr(source, name, None) or default)
        return cls(*(float(getattr(source, name)) for name in cls.NAMES), **optional)

    @property
    def human_step(self) -> float:
        """Return the period (s) at which the human acts.

        ``human_period``, else the control period (a source without it: once a period).
        """
        return self.human_period if self.human_period > 0 else self.control_period

    @property
    def human_slices(self) -> int:
        """Return the human's steps per control period (>= 1; the protocol's slices).

        The period's state and its slice states: the calls a partner of the offline loop
        (``SimStepper.run_period``) gets per control period while the human is involved.
        """
        return max(1, int(round(self.control_period / self.human_step)))

    def full_scale(self, dof: str) -> float:
        """Return the force (N) or torque (N*m) of a normalized command of 1 on ``dof``."""
        return self.max_force if check_dof(dof) == TRANSLATION else self.max_torque

    def problems(self) -> list:
        """Return why these values cannot be used (each must be finite and > 0)."""
        return [f'{name} must be a finite number > 0, got {getattr(self, name)!r}'
                for name in self.NAMES
                if not (isinstance(getattr(self, name), (int, float))
                        and math.isfinite(getattr(self, name)) and getattr(self, name) > 0)]

    def describe(self) -> str:
        """Return one line for logs."""
        return (f'control period {self.control_period:g} s, max_force {self.max_force:g} N, '
                f'max_torque {self.max_torque:g} N*m')


# --------------------------------------------------------------------------- message types

TASK_STATE_TYPE = 'hrc_msgs/msg/TaskState'
HUMAN_ACTION_TYPE = 'hrc_msgs/msg/HumanAction'
SESSION_STATUS_TYPE = 'hrc_msgs/msg/SessionStatus'
EPISODE_SUMMARY_TYPE = 'hrc_msgs/msg/EpisodeSummary'
AGENT_STEP_TYPE = 'hrc_msgs/msg/AgentStep'
WRENCH_STAMPED_TYPE = 'geometry_msgs/msg/WrenchStamped'
JOINT_STATE_TYPE = 'sensor_msgs/msg/JointState'
STRING_TYPE = 'std_msgs/msg/String'

# --------------------------------------------------------------------------- time

NS_PER_S = 1_000_000_000
NS_PER_MS = 1_000_000


def seconds_to_ns(seconds: float) -> int:
    """Return ``seconds`` as integer nanoseconds (rounded)."""
    return int(round(seconds * NS_PER_S))


def ns_to_seconds(nanoseconds: int) -> float:
    """Return ``nanoseconds`` in seconds."""
    return nanoseconds / NS_PER_S


# --------------------------------------------------------------------------- colours
# The bodies' colours (the paper's figure), RGB in 0..1: the sim's URDF, its markers and the
# display all draw with these.
BODY_COLOURS = {
    'rod': (0.6, 0.6, 0.6),
    'slider': (1.0, 0.55, 0.1),
    'pendulum': (0.15, 0.35, 0.85),
    'ball': (0.45, 0.45, 0.45),
}


def rgb8(colour) -> tuple:
    """Return an RGB colour in 0..1 as 8-bit integers (0..255)."""
    return tuple(int(round(channel * 255)) for channel in colour)


# --------------------------------------------------------------------------- ids
# Session ids and subject ids become file and directory names and travel in every bag, so one
# rule holds wherever they enter: 1..64 characters, letters, digits, '_', '.', '-', starting
# with a letter or digit (so no path separator, no '..' component, no hidden file, no option).
ID_PATTERN = re.compile(r'[A-Za-z0-9][A-Za-z0-9_.-]{0,63}')   # the whole id must match
ID_RULE = ("1..64 characters from letters, digits, '_', '.', '-', starting with a letter or "
           "digit, without '..'")


def id_problem(text, what: str = 'id'):
    """Return why ``text`` is not a valid id (naming it ``what``), or None if it is valid."""
    if not isinstance(text, str):
        return f'{what} must be a string, got {type(text).__name__}'
    if not ID_PATTERN.fullmatch(text) or '..' in text:
        return f'{what} {text!r} is not valid: {ID_RULE}'
    return None


def check_id(text, what: str = 'id') -> str:
    """Return ``text`` or raise ValueError with the reason it is not a valid id."""
    problem = id_problem(text, what)
    if problem:
        raise ValueError(problem)
    return text


def make_session_id(case: int, seed: int, now: datetime.datetime = None,
                    timestamped: bool = True) -> str:
    """Return the session id 'case{N}-seed{S}-{YYYYmmdd-HHMMSS}' (local time, no personal data).

    ``timestamped=False`` gives 'case{N}-seed{S}', for sessions grouped under an experiment
    folder that already names the time.
    """
    if not timestamped:
        return f'case{case}-seed{seed}'
    now = now or datetime.datetime.now()
    return f'case{case}-seed{seed}-{now:%Y%m%d-%H%M%S}'


# --------------------------------------------------------------------------- files

PUBLIC_FILE_MODE = 0o644
PERSONAL_FILE_MODE = 0o600   # files holding a subject id or notes: owner only


def os_error_text(error: OSError) -> str:
    """Return "<file>: <reason> (<ENAME>)" of an OSError: what a person can act on, one line."""
    name = errno.errorcode.get(error.errno or 0, '')
    target = error.filename2 or error.filename     # a rename's target, else the file
    where = f'{target}: ' if target else ''
    reason = error.strerror or str(error)
    return f'{where}{reason}' + (f' ({name})' if name else '')


def atomic_write(path, data, mode: int = PUBLIC_FILE_MODE) -> None:
    """Write ``data`` (str as UTF-8, or bytes) to ``path`` atomically and durably.

    A temporary file in the same directory is created with ``mode`` (whatever the umask),
    written, fsynced and renamed over ``path``; then the directory is fsynced so the rename
    survives a crash. Readers see the old file or the new one, never a part.
    """
    path = os.fspath(path)
    directory = os.path.dirname(os.path.abspath(path))
    payload = data.encode('utf-8') if isinstance(data, str) else bytes(data)
    descriptor, temporary = tempfile.mkstemp(prefix='.' + os.path.basename(path) + '.',
                                             suffix='.tmp', dir=directory)
    try:
        os.fchmod(descriptor, mode)
        with os.fdopen(descriptor, 'wb') as stream:
            stream.write(payload)
            stream.flush()
            os.fsync(stream.fileno())
        os.replace(temporary, path)
    except BaseException:
        try:
            os.unlink(temporary)
        except FileNotFoundError:
            pass
        raise
    directory_descriptor = os.open(directory, os.O_RDONLY)
    try:
        os.fsync(directory_descriptor)
    finally:
        os.close(directory_descriptor)
