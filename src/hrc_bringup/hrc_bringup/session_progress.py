"""What the session runner prints while a session runs: a line per episode and milestone."""

import copy
import time

from hrc_common.episode_numbers import episode_number
from hrc_common import qos, topics
from hrc_common.contract import HOLD_ABORTED, HOLD_NOT_INVOLVED, Phase, phase_label, source_label
from hrc_common.nodes import DrainedNode, take_waiting
from hrc_msgs.msg import EpisodeSummary, HumanAction, SessionStatus

# The human's actions (one per step, up to ~500 steps/s in lockstep) are taken in batches every
# ACTION_DRAIN_PERIOD_S instead of an executor turn each (the runner's turn per action
# was ~0.5 ms of CPU per step, a sixth of a lockstep session's); the reader keeps the newest
# ACTION_HISTORY, so no change of source is missed below ACTION_HISTORY / ACTION_DRAIN_PERIOD_S
# actions per second.
ACTION_DRAIN_PERIOD_S = 0.1
ACTION_HISTORY = 1000


# The label of an episode on its progress line, by EpisodeSummary.kind (0: a bag's episode from
# before the kinds were recorded: evaluation or training as the flag says).
EPISODE_LABELS = {EpisodeSummary.KIND_TRAINING: 'training', EpisodeSummary.KIND_JUDGING: 'judging',
                  EpisodeSummary.KIND_EVALUATION: 'evaluation',
                  EpisodeSummary.KIND_PRACTICE: 'practice'}


def episode_label(summary) -> str:
    """Return training, judging, evaluation or practice for an EpisodeSummary."""
    return EPISODE_LABELS.get(summary.kind,
                              'evaluation' if summary.evaluation else 'training')

