"""The Gymnasium and PettingZoo environments: API checks, seeding, reward identity, bad input."""

import functools
import warnings

import gymnasium
from gymnasium.utils.env_checker import check_env
import numpy as np
from pettingzoo.test import parallel_api_test, parallel_seed_test
import pytest

import hrc_gym
from hrc_common.params import ParameterError
from hrc_common.session_plan import SessionSettings
from hrc_gym.compare import train_ours
from hrc_gym.env import SliderPendulumBallEnv
from hrc_sim_node.physics import PhysicsParams


def _checked(env):
    """Run check_env and fail on any warning it raises (a warning is a finding)."""
    with warnings.catch_warnings():
        warnings.simplefilter('error')
        check_env(env)


def test_make_finds_the_registered_id_and_check_env_passes():
    env = gymnasium.make(hrc_gym.ENV_ID, case=2, training_step=0, preset='tuned',
                         render_mode='rgb_array')
    by_module = gymnasium.make('hrc_gym:' + hrc_gym.ENV_ID, case=4)
    by_module.close()
    try:
        assert isinstance(env.unwrapped, SliderPendulumBallEnv)
        assert by_module.spec.id == hrc_gym.ENV_ID
        _checked(env.unwrapped)
        env.reset(seed=0)
        image = env.render()
        assert image.shape == (240, 320, 3) and image.dtype == np.uint8
        assert image.std() > 0  # something is drawn
    finally:
        env.close()


def test_check_env_passes_with_the_human_and_rates():
    env = gymnasium.make(hrc_gym.ENV_ID, case=2, training_step=-1, human='paper',
                         observe_rates=True, render_mode='rgb_array')
    try:
        _checked(env.unwrapped)
        assert env.observation_space.shape == (7,)
    finally:
        env.close()


def _trajectory(env, seed, actions):
    observation, _ = env.reset(seed=seed)
    rows = [observation]
    for episode in range(2):
        if episode:
            rows.append(env.reset()[0])
        for action in actions:
            observation, reward, terminated, truncated, info = env.step(action)
            rows.append(np.concatenate([observation, [reward, info['human_action']]]))
            if terminated or truncated:
                break
    return np.concatenate([np.ravel(row) for row in rows])


def test_same_seed_same_trajectory_with_the_simulated_human():
    # The whole task: physics starts, human noise and the human's practice all from the seed.
    actions = [np.array([np.sin(0.1 * k)], dtype=np.float32) for k in range(200)]
    env = SliderPendulumBallEnv(case=6, human='paper', preset='tuned')
    other = SliderPendulumBallEnv(case=6, human='paper', preset='tuned')
    try:
        first = _trajectory(env, 7, actions)
        again = _trajectory(other, 7, actions)
        np.testing.assert_array_equal(first, again)
        assert not np.array_equal(first, _trajectory(env, 8, actions))
        # The human acted (its commands move the stick) and the episode ended by truncation at
        # step 200.
        env.reset(seed=7)
        human_commands = []
        for action in actions:
            _, _, terminated, truncated, info = env.step(action)
            human_commands.append(info['human_action'])
        assert np.std(human_commands) > 0.01 and np.max(np.abs(human_commands)) > 0.05
        assert truncated and not terminated and info['step'] == 200
        assert set(info['episode_errors']) == {'ball', 'slider', 'pendulum'}
    finally:
        env.close()
        other.close()


def test_robot_alone_step_gives_the_human_nothing_to_do_and_rewards_level_two_only():
    env = SliderPendulumBallEnv(case=2, training_step=0, human='paper', preset='tuned')
    try:
        observation, _ = env.reset(seed=1)
        _, reward, _, _, info = env.step(np.array([0.3], dtype=np.float32))
        assert info['human_action'] == 0.0 and observation[3] == 0.0
        assert set(info['reward_components']) == {'slider', 'pendulum'}
        assert reward == pytest.approx(sum(info['reward_components'].values()))
    finally:
        env.close()


