"""The human's per-step core without ROS: inputs, roles, abort, repeats, the simulated human."""

import dataclasses
import math

import pytest

from hrc_common.paths import params_dir
from hrc_common.contract import SimLimits
from hrc_common.params import ParameterError
from hrc_joystick_node.human_core import HumanCore, HumanParams, SOURCE_CODE
from hrc_joystick_node.inputs import DEVICE, JOY, MODEL, SCRIPT, SIM, StickReading, ZERO
from hrc_joystick_node.population import sample_person
from hrc_joystick_node.human_profile import load_profiles
from hrc_joystick_node.sim_human import SimulatedHuman

CONTROL_PERIOD = 0.2   # s: the sim's control period (params/sim.yaml), the people's call period
PROFILES = load_profiles(params_dir()
                         / 'sim_human.yaml')
PERIOD_NS = 200_000_000


@dataclasses.dataclass
class State:
    """A PhysicsState-like state."""

    step: int = 0
    time: float = 0.0
    slider_position: float = 0.0
    slider_velocity: float = 0.0
    pendulum_angle: float = 0.0
    pendulum_angular_velocity: float = 0.0
    ball_position: float = 0.0
    ball_velocity: float = 0.0


LIMITS = SimLimits(control_period=0.2, max_force=2.0, max_torque=0.5)   # a sim's


def states(count, angle=0.2):
    return [State(step=step, time=0.2 * step, pendulum_angle=angle * (1 - step / count),
                  pendulum_angular_velocity=-angle / count / 0.2) for step in range(count)]


def stamp(episode, step, steps_per_episode=201):
    return (episode * steps_per_episode + step) * PERIOD_NS


def core_of(params: HumanParams) -> HumanCore:
    """Return the core of ``params`` once it knows the sim's limits (as the node's does)."""
    core = HumanCore(params, PROFILES)
    core.set_limits(LIMITS)
    return core


def test_no_answer_before_the_sims_limits_and_the_sims_values_are_used():
    core = HumanCore(HumanParams(input='sim', profile='paper', seed=3), PROFILES)
    core.on_inputs(False, '', False, '')
    with pytest.raises(RuntimeError, match="the sim's limits are not known yet"):
        core.answer(0, 0, 0, State(pendulum_angle=0.3))
    with pytest.raises(ValueError) as refused:
        core.set_limits(SimLimits(control_period=0.0, max_force=2.0, max_torque=math.inf))
    assert 'control_period' in str(refused.value) and 'max_torque' in str(refused.value)
    # Another sim: a 0.1 s period (the simulated human's delay counts in its steps) and a
    # stronger hinge; the answers follow them.
    other = SimLimits(control_period=0.1, max_force=3.0, max_torque=0.8)
    assert core.set_limits(other)
    reference = SimulatedHuman(PROFILES['paper'], 'rotation', seed=3, control_period=0.1)
    reference.reset(0)
    for state in states(10):
        answer = core.answer(0, state.step, stamp(0, state.step), state)
        assert answer.command == reference.act(state, ['pendulum'],
                                               now=stamp(0, state.step) * 1e-9)
        assert answer.wrench == pytest.approx(0.8 * answer.command)


def test_source_codes_are_the_message_constants():
    from hrc_msgs.msg import HumanAction

    assert SOURCE_CODE == {DEVICE: HumanAction.SOURCE_DEVICE, JOY: HumanAction.SOURCE_JOY,
                           SIM: HumanAction.SOURCE_SIMULATED, MODEL: HumanAction.SOURCE_SIMULATED,
                           SCRIPT: HumanAction.SOURCE_REPLAY, ZERO: HumanAction.SOURCE_NONE}


def test_the_simulated_human_answers_on_the_simulation_clock_and_repeats_do_not_advance_it():
    params = HumanParams(input='sim', profile='paper', seed=3)
    core = core_of(params)
    core.on_inputs(False, '', False, '')
    reference = SimulatedHuman(PROFILES['paper'], 'rotation', seed=3,
                               control_period=CONTROL_PERIOD)
    reference.reset(0)
    for state in states(20):
        answer = core.answer(0, state.step, stamp(0, state.step), state)
        expected = reference.act(state, ['pendulum'], now=stamp(0, state.step) * 1e-9)
        assert answer.command == expected and answer.source == SIM and answer.engaged
        assert answer.wrench == pytest.approx(0.5 * expected)  # max_torque
        assert answer.detail == 'paper'
        again = core.answer(0, state.step, stamp(0, state.step), state)
        assert again.repeated and again.command == answer.command
    # Episodes the person sits out are rest on the state stamps: the person is less tired
    # than one who went on at once.
    tired = core.sim_human.fatigue.level
    later = core.answer(30, 0, stamp(30, 0), State())
    assert later.source == SIM
    assert core.sim_human.fatigue.level < 0.9 * tired