class Progress:
    """Prints what happens: /hrc/session, /hrc/episode, /hrc/human/action (every 0.1 s)."""

    def __init__(self, context, interactive: bool, max_training_episodes=None,
                 evaluation_episodes: int = 0):
        """Listen on ``context``; the agent's session parameters go into the verdict.

        ``max_training_episodes`` (None: no cap) and ``evaluation_episodes`` are said when
        training ends unconverged.
        """
        self.node = DrainedNode('session_runner', context=context)
        self.interactive = interactive
        self.max_training_episodes = max_training_episodes
        self.evaluation_episodes = evaluation_episodes
        self.status = None
        self.episodes = []
        self.started = time.monotonic()
        self.alone_since = None     # (monotonic s, training episodes done) the robot went alone
        self._verdict_due = None    # the status that ended training, until its episodes are in
        self.person_joined = None   # monotonic s the person's first training step was announced
        # Why the runner paused the session for a lost input ('' = it did not): the input
        # guard's word; the agent it stops for it says "aborted", which is not what happened.
        self.paused_for_input = lambda: ''
        self.node.create_subscription(SessionStatus, topics.SESSION, self._on_status,
                                      qos.SESSION_QOS)
        self.node.create_subscription(EpisodeSummary, topics.EPISODE, self._on_episode,
                                      qos.EPISODE_QOS)
        self.input_source = None   # (source, detail) of the person's side, as last announced
        actions_qos = copy.copy(qos.HUMAN_ACTION_QOS)
        actions_qos.depth = ACTION_HISTORY
        self._actions = self.node.create_drained_subscription(HumanAction, topics.HUMAN_ACTION,
                                                              actions_qos)
        self.node.create_timer(ACTION_DRAIN_PERIOD_S, self.take_actions)

    def take_actions(self):
        """Read the human's actions that arrived since the last call, in order."""
        for action, _ in take_waiting(self._actions, ACTION_HISTORY):
            self._on_action(action)

    def _on_status(self, status):
        # Announce what changes the task for the team; the training <-> updating toggles between
        # episodes are shown on the progress line only.
        def milestone(status):
            phase = phase_label(status.phase, '?')
            if phase == 'aborted' and self.paused_for_input():
                phase = 'paused (joystick disconnected)'
            return (status.training_step, status.human_involved,
                    phase if phase not in ('training', 'updating') else 'training')

        changed = self.status is None or milestone(status) != milestone(self.status)
        if (changed and status.strategy != 'practice'
                and phase_label(status.phase, '') in ('evaluation', 'done')
                and (self.status is None or phase_label(self.status.phase, '') in (
                    'training', 'updating', 'paused'))):
            self._verdict_due = status    # said once the episodes are in
        self.status = status
        self._settle_verdict()
        self._track_person_time(status)
        if changed:
            self._print(f'[session] case {status.case_id} {status.strategy}: training step '
                        f'{status.training_step + 1}/{max(status.training_step_count, 1)}, '
                        f'phase {milestone(status)[2]}, human '
                        f'{"involved" if status.human_involved else "not involved"}, robot '
                        f'subtasks {list(status.robot_subtasks)}, human subtasks '
                        f'{list(status.human_subtasks)}', permanent=True)

    def _settle_verdict(self, final: bool = False) -> None:
        """Say whether training ended unconverged once its episode summaries are all here.

        The status that ends training and the last summaries travel on two topics: under load
        (or a runner that joined late and gets them as history) the executor may hand over the
        status first, and a verdict drawn then would read the wrong last episode and step. So
        it waits for ``total_episodes`` summaries of training; ``final`` (the session is
        closing) says it with what came.
        """
        status = self._verdict_due
        if status is None:
            return
        training = sum(1 for summary in self.episodes if not summary.evaluation)
        if training < status.total_episodes and not final:
            return
        self._verdict_due = None
        self._say_if_not_converged(status)

    def _say_if_not_converged(self, status):
        """Say when training ended without the robot converging, with the numbers."""
        training = [summary for summary in self.episodes if not summary.evaluation]
        if training and training[-1].converged:
            return
        cap = self.max_training_episodes
        current = training[-1].training_step if training else status.training_step
        step = f'training step {current + 1} of {max(status.training_step_count, 1)}'
        never = ('; the person never trained with the robot' if status.human_subtasks
                 and self.person_joined is None else '')
        # A runner that joined late may first see the session already done (the agent keeps only
        # the newest status): the test episodes follow training all the same when there are any.
        phase = phase_label(status.phase, '')
        tests_follow = phase == 'evaluation' or (
            phase == 'done' and self.evaluation_episodes > 0)
        self._print(f'[session] the robot did not converge in {status.total_episodes} '
                    f'episodes ({step}' + (f', at most {cap}' if cap else '') + ')' + never
                    + ('; the test episodes start' if tests_follow else ''), permanent=True)

    def _on_action(self, action):
        """Say which input drives the person's side whenever it changes (never silently)."""
        if action.source_detail.startswith(HOLD_NOT_INVOLVED):
            return  # zero on purpose: the person has no part in this training step
        if action.source_detail.startswith(HOLD_ABORTED) and self.paused_for_input():
            return  # the agent stopped for the lost input, not an operator's abort
        source = source_label(action.source)
        detail = action.source_detail.split(' (', 1)[0] if source != 'none' \
            else action.source_detail
        if (source, detail) != self.input_source:
            self.input_source = (source, detail)
            self._print(f'[session] the human side is driven by: {source} ({detail})',
                        permanent=True)

    def restart(self) -> None:
        """Forget the practice: the condition's clock and person time start now."""
        self.status, self.episodes, self._verdict_due = None, [], None
        self.started = time.monotonic()
        self.alone_since = self.person_joined = None

    def _track_person_time(self, status):
        """Note when the robot practises alone and when the person joins; say so once."""
        now = time.monotonic()
        if status.strategy == 'practice':
            return
        if not status.human_involved and phase_label(status.phase, '') in ('training',
                                                                            'updating'):
            if self.alone_since is None:
                self.alone_since = (now, status.total_episodes)   # (when, episodes then)
            return
        if status.human_involved and self.person_joined is None and status.phase in (
                Phase.TRAINING, Phase.UPDATING):
            self.person_joined = now
            alone = ''
            lonely = status.total_episodes - status.human_involved_episodes
            if self.alone_since is not None:
                # Counted from this one status, not from the first lonely one this runner saw:
                # a busy runner may miss statuses (the agent keeps only the newest), and every
                # episode so far without the person was the robot's own.
                alone = (f'; the robot practised alone: {lonely} episodes '
                         f'in {now - self.alone_since[0]:.0f} s')
            elif lonely > 0:
                # This runner's session reader matched the agent only after the robot's lonely
                # episodes (a short lockstep phase on a busy machine): their time is bounded by
                # the session's so far.
                alone = (f'; the robot practised alone: {lonely} episodes '
                         f'in at most {now - self.started:.0f} s')
            self._print(f'[session] the person joins now, at episode '
                        f'{status.total_episodes + 1}, {now - self.started:.0f} s after the '
                        f'start{alone}', permanent=True)

    def _on_episode(self, summary):
        if any(seen.episode == summary.episode for seen in self.episodes):
            return
        self.episodes.append(summary)
        # Training and test episodes with the person, as the page counts them.
        human_episodes = sum(s.human_involved for s in self.episodes)
        steps = max(self.status.training_step_count, 1) if self.status else 1
        case = self.status.case_id if self.status else summary.case_id
        self._print(f'[case {case} | step {summary.training_step + 1}/{steps} | episode '
                    f'{episode_number(summary.episode):3d} | {episode_label(summary)}] return '
                    f'{summary.episode_return:7.1f}  error slider '
                    f'{summary.slider_error:.3f} m  pendulum {summary.pendulum_error:.3f} rad  '
                    f'ball {summary.ball_error:.3f} m  human '
                    f'{"yes" if summary.human_involved else "no "} ({human_episodes} so far)'
                    + ('  converged' if summary.converged else ''),
                    permanent=not self.interactive or summary.evaluation or summary.converged)
        self._settle_verdict()

    def _print(self, line, permanent=True):
        """Print a line; on a terminal, a non-permanent line is overwritten by the next one."""
        if self.interactive:
            print('\r\033[K' + line, end='\n' if permanent else '', flush=True)
        else:
            print(line, flush=True)

    def close(self):
        """Say what is still due, then destroy the node."""
        self.take_actions()
        self._settle_verdict(final=True)
        self.node.destroy_node()
