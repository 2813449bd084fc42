"""The records of the agent's steps and episodes: what :class:`AgentCore` plans and returns.

Plain dataclasses (no torch, no rclpy): an episode's plan (:class:`EpisodePlan`), one step's
decision and its reward (:class:`StepRecord`, :class:`Decision`: an AgentStep message) and a
finished episode (:class:`EpisodeResult`: an EpisodeSummary message, kept in checkpoints as
plain data by :data:`RESULT_FIELDS`).
"""

from dataclasses import dataclass

from hrc_common.contract import Phase


RESULT_FIELDS = ('episode', 'training_step', 'human_involved', 'evaluation', 'steps',
                 'terminated', 'truncated', 'episode_return', 'errors', 'robot_effort',
                 'human_effort', 'converged', 'event', 'judging', 'robot_reversals',
                 'human_reversals', 'commands_missing')
# Fields that checkpoints written before them do not hold, and the value they read as.
RESULT_DEFAULTS = {'robot_reversals': float('nan'), 'human_reversals': float('nan'),
                   'commands_missing': 0}


@dataclass(frozen=True)
class EpisodePlan:
    """What the next episode is: its index in the session, its seed, and its kind.

    ``evaluation``: the frozen policy after training (Table II); ``judging``: a deterministic
    episode during training on which the step's condition is judged; neither: training.
    """

    episode: int
    seed: int
    evaluation: bool
    training_step: int
    human_involved: bool
    judging: bool = False
    partner: str = 'person'   # who acts as the human when involved (strategies.PARTNERS)

    @property
    def with_person(self) -> bool:
        """Return True when the session's person acts in this episode (their time counts)."""
        return self.human_involved and self.partner == 'person'

    @property
    def deterministic(self) -> bool:
        """Return True when the policy's mean action is taken (no exploration, no learning)."""
        return self.evaluation or self.judging


@dataclass
class StepRecord:
    """The agent's decision in one state and the reward it earned (one AgentStep message)."""

    episode: int
    step: int
    observed_human_action: float
    action: float            # normalized command sent, in [-1, 1]
    raw_action: float        # Gaussian sample before clipping (what PPO's log-prob refers to)
    wrench: float            # N or N*m
    value: float
    log_prob: float
    deterministic: bool
    subtask_ids: tuple = ()
    reward_components: tuple = ()
    reward: float = 0.0


@dataclass
class Decision:
    """What :meth:`AgentCore.act` returns."""

    action: float            # normalized, [-1, 1], on the robot's degree of freedom
    wrench: float            # the action in N (translation) or N*m (rotation)
    record: StepRecord       # this step (its reward is filled in when the next state arrives)
    previous: StepRecord = None  # the previous step, now complete with its reward
    update: dict = None      # statistics of a PPO update whose weights took over at this step


@dataclass
class EpisodeResult:
    """Summary of a finished episode (one EpisodeSummary message) and what it changed."""

    episode: int
    training_step: int
    human_involved: bool
    evaluation: bool
    steps: int
    terminated: bool
    truncated: bool
    episode_return: float
    errors: dict             # subtask id -> mean |x - mu| over the states reached
    robot_effort: float      # variance of the robot's normalized action
    human_effort: float      # variance of the human's normalized action (of every command
    #                          applied at the human's rate when the states carry them)
    converged: bool          # the step's condition was met after this episode
    event: str               # '' | 'advanced' | 'training_finished' | 'evaluation_finished'
    last_record: StepRecord = None
    phase_after: Phase = None    # the session's phase after this episode
    judging: bool = False    # a judging episode (deterministic, counted in the totals)
    robot_reversals: float = 0.0   # reversals of the robot's command per second
    human_reversals: float = 0.0   # of the human's (hrc_common.smoothness)
    commands_missing: int = 0      # periods in which a command was late (the sim applied 0)

    def to_plain(self) -> dict:
        """Return the metrics as plain data (checkpoints; no step record)."""
        return {name: (dict(self.errors) if name == 'errors' else getattr(self, name))
                for name in RESULT_FIELDS}

    @classmethod
    def from_plain(cls, data: dict) -> 'EpisodeResult':
        """Rebuild a result saved by :meth:`to_plain`."""
        return cls(**{name: (dict(data[name]) if name == 'errors'
                             else data.get(name, RESULT_DEFAULTS.get(name)))
                      for name in RESULT_FIELDS if name in data or name in RESULT_DEFAULTS})

    @property
    def total_error(self) -> float:
        """Return the sum of the errors (mixed units, as the paper's Table II)."""
        return float(sum(self.errors.values()))