def test_roles_not_involved_and_abort():
    core = core_of(HumanParams(input='sim', profile='skilled'))
    core.on_inputs(False, '', False, '')
    assert core.answer(0, 0, stamp(0, 0), State(pendulum_angle=0.3)).command < 0.0
    changed, unknown = core.on_session('translation', True, ['T2_1', 'juggle'])
    assert changed and unknown == ['juggle'] and core.subtasks == ['slider']
    answer = core.answer(0, 1, stamp(0, 1), State(slider_position=0.05))
    assert answer.dof == 'translation' and answer.command < 0.0
    assert answer.wrench == pytest.approx(2.0 * answer.command)  # max_force
    core.on_session('translation', False, [])
    answer = core.answer(0, 2, stamp(0, 2), State(slider_position=0.05))
    assert (answer.command, answer.engaged, answer.source) == (0.0, False, ZERO)
    assert answer.detail.startswith('not involved')
    core.on_session('translation', True, ['slider'], aborted=True)
    zero = core.abort_answer()
    assert (zero.episode, zero.step, zero.stamp_ns) == (0, 2, stamp(0, 2))
    assert (zero.command, zero.engaged, zero.source) == (0.0, False, ZERO)
    after = core.answer(0, 3, stamp(0, 3), State(slider_position=0.05))
    assert after.command == 0.0 and 'aborted' in after.detail
    # An abort while the human sits out sends nothing: the last answer is of another step.
    core.on_session('translation', False, [], aborted=True)
    assert core.abort_answer() is None


def test_a_joystick_drives_it_and_its_loss_holds_zero_and_asks_for_a_pause():
    params = HumanParams(input='device', device='/dev/input/js0', enable_button=0,
                         deadzone=0.0)
    core = core_of(params)
    core.on_inputs(False, 'cannot open /dev/input/js0: No such file or directory', False, '')
    answer = core.answer(0, 0, stamp(0, 0), State())
    assert (answer.command, answer.engaged, answer.source) == (0.0, False, ZERO)
    assert answer.detail.startswith('no joystick yet (zero held, session should pause)')
    status = core.input_status
    assert (status.state, status.pause_requested, status.level) == ('missing', True, 2)

    core.on_inputs(True, '/dev/input/js0 open (char)', False, '')
    stick = {DEVICE: StickReading(0.5, True, '/dev/input/js0')}
    answer = core.answer(0, 1, stamp(0, 1), State(), stick)
    assert (answer.command, answer.engaged, answer.source) == (0.5, True, DEVICE)
    assert answer.detail == '/dev/input/js0'
    assert core.input_status.level == 0
    released = {DEVICE: StickReading(0.5, False, '/dev/input/js0')}
    answer = core.answer(0, 2, stamp(0, 2), State(), released)
    assert (answer.command, answer.engaged) == (0.0, False)
    assert 'enable button released' in answer.detail

    core.on_inputs(False, '/dev/input/js0 vanished: read failed: No such device', False, '')
    answer = core.answer(0, 3, stamp(0, 3), State(pendulum_angle=0.3), stick)
    assert (answer.command, answer.source) == (0.0, ZERO), 'never a silent stand-in'
    assert answer.detail.startswith('joystick disconnected (zero held, session should pause)')
    assert 'No such device' in answer.detail
    status = core.input_status
    assert (status.state, status.active, status.pause_requested) == ('lost', ZERO, True)


def test_the_simulated_human_stands_in_only_when_asked_and_says_so():
    core = core_of(HumanParams(input='device', on_input_lost='sim', profile='skilled'))
    core.on_inputs(True, 'open', False, '')
    core.on_inputs(False, '/dev/input/js0 vanished', False, '')
    answer = core.answer(0, 0, stamp(0, 0), State(pendulum_angle=0.3))
    assert answer.source == SIM and answer.engaged and answer.command < 0.0
    assert answer.detail.startswith('skilled (joystick disconnected (the simulated human '
                                    'stands in')
    status = core.input_status
    assert (status.state, status.pause_requested, status.level) == ('lost', False, 1)


