"""A cloned model as an offline partner acts at the rate it was cloned at.

The offline loop calls a partner at the human's rate (the period's state, then each slice
state); the model was cloned from recordings cut at the control period, so it acts on the
period's state and holds its command over the slices, as the engine's and the graph's human
core run it. Tiny seeded models and fixed states: deterministic, no sim.
"""

import dataclasses
import math
from types import SimpleNamespace

import pytest
import torch

from hrc_agent_node.agent_core import AgentCore
from hrc_agent_node.config import AgentParams
from hrc_common.contract import SimLimits
from hrc_common.params import from_dict
from hrc_common.session_plan import SessionSettings
from hrc_engine.engine import compose_parameters, EngineConfig
from hrc_engine.engine import run_session as run_engine_session
from hrc_engine.offline import run_session as run_offline_session
from hrc_engine.partners import ClonedPartner, make_partner, MixturePartner, parse_specs
from hrc_joystick_node.human_core import core_from_parameters
from hrc_joystick_node.human_model import build_network, save_human_model
from hrc_sim_node.physics import physics_params_of, PhysicsParams, SliderPendulumBall
from hrc_sim_node.protocol import ProtocolSettings
from hrc_sim_node.sim_params import SimParams

SUBTASKS = ['pendulum', 'ball']
EPISODES = 2
STEPS = 6           # answered control steps per episode


@pytest.fixture(scope='module')
def model_file(tmp_path_factory):
    """Return a rotation model of 3 states of history with seeded weights (answers vary)."""
    torch.manual_seed(7)
    config = {'history_steps': 3, 'hidden': [8], 'dof': 'rotation', 'control_period': 0.2,
              'description': 'seeded test weights'}
    path = tmp_path_factory.mktemp('clone') / 'clone.pt'
    save_human_model(path, config, build_network(config).state_dict())
    return path


def limits_with(human_period: float) -> SimLimits:
    """Return the default physics' limits with the sim's ``human_period`` (s)."""
    return dataclasses.replace(SimLimits.of(PhysicsParams()), human_period=human_period)


def moments(limits: SimLimits):
    """Yield (episode, step, slice, stamp_ns, state) in the offline loop's order of calls.

    A swinging system sampled at every human step (the state moves within a period, so an
    answer to a slice state differs from the answer to the period's state).
    """
    for episode in range(EPISODES):
        for step in range(STEPS):
            for slice_index in range(limits.human_slices):
                seconds = step * limits.control_period + slice_index * limits.human_step
                phase = 3.0 * seconds + episode
                state = SimpleNamespace(slider_position=0.02 * math.sin(phase),
                                        slider_velocity=0.06 * math.cos(phase),
                                        pendulum_angle=0.3 * math.cos(2.0 * phase),
                                        pendulum_angular_velocity=-1.8 * math.sin(2.0 * phase),
                                        ball_position=0.1 * math.sin(0.5 * phase),
                                        ball_velocity=0.15 * math.cos(0.5 * phase))
                yield episode, step, slice_index, int(round(seconds * 1e9)), state


def partner_commands(partner, limits: SimLimits) -> list:
    """Return ``partner``'s answers, called as the offline loop calls it."""
    commands = []
    for episode, step, slice_index, _, state in moments(limits):
        if step == 0 and slice_index == 0:
            partner.start_episode(episode)
        commands.append(partner(state, SUBTASKS))
    return commands


def human_core_commands(model_file, limits: SimLimits) -> list:
    """Return the engine's and the graph's human core's answers (input model) to the same."""
    core = core_from_parameters({'input': 'model', 'model_file': str(model_file),
                                 'dof': 'rotation'}, limits)
    core.on_session('rotation', True, SUBTASKS)
    return [core.answer(episode, step, stamp_ns, state, slice_index=slice_index).command
            for episode, step, slice_index, stamp_ns, state in moments(limits)]


@pytest.mark.parametrize('human_period', [0.02, 0.05])
def test_a_cloned_partner_acts_once_a_control_period_as_the_human_core_runs_it(model_file,
                                                                             human_period):
    limits = limits_with(human_period)
    # the call count per period comes from the limits (10 at 0.02 s, 4 at 0.05 s), and it is
    # the protocol's and the physics' number of slices
    slices = round(limits.control_period / human_period)
    assert limits.human_slices == slices == ProtocolSettings(
        human_period=human_period).human_slices
    assert dataclasses.replace(PhysicsParams(), human_period=human_period).human_slices == slices
    commands = partner_commands(ClonedPartner(model_file, 'rotation', limits), limits)
    assert commands == human_core_commands(model_file, limits)
    # held over each period's slices: one new command per control step
    assert all(command == commands[index - index % slices]
               for index, command in enumerate(commands))
    assert len(set(commands)) == EPISODES * STEPS


def test_make_partner_and_the_mixture_hold_a_clone_over_the_slices(model_file):
    limits = limits_with(0.02)
    spec = parse_specs([f'model:{model_file}'])[0]
    assert make_partner(spec, 'rotation', 0, limits).calls_per_command == 10
    mixture = MixturePartner([spec], 'rotation', 3, limits)
    mixture.start_episode(0)
    assert mixture.partner.calls_per_command == 10


@pytest.mark.slow
def test_the_offline_loop_with_a_clone_runs_the_engines_session_with_input_model(model_file,
                                                                                 tmp_path):
    # A short case-5 session (the person acts from the first episode; a PPO update after the
    # second episode, then an evaluation episode): the in-process engine's human core runs the
    # model, the offline loop the ClonedPartner; every episode's return must be the same float.
    config = EngineConfig(SessionSettings(
        case=5, seed=0, training_episodes=2, evaluation_episodes=1, session_id='clone',
        human_input='model', record=False, bags_dir=str(tmp_path / 'bags'),
        runs_dir=str(tmp_path / 'runs'),
        overrides={'sim.episode_duration': 8.0, 'agent.horizon': 80,
                   'human.model_file': str(model_file)}), checkpoints=False)
    _, parameters = compose_parameters(config)
    engine = run_engine_session(config)
    physics = physics_params_of(from_dict(SimParams, dict(parameters['sim'])))
    limits = SimLimits.of(physics)
    assert limits.human_slices == 10

    core = AgentCore(from_dict(AgentParams, dict(parameters['agent'], checkpoint_dir='')),
                     limits=limits)
    partner = ClonedPartner(model_file, core.human_dof, limits)
    returns = []
    with SliderPendulumBall(physics) as sim:
        summary = run_offline_session(core, sim, partner, on_episode=lambda result, _:
                                      returns.append(result.episode_return))
    assert returns == [episode['episode_return'] for episode in engine.episodes]
    assert summary['evaluation'] == engine.evaluation
