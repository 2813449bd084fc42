"""The words of the person's page: banner, panel, result, countdown and the console's milestone.

Pure: computed from a :class:`hrc_live.display_core.Snapshot` (what the display node last
received). :func:`overlay` is the one place of the person's words. They are written for a
participant, not an RL engineer: an episode is a "round", a training step a "part", an
evaluation episode a "test round"; the numbers are the experimenter's (episode N on the console
and in the runner's lines is round N on the page, both counted from 1).
:class:`SteadyBanner` keeps a banner up at least ``BANNER_HOLD_S`` unless the situation (its
tone) changes, so that a person never reads a flickering text.
"""

from dataclasses import replace
import math
import re
import typing

from hrc_common.session_control import about_lost_input
from hrc_live.display_core import AgentPlan, Overlay, ResultView, SessionView, Snapshot


# What each subtask asks of the person, and what each degree of freedom gives them.
SUBTASK_WORDS = {'slider': 'keep the slider in the middle of the rod',
                 'pendulum': 'keep the pendulum level',
                 'ball': 'keep the ball in the middle of the pendulum'}
CONTROL_WORDS = {'translation': 'You move the slider up and down (stick up = up).',
                 'rotation': 'You tilt the pendulum (stick up = right end up).'}
# What the person's action does to the subtasks they are asked for, by their degree of freedom
# (the couplings of hrc_sim_node.physics: accelerating the slider up presses the beam's free,
# right end down; turning the beam pushes the slider the other way; the ball rolls toward the
# lower end of the beam).
EFFECT_WORDS = {
    ('translation', 'ball'): 'Your moves tilt the beam: a quick move up dips its right end, a '
                             'quick move down lifts it. The ball rolls toward the lower end.',
    ('translation', 'pendulum'): 'A quick move up dips the right end of the beam, a quick move '
                                 'down lifts it: move smoothly to keep it level.',
    ('rotation', 'ball'): 'The ball rolls toward the lower end of the beam: lift the end it '
                          'is rolling to.',
    ('rotation', 'slider'): 'Turning the beam fast pushes the slider the other way: turn '
                            'smoothly to keep it still.'}
BANNER_HOLD_S = 1.0     # s a banner stays up at least, unless its tone changes
ALONE_BANNER = 'The robot is practising alone: please wait'
REPLAY_BANNER = 'Replay of a recorded session: nothing you do now is used'
INVALID_STATE_NOTICE = ('The simulation sent an invalid state (not a finite number): the '
                        'picture is frozen. Operator: see the sim log.')
# What the person reads when their joystick is lost (the technical reason is on the console).
INPUT_LOST_BANNER = 'The joystick is disconnected: paused. Please wait for the operator.'
INPUT_LOST_NOTICE = ('The joystick is disconnected. Please let go of it and wait: the operator '
                     'will reconnect it and resume.')


def is_evaluating(session: SessionView, plan: typing.Optional[AgentPlan]) -> bool:
    """Return whether the current (or next) episode is a test (evaluation) episode."""
    if session.phase == 'evaluation':
        return True
    return (session.phase in ('paused', 'aborted', 'updating') and plan is not None
            and session.total_episodes < session.episode)


def episode_label(session: SessionView, plan: typing.Optional[AgentPlan]) -> str:
    """Return "Round x of at most y" (or "Test round k of n") for the current or next episode.

    Training episode x is ``total_episodes + 1``; test episode k counts from the first
    evaluation episode, whose index is the number of training episodes. The result box uses
    the same numbers (:func:`result_number`).
    """
    if session.strategy == 'practice':
        # the runner's practice: "practice: episode k of n, ..." in its message
        planned = re.search(r'episode \d+ of (\d+)', session.message)
        count = int(planned.group(1)) if planned else None
        number = session.total_episodes + 1 if count is None else min(
            session.total_episodes + 1, count)
        if count is not None and session.total_episodes >= count:
            return f'Practice: {count} rounds done'
        return f'Practice round {number}' + (f' of {count}' if count else '')
    if session.phase == 'done':
        return f'{session.total_episodes} rounds done'
    if is_evaluating(session, plan):
        index = session.episode - session.total_episodes + 1
        if plan is not None:    # never "3 of 2": a counter stays within its maximum
            index = min(index, plan.evaluation_episodes)
        total = f' of {plan.evaluation_episodes}' if plan is not None else ''
        return f'Test round {max(index, 1)}{total}'
    number = session.total_episodes + 1
    if plan is not None:
        number = min(number, plan.max_training_episodes)
    total = f' of at most {plan.max_training_episodes}' if plan is not None else ''
    return f'Round {number}{total}'


