"""The partner model: it predicts a scripted partner's next action and tells two partners apart.

A scripted partner reacts to the ball with a gain, keeps part of its last command and adds
seeded noise: a_h(t) = -gain * B_y(t-1) + 0.5 a_h(t-1) + noise, on a ball that sways as a
seeded random walk. Deterministic (seeds); no sim needed for the estimator itself.
"""

import numpy as np
import pytest

from hrc_agent_node.partner_model import FEATURE_NAMES, FEATURE_SIZE, PartnerModel


def scripted(gain: float, steps: int, seed: int, noise: float = 0.02):
    """Yield (step, state features, partner action) of a scripted partner."""
    rng = np.random.default_rng(seed)
    ball, action = 0.0, 0.0
    for step in range(steps):
        yield step, (ball, 0.1 * rng.standard_normal(), 0.1 * rng.standard_normal()), action
        action = -gain * ball + 0.5 * action + noise * rng.standard_normal()
        ball = float(np.clip(0.9 * ball + 0.3 * rng.standard_normal(), -1, 1))


def run(gain: float, steps: int = 40, seed: int = 0) -> PartnerModel:
    model = PartnerModel()
    for step, state, action in scripted(gain, steps, seed):
        model.update(step, state, action)
    return model


def test_it_predicts_the_scripted_partners_next_action():
    model = PartnerModel()
    errors = []
    for step, state, action in scripted(0.8, 60, seed=1):
        if step >= 20:          # after 4 s of the interaction
            errors.append(abs(model.predict() - action))
        model.update(step, state, action)
    assert np.mean(errors) < 0.05          # the noise is 0.02; an action is ~0.3
    gains = dict(zip(FEATURE_NAMES[1:], model.features()[1:6]))
    assert gains['gain_ball'] == pytest.approx(-0.8, abs=0.1)
    assert gains['persistence'] == pytest.approx(0.5, abs=0.1)


def test_it_separates_two_partners_who_differ_in_one_trait():
    # the same seeds (states, noise), the gain on the ball 0.4 or 0.9: within 8 s
    weak = [run(0.4, seed=seed).features()[1] for seed in range(5)]
    strong = [run(0.9, seed=seed).features()[1] for seed in range(5)]
    assert max(strong) < min(weak)
    assert np.mean(weak) - np.mean(strong) > 5 * max(np.std(weak), np.std(strong))


def test_a_step_is_taken_once_and_an_episode_starts_afresh():
    model = run(0.8)
    features = model.features()
    assert features.shape == (FEATURE_SIZE,)
    assert np.array_equal(model.update(39, (9.0, 9.0, 9.0), 1.0), features)   # step 39 again
    model.reset()
    assert not model.features().any()
