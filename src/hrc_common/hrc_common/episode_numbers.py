"""One episode numbering wherever a person or an experimenter reads it.

Data keep the 0-based episode *index*: the ``episode`` field of every message, the journals, the
checkpoints and every bag recorded so far (changing it would make old data read differently).
Everything written for people -- the person's page, the console, the runner's and the operator's
lines, bag file names, figures and tables -- shows the episode *number*, counted from 1: the
session's first episode is "episode 1", whatever its kind (practice, training, judging or
evaluation episodes all count, so a number names one recorded episode and one bag file).
"""


def episode_number(index: int) -> int:
    """Return the number people read for the episode with this 0-based index."""
    return int(index) + 1


def episode_index(number: int) -> int:
    """Return the 0-based index of the episode people call ``number`` (episode_number inverted)."""
    if int(number) < 1:
        raise ValueError(f'episode numbers start at 1, got {number}')
    return int(number) - 1
