"""What the report uses of one session, and the per-session measures (pure, no ROS).

A :class:`SessionRecord` is the list of a session's episode summaries plus what identifies it
(case, strategy, roles, seed, simulated-human profile, learning configuration). :func:`measures`
turns it into the values of Table II and the three factors. :func:`load_records` fills records
from bags (through :mod:`hrc_bag.report.loading`); tests may build them directly. The report
(``hrc bag report``) and the study (``hrc results``) both compute from these.

Definitions (the study's rules, see docs/results.md):

* The final evaluation block: the evaluation episodes after training ended (the frozen policy
  evaluated for Table II's performance and effort). The deterministic episodes run *during*
  training to judge convergence (the agent's judging episodes; their summaries are not marked
  as evaluation) are part of training: they count in the episode total, and as human-involved
  whenever the human acted in them (the person's time is the burden metric).
* Episodes to convergence: every episode before the final block; "converged" when an episode
  of the strategy's last training step carries the convergence flag. A session that stopped at
  the episode limit without it is right-censored at its episode count (and so is its count of
  human-involved episodes).
* Episode kinds (``EpisodeSummary.kind``: training, judging, evaluation, practice): when the
  summaries say, the final block starts at the first evaluation episode and practice episodes
  count in neither the training totals nor the final block. Bags recorded before the field
  (kind unknown, ``EpisodeRecord.kind == ''``): the rule above, and every non-evaluation
  episode reads as training (judging episodes cannot be told apart there).
"""

from dataclasses import dataclass, field
import functools
import math

from hrc_common import bounded_yaml
from hrc_common.cases import case_table, cases_file_path
from hrc_common.contract import EpisodeKind
from hrc_common.smoothness import chatters

from hrc_bag.report.counting import (case_floors, episodes_before, paper_counts,
                                     tolerance_error)
from hrc_bag.report.loading import load_sessions
from hrc_bag.report.session_config import (episode_limit_of, episode_seconds_of, learning_of,
                                           limits_of, nested, person_of, profile_of,
                                           UNRECORDED)

STRATEGY_ORDER = ['responsibility_guided', 'level_guided', 'learn_together']
STRATEGY_SHORT = {'responsibility_guided': 'task first', 'level_guided': 'human first',
                  'learn_together': 'together'}
ERROR_KEYS = ('slider_error', 'pendulum_error', 'ball_error', 'total_error')
EFFORT_KEYS = ('human_effort', 'robot_effort')
REVERSAL_KEYS = ('human_reversals', 'robot_reversals')   # per second, hrc_common.smoothness
# Effort in physical units: the variance of the command in N^2 (translation, the slider's
# force) or (N*m)^2 (rotation, the pendulum's torque) = variance of the normalized command
# times the limit squared (the sim's max_force / max_torque: a normalized 1 is the limit).
PHYSICAL_EFFORT_KEYS = ('human_effort_physical', 'robot_effort_physical')
EFFORT_UNITS = {'translation': 'N^2', 'rotation': '(N*m)^2'}


@functools.lru_cache(maxsize=None)
def strategy_step_counts() -> dict:
    """Return {strategy: its number of training steps} (``params/cases.yaml``).

    The last step's convergence ends training.
    """
    with open(cases_file_path(), 'rb') as stream:
        strategies = bounded_yaml.load(stream.read(), str(cases_file_path()))['strategies']
    return {name: len(strategy['steps']) for name, strategy in strategies.items()}


def case_roles() -> dict:
    """Return {case id: (strategy, robot DOF)} of the paper's cases (``params/cases.yaml``)."""
    return {case_id: (spec.strategy, spec.robot_dof) for case_id, spec in case_table().items()}


@dataclass(frozen=True)
class EpisodeRecord:
    """One episode summary (the fields of hrc_msgs/EpisodeSummary the study uses)."""

    episode: int
    training_step: int
    human_involved: bool
    evaluation: bool
    converged: bool
    episode_return: float
    slider_error: float
    pendulum_error: float
    ball_error: float
    total_error: float
    human_effort: float
    robot_effort: float
    final_evaluation: bool = None   # None: unknown, inferred (see final_block)
    kind: str = ''                  # training | judging | evaluation | practice; '' unknown
    steps: int = 0                  # control steps in the episode (0: unknown)
    robot_reversals: float = math.nan   # per second (hrc_common.smoothness; NaN: not recorded)
    human_reversals: float = math.nan
    commands_missing: int = 0       # periods whose command came late (the sim applied 0)


KINDS = ('training', 'judging', 'evaluation', 'practice')


def record_kind(episode: EpisodeRecord) -> str:
    """Return the episode's kind: its own when known, else evaluation or training (old bags)."""
    if episode.kind in KINDS:
        return episode.kind
    return 'evaluation' if episode.evaluation else 'training'