def result_number(result: ResultView, session: typing.Optional[SessionView]) -> str:
    """Return "Round x" or "Test round k" of a finished episode, numbered as the label."""
    if not result.evaluation:
        return f'Round {result.episode + 1}'
    training = session.total_episodes if session is not None else 0
    return f'Test round {result.episode - training + 1}'


def result_lines(result: ResultView, previous: typing.Optional[ResultView],
                 session: typing.Optional[SessionView] = None) -> tuple:
    """Return the short result of an episode, in the person's terms."""
    lines = [f'{result_number(result, session)} done',
             f'ball off centre: {100 * result.ball_error:.1f} cm on average',
             f'pendulum tilt: {math.degrees(result.pendulum_error):.1f} deg, '
             f'slider: {100 * result.slider_error:.1f} cm']
    if previous is not None and previous.total_error > 0 and (
            previous.evaluation == result.evaluation):
        change = (result.total_error - previous.total_error) / previous.total_error
        if change < -0.05:
            lines.append('Better than the round before.')
        elif change > 0.05:
            lines.append('Not as good as the round before.')
        else:
            lines.append('About as good as the round before.')
    if result.converged:
        lines.append('The team reached the goal of this part.')
    return tuple(lines)


def episodes_with_person(snapshot: Snapshot) -> int:
    """Return the episodes the person has played so far: training and test."""
    training = snapshot.session.human_involved_episodes if snapshot.session else 0
    return training + len(snapshot.evaluation_with_human)


def countdown_of(snapshot: Snapshot, in_episode: bool) -> typing.Optional[int]:
    """Return the whole seconds until the next episode starts, if known."""
    session, plan = snapshot.session, snapshot.plan
    if (in_episode or plan is None or plan.episode_break <= 0 or snapshot.break_started is None
            or session.phase not in ('training', 'updating', 'evaluation')):
        return None
    return max(0, math.ceil(snapshot.break_started + plan.episode_break - snapshot.now))


def role_lines(session: SessionView) -> list:
    """Return what the person does, their task and what their action does to it."""
    if not session.human_involved:
        return ['The robot works alone in this part.']
    lines = [CONTROL_WORDS.get(session.human_dof, '')]
    lines += [f'Your task: {SUBTASK_WORDS.get(subtask, subtask)}.'
              for subtask in session.human_subtasks]
    lines += [EFFECT_WORDS[(session.human_dof, subtask)] for subtask in session.human_subtasks
              if (session.human_dof, subtask) in EFFECT_WORDS]
    return lines


def panel_lines(snapshot: Snapshot, label: str, in_episode: bool) -> list:
    """Return the panel's lines: the round, the part, the role, the wait, the time left."""
    session, state, now = snapshot.session, snapshot.state, snapshot.now
    lines = [label] + (['Replay: ' + snapshot.replay] if snapshot.replay else [])
    if session.training_step_count > 1:
        lines.append(f'Part {session.training_step + 1} of {session.training_step_count}')
    lines += role_lines(session)
    if snapshot.alone is not None and (snapshot.alone.episodes or snapshot.alone.ended is None):
        lines.append(snapshot.alone.words(now, unit='round'))
        wait = alone_wait(snapshot)
        if wait is not None:
            lines.append(f'You join in at most about {wait_words(wait)} (the robot may be '
                         f'ready sooner).')
    if in_episode and session.human_involved:   # lonely episodes run faster than the clock
        steps_left = max(0, snapshot.physics.steps_per_episode - state.step)
        lines.append(f'Time left: {steps_left * snapshot.physics.control_period:.0f} s')
    lines.append(f'Rounds you played so far: {episodes_with_person(snapshot)}')
    if snapshot.result is not None:
        lines.append(f'Last round: ball {100 * snapshot.result.ball_error:.1f} cm off centre')
    return lines


def banner_of(snapshot: Snapshot, in_episode: bool, countdown) -> tuple:
    """Return (banner, tone) of ``snapshot``: what to do now, one text per situation."""
    session, phase = snapshot.session, snapshot.session.phase
    if snapshot.input_lost or (phase == 'aborted' and about_lost_input(session.message)):
        # the runner stops the agent for a lost joystick: the aborted status says so itself
        return INPUT_LOST_BANNER, 'stop'
    if snapshot.replay:
        return REPLAY_BANNER, 'info'
    if phase == 'aborted':
        return 'Stopped by the operator. Please let go of the joystick.', 'stop'
    if phase == 'done':
        return 'The session is finished. Thank you!', 'info'
    if phase == 'paused' and about_lost_input(session.message):
        # the runner's pause for a lost input: the joystick is back, the operator resumes
        return 'The joystick is connected again: please wait for the operator', 'wait'
    if phase == 'paused':
        return 'Paused by the operator: please wait', 'wait'
    if not session.human_involved:
        # one text in and between the robot's own rounds (they come many times a second)
        return ALONE_BANNER, 'wait'
    if in_episode:
        tasks = [SUBTASK_WORDS.get(subtask, subtask) for subtask in session.human_subtasks]
        return (('Your turn: ' + ' and '.join(tasks)) if tasks else 'Your turn'), 'act'
    if phase == 'updating':
        return 'The robot is learning from the last round: please wait', 'wait'
    if countdown and not snapshot.person_played and episodes_with_person(snapshot) == 0:
        return f'Get ready: your first round starts in {countdown} s', 'wait'
    if countdown:
        return f'Get ready: the next round starts in {countdown} s', 'wait'
    return 'The next round is starting', 'wait'


