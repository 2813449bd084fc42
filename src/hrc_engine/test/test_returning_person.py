"""A returning person: a new session starts from the policy a finished session learned with them.

Two in-process sessions of case 2 (task first: the robot alone, then the person) with the real
PyBullet sim and the simulated person, 8 s episodes: the first runs to its end and leaves
final.pt; the second starts from it (agent.start_from): its counters start at zero, it skips
the robot-alone step, and its first episode is a judging episode of the inherited policy with
the person. Without the start (a fresh policy) the first episode is the robot alone, training;
adapting to a new person (``adapt_from``) it trains with the person from the first episode.
"""

import torch

from hrc_agent_node.checkpoint import read_checkpoint
from hrc_common.contract import EpisodeKind
from hrc_common.session_plan import SessionSettings
from hrc_engine.engine import EngineConfig, SummariesSession

OVERRIDES = {'sim.episode_duration': 8.0}


def run(tmp_path, session_id, overrides=(), **settings):
    session = SummariesSession(EngineConfig(SessionSettings(
        case=2, seed=0, session_id=session_id, record=False, runs_dir=str(tmp_path / 'runs'),
        evaluation_episodes=1, overrides={**OVERRIDES, **dict(overrides)}, **settings)))
    session.run()
    return session.summaries


def test_the_second_session_judges_the_inherited_policy_with_the_person_first(tmp_path):
    first = run(tmp_path, 'first', training_episodes=6)
    assert first[0]['training_step'] == 0 and not first[0]['human_involved']
    final = tmp_path / 'runs' / 'checkpoints' / 'first' / 'final.pt'
    assert final.is_file()
    second = run(tmp_path, 'second', training_episodes=6, start_from=str(final))
    opening = second[0]
    assert opening['episode'] == 0 and opening['training_step'] == 1      # the last step
    assert opening['human_involved'] and opening['kind'] == 2            # KIND_JUDGING


def test_adapt_from_learns_from_each_of_the_persons_episodes_then_evaluates(tmp_path):
    """A new person meets a robot trained before (``--adapt-from``).

    Three training episodes with the person, no judging episode, then the evaluation.
    """
    run(tmp_path, 'first', training_episodes=6)
    checkpoints = tmp_path / 'runs' / 'checkpoints'
    # SAC starts learning after 20 of the person's transitions (three 8 s episodes hold 120;
    # a study's 40 s episodes hold 200 each, over the default 200)
    adapting = run(tmp_path, 'adapting', adapt_from=str(checkpoints / 'first' / 'final.pt'),
                   overrides={'agent.sac_learning_starts': 20})
    kinds = [summary['kind'] for summary in adapting]
    assert kinds == [EpisodeKind.TRAINING] * 3 + [EpisodeKind.EVALUATION]
    assert all(summary['human_involved'] and summary['training_step'] == 1
               for summary in adapting)
    # the policy learned from the person's episodes
    before, after = (read_checkpoint(checkpoints / name / 'final.pt')['core']['sac']
                     for name in ('first', 'adapting'))
    assert after['updates'] > before['updates']
    assert any(not torch.equal(before['actor'][name], after['actor'][name])
               for name in before['actor'])
