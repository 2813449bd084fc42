"""What the display's pure core is fed in its tests: a session status as the display reads it."""

from hrc_live.display_core import SessionView


def case2_view(**changes) -> SessionView:
    """Case 2's status in its joint step: the person on the slider, for the slider and the ball."""
    values = dict(session_id='case2-seed0', case_id=2, strategy='responsibility_guided',
                  training_step=1, training_step_count=2, human_dof='translation',
                  human_involved=True, human_subtasks=('slider', 'ball'), episode=9,
                  total_episodes=9, human_involved_episodes=0, phase='training')
    values.update(changes)
    return SessionView(**values)
