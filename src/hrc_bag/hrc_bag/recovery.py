"""Finish an MCAP file whose writer was killed (pure, no rclpy).

A killed recorder leaves its open episode file without summary, indexes and footer; readers
that need the index (rosbags, ``ros2 bag play``) refuse it. :func:`recover_file` scans it up to
its last complete record and writes it again, finished, with the same schemas, channels
(metadata included), messages and metadata records; the original is replaced only once the new
file is complete, so a recovery that is itself interrupted loses nothing.
"""

import os
import pathlib

from hrc_bag.bag_reader import scan_records
from hrc_bag.qos_yaml import load_yaml
from hrc_bag.episode_file import EpisodeFile
from hrc_bag.format import (describe_error, EPISODE_RECORD, FileInfo, RawMessage,
                            RecordingError, ROSBAG2_RECORD, TopicDescription)


def _description(channel, schemas) -> TopicDescription:
    schema = schemas.get(channel.schema_id)
    profiles = load_yaml(channel.metadata.get('offered_qos_profiles', '') or '') or []
    return TopicDescription(
        type_name=schema.name if schema is not None else '',
        offered_qos_profiles=tuple(profiles),
        type_description_hash=channel.metadata.get('topic_type_hash', ''),
        message_definition=bytes(schema.data).decode() if schema is not None else '')


def recover_file(path, compression: str = 'zstd') -> FileInfo:
    """Rewrite an unfinished MCAP file as a finished one in place; return its info."""
    path = pathlib.Path(path)
    try:
        schemas, channels, messages, metadata, _ = scan_records(path)
    except OSError as error:
        raise RecordingError(f'cannot read {path}: {describe_error(error)}') from error
    # written again at close, from the messages
    metadata.pop(ROSBAG2_RECORD, None)
    metadata.pop(EPISODE_RECORD, None)
    temporary = path.with_name(f'.{path.name}.recovering')
    try:
        mode = path.stat().st_mode & 0o777          # a personal file stays owner-only
        if temporary.exists():
            temporary.unlink()
    except OSError as error:
        raise RecordingError(f'cannot recover {path}: {describe_error(error)}') from error
    # written under its final name: the embedded rosbag2 record names the file, not the
    # temporary one
    output = EpisodeFile(temporary, compression, metadata=metadata, name=path.name, mode=mode)
    descriptions = {}
    for message in sorted(messages, key=lambda message: message.log_time):
        channel = channels.get(message.channel_id)
        if channel is None:
            continue
        description = descriptions.get(channel.id)
        if description is None:
            description = descriptions[channel.id] = _description(channel, schemas)
        if not description.type_name:
            continue
        output.write(RawMessage(channel.topic, description.type_name, bytes(message.data),
                                message.log_time, message.publish_time, message.sequence),
                     description)
    info = output.close()
    try:
        os.replace(temporary, path)
    except OSError as error:
        raise RecordingError(f'cannot replace {path}: {describe_error(error)}') from error
    return info
