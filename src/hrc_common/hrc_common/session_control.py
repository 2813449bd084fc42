"""Operator controls of a session: the agent's services and the exit code of an operator abort.

The agent owns the episode loop, so it serves the controls (``std_srvs/srv/Trigger``):

* ``/hrc/agent/pause``: pause at the next episode boundary (phase ``paused`` on /hrc/session;
  the agent does not reset the sim until resumed);
* ``/hrc/agent/resume``: continue (or cancel a pause that has not taken effect yet);
* ``/hrc/agent/abort``: stop now (safety): the agent sends a zero wrench, announces phase
  ``aborted``, keeps its last episode-end checkpoint and exits with :data:`EXIT_OPERATOR_ABORT`;
  the sim holds and the human node sends zero when they see the phase.
"""

PAUSE_SERVICE = '/hrc/agent/pause'
RESUME_SERVICE = '/hrc/agent/resume'
ABORT_SERVICE = '/hrc/agent/abort'
OPERATOR_SERVICES = {'pause': PAUSE_SERVICE, 'resume': RESUME_SERVICE, 'abort': ABORT_SERVICE}
# The session runner's abort for a lost joystick: as ``abort``, but the aborted status says why
# (STOPPED_FOR_INPUT in its message), so every reader tells a lost joystick from an operator's
# abort from that one message, never from which of two topics arrived first.
STOP_FOR_INPUT_SERVICE = '/hrc/agent/stop_for_input'
# What every status about a lost joystick says (the agent's aborted one, the runner's paused
# stand-in): readers tell it from an operator's abort or pause by these words alone.
LOST_INPUT_WORDS = 'joystick disconnected'
STOPPED_FOR_INPUT = f'for the lost input ({LOST_INPUT_WORDS}), by the session runner'


def about_lost_input(message: str) -> bool:
    """Return True when a session status's message is about a lost joystick."""
    return LOST_INPUT_WORDS in message.lower()

# Exit code of the agent (and of the session runner) after an operator abort: a clean,
# requested stop that can be resumed, distinct from success (0), a failure (1) and bad
# parameters (2, hrc_common.nodes.EXIT_BAD_PARAMETERS).
EXIT_OPERATOR_ABORT = 3

# Checkpoint file names in <checkpoint_dir>/<session_id>/, written by the agent node and the
# in-process engine alike: at every episode end (the one to resume from), and once at the end
# of training.
LATEST_CHECKPOINT = 'latest.pt'
FINAL_CHECKPOINT = 'final.pt'
