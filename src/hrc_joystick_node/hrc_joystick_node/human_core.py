"""The human's per-step logic as a pure core: plain values and a clock in, decisions out.

No rclpy: the human node (:mod:`hrc_joystick_node.human_node`) converts messages to the calls
below and the answers back to messages; the in-process engine (``hrc_engine``) calls the same
core directly, so both answer every state the same way::

    core = HumanCore(HumanParams(input='sim', profile='paper', seed=3), profiles)
    core.set_limits(SimLimits(control_period, max_force, max_torque))   # the sim's, at run time
    core.on_session('rotation', involved=True, subtasks=['pendulum'], aborted=False)
    answer = core.answer(episode, step, stamp_ns, state)   # a HumanAnswer

What it decides, per state (not the last of its episode, which needs no answer):

* the session aborted: zero, ``engaged`` false, source ``none``;
* the same state again (same episode and step): the same answer, ``repeated`` true, and the
  simulated human is not advanced twice;
* the human not involved in this training step: no answer is sent at all
  (:attr:`HumanCore.answers_states` false: the sim neither awaits nor applies one); asked,
  zero, ``engaged`` false, source ``none``;
* otherwise the active input (:class:`~hrc_joystick_node.inputs.InputSelector`): the stick of
  the device or ``/joy`` (deadzone, inversion, deadman), the simulated human (reset at each new
  episode or when a step does not follow the last one; its clock is the state's stamp, so
  fatigue and rest run on simulation time), or a held zero when the input is missing or lost
  and the policy ``on_input_lost`` is ``pause`` (the default: the input status asks the session
  to pause) or ``zero``. The simulated human stands in for a missing or lost joystick only
  with ``on_input_lost: sim``; every answer says which input drove it (``source``) and why.

The sim owns the control period (the simulated human's delay and fatigue run in its steps) and
the force/torque of a full command (``hrc_common.contract.SimLimits``): the core has no
parameters for them and answers no state until :meth:`HumanCore.set_limits` gave them (the
node reads them from the sim's parameter service, the in-process engine from its physics).

The input status (:class:`InputStatus`) is what the node publishes on ``/hrc/human/input``.
"""

from dataclasses import dataclass
import typing

from hrc_common.contract import HOLD_ABORTED, HOLD_NOT_INVOLVED, InputSource, SimLimits
from hrc_common.dof import check_dof, DOFS
from hrc_common.params import from_dict, param, ParameterError
from hrc_joystick_node.human_model import ClonedHuman, load_human_model
from hrc_joystick_node.human_profile import (default_profiles_path, HumanProfile, load_profiles,
                                             RETIRED_PROFILES, unknown_profile_reason)
from hrc_joystick_node.inputs import (AUTO, DEVICE, FALLBACKS, INPUT_MODES, InputSelector, JOY,
                                      MODEL, PAUSE, SCRIPT, SIM, stick_command, StickReading,
                                      ZERO)
from hrc_joystick_node.population import person_or_profile
from hrc_joystick_node.sim_human import BALL, normalize_subtasks, OWN_SUBTASK, SimulatedHuman
from hrc_joystick_node.stick_script import StickScript, StickScriptError

# HumanAction.SOURCE_* by input name; a cloned model is a simulated human (its detail names
# the file); a scripted stick is a stick trace replayed (its detail names the script).
SOURCE_CODE = {name: int(source) for name, source in (
    (DEVICE, InputSource.DEVICE), (JOY, InputSource.JOY), (SIM, InputSource.SIMULATED),
    (MODEL, InputSource.SIMULATED), (SCRIPT, InputSource.REPLAY), (ZERO, InputSource.NONE))}


