"""Checkpoints: round trip, exact resume, evaluation-only loading, clear errors.

Identical policy outputs after a round trip, resumed sessions continue exactly, a policy loads
for evaluation alone, incompatible or foreign files fail with a clear reason, a crafted file
runs no code, a file of the wrong layout is refused with every reason.
"""

import pickle

import numpy as np
import pytest
import torch

from hrc_agent_node.agent_core import AgentCore
from hrc_agent_node.checkpoint import (CheckpointError, load_into, make_checkpoint,
                                       save_checkpoint)
from hrc_agent_node.config import AgentParams
from hrc_engine.offline import make_partner, run_session
from hrc_common.params import with_overrides
from hrc_sim_node.physics import PhysicsParams, SliderPendulumBall

# Short episodes (4 s = 20 steps) and a small horizon keep these tests fast.
PHYSICS = PhysicsParams(episode_duration=4.0)


def params(**overrides):
    values = dict(case=3, seed=5, preset='tuned', horizon=40, minibatch_size=16,
                  max_training_episodes=6, evaluation_episodes=1, checkpoint_dir='')
    values.update(overrides)
    return with_overrides(AgentParams(), **values)


def run(core, episodes):
    with SliderPendulumBall(PHYSICS) as sim:
        returns = []
        run_session(core, sim, make_partner(core),
                    on_episode=lambda result, stats: returns.append(result.episode_return),
                    max_episodes=episodes)
    return returns


def observations():
    return np.random.default_rng(0).normal(size=(10, 7)).astype(np.float32)


@pytest.mark.slow
def test_round_trip_gives_identical_policy_outputs(tmp_path):
    core = AgentCore(params())
    run(core, 3)                         # trained a little: one update happened
    assert core.ppo.updates == 1
    path = save_checkpoint(core, tmp_path / 'a.pt')
    loaded = AgentCore(params(seed=99))  # another seed: different initial weights
    load_into(loaded, path)
    for observation in observations():
        assert loaded.ppo.act(observation, deterministic=True) == \
            core.ppo.act(observation, deterministic=True)
        # The exploration generator travels too: the same noise follows.
        assert loaded.ppo.act(observation) == core.ppo.act(observation)
    assert (loaded.episode, loaded.total_episodes, loaded.human_involved_episodes) == \
        (core.episode, core.total_episodes, core.human_involved_episodes)


def test_resumed_session_continues_exactly(tmp_path):
    straight = AgentCore(params())
    straight_returns = run(straight, 5)
    first = AgentCore(params())
    first_returns = run(first, 2)
    save_checkpoint(first, tmp_path / 'latest.pt')
    resumed = AgentCore(params())
    load_into(resumed, tmp_path / 'latest.pt')
    assert resumed.episode == 2 and resumed.total_episodes == 2
    resumed_returns = run(resumed, 3)
    assert first_returns + resumed_returns == pytest.approx(straight_returns, rel=0, abs=0)
    assert resumed.total_episodes == straight.total_episodes == 5


def test_resumed_session_continues_exactly_with_updates_inside_episodes(tmp_path):
    """Horizon 15 in 20-step episodes: updates at steps 15 and at episode ends."""
    new_rules = dict(horizon=15, minibatch_size=8)
    straight = AgentCore(params(**new_rules))
    straight_returns = run(straight, 5)
    first = AgentCore(params(**new_rules))
    first_returns = run(first, 2)
    assert first.ppo.updates == 2          # inside episode 0 and at its end; 1 is judging
    save_checkpoint(first, tmp_path / 'latest.pt')
    resumed = AgentCore(params(**new_rules))
    load_into(resumed, tmp_path / 'latest.pt')
    resumed_returns = run(resumed, 3)
    assert first_returns + resumed_returns == pytest.approx(straight_returns, rel=0, abs=0)
    assert resumed.ppo.updates == straight.ppo.updates


def test_policy_loads_for_evaluation_alone(tmp_path):
    trained = AgentCore(params())
    run(trained, 3)
    path = save_checkpoint(trained, tmp_path / 'trained.pt')
    evaluator = AgentCore(params(evaluation_only=True, resume_from=str(path), case=5,
                                 evaluation_episodes=2))
    load_into(evaluator, path, resume=False)   # another case, same robot dof: allowed
    assert evaluator.phase == 'evaluation' and evaluator.episode == 3
    run(evaluator, 5)
    assert evaluator.phase == 'done' and len(evaluator.evaluation_results) == 2
    assert all(result.evaluation for result in evaluator.evaluation_results)
    assert evaluator.ppo.updates == trained.ppo.updates   # nothing learned in evaluation


