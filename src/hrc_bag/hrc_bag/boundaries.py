"""What a message means for the episode files: the events the recorder's routing reads.

Pure (no rclpy). The node (or a synthetic session) turns each message into one of these
events, TaskState read from its CDR bytes when it can (:func:`boundary_event_of_cdr`), and
:class:`hrc_bag.recording.EpisodeRecorder` routes it.
"""

from dataclasses import dataclass
import typing

from hrc_common.contract import EPISODE_SUMMARY_TYPE, SESSION_STATUS_TYPE, TASK_STATE_TYPE

from hrc_bag import cdr_peek
from hrc_bag.format import plain_values


@dataclass(frozen=True)
class StateSeen:
    """A TaskState was received."""

    episode: int
    step: int
    final: bool                             # terminated or truncated


@dataclass(frozen=True)
class SummarySeen:
    """An EpisodeSummary was received."""

    episode: int
    session_id: str
    steps: int = -1                         # control steps of the episode (-1: not said)


@dataclass(frozen=True)
class SessionSeen:
    """A SessionStatus was received (``status``: its fields as plain Python values)."""

    status: dict


# the types whose messages mark episode boundaries (the node deserializes only these)
BOUNDARY_TYPES = (TASK_STATE_TYPE, EPISODE_SUMMARY_TYPE, SESSION_STATUS_TYPE)


def boundary_event(type_name: str, message):
    """Return the event a message of ``type_name`` means for the episode files (or None)."""
    if type_name == TASK_STATE_TYPE:
        return StateSeen(int(message.episode), int(message.step),
                         bool(message.terminated or message.truncated))
    if type_name == EPISODE_SUMMARY_TYPE:
        return SummarySeen(int(message.episode), str(message.session_id), int(message.steps))
    if type_name == SESSION_STATUS_TYPE:
        return SessionSeen(plain_values(message))
    return None


def boundary_event_of_cdr(type_name: str, data: bytes, deserialize: typing.Callable):
    """Return the event of a message given as CDR bytes (or None), deserializing only if needed.

    A TaskState (one every step) is read from its bytes (:func:`hrc_bag.cdr_peek.task_state`);
    the rare EpisodeSummary and SessionStatus, and a TaskState whose layout the reader does
    not know, are deserialized with ``deserialize(data)``.
    """
    if type_name == TASK_STATE_TYPE:
        peeked = cdr_peek.task_state(data)
        if peeked is not None:
            return StateSeen(*peeked)
    if type_name in BOUNDARY_TYPES:
        return boundary_event(type_name, deserialize(data))
    return None
