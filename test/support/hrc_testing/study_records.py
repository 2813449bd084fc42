"""Seeded synthetic SessionRecords (no bags) for the tests of the study's findings and chooser."""

import numpy

from hrc_common.cases import paper_case_ids

from hrc_bag.report.records import case_roles, EpisodeRecord, SessionRecord, strategy_step_counts


def make_session(case_id: int, seed: int, total_error: float, episodes: int, converged: bool,
                 human_from: int = 0, profile: str = 'paper', evaluation_every: int = 0,
                 final_evaluations: int = 3, human_effort: float = 0.005,
                 rng=None, kinds: bool = False, person: int = -1) -> SessionRecord:
    """Return a session of ``episodes`` episodes before a final evaluation block.

    The human acts from episode index ``human_from`` on; every ``evaluation_every``-th episode
    of training is an evaluation episode that judges convergence (0: none); the last training
    episode carries the convergence flag when ``converged``. Final evaluation episodes have
    errors around ``total_error`` (seeded noise of 1%). With ``kinds`` the summaries say their
    kind (as bags with EpisodeSummary.kind): the evaluation episodes during training are
    'judging' (return 100, deterministic), the rest 'training' (return = episode index), the
    final block 'evaluation'; without, the kind is unknown (as older bags).
    """
    rng = rng if rng is not None else numpy.random.default_rng(seed)
    strategy, robot_dof = case_roles()[case_id]
    steps = strategy_step_counts()[strategy]
    records = []
    step_change = human_from if strategy == 'responsibility_guided' else episodes // 2
    if strategy == 'learn_together':
        step_change = 0
    for index in range(episodes):
        step = 0 if index < step_change else steps - 1
        evaluation = bool(evaluation_every) and (index + 1) % evaluation_every == 0
        records.append(EpisodeRecord(
            episode=index, training_step=step, human_involved=index >= human_from,
            evaluation=evaluation and not kinds, converged=converged and index == episodes - 1,
            episode_return=100.0 if kinds and evaluation else float(index), slider_error=0.1,
            pendulum_error=0.1, ball_error=0.1, total_error=0.3, human_effort=0.5,
            robot_effort=0.5,
            kind=('judging' if evaluation else 'training') if kinds else ''))
    for offset in range(final_evaluations):
        error = total_error * (1 + 0.01 * rng.standard_normal())
        records.append(EpisodeRecord(
            episode=episodes + offset, training_step=steps - 1, human_involved=True,
            evaluation=True, converged=False, episode_return=0.0, slider_error=error / 3,
            pendulum_error=error / 3, ball_error=error / 3, total_error=error,
            human_effort=human_effort, robot_effort=0.002,
            kind='evaluation' if kinds else ''))
    return SessionRecord(session_id=f'{profile}-case{case_id}-seed{seed}', case_id=case_id,
                         strategy=strategy, robot_dof=robot_dof, seed=seed, profile=profile,
                         episodes=records, episode_limit=300, extra={'person': person})


def paper_like(seeds: int = 10, profile: str = 'paper', seed: int = 0, flip: bool = False):
    """Return sessions in which the paper's five findings hold clearly (or ``flip`` (a), (e)).

    Errors: case 2 lowest, case 5 highest, rotation cases below their twins; case 5 never
    converges; level-guided cases converge fastest; task first has the fewest human episodes.
    """
    rng = numpy.random.default_rng(seed)
    error = {1: 0.60, 2: 0.10, 3: 0.90, 4: 0.30, 5: 1.50, 6: 0.40}
    if flip:   # the robot on translation now wins, and task first is worst
        error = {1: 0.95, 2: 1.30, 3: 0.50, 4: 0.90, 5: 0.55, 6: 1.00}
    length = {1: 120, 2: 110, 3: 60, 4: 50, 5: 300, 6: 90}
    human_episodes = {1: 20, 2: 15}      # task first: the human joins for the last ones
    sessions = []
    for case_id in paper_case_ids():   # the values above are the paper's six cases
        for person in range(seeds):
            episodes = int(length[case_id] * rng.uniform(0.8, 1.2)) if case_id != 5 else 300
            sessions.append(make_session(
                case_id, person, error[case_id] * rng.uniform(0.9, 1.1), episodes,
                converged=case_id != 5,
                human_from=episodes - human_episodes[case_id] if case_id in human_episodes
                else 0,
                profile=profile, rng=rng))
    return sessions