def test_a_human_model_object_is_asked_with_its_subtasks():
    class Constant:
        def __init__(self):
            self.calls, self.resets = [], []

        def reset(self, episode):
            self.resets.append(episode)

        def act(self, state, subtasks):
            self.calls.append(tuple(subtasks))
            return 0.5

    model = Constant()
    env = SliderPendulumBallEnv(case=2, training_step=1, human_model=model)
    try:
        env.reset(seed=0)
        observation, _, _, _, info = env.step(np.zeros(1, dtype=np.float32))
        env.reset()
        # Case 2: the human translates; it holds the slider (its direct subtask) and the ball.
        assert model.calls == [('ball', 'slider')] and model.resets == [0, 1]
        assert info['human_action'] == 0.5
        assert observation[3] == pytest.approx(0.5)  # a_h: the applied command, normalized
    finally:
        env.close()


def test_our_ppo_earns_exactly_the_environment_reward():
    # train_ours raises if AgentCore's own return of an episode differs from the env's.
    records = train_ours('whole', 3, 2)
    assert len(records) == 2 and all(record['return'] > 0 for record in records)


def test_parallel_api_test_and_seed_test_pass():
    parallel_seed_test(functools.partial(hrc_gym.parallel_env, case=6, preset='tuned'),
                       num_cycles=50)
    env = hrc_gym.parallel_env(case=6, preset='tuned', render_mode='rgb_array')
    try:
        parallel_api_test(env, num_cycles=210)
        observations, _ = env.reset(seed=0)
        assert set(observations) == {'robot', 'human'}
        _, rewards, _, _, infos = env.step({'robot': np.array([0.1], dtype=np.float32),
                                            'human': np.array([-0.2], dtype=np.float32)})
        # Case 6: the robot's reward is all three subtasks; the human's its own two.
        assert set(infos['robot']['reward_components']) == {'ball', 'slider', 'pendulum'}
        assert set(infos['human']['reward_components']) == {'ball', 'slider'}
        assert rewards['robot'] > rewards['human'] > 0
        assert env.render().shape == (240, 320, 3)
    finally:
        env.close()


def test_bad_parameters_are_refused_with_every_reason():
    with pytest.raises(ParameterError) as caught:
        SliderPendulumBallEnv(case=9, observe_rates='yes', colour='red')
    assert 'colour' in str(caught.value)
    with pytest.raises(ParameterError) as caught:
        SliderPendulumBallEnv(case=9, observe_rates='yes')
    assert 'case' in str(caught.value) and 'observe_rates' in str(caught.value)
    with pytest.raises(ParameterError, match='training_step 3'):
        SliderPendulumBallEnv(case=2, training_step=3)
    with pytest.raises(ParameterError, match='martian'):
        SliderPendulumBallEnv(human='martian')
    with pytest.raises(ParameterError, match='does not involve the human'):
        hrc_gym.parallel_env(case=2, training_step=0)
    with pytest.raises(ParameterError, match='render_mode'):
        SliderPendulumBallEnv(render_mode='human')


def test_a_population_member_is_drawn_by_the_reset_seed():
    env = SliderPendulumBallEnv(case=6, human='population:paper')
    try:
        env.reset(seed=0)
        first = env.human.core.profile
        env.reset(seed=1)
        second = env.human.core.profile
        env.reset(seed=0)
        assert env.human.core.profile == first and second != first
        assert first.reaction_delay != second.reaction_delay
    finally:
        env.close()


def test_a_cloned_human_model_file_drives_the_human(tmp_path):
    from hrc_joystick_node.human_model import build_network, save_human_model
    import torch

    config = {'history_steps': 2, 'hidden': [4], 'dof': 'translation', 'control_period': 0.2,
              'description': 'test model'}
    network = build_network(config)
    with torch.no_grad():
        for parameter in network.parameters():
            parameter.zero_()
        network[-2].bias.fill_(0.5)   # tanh(0.5): a constant push, whatever it sees
    path = tmp_path / 'clone.pt'
    save_human_model(path, config, network.state_dict())
    env = SliderPendulumBallEnv(case=6, human=f'model:{path}')
    try:
        env.reset(seed=0)
        _, _, _, _, info = env.step(np.zeros(1, dtype=np.float32))
        assert info['human_action'] == pytest.approx(np.tanh(0.5))
    finally:
        env.close()
    with pytest.raises(ParameterError):
        SliderPendulumBallEnv(case=6, human=f'model:{tmp_path / "missing.pt"}')