def kinds_known(session) -> bool:
    """Return whether the session's summaries say their kind (bags with EpisodeSummary.kind)."""
    return any(episode.kind in KINDS for episode in session.episodes)


@dataclass
class SessionRecord:
    """One session: a case, a seed (a simulated person), its episodes in order."""

    session_id: str
    case_id: int
    strategy: str
    robot_dof: str
    seed: int
    profile: str
    episodes: list                  # EpisodeRecord, ordered by episode
    step_count: int = 0             # training steps of the strategy (0: from cases.yaml)
    episode_limit: int = 0          # the agent's max_training_episodes (0: unknown)
    path: str = ''
    extra: dict = field(default_factory=dict)
    learning: str = UNRECORDED      # the learning configuration's name (session.yaml)
    learning_settings: dict = field(default_factory=dict)

    @property
    def steps(self) -> int:
        """Return the number of training steps of the session's strategy."""
        return self.step_count or strategy_step_counts().get(self.strategy, 1)


@functools.lru_cache(maxsize=1)
def default_limits() -> dict:
    """Return the sim's default command limits {dof: N or N*m} (hrc_sim_node's PhysicsParams)."""
    from hrc_sim_node.physics import PhysicsParams  # lazy: only for sessions without limits
    params = PhysicsParams()
    return {'translation': float(params.max_force), 'rotation': float(params.max_torque)}


def command_limits(session: SessionRecord) -> dict:
    """Return {dof: limit} of a session: its recorded sim parameters, else the sim's defaults."""
    return {**default_limits(), **session.extra.get('limits', {})}


def other_dof_of(dof: str) -> str:
    """Return the degree of freedom the other actor drives."""
    return 'rotation' if dof == 'translation' else 'translation'


def final_block_start(session: SessionRecord) -> int:
    """Return the index in ``session.episodes`` where the final evaluation block starts.

    When the episodes say which are final evaluation (``final_evaluation`` set), that decides.
    Otherwise: the trailing run of evaluation episodes, less a leading episode that carries the
    convergence flag (that one judged convergence during training).
    """
    episodes = session.episodes
    if kinds_known(session):
        kinds = [record_kind(episode) for episode in episodes]
        return kinds.index('evaluation') if 'evaluation' in kinds else len(episodes)
    if any(episode.final_evaluation is not None for episode in episodes):
        flags = [bool(episode.final_evaluation) for episode in episodes]
        return flags.index(True) if True in flags else len(episodes)
    start = len(episodes)
    while start > 0 and episodes[start - 1].evaluation:
        start -= 1
    if start < len(episodes) and episodes[start].converged and \
            episodes[start].training_step == session.steps - 1:
        start += 1
    return start


def measures(session: SessionRecord) -> dict:
    """Return the per-session values of Table II and the three factors (NaN: no data).

    Keys: human_involved_episodes (the person's episodes), total_episodes (every episode of
    training: the judging episodes run during training and the pre-training's episodes before
    the bags, not practice), pretraining_episodes, percentage, converged (bool), the four errors
    and two efforts (means over the final evaluation block), tolerance_error (the unit-free
    total, :func:`hrc_bag.report.counting.tolerance_error`), evaluation_episodes,
    practice_episodes, person_minutes (the human-involved episodes at the session's episode
    duration), the efforts in physical units (``*_effort_physical``: N^2 or (N*m)^2, see
    PHYSICAL_EFFORT_KEYS), each actor's reversals per second and whether the robot chatters
    (``robot_chatters``: above the human rate, :mod:`hrc_common.smoothness`), the floors of the
    strict rule and the counts above them, and the paper's counting
    (:func:`hrc_bag.report.counting.paper_counts`).
    """
    start = final_block_start(session)
    before, final = session.episodes[:start], session.episodes[start:]
    training = [episode for episode in before if record_kind(episode) != 'practice']
    final = [episode for episode in final if record_kind(episode) != 'practice']
    # Table II over the complete evaluation episodes (every command arrived) when there are any
    complete = [episode for episode in final if not episode.commands_missing]
    incomplete = len(final) - len(complete)
    final = complete or final
    involved = sum(1 for episode in training if episode.human_involved)
    last_step = session.steps - 1
    converged = any(episode.converged and episode.training_step == last_step
                    for episode in training)
    pretraining = episodes_before(session)
    values = {
        'human_involved_episodes': float(involved),
        'total_episodes': float(len(training) + pretraining),
        'pretraining_episodes': float(pretraining),
        'percentage': 100.0 * involved / (len(training) + pretraining) if training
        else math.nan,
        'converged': converged,
        'evaluation_episodes': float(len(final)),
        'incomplete_evaluations': float(incomplete),
        'practice_episodes': float(len(session.episodes) - len(training) - len(final)),
        # What a lab budgets for the person: their episodes during training at the session's
        # episode duration, breaks and the final evaluation excluded (NaN: duration unknown).
        'person_minutes': involved * session.extra.get('episode_seconds', math.nan) / 60.0,
    }
    for key in ERROR_KEYS + EFFORT_KEYS + REVERSAL_KEYS:
        samples = [getattr(episode, key) for episode in final]
        values[key] = sum(samples) / len(samples) if samples else math.nan
    values['robot_chatters'] = chatters(values['robot_reversals'])
    values['tolerance_error'] = tolerance_error(values)
    limits = command_limits(session)
    values['robot_effort_physical'] = values['robot_effort'] * limits.get(
        session.robot_dof, math.nan) ** 2
    values['human_effort_physical'] = values['human_effort'] * limits.get(
        other_dof_of(session.robot_dof), math.nan) ** 2
    person_floor, floor = case_floors(session)
    values.update(person_floor=float(person_floor), episode_floor=float(floor),
                  human_involved_above_floor=values['human_involved_episodes'] - person_floor,
                  episodes_above_floor=values['total_episodes'] - floor)
    known = kinds_known(session)
    values.update(paper_counts(session, [episode.kind if known else ''
                                         for episode in session.episodes]))
    return values