@pytest.mark.parametrize('other, reason', [
    ({'hidden_size': 32}, 'hidden_size is 64 in the checkpoint but 32 here'),
    ({'observe_rates': False}, 'observation_size is 7 in the checkpoint but 4 here'),
    ({'case': 4}, "the policy drives 'translation' but the robot drives 'rotation'"),
    ({'case': 5}, 'it belongs to case 3, not case 5'),
])
def test_incompatible_checkpoint_fails_clearly(tmp_path, other, reason):
    path = save_checkpoint(AgentCore(params()), tmp_path / 'c.pt')
    with pytest.raises(CheckpointError) as error:
        load_into(AgentCore(params(**other)), path)
    assert 'is incompatible' in str(error.value) and reason in str(error.value)


def test_foreign_damaged_missing_and_old_files_fail_clearly(tmp_path):
    core = AgentCore(params())
    with pytest.raises(CheckpointError, match='does not exist'):
        load_into(core, tmp_path / 'nothing.pt')
    damaged = tmp_path / 'damaged.pt'
    damaged.write_bytes(b'not a checkpoint at all')
    with pytest.raises(CheckpointError, match='cannot be read'):
        load_into(core, damaged)
    foreign = tmp_path / 'foreign.pt'
    torch.save({'model': 1}, foreign)
    with pytest.raises(CheckpointError, match='is not an hrc agent checkpoint'):
        load_into(core, foreign)
    old = make_checkpoint(core)
    old['format_version'] = 0
    torch.save(old, tmp_path / 'old.pt')
    with pytest.raises(CheckpointError, match='format version 0; this agent reads version 2'):
        load_into(core, tmp_path / 'old.pt')


def test_no_checkpoint_during_an_episode():
    core = AgentCore(params())
    core.start_episode()
    with pytest.raises(RuntimeError, match='between episodes'):
        make_checkpoint(core)


class Payload:
    """Pickles as a call of open(marker, 'w'): unpickled by plain pickle, it creates the file."""

    def __init__(self, marker):
        self.marker = str(marker)

    def __reduce__(self):
        return (open, (self.marker, 'w'))


def test_payload_is_live_under_plain_pickle(tmp_path):
    """The payload the next test uses does run code when a file is loaded without the guard."""
    marker = tmp_path / 'ran'
    pickle.loads(pickle.dumps(Payload(marker))).close()
    assert marker.exists()
    marker.unlink()
    torch.save({'x': Payload(marker)}, tmp_path / 'p.pt')
    torch.load(tmp_path / 'p.pt', weights_only=False)['x'].close()
    assert marker.exists()


@pytest.mark.parametrize('how', ['alone', 'hidden in a valid checkpoint', 'plain pickle'])
def test_crafted_checkpoint_runs_no_code_and_is_refused(tmp_path, how):
    marker = tmp_path / 'ran'
    path = tmp_path / 'crafted.pt'
    core = AgentCore(params())
    if how == 'alone':
        torch.save(Payload(marker), path)
    elif how == 'hidden in a valid checkpoint':
        checkpoint = make_checkpoint(core)
        checkpoint['core']['ppo']['policy']['extra'] = Payload(marker)
        torch.save(checkpoint, path)
    else:
        with open(path, 'wb') as stream:
            pickle.dump({'format': 'hrc_agent_checkpoint', 'x': Payload(marker)}, stream,
                        protocol=2)
    with pytest.raises(CheckpointError) as error:
        load_into(core, path)
    assert 'refused: it holds objects other than tensors and plain containers' in \
        str(error.value)
    assert not marker.exists(), 'the payload ran'


@pytest.mark.parametrize('change, reasons', [
    (lambda c: {key: c[key] for key in ('format', 'format_version')},
     ["checkpoint lacks 'config'", "checkpoint lacks 'network'", "checkpoint lacks 'core'"]),
    (lambda c: {**c, 'network': 5}, ['checkpoint.network must be a mapping, got int']),
    (lambda c: {**c, 'core': {**c['core'], 'counters': {'episode': 'x'}}},
     ['checkpoint.core.counters.episode must be int, got str',
      "checkpoint.core.counters lacks 'total_episodes'"]),
])
def test_checkpoint_of_the_wrong_layout_is_refused_with_every_reason(tmp_path, change,
                                                                     reasons):
    core = AgentCore(params())
    torch.save(change(make_checkpoint(core)), tmp_path / 'bad.pt')
    with pytest.raises(CheckpointError) as error:
        load_into(core, tmp_path / 'bad.pt')
    assert 'is malformed' in str(error.value)
    assert all(reason in str(error.value) for reason in reasons), str(error.value)
