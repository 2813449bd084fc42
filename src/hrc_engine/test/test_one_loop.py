"""The offline runner steps through the engine's loop: for a seed it gives the engine's episodes.

The engine (``hrc_engine.engine``) and the offline runner (``hrc_engine.offline``) both run
``hrc_engine.loop``; with the same seed and the same simulated person the offline runner's
episode records are the engine's (src/hrc_gym/test/test_gym_loop.py: the environment's step).
"""

from hrc_agent_node.agent_core import AgentCore
from hrc_agent_node.config import AgentParams
from hrc_common.contract import SimLimits
from hrc_common.params import from_dict
from hrc_common.session_plan import SessionSettings
from hrc_engine.engine import compose_parameters, EngineConfig, run_session as engine_session
from hrc_engine.offline import run_session as offline_session
from hrc_engine.partners import SimulatedHumanPartner
from hrc_joystick_node.human_profile import load_profile
from hrc_sim_node.physics import physics_params_of, SliderPendulumBall
from hrc_sim_node.sim_params import SimParams

RECORD = ('episode', 'training_step', 'human_involved', 'evaluation', 'steps',
          'episode_return', 'slider_error', 'pendulum_error', 'ball_error', 'total_error',
          'robot_effort', 'human_effort', 'converged')


def engine_and_offline(case: int, training: int, evaluation: int, overrides=None) -> tuple:
    """Return (the engine's episode records, the offline runner's) of one short session."""
    config = EngineConfig(SessionSettings(
        case=case, seed=3, training_episodes=training, evaluation_episodes=evaluation,
        session_id='one-loop', record=False,
        overrides=dict({'sim.episode_duration': 8.0, 'agent.horizon': 40,
                            'agent.minibatch_size': 20}, **(overrides or {}))),
        checkpoints=False)
    _, parameters = compose_parameters(config)
    engine = engine_session(config)
    physics = physics_params_of(from_dict(SimParams, dict(parameters['sim'])))
    limits = SimLimits.of(physics)
    core = AgentCore(from_dict(AgentParams, dict(parameters['agent'], checkpoint_dir='')),
                     limits=limits)
    human = parameters['human']
    partner = SimulatedHumanPartner(load_profile(human['profile']), core.human_dof,
                                    human['seed'], limits.human_step)
    results = []
    with SliderPendulumBall(physics) as sim:
        offline_session(core, sim, partner, on_episode=lambda result, _: results.append(result))
    offline = [{'episode': result.episode, 'training_step': result.training_step,
                'human_involved': result.human_involved, 'evaluation': result.evaluation,
                'steps': result.steps, 'episode_return': result.episode_return,
                **{f'{name}_error': result.errors[name] for name in ('slider', 'pendulum',
                                                                     'ball')},
                'total_error': result.total_error, 'robot_effort': result.robot_effort,
                'human_effort': result.human_effort, 'converged': result.converged}
               for result in results]
    return [{name: episode[name] for name in RECORD} for episode in engine.episodes], offline


def test_the_offline_runner_gives_the_engines_episodes_robot_alone_with_updates():
    # case 2's first step: the robot alone; four episodes with PPO updates in between (the
    # 40-step horizon), then the evaluation episode
    engine, offline = engine_and_offline(2, 4, 1)
    assert len(engine) == 5 and engine == offline


def test_the_offline_runner_gives_the_engines_episodes_with_the_simulated_person():
    # case 5: the person acts from the first episode, at the human's rate (ten slices); their
    # practice, fatigue and rest carry over the episodes on the session's clock
    engine, offline = engine_and_offline(5, 3, 1)
    assert all(episode['human_involved'] and episode['human_effort'] > 0 for episode in engine)
    assert len(engine) == 4 and engine == offline
