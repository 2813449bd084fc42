"""Parameters of the recorder node (pure, no rclpy): node ``recorder``, params/recorder.yaml."""

from dataclasses import dataclass

from hrc_common.contract import id_problem
from hrc_common.params import param
from hrc_common.topics import (AGENT_STEP, EPISODE, HUMAN_ACTION, HUMAN_CMD_WRENCH,
                               JOINT_STATES, ROBOT_CMD_WRENCH, ROBOT_DESCRIPTION, SESSION, STATE)

DEFAULT_TOPICS = [STATE, ROBOT_CMD_WRENCH, HUMAN_CMD_WRENCH, HUMAN_ACTION, SESSION, EPISODE,
                  AGENT_STEP, JOINT_STATES, ROBOT_DESCRIPTION]


@dataclass
class RecorderParams:
    """Parameters of the recorder node (node ``recorder``, params/recorder.yaml)."""

    output_dir: str = param(
        'bags', 'folder that receives one subfolder per session (created if missing)')
    session_id: str = param(
        '', 'session folder and file name prefix (the contract id rule: 1..64 letters, '
        "digits, '_', '.', '-'); empty: the "
        'session_config session_id, else the first /hrc/session, else the start time')
    session_config: str = param(
        '', 'YAML file with the session configuration (case, strategy, roles, seeds, every '
        "node's parameters, package version) stored in every file; empty: what the recorder "
        'knows')
    topics: list = param(
        list(DEFAULT_TOPICS), 'topics to record; /hrc topics are subscribed at once, others '
        'when a publisher shows their type')
    compression: str = param('zstd', 'chunk compression', choices=('zstd', 'lz4', 'none'))
    chunk_size: int = param(
        262144, 'a chunk is closed when it holds this many bytes (B)', low=1024,
        high=64 * 1024 * 1024)
    flush_period: float = param(
        0.1, 'the open chunk is written at least this often (s); a SIGKILL loses at most this '
        'much (plus reorder_window) of the open episode', low=0.02, high=60.0)
    close_grace: float = param(
        0.0, 'an episode file closes this long (s) after its EpisodeSummary (the last message '
        'of an episode) is handled; a later message of the episode goes to the newest file',
        low=0.0, high=10.0)
    summary_timeout: float = param(
        5.0, 'an episode file closes this long (s) after its final state if no EpisodeSummary '
        'comes', low=0.1, high=600.0)
    reorder_window: float = param(
        0.2, 'messages are handled in the order DDS received them, after waiting this long (s) '
        'for those the executor serves late (it serves topics in its own order)', low=0.0,
        high=10.0)
    max_buffered: int = param(
        100000, 'messages kept in memory between episodes; beyond, the oldest are dropped '
        'with an error log', low=100, high=10_000_000)
    recover: bool = param(
        True, 'at start, finish the files of this session that a killed recorder left open')
    subscription_depth: int = param(
        1000, 'history depth of the recording subscriptions', low=1, high=100000)
    batch_period: float = param(
        0.05, 'the recording subscriptions are drained this often (s), all their waiting '
        'messages in one batch (not an executor turn and a callback per message: the '
        "recorder's cost); at least twice per flush_period; longer costs less CPU and adds to "
        'what a SIGKILL can lose of the open episode', low=0.001, high=1.0)
    exit_after_session: bool = param(
        True, 'exit once the agent says the session is done (phase done on /hrc/session), as a '
        'node started by hand should; hrc session turns it off for the nodes it stops itself')
    discovery_period: float = param(
        0.5, 'period (s) of the graph check for topics of not yet known type', low=0.05,
        high=10.0)

    def check(self):
        """Return the reasons why fields that depend on each other are bad."""
        reasons = []
        problem = id_problem(self.session_id, 'session_id') if self.session_id else None
        if problem:
            reasons.append(f'{problem} (it names the session folder and the files)')
        if not self.topics:
            reasons.append('topics: at least one topic is needed')
        if len(set(self.topics)) != len(self.topics):
            reasons.append(f'topics: listed twice in {self.topics}')
        if not self.output_dir:
            reasons.append('output_dir: must not be empty')
        return reasons