def test_a_person_of_the_population_and_bad_profiles():
    core = core_of(HumanParams(input='sim', profile='paper', person=4))
    assert core.profile == sample_person(PROFILES['paper'], 4)
    core.on_inputs(False, '', False, '')
    assert core.answer(0, 0, 0, State()).detail == 'paper person 4'
    assert HumanCore(HumanParams(input='sim'), PROFILES).profile == PROFILES['paper']
    with pytest.raises(ParameterError, match="profile: 'expert' is not in"):
        HumanCore(HumanParams(profile='expert'), PROFILES)


def test_a_core_from_composed_parameters_as_the_in_process_engine_builds_it():
    import yaml

    from hrc_joystick_node.human_core import core_from_parameters

    path = params_dir() / 'human.yaml'
    parameters = yaml.safe_load(path.read_text())['human']['ros__parameters']
    parameters.update(input='sim', person=2, seed=5)
    core = core_from_parameters(parameters, LIMITS)
    assert core.profile == sample_person(PROFILES['paper'], 2)
    assert core.answer(0, 0, 0, State(pendulum_angle=0.3)).source == SIM
    with pytest.raises(ParameterError, match="unknown parameter 'persn'"):
        core_from_parameters({'persn': 2}, LIMITS)


def test_a_person_at_the_stick_is_forwarded_between_states_with_the_newest_stamp():
    params = HumanParams(input='device', device='/dev/input/js0', deadzone=0.0)
    core = core_of(params)
    core.on_inputs(True, '/dev/input/js0 open (char)', False, '')
    at = {DEVICE: StickReading(0.25, None, '/dev/input/js0')}
    assert core.forward(at) is None                       # nothing answered yet
    answer = core.answer(0, 4, stamp(0, 4), State(), at, slice_index=3)
    assert core.forward(at) is None                       # the stick did not move
    moved = core.forward({DEVICE: StickReading(-0.5, None, '/dev/input/js0')})
    assert (moved.command, moved.wrench) == (-0.5, -0.5 * LIMITS.max_torque)
    assert (moved.episode, moved.step, moved.slice, moved.stamp_ns) == (
        0, 4, 3, answer.stamp_ns)                         # answers the newest state
    assert core.last_answer == moved                      # a repeat of the state sends it
    # A simulated person: never forwarded.
    simulated = core_of(HumanParams(input='sim'))
    simulated.on_inputs(False, '', False, '')
    simulated.answer(0, 0, stamp(0, 0), State())
    assert simulated.forward(at) is None


def test_the_simulated_person_acts_at_the_sims_human_period_on_slice_states():
    core = HumanCore(HumanParams(input='sim', profile='paper', seed=3), PROFILES)
    core.set_limits(dataclasses.replace(LIMITS, human_period=0.02))
    core.on_inputs(False, '', False, '')
    assert core.sim_human.control_period == 0.02
    first = core.answer(0, 0, stamp(0, 0), State(), slice_index=0)
    second = core.answer(0, 0, stamp(0, 0) + 20_000_000, State(pendulum_angle=0.1),
                         slice_index=1)
    assert not second.repeated and second.slice == 1
    assert core.answer(0, 0, stamp(0, 0) + 20_000_000, State(), slice_index=1).repeated
    assert first.slice == 0


def test_a_returning_simulated_person_starts_with_their_practice():
    def practice(**changes):
        core = HumanCore(HumanParams(input='sim', profile='paper', seed=3, **changes), PROFILES)
        core.set_limits(LIMITS)
        core.on_inputs(False, '', False, '')
        core.answer(0, 0, stamp(0, 0), State())
        return core.sim_human.practiced_episodes, core.sim_human.practice_factor

    new_episodes, new_factor = practice()
    back_episodes, back_factor = practice(practiced_episodes=40)
    assert (new_episodes, back_episodes) == (0, 40)
    # paper: untrained_factor 1.5 over learning_episodes 15; after 40 episodes e^-40/15 is left
    assert new_factor == pytest.approx(1.5)
    assert back_factor == pytest.approx(1 + 0.5 * math.exp(-40 / 15))