@dataclass
class HumanParams:
    """Parameters of the human node (node ``human``, params/human.yaml)."""

    input: str = param('auto', 'where the command comes from: auto = the device if it opens, '
                       'else /joy if a publisher is seen; sim = the simulated human; model = '
                       'a cloned human model (model_file); script = a scripted stick '
                       '(script_file: the joystick path in simulation time, deterministic)',
                       choices=INPUT_MODES)
    device: str = param('/dev/input/js0', 'Linux joystick device (or a FIFO/file carrying its '
                        'js_event stream)')
    axis: int = param(1, 'joystick axis that drives the command, same index on the device and '
                      'on /joy (1 = left stick vertical on most gamepads)', low=0, high=63)
    invert: bool = param(False, 'flip the axis: by default stick up/left (the Joy convention, '
                         '+1) commands + (slider up, east end of the beam up)')
    deadzone: float = param(0.05, 'axis magnitudes below this read as 0; the rest is rescaled '
                            'to [0, 1] (normalized units)', low=0.0, high=0.9)
    enable_button: int = param(-1, 'deadman button that must be held for a non-zero command '
                               '(-1 = none)', low=-1, high=255)
    joy_timeout: float = param(1.0, '/joy counts as silent after this long without a message '
                               '(s, wall time); the joy node must publish faster '
                               '(autorepeat_rate)', low=0.05, high=60.0)
    on_input_lost: str = param(PAUSE, 'when the joystick (device or /joy) is missing or lost: '
                               'pause = hold zero and ask the session to pause (reported on '
                               '/hrc/human/input), zero = hold zero, sim = the simulated human '
                               'stands in (only when asked for)', choices=FALLBACKS)
    reopen_period: float = param(1.0, 'interval between attempts to (re)open an absent device '
                                 '(s)', low=0.05, high=60.0)
    input_check_period: float = param(0.1, 'interval of the input check: drain the device, '
                                      'watch the /joy deadline, publish the input status (s)',
                                      low=0.01, high=5.0)
    dof: str = param('rotation', 'degree of freedom of the human until /hrc/session says',
                     choices=DOFS)
    involved: bool = param(True, 'whether the human acts, until /hrc/session says')
    hold_ball: bool = param(False, 'whether the human is also asked to hold the ball, until '
                            "/hrc/session lists the human's subtasks")
    sim_node: str = param('sim', "node whose parameters give the sim's control period (s), "
                          'max_force (N) and max_torque (N*m), read at start through its '
                          'get_parameters service; states are answered once they are known')
    profile: str = param('paper', 'simulated-human profile (a name in profiles_file)')
    profiles_file: str = param('', 'simulated-human profiles YAML (empty = the installed '
                               'share/hrc_joystick_node/params/sim_human.yaml)')
    person: int = param(-1, 'simulated human: draw person number N of the population around '
                        'the profile (hrc_joystick_node.population); -1 = the profile itself',
                        low=-1, high=2 ** 31 - 1)
    seed: int = param(0, 'seed of the simulated human (with the episode index)', low=0,
                      high=2 ** 31 - 1)
    practiced_episodes: int = param(
        0, 'simulated human: episodes the person has practised before this session (a '
        'returning person: their learning curve starts there; sim_human.SimulatedHuman)',
        low=0, high=100000)
    model_file: str = param('', 'cloned human-model checkpoint (.pt, hrc_joystick_node.'
                            'human_model) used with input model')
    script_file: str = param('', 'stick script (CSV "time,axis[,enable]", time in s from each '
                             "episode's start; hrc_joystick_node.stick_script) used with input "
                             'script')
    exit_after_session: bool = param(
        True, 'exit once the agent says the session is done (phase done on /hrc/session), as a '
        'node started by hand should; hrc session turns it off for the nodes it stops itself')

    def check(self):
        """Return the reasons the parameters do not fit together."""
        reasons = []
        if self.input == MODEL and not self.model_file:
            reasons.append('model_file: input model needs a checkpoint path')
        if self.input == SCRIPT and not self.script_file:
            reasons.append('script_file: input script needs a stick script (CSV) path')
        return reasons


class HumanAnswer(typing.NamedTuple):
    """The human's answer to one state."""

    episode: int
    step: int
    stamp_ns: int           # the answered state's stamp (simulation time, ns)
    command: float          # normalized, [-1, 1]
    wrench: float           # N (translation) or N*m (rotation) on ``dof``
    dof: str
    source: str             # the input that drove it: device, joy, sim or zero
    detail: str             # e.g. device path, profile name, why zero
    engaged: bool
    repeated: bool = False  # the same state again: the earlier answer, model not advanced
    slice: int = 0          # > 0: the answer to a slice state (the human's rate) of ``step``

    @property
    def source_code(self) -> int:
        """HumanAction.SOURCE_* of :attr:`source`."""
        return SOURCE_CODE[self.source]


