"""The paper's counting, the paper-style stop, the floors, the unit-free error, the views."""

import math

from hrc_bag.report.counting import (case_floors, paper_counts, step_reward_peak, STOP_WINDOW,
                                     tolerance_error)
from hrc_bag.report.records import EpisodeRecord, measures, SessionRecord
from hrc_testing.study_records import make_session, paper_like
import pytest

from hrc_study.findings import evaluate_findings
from hrc_study.paper_view import (paper_counting_markdown, paper_counting_note,
                                  robustness_markdown)

PEAK = 10 / math.sqrt(2 * math.pi)      # every preset's component peak (params/task_tree.yaml)
STEPS = 200                              # a 40 s episode at 0.2 s


def episode(index, kind, step, fraction=0.5, human=True, converged=False, total=0.03):
    """Return an episode whose return is ``fraction`` of a 3-subtask step's maximum."""
    return EpisodeRecord(episode=index, training_step=step, human_involved=human,
                         evaluation=kind == 'evaluation', converged=converged,
                         episode_return=fraction * 3 * PEAK * STEPS, slider_error=total / 3,
                         pendulum_error=total / 3, ball_error=total / 3, total_error=total,
                         human_effort=0.01, robot_effort=0.01, kind=kind, steps=STEPS)


def session(episodes, case_id=6, strategy='learn_together', agent=None):
    return SessionRecord(session_id='s', case_id=case_id, strategy=strategy,
                         robot_dof='rotation', seed=0, profile='paper', episodes=episodes,
                         episode_limit=300,
                         extra={'agent': agent or {'judging_interval': 2, 'preset': 'tuned'}})


def test_the_step_maximum_is_every_component_at_its_peak():
    # case 6's only step rewards slider, pendulum and ball; responsibility-guided step 1 two
    assert step_reward_peak('learn_together', 0, 'rotation', 'tuned') == pytest.approx(3 * PEAK)
    assert step_reward_peak('responsibility_guided', 0, 'rotation', 'paper') == \
        pytest.approx(2 * PEAK)
    assert math.isnan(step_reward_peak('learn_together', 5, 'rotation', 'tuned'))


def test_the_paper_counts_training_episodes_and_stops_on_the_window_mean():
    # training fractions 0.5, 0.9, 1.0, 1.0, 0.95, 0.97, 0.99 with judging episodes between:
    # windows of 5 training returns: (0.5+0.9+1+1+0.95)/5 = 0.87, then (0.9+1+1+0.95+0.97)/5
    # = 0.964 >= 0.95 at the 6th training episode
    fractions = [0.5, 0.9, 1.0, 1.0, 0.95, 0.97, 0.99]
    episodes, index = [], 0
    for number, fraction in enumerate(fractions):
        episodes.append(episode(index, 'training', 0, fraction))
        index += 1
        if number % 2 == 1:
            episodes.append(episode(index, 'judging', 0, 1.0))
            index += 1
    episodes.append(episode(index, 'evaluation', 0))
    record = session(episodes)
    values = paper_counts(record, [item.kind for item in record.episodes])
    assert STOP_WINDOW == 5
    assert values['paper_episodes'] == 7 and values['paper_person_episodes'] == 7
    assert values['window_stopped'] and values['window_episodes'] == 6
    assert values['window_person_episodes'] == 6
    # the strict count holds the 3 judging episodes too
    assert measures(record)['total_episodes'] == 10


def test_a_window_that_never_reaches_the_fraction_keeps_the_sessions_count():
    episodes = [episode(index, 'training', 0, 0.9) for index in range(8)]
    record = session(episodes + [episode(8, 'evaluation', 0)])
    values = paper_counts(record, [item.kind for item in record.episodes])
    assert not values['window_stopped'] and values['window_episodes'] == 8


def test_sessions_without_kinds_have_no_paper_counts():
    record = session([episode(0, '', 0), episode(1, '', 0)])
    values = paper_counts(record, ['', ''])
    assert math.isnan(values['paper_episodes']) and not values['window_stopped']


def test_partners_first_counts_its_pre_training_episodes():
    # the person's session resumes the pre-trained checkpoint: its first episode is number 40
    # (robot alone and population, run in process); the person's 4 episodes stay apart
    episodes = [episode(40 + index, 'judging' if index else 'judging', 2) for index in range(4)]
    episodes.append(episode(44, 'evaluation', 2))
    record = session(episodes, case_id=8, strategy='partners_first')
    values = measures(record)
    assert values['pretraining_episodes'] == 40 and values['total_episodes'] == 44
    assert values['human_involved_episodes'] == 4
    assert values['percentage'] == pytest.approx(100 * 4 / 44)