def case_label(case_id: int, profile: str = '') -> str:
    """Return e.g. 'case 2' or 'case 2 (symmetric)'."""
    return f'case {case_id}' + (f' ({profile})' if profile and profile != 'paper' else '')


def record_from_bag_session(session) -> SessionRecord:
    """Convert a loaded bag :class:`hrc_bag.report.loading.Session` into a SessionRecord."""
    episodes = [EpisodeRecord(
        episode=int(summary.episode), training_step=int(summary.training_step),
        human_involved=bool(summary.human_involved), evaluation=bool(summary.evaluation),
        converged=bool(summary.converged), episode_return=float(summary.episode_return),
        slider_error=float(summary.slider_error), pendulum_error=float(summary.pendulum_error),
        ball_error=float(summary.ball_error), total_error=float(summary.total_error),
        human_effort=float(summary.human_effort), robot_effort=float(summary.robot_effort),
        final_evaluation=_final_flag(summary), kind=_kind_label(summary),
        steps=int(getattr(summary, 'steps', 0) or 0),
        robot_reversals=float(getattr(summary, 'robot_reversals', math.nan)),
        human_reversals=float(getattr(summary, 'human_reversals', math.nan)),
        commands_missing=int(getattr(summary, 'commands_missing', 0) or 0))
        for summary in session.summaries]
    strategy, robot_dof = case_roles().get(session.case_id, (session.strategy, session.robot_dof))
    try:
        seed = int(session.seed)
    except ValueError:
        seed = -1
    step_count = max((int(status.training_step_count) for status in session.statuses),
                     default=0)
    learning, settings = learning_of(session.config)
    return SessionRecord(session_id=session.session_id, case_id=session.case_id,
                         strategy=session.strategy or strategy,
                         robot_dof=session.robot_dof or robot_dof, seed=seed,
                         profile=profile_of(session.config), episodes=episodes,
                         step_count=step_count,
                         episode_limit=episode_limit_of(session.config),
                         path=str(session.path),
                         extra={'bag_session': session, 'person': person_of(session.config),
                                'subject_id': str(session.config.get('subject_id') or ''),
                                'limits': limits_of(session.config),
                                'episode_seconds': episode_seconds_of(session.config),
                                'agent': nested(session.config, 'parameters', 'agent',
                                                default={}) or {}},
                         learning=learning, learning_settings=settings)


def _kind_label(summary) -> str:
    """Return the summary's kind label, '' when it does not say (bags before the field)."""
    try:
        kind = EpisodeKind(int(getattr(summary, 'kind', 0)))
    except ValueError:
        return ''
    return '' if kind is EpisodeKind.UNKNOWN else kind.label


def _final_flag(summary):
    """Return the summary's own final-evaluation flag if the message has one, else None."""
    for name in ('final_evaluation', 'final'):
        if hasattr(summary, name):
            return bool(getattr(summary, name))
    return None


def session_order(record) -> tuple:
    """Return the key sessions are listed by: profile, case, seed, session id."""
    return (record.profile, record.case_id, record.seed, record.session_id)


def load_records(paths, log=print) -> list:
    """Return a SessionRecord per session under ``paths`` (sorted by :func:`session_order`).

    The sessions are read by :func:`hrc_bag.report.loading.load_sessions` (its notices and
    skipped sessions go to ``log``; a path without sessions raises FileNotFoundError, files
    that are not MCAP raise ``hrc_bag.bag_reader.BagError`` with every reason).
    """
    records = [record_from_bag_session(session) for session in load_sessions(paths, log)]
    records.sort(key=session_order)
    return records