def applied_after_five_steps(human_period: float) -> list:
    """Return the human commands the sim applied in the 5th period of case 6 (seed 5)."""
    env = SliderPendulumBallEnv(case=6, human='paper',
                                physics_params=PhysicsParams(human_period=human_period,
                                                             episode_duration=8.0))
    try:
        env.reset(seed=5)
        for _ in range(5):
            env.step(np.zeros(1))
        return list(env.task.human_applied)
    finally:
        env.close()


def test_the_human_acts_at_its_rate():
    # the simulated person acted in every 20 ms slice: ten commands applied in the period
    applied = applied_after_five_steps(0.02)
    assert len(applied) == 10 and len(set(applied)) > 1, applied
    # at the control period (0.2 s) one command holds for the whole period
    assert len(applied_after_five_steps(0.2)) == 1


def test_a_session_gives_the_case_the_seed_the_profile_and_the_physics():
    """The one session configuration drives the environment as the keywords do."""
    actions = [np.array([np.sin(0.1 * k)], dtype=np.float32) for k in range(200)]
    by_keywords = SliderPendulumBallEnv(case=6, human='novice', preset='tuned')
    # the default learning configuration (sac) rewards with the tuned preset
    session = SessionSettings(case=6, seed=7, human_profile='novice')
    by_session = SliderPendulumBallEnv(session=session)
    try:
        assert by_session.config == by_keywords.config
        assert by_session.task.physics.params == PhysicsParams()   # params/sim.yaml's
        expected = _trajectory(by_keywords, 7, actions)
        # the first reset() without a seed takes the session's seed
        np.testing.assert_array_equal(_trajectory(by_session, None, actions), expected)
    finally:
        by_keywords.close()
        by_session.close()
    # --set sim.* makes the physics; --set human.profile picks the human
    env = SliderPendulumBallEnv(session=SessionSettings(
        case=2, overrides={'sim.max_torque': 0.8, 'human.profile': 'skilled'}))
    try:
        assert env.task.physics.params.max_torque == 0.8 and env.task.limits.max_torque == 0.8
        assert env.config.human == 'skilled' and env.config.case == 2
    finally:
        env.close()
    # the session's learning configuration gives the reward preset
    for learning, preset in (('sac', 'tuned'), ('ppo', 'graded'), ('paper', 'paper')):
        env = SliderPendulumBallEnv(session=SessionSettings(case=2, learning=learning))
        try:
            assert env.config.preset == preset, learning
        finally:
            env.close()


def test_a_session_and_keywords_saying_the_same_thing_are_refused_with_every_reason():
    with pytest.raises(ParameterError) as caught:
        SliderPendulumBallEnv(session=SessionSettings(case=9, seed=-1))
    assert 'case must be one of 1..8, got 9' in str(caught.value)
    assert 'seed must be >= 0' in str(caught.value)
    with pytest.raises(ParameterError) as caught:
        SliderPendulumBallEnv(session=SessionSettings(overrides={'agent.horizon': 20}),
                              case=3, human='paper', physics_params=PhysicsParams(),
                              preset='graded')
    for reason in ('case: given by the session', 'human: given by the session',
                   'preset: given by the session', 'physics_params: given by the session',
                   "overrides 'agent.horizon'"):
        assert reason in str(caught.value)


def test_the_case_is_checked_against_params_cases_yaml():
    """No case range of its own: a case of params/cases.yaml is accepted, another refused."""
    env = SliderPendulumBallEnv(case=8, training_step=-1)
    try:
        assert env.task.case.strategy == 'partners_first'
    finally:
        env.close()
    with pytest.raises(ParameterError, match='case must be one of 1..8, got 9'):
        SliderPendulumBallEnv(case=9)
