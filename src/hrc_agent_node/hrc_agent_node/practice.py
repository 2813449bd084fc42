"""The practice phase: the person alone on their degree of freedom before a live condition.

Pure (no rclpy): the agent node runs it when its parameter ``practice_episodes`` is N > 0 (the
session runner's ``--practice N``), instead of a training session. The robot does not act and
learns nothing; the agent only drives the episodes, as it does in a session, so it stays the
one publisher of ``/hrc/session``:

* it announces the practice (strategy ``practice``, one step, the person involved on the
  subtask of their degree of freedom: :func:`practice_subtask`) before the first episode and
  after each one, with the episodes done so far;
* it resets the sim for each episode in realtime (seed -1: the sim's own sequence, as the
  session runner's practice did), ``episode_break`` wall seconds apart;
* at each episode's final state it publishes an ``EpisodeSummary`` of kind ``practice``
  (the errors of the states reached; no return, no effort: the robot did not act), so the
  practice's episodes are labelled as practice wherever they are read.

The practice is recorded as its own session ``<session-id>-practice`` (the runner's choice).
"""

from dataclasses import dataclass, field

from hrc_common.contract import DOF_INDEX, EpisodeKind, Phase

# Subtasks whose mean error an EpisodeSummary carries (its fields <id>_error).
SUMMARY_SUBTASKS = ('slider', 'pendulum', 'ball')
STRATEGY = 'practice'


def practice_subtask(human_dof: str) -> str:
    """Return the subtask the person holds alone on their degree of freedom."""
    return 'slider' if human_dof == 'translation' else 'pendulum'


@dataclass(frozen=True)
class PracticeReset:
    """The reset that starts a practice episode (ResetEpisode request fields)."""

    seed: int
    episode: int
    clock_mode: str


@dataclass
class PracticeRun:
    """Counts the practice's episodes and says what the agent publishes for them.

    ``error(subtask_id, state)`` is the task tree's |x - mu| (the same errors a session's
    summaries carry).
    """

    episodes: int
    session_id: str
    case_id: int
    robot_dof: str
    human_dof: str
    error: object
    done: int = 0                    # episodes finished
    in_episode: bool = False
    error_sums: dict = field(default_factory=dict)
    states_reached: int = 0
    last_step: int = -1

    def __post_init__(self):
        if self.episodes < 1:
            raise ValueError(f'a practice needs at least one episode, got {self.episodes}')

    @property
    def finished(self) -> bool:
        """Return True once every practice episode has run."""
        return self.done >= self.episodes

    @property
    def subtask(self) -> str:
        """Return the subtask the person holds."""
        return practice_subtask(self.human_dof)

    def message(self) -> str:
        """Return the status message the person's page and the console show."""
        return (f'practice: episode {min(self.done + 1, self.episodes)} of {self.episodes}, '
                f'the person alone (the robot does not act)')

    def status(self) -> dict:
        """Return the fields of the SessionStatus announcing the practice now."""
        return dict(session_id=self.session_id, case_id=self.case_id, strategy=STRATEGY,
                    training_step=0, training_step_count=1,
                    robot_dof=DOF_INDEX[self.robot_dof], human_dof=DOF_INDEX[self.human_dof],
                    human_involved=True, robot_subtasks=[], human_subtasks=[self.subtask],
                    episode=self.done, total_episodes=self.done,
                    human_involved_episodes=self.done, phase=int(Phase.TRAINING),
                    message=self.message())

    def start_episode(self) -> PracticeReset:
        """Begin the next practice episode; return its reset (realtime, the sim's seed)."""
        if self.finished:
            raise RuntimeError('the practice has run all its episodes')
        self.in_episode = True
        self.error_sums = {subtask: 0.0 for subtask in SUMMARY_SUBTASKS}
        self.states_reached, self.last_step = 0, -1
        return PracticeReset(seed=-1, episode=self.done, clock_mode='realtime')

    def on_state(self, state):
        """Take a state of the running episode; return the summary fields at its final state.

        Returns None for any other state (and for a state of another episode or one seen
        before). The errors are means over the states reached after step 0.
        """
        if not self.in_episode or state.episode != self.done or state.step <= self.last_step:
            return None
        self.last_step = state.step
        if state.step > 0:
            self.states_reached += 1
            for subtask in SUMMARY_SUBTASKS:
                self.error_sums[subtask] += self.error(subtask, state)
        if not (state.truncated or state.terminated):
            return None
        errors = {subtask: total / max(self.states_reached, 1)
                  for subtask, total in self.error_sums.items()}
        summary = dict(session_id=self.session_id, case_id=self.case_id, episode=self.done,
                       training_step=0, human_involved=True, evaluation=False,
                       kind=int(EpisodeKind.PRACTICE), steps=int(state.step),
                       terminated=bool(state.terminated), truncated=bool(state.truncated),
                       episode_return=0.0, total_error=float(sum(errors.values())),
                       robot_effort=0.0, human_effort=0.0, converged=False,
                       **{f'{subtask}_error': float(value) for subtask, value in errors.items()})
        self.done += 1
        self.in_episode = False
        return summary