@pytest.mark.parametrize('strategy, interval, floors', [
    ('learn_together', 2, (5, 5)),           # one step: T 2 + W 3
    ('level_guided', 2, (10, 10)),           # two steps with the person
    ('responsibility_guided', 2, (5, 10)),   # robot alone, then the person
    ('responsibility_guided', 0, (4, 8)),    # T = 1 when judging follows every update
    ('partners_first', 2, (3, 13)),          # alone 5, population 5, the person judged first 3
])
def test_the_floor_of_each_strategy(strategy, interval, floors):
    record = session([], strategy=strategy, agent={'judging_interval': interval})
    assert case_floors(record) == floors


def test_the_unit_free_error_sums_each_subtask_over_its_tolerance():
    # tolerances 0.01 m, 0.1 rad, 0.05 m: 0.005 / 0.01 + 0.05 / 0.1 + 0.01 / 0.05 = 1.2
    assert tolerance_error({'slider_error': 0.005, 'pendulum_error': 0.05,
                            'ball_error': 0.01}) == pytest.approx(1.2)


def test_a_finding_that_flips_with_units_says_so():
    # the rotation cases beat their twins in metres + radians (pendulum errors small in rad)
    # but lose once each subtask is over its tolerance (their slider errors are large in
    # tolerances of 0.01 m)
    sessions = paper_like(seeds=10)
    for record in sessions:
        rotation = record.robot_dof == 'rotation'
        slider, pendulum = (0.012, 0.02) if rotation else (0.002, 0.05)
        record.episodes = [item if item.kind != '' or not item.evaluation else EpisodeRecord(
            **{**item.__dict__, 'slider_error': slider * (1 + 0.01 * record.seed),
               'pendulum_error': pendulum, 'ball_error': 0.02,
               'total_error': slider * (1 + 0.01 * record.seed) + pendulum + 0.02})
            for item in record.episodes]
    measured = {finding.key: finding for finding in evaluate_findings(sessions)}
    unit_free = {finding.key: finding for finding in evaluate_findings(
        sessions, keys={'error': 'tolerance_error'})}
    assert measured['e'].verdict == 'holds' and unit_free['e'].verdict == 'does not hold'
    table = robustness_markdown(sessions, 'paper')
    row = next(line for line in table.splitlines() if line.startswith('| (e) |'))
    assert 'unit-free error (each subtask over its tolerance)' in row.split('|')[-2]


def test_a_compound_finding_reports_each_branch():
    # paper_like: case 5 never converges (fails: supported) and has the largest error
    findings = {finding.key: finding for finding in evaluate_findings(paper_like(seeds=8))}
    branches = findings['d'].branches
    assert branches[0].startswith('case 5 fails: supported on its own')
    assert branches[1].startswith('case 5 worst: supported on its own')
    # case 5 fastest and best: both branches refuted
    sessions = [make_session(case, seed, 0.1 if case == 5 else 0.5 + 0.01 * seed,
                             20 if case == 5 else 80 + seed, True)
                for case in range(1, 7) for seed in range(8)]
    branches = {f.key: f for f in evaluate_findings(sessions)}['d'].branches
    assert branches[0].startswith('case 5 fails: refuted on its own')
    assert 'goes the other way' in branches[0]
    assert branches[1].startswith('case 5 worst: refuted on its own')


def test_the_paper_counting_table_sets_the_three_counts_beside_the_paper():
    sessions = [make_session(2, seed, 0.3, 30 + seed, True, human_from=10, kinds=True,
                             evaluation_every=3) for seed in range(4)]
    rows = {2: [measures(record) for record in sessions]}
    table = paper_counting_markdown(rows)
    line = next(line for line in table.splitlines() if line.startswith('| 2 |'))
    assert line.endswith('| 6 / 31 |')            # the paper's case 2
    strict = sum(rows[2][i]['total_episodes'] for i in range(4)) / 4
    assert f'/ {strict:.1f}' in line.split('|')[2]


def test_a_partners_first_session_pools_by_its_own_budget():
    # its recorded limit is the pre-training's 40 episodes plus the session's 300
    from dataclasses import replace

    from hrc_bag.report.configurations import pooling_problems

    plain = make_session(2, 0, 0.3, 30, True)
    pretrained = make_session(8, 0, 0.3, 4, True, human_from=0)
    pretrained.episodes = [replace(item, episode=item.episode + 40)
                           for item in pretrained.episodes]
    pretrained.episode_limit = 340
    assert pooling_problems([plain, pretrained]) == []
    pretrained.episode_limit = 300
    assert 'their episode limits' in pooling_problems([plain, pretrained])[0]


def test_the_note_says_when_no_session_reached_the_paper_style_stop():
    never = {2: [{'window_stopped': False}, {'window_stopped': False}]}
    once = {2: [{'window_stopped': False}, {'window_stopped': True}]}
    assert paper_counting_note(never).startswith('**No session reached the paper-style stop.**')
    assert 'No session reached' not in paper_counting_note(once)