class InputStatus(typing.NamedTuple):
    """Which input drives the human now and whether it is healthy (``/hrc/human/input``)."""

    mode: str               # the parameter input: auto, device, joy, sim
    active: str             # device, joy, sim or zero
    state: str              # ok | missing (never seen) | lost (seen, then gone)
    fallback: str           # on_input_lost: pause, zero or sim (what holds while not ok)
    pause_requested: bool   # missing or lost with on_input_lost pause: the session should pause
    reason: str             # one line a person can read ("joystick disconnected: ...")

    @property
    def level(self) -> int:
        """0 OK, 1 WARN (zero held or the simulated human standing in), 2 ERROR (pause)."""
        if self.state == 'ok':
            return 0
        return 2 if self.pause_requested else 1


def resolve_profile(params: HumanParams, profiles: typing.Dict[str, HumanProfile],
                    where='profiles_file') -> HumanProfile:
    """Return the person the parameters name (profile, then the population draw)."""
    if params.profile not in profiles:
        if params.profile in RETIRED_PROFILES:
            raise ParameterError(f'profile: {unknown_profile_reason(params.profile, profiles)}')
        raise ParameterError(f'profile: {params.profile!r} is not in {where} '
                             f'(known: {sorted(profiles)})')
    return person_or_profile(profiles[params.profile], params.person)


def core_from_parameters(parameters: dict, limits: SimLimits) -> 'HumanCore':
    """Return the core for the human node's parameters given as a plain dict.

    E.g. as ``hrc_common.session_plan.compose`` composes them; checked as the node checks them
    (ParameterError with every reason). No device or /joy in this process: input ``sim``.
    ``limits``: the sim's (as the node reads them from the sim's parameters).
    """
    params = from_dict(HumanParams, dict(parameters))
    path = params.profiles_file or default_profiles_path()
    core = HumanCore(params, load_profiles(path), str(path))
    core.set_limits(limits)
    core.on_inputs(False, 'no device in this process', False, '/joy not used')
    return core


