"""One episode numbering wherever a person or an experimenter reads it.

Data keep the 0-based episode *index*: the ``episode`` field of every message, the journals and
the checkpoints. What is written for people -- the person's page, the runner's lines, the
session status the agent announces (the console shows it), ``hrc operator status``, the
report's notices and the bag file names (``<session>_episode0001.mcap``; folders written before
hrc 1.0 hold ``<session>_ep0000.mcap``, by index, and are still read) -- shows the episode
*number*, counted from 1: the session's first
episode is "episode 1", whatever its kind (practice, training, judging or evaluation episodes
all count, so a number names one recorded episode). The console labels its number "from 1, as
on the page"; the report's figures count episodes from 1 too.
"""


def episode_number(index: int) -> int:
    """Return the number people read for the episode with this 0-based index."""
    return int(index) + 1


def episode_index(number: int) -> int:
    """Return the 0-based index of the episode people call ``number`` (episode_number inverted)."""
    if int(number) < 1:
        raise ValueError(f'episode numbers start at 1, got {number}')
    return int(number) - 1