def overlay(snapshot: Snapshot, result_seconds: float = 5.0) -> Overlay:
    """Return the banner, panel lines, result box and countdown of ``snapshot``."""
    session, state, now = snapshot.session, snapshot.state, snapshot.now
    notice = INVALID_STATE_NOTICE if snapshot.invalid_state else ''
    if snapshot.input_lost:
        notice = INPUT_LOST_NOTICE      # the person needs no device path or FIFO detail
    if session is None:
        return Overlay('Please wait: the session is starting', 'info',
                       ('The experimenter is preparing the session.',), notice=notice)
    label = episode_label(session, snapshot.plan)
    in_episode = (state is not None and not state.final and state.episode >= session.episode
                  and not snapshot.interrupted)
    result = ()
    # The result stays up during the break and the first seconds of the next episode.
    showing_result = snapshot.result is not None and (
        not in_episode or (snapshot.episode_started is not None
                           and now - snapshot.episode_started < result_seconds))
    if showing_result:
        result = result_lines(snapshot.result, snapshot.previous_result, session)
    countdown = countdown_of(snapshot, in_episode)
    banner, tone = banner_of(snapshot, in_episode, countdown)
    lines = panel_lines(snapshot, label, in_episode)
    return Overlay(banner, tone, tuple(line for line in lines if line), result, countdown,
                   label, notice)


class SteadyBanner:
    """Holds a banner at least ``hold`` s unless its tone (the situation) changes.

    A text that would replace another of the same tone sooner waits; the newest text is then
    shown once the hold is over (:meth:`shown` is called at the words' rate).
    """

    def __init__(self, hold: float = BANNER_HOLD_S):
        self.hold = hold
        self.text, self.tone, self.since = None, None, -math.inf

    def shown(self, words: Overlay, now: float) -> Overlay:
        """Return ``words`` with the banner that is shown at ``now`` (monotonic s)."""
        changed = words.banner != self.text
        if changed and (words.tone != self.tone or now - self.since >= self.hold
                        or words.countdown is not None):
            self.text, self.tone, self.since = words.banner, words.tone, now
        return replace(words, banner=self.text, tone=self.tone)


def alone_wait(snapshot: Snapshot) -> typing.Optional[float]:
    """Return at most how many more seconds the robot practises alone (None: unknown)."""
    alone, session, plan = snapshot.alone, snapshot.session, snapshot.plan
    if alone is None or alone.ended is not None or session is None or plan is None:
        return None
    return alone.wait_estimate(snapshot.now, plan.max_training_episodes,
                               session.total_episodes)


def wait_words(seconds: float) -> str:
    """Return a wait for a person: "40 s", "3 min" (rounded up)."""
    if seconds < 90:
        return f'{max(5, 5 * math.ceil(seconds / 5)):.0f} s'
    return f'{math.ceil(seconds / 60)} min'


def milestone(snapshot: Snapshot) -> str:
    """Return what the experimenter must know about the team now (the console's line).

    The robot alone (with the wait), "the person joins now" (the first 60 s after), or "the
    robot did not converge in N episodes" once training ended without it.
    """
    session, alone, now = snapshot.session, snapshot.alone, snapshot.now
    if session is None or session.strategy == 'practice':
        return ''
    cap = snapshot.plan.max_training_episodes if snapshot.plan is not None else None
    if session.phase in ('evaluation', 'done') and snapshot.last_training_converged is False:
        return (f'the robot did not converge in {session.total_episodes} episodes'
                + (f' (at most {cap})' if cap else '')
                + ('; the person never trained with it' if session.human_involved_episodes == 0
                   and session.human_subtasks else ''))
    if alone is not None and alone.ended is None:
        wait = alone_wait(snapshot)
        return (alone.words(now).rstrip('.') + (f'; the person joins in at most about '
                                                f'{wait_words(wait)}' if wait is not None
                                                else ''))
    if alone is not None and alone.ended is not None and now - alone.ended < 60.0:
        return (f'the person joins now, at episode {alone.first_episode + alone.episodes + 1} '
                f'({alone.words(now).rstrip(".").lower()})')
    return ''
