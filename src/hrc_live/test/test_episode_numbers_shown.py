"""What people read counts episodes from 1 (hrc_common.episode_numbers); data keep the index.

``hrc operator status`` said "episode 0" for the page's "Episode 1".
"""

from hrc_common.episode_numbers import episode_index, episode_number
from hrc_msgs.msg import SessionStatus
import pytest

from hrc_live.operator_cli import describe_status


def test_operator_status_names_the_episode_by_its_number():
    status = SessionStatus(session_id='s', case_id=2, episode=0, total_episodes=0)
    assert 'episode 1; 0 training episodes done' in describe_status(status)
    status.episode = 93
    assert 'episode 94; ' in describe_status(status)


def test_numbers_and_indexes_convert_both_ways():
    assert [episode_number(index) for index in (0, 93)] == [1, 94]
    assert episode_index(episode_number(41)) == 41
    with pytest.raises(ValueError, match='episode numbers start at 1, got 0'):
        episode_index(0)