class HumanCore:
    """The human's per-step decisions (see the module docstring)."""

    def __init__(self, params: HumanParams, profiles: typing.Dict[str, HumanProfile],
                 profiles_where: str = 'profiles_file'):
        self.params = params
        self.profile = resolve_profile(params, profiles, profiles_where)
        self.dof = check_dof(params.dof)
        self.involved = bool(params.involved)
        self.subtasks = self.default_subtasks(self.dof)
        self.session_seen = False
        self.aborted = False
        self.selector = InputSelector(params.input, params.on_input_lost)
        if params.input == MODEL:  # a bad model file is refused now, not at the first state
            load_human_model(params.model_file)
        self.script = None
        if params.input == SCRIPT:   # a bad script is refused now, with every reason
            try:
                self.script = StickScript.load(params.script_file)
            except StickScriptError as error:
                raise ParameterError(f'script_file: {error}')
        self.limits: typing.Optional[SimLimits] = None
        self.sim_human = None   # created when the sim's control period is known (set_limits)
        self._sim_episode = None
        self._sim_step = None
        self.last_answer: typing.Optional[HumanAnswer] = None
        self.answered = 0

    # -- roles ---------------------------------------------------------------------------
    def default_subtasks(self, dof: str) -> typing.List[str]:
        """Return the subtasks before a session says: the own level-2 one (and the ball)."""
        return [OWN_SUBTASK[dof]] + ([BALL] if self.params.hold_ball else [])

    def set_limits(self, limits: SimLimits) -> bool:
        """Take the sim's control period and limits; return True if they changed.

        Raises ValueError with every reason when a value is not a finite number > 0.
        """
        problems = limits.problems()
        if problems:
            raise ValueError("the sim's limits are unusable: " + '; '.join(problems))
        changed = limits != self.limits
        if self.limits is None or self._person_period(limits) != self._person_period(
                self.limits):
            self.sim_human = self._new_sim_human(self.dof, self._person_period(limits))
            self._sim_episode = None
        self.limits = limits
        return changed

    def _person_period(self, limits: SimLimits) -> float:
        """Return how often the simulated person acts (s).

        The simulated human acts at the human's rate (the sim's ``human_period``); a cloned
        model at the control period, the rate its recordings were cut at (one HumanAction a
        control step), holding its command over the period's slices.
        """
        return limits.control_period if self.params.input == MODEL else limits.human_step

    def _new_sim_human(self, dof: str, control_period: float):
        if self.params.input == MODEL:
            return ClonedHuman(self.params.model_file, dof, seed=self.params.seed,
                               control_period=control_period)
        return SimulatedHuman(self.profile, dof, seed=self.params.seed,
                              control_period=control_period,
                              practiced_episodes=self.params.practiced_episodes)

    def on_session(self, dof: str, involved: bool, subtasks, aborted: bool = False
                   ) -> typing.Tuple[bool, typing.List[str]]:
        """Take the roles a session announces; return (roles changed, unknown subtask ids)."""
        dof = check_dof(dof)
        known, unknown = normalize_subtasks(subtasks)
        changed = (not self.session_seen or dof != self.dof
                   or bool(involved) != self.involved or known != self.subtasks)
        if dof != self.dof and self.limits is not None:
            self.sim_human = self._new_sim_human(dof, self._person_period(self.limits))
            self._sim_episode = None
        self.dof, self.involved, self.subtasks = dof, bool(involved), known
        self.session_seen = True
        self.aborted = bool(aborted)
        return changed, unknown

    # -- inputs --------------------------------------------------------------------------
    def on_inputs(self, device_present: bool, device_status: str, joy_alive: bool,
                  joy_status: str) -> typing.Optional[str]:
        """Re-evaluate the active input; return a log line when it changed."""
        return self.selector.update(device_present, device_status, joy_alive, joy_status)

    @property
    def input_status(self) -> InputStatus:
        """The input status now (what the node publishes)."""
        selector = self.selector
        return InputStatus(selector.mode, selector.active or ZERO, selector.state,
                           selector.on_input_lost, selector.pause_requested,
                           selector.status_line())

    # -- the step ------------------------------------------------------------------------
    @property
    def answers_states(self) -> bool:
        """Return True when the human answers the sim's states: only while involved.

        A human who sits out a training step has nothing of theirs applied, and the sim does
        not await them then (``hrc_sim_node.protocol.StepProtocol.awaits_human``, from the same
        announcement): answering every state with zero was two of a lockstep step's five
        messages in the robot-alone episodes. The simulated human is not advanced by such
        states either way, so the session's numbers are the same.
        """
        return self.involved

    def answer(self, episode: int, step: int, stamp_ns: int, state,
               sticks: typing.Optional[dict] = None, slice_index: int = 0) -> HumanAnswer:
        """Answer one state (not the last of its episode).

        ``state``: anything with the PhysicsState attributes the simulated human reads;
        ``stamp_ns``: its stamp (simulation time since the session start, ns); ``sticks``:
        ``{input: StickReading}`` for the joystick inputs the caller read just now (device,
        joy); ``slice_index`` > 0: a slice state within the period of ``step`` (the sim's
        human_period), which the simulated person acts on as on any other moment.
        """
        if self.limits is None:
            raise RuntimeError("the sim's limits are not known yet: call set_limits() first")
        last = self.last_answer
        if self.aborted:
            return self._zero(episode, step, stamp_ns, HOLD_ABORTED)
        if last is not None and (last.episode, last.step, last.slice) == (episode, step,
                                                                          slice_index):
            return last._replace(repeated=True)
        command, engaged, source, detail = self._decide(episode, (step, slice_index),
                                                        stamp_ns, state, sticks or {})
        scale = self.limits.full_scale(self.dof)
        answer = HumanAnswer(int(episode), int(step), int(stamp_ns), command, command * scale,
                             self.dof, source, detail, engaged, slice=int(slice_index))
        self.last_answer = answer
        self.answered += 1
        return answer

    def forward(self, sticks: dict) -> typing.Optional[HumanAnswer]:
        """Answer the newest state again with the stick as it is now; None if nothing to send.

        Only for a person at a joystick (the active input device or /joy, involved, the
        session not aborted): between two states the stick moves and the
        realtime sim applies the newest command at its next human slice, so a move reaches
        the physics within one human period instead of waiting for the next state. Nothing
        is sent when the command did not change.
        """
        last = self.last_answer
        if (last is None or self.aborted or not self.involved
                or self.selector.active not in (DEVICE, JOY)):
            return None
        command, engaged, source, detail = self._decide(
            last.episode, (last.step, last.slice), last.stamp_ns, None, sticks)
        if (command, engaged, source) == (last.command, last.engaged, last.source):
            return None
        answer = last._replace(command=command, wrench=command * self.limits.full_scale(self.dof),
                               source=source, detail=detail, engaged=engaged, repeated=False)
        self.last_answer = answer
        return answer

    def abort_answer(self) -> typing.Optional[HumanAnswer]:
        """Return a zero answer to the last answered state (sent at once on an abort).

        None when nothing was answered, or when the human sits out the aborted step and sends
        nothing (:attr:`answers_states`): the last answer belongs to an earlier episode then.
        """
        last = self.last_answer
        if last is None or not self.answers_states:
            return None
        return self._zero(last.episode, last.step, last.stamp_ns,
                          HOLD_ABORTED)

    def _zero(self, episode, step, stamp_ns, why) -> HumanAnswer:
        answer = HumanAnswer(int(episode), int(step), int(stamp_ns), 0.0, 0.0, self.dof, ZERO,
                             why, False)
        self.last_answer = answer
        return answer

    def _decide(self, episode, moment, stamp_ns, state, sticks) -> tuple:
        """Return (command, engaged, input, detail) for one new state.

        ``moment``: (step, slice) of the state, ordered in time within the episode.
        """
        active = self.selector.active
        if not self.involved:
            return 0.0, False, ZERO, f'{HOLD_NOT_INVOLVED} (input: {active})'
        params = self.params
        if active in (DEVICE, JOY):
            reading = sticks.get(active) or StickReading(None, None, active)
            command, engaged, why = stick_command(reading.axis, reading.enable,
                                                  params.enable_button >= 0, params.deadzone,
                                                  params.invert)
            return command, engaged, active, reading.name + (f' ({why})' if why else '')
        if active == SCRIPT:
            step, slice_index = moment   # the stick where the script has it at this moment
            sample = self.script.at(step * self.limits.control_period
                                    + slice_index * self.limits.human_step)
            command, engaged, why = stick_command(sample.axis, sample.enable,
                                                  params.enable_button >= 0, params.deadzone,
                                                  params.invert)
            return command, engaged, SCRIPT, f'script {self.script.name}' + (
                f' ({why})' if why else '')
        last = self.last_answer
        if (active == MODEL and moment[1] > 0 and last is not None and last.source == MODEL
                and (last.episode, last.step) == (episode, moment[0])):
            return last.command, True, MODEL, last.detail   # held within the period
        if active in (SIM, MODEL):
            if (episode != self._sim_episode or self._sim_step is None
                    or moment <= self._sim_step):
                self.sim_human.reset(episode)
                self._sim_episode = episode
            self._sim_step = moment
            command = self.sim_human.act(state, self.subtasks, now=stamp_ns * 1e-9)
            if active == MODEL:
                note = self.sim_human.note
                return command, True, MODEL, f'model {params.model_file}' + (
                    f' ({note})' if note else '')
            detail = params.profile + (f' person {params.person}' if params.person >= 0 else '')
            if params.input != SIM:  # standing in for a missing or lost joystick: say so
                detail += f' ({self.selector.status_line()})'
            return command, True, SIM, detail
        return 0.0, False, ZERO, self.selector.status_line()


__all__ = ['AUTO', 'core_from_parameters', 'HumanAnswer', 'HumanCore', 'HumanParams',
           'InputStatus', 'SOURCE_CODE', 'resolve_profile']
