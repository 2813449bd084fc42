"""The session folder's metadata.yaml: rosbag2's bag metadata of the closed files (pure).

rosbag2 metadata version 9 (storage ``mcap``), as ``ros2 bag`` and rosbags read it:
:func:`bag_metadata` builds it for a list of closed files (:class:`hrc_bag.format.FileInfo`),
:func:`dump_bag_metadata` writes its text without dumping every closed file again, and
:class:`SessionIndex` keeps the session's list, continues one an earlier recorder left and
rewrites the file atomically at each closed file. Each episode file also embeds its own
metadata (the ``rosbag2`` record, :class:`hrc_bag.episode_file.EpisodeFile`).
"""

import os
import pathlib

from hrc_common.contract import atomic_write, PUBLIC_FILE_MODE
import yaml

from hrc_bag.format import (BAG_VERSION, describe_error, FileInfo, MESSAGE_ENCODING,
                            METADATA_FILE, RecordingError, STORAGE_IDENTIFIER,
                            TopicDescription)
from hrc_bag.qos_yaml import dump_profiles, dump_yaml, load_yaml
from hrc_common import bounded_yaml


def topic_metadata(topic: str, description: TopicDescription) -> dict:
    """Return the rosbag2 ``topic_metadata`` mapping of a topic (metadata version 9)."""
    return {
        'name': topic,
        'type': description.type_name,
        'serialization_format': MESSAGE_ENCODING,
        'offered_qos_profiles': [dict(profile) for profile in description.offered_qos_profiles],
        'type_description_hash': description.type_description_hash,
    }


def topic_entries(info: FileInfo) -> list:
    """Return the (topic, TopicDescription, message count) entries of one file."""
    return [(topic, info.topics[topic], count) for topic, count in info.topic_counts.items()]


def description_key(topic: str, description: TopicDescription) -> tuple:
    """Return what makes two topic entries of metadata.yaml the same entry."""
    return (topic, description.type_name, dump_profiles(description.offered_qos_profiles),
            description.type_description_hash)


def bag_metadata(files: list, entries: list, custom_data: dict) -> dict:
    """Return rosbag2's ``rosbag2_bagfile_information`` for ``files`` (FileInfo, in order).

    ``entries`` are (topic, TopicDescription, message count). A topic whose publishers offered
    other QoS profiles in another file gets an entry per variant, so that readers which match
    a file's channels to metadata.yaml's topics (rosbags) find every message.
    """
    non_empty = [info for info in files if info.message_count]
    start = min((info.start for info in non_empty), default=0)
    end = max((info.end for info in non_empty), default=0)
    return {
        'version': BAG_VERSION,
        'storage_identifier': STORAGE_IDENTIFIER,
        'duration': {'nanoseconds': end - start},
        'starting_time': {'nanoseconds_since_epoch': start},
        'message_count': sum(info.message_count for info in files),
        'topics_with_message_count': [
            {'topic_metadata': topic_metadata(topic, description), 'message_count': count}
            for topic, description, count in sorted(entries, key=lambda entry: entry[0])],
        'compression_format': '',           # chunks are compressed inside the MCAP files
        'compression_mode': '',
        'relative_file_paths': [info.name for info in files],
        'files': [{'path': info.name,
                   'starting_time': {'nanoseconds_since_epoch': info.start},
                   'duration': {'nanoseconds': info.end - info.start},
                   'message_count': info.message_count} for info in files],
        'custom_data': {str(key): str(value) for key, value in custom_data.items()} or None,
        'ros_distro': os.environ.get('ROS_DISTRO', 'jazzy'),
    }


# metadata.yaml's two lists that grow with every closed file. The whole document was dumped
# again at every close: the pure-Python YAML representer over every file so far, 4.8 ms at 100
# files and 14 ms at 300 (quadratic over a session, 12% of the recorder's Python in a
# 30-episode session); each file's lines are dumped once now and joined.
GROWING_LISTS = ('relative_file_paths', 'files')


def dump_bag_metadata(files: list, entries: list, custom_data: dict, cache: dict) -> str:
    """Return metadata.yaml's text: ``dump_yaml`` of ``bag_metadata``, the same text.

    ``cache`` (a dict the caller keeps between calls) holds each file's lines of the two lists
    that grow with the session, dumped once each; the rest is dumped every time.
    """
    information = bag_metadata(files, entries, custom_data)
    placeholders = {key: f'HRCGROWINGLIST{index}' for index, key in enumerate(GROWING_LISTS)}
    lists = {key: information[key] for key in GROWING_LISTS}
    information.update(placeholders)
    text = dump_yaml({'rosbag2_bagfile_information': information})
    for key in GROWING_LISTS:
        if not lists[key]:
            lines = f'  {key}: []\n'
        else:
            items = []
            for info, item in zip(files, lists[key]):
                cache_key = (key, info.name, info.start, info.end, info.message_count)
                if cache_key not in cache:
                    # a sequence inside a mapping is written without indentation of its own
                    # ("  files:" then "  - path: ..."): the item's lines indented by two
                    cache[cache_key] = ''.join('  ' + line for line in
                                               dump_yaml([item]).splitlines(keepends=True))
                items.append(cache[cache_key])
            lines = f'  {key}:\n' + ''.join(items)
        text = text.replace(f'  {key}: {placeholders[key]}\n', lines, 1)
    return text


def custom_data_of(information: dict) -> dict:
    """Return the custom_data mapping of a rosbag2 metadata dict (or {})."""
    custom = information.get('custom_data') if isinstance(information, dict) else None
    return dict(custom) if isinstance(custom, dict) else {}


class SessionIndex:
    """The session folder's metadata.yaml: the closed files of the session, in order.

    An existing metadata.yaml (an earlier recorder of the same session) is continued; one
    that cannot be used (unreadable, not YAML, not a mapping, wrong shape) is set aside:
    ``problem`` says why, and the files it listed are listed again by whoever finds them
    (the recorder's recovery lists every MCAP file it finds unlisted).
    """

    def __init__(self, folder, custom_data: dict, mode: int = PUBLIC_FILE_MODE):
        self.folder = pathlib.Path(folder)
        self.path = self.folder / METADATA_FILE
        self.custom_data = dict(custom_data)
        self.mode = mode
        self.files = []
        self.problem = ''
        self._entries = {}                  # description_key -> [topic, description, count]
        self._file_lines = {}               # dump_bag_metadata's cache of each file's lines
        if self.path.is_file():
            try:
                self._load()
            except (OSError, UnicodeDecodeError, ValueError, KeyError, TypeError,
                    AttributeError) as error:
                self.problem = f'{self.path} cannot be used ({error}): rebuilt from the files'
                self.files, self._entries = [], {}

    def _load(self) -> None:
        """Continue a session an earlier recorder started (its closed files stay listed)."""
        try:
            document = load_yaml(self.path.read_text())
        except yaml.YAMLError as error:
            raise ValueError(f'not YAML: {bounded_yaml.describe(error)}') from None
        if document is None:
            return
        if not isinstance(document, dict):
            raise ValueError(f'a {type(document).__name__}, not a mapping')
        information = document.get('rosbag2_bagfile_information', {}) or {}
        if not isinstance(information, dict):
            raise ValueError('rosbag2_bagfile_information is not a mapping')
        for entry in information.get('topics_with_message_count', []) or []:
            metadata = entry['topic_metadata']
            profiles = metadata.get('offered_qos_profiles') or []
            if isinstance(profiles, str):
                profiles = load_yaml(profiles) or []
            description = TopicDescription(metadata['type'], tuple(profiles),
                                           metadata.get('type_description_hash', ''))
            self._count(metadata['name'], description, int(entry['message_count']))
        for entry in information.get('files', []) or []:
            start = int(entry['starting_time']['nanoseconds_since_epoch'])
            self.files.append(FileInfo(str(entry['path']), start,
                                       start + int(entry['duration']['nanoseconds']),
                                       int(entry['message_count']), {}, {}))
        self.custom_data = {**custom_data_of(information), **self.custom_data}

    def _count(self, topic: str, description: TopicDescription, count: int) -> None:
        key = description_key(topic, description)
        entry = self._entries.setdefault(key, [topic, description, 0])
        entry[2] += count

    def listed(self, name: str) -> bool:
        """Return True when the file ``name`` is listed already."""
        return any(info.name == name for info in self.files)

    def append(self, info: FileInfo) -> None:
        """List a closed file (without rewriting metadata.yaml)."""
        self.files.append(info)
        for topic, description, count in topic_entries(info):
            self._count(topic, description, count)

    def add(self, info: FileInfo) -> None:
        """List a closed file and rewrite metadata.yaml."""
        self.append(info)
        self.write()

    def write(self) -> None:
        """Rewrite metadata.yaml atomically."""
        entries = [tuple(entry) for entry in self._entries.values()]
        text = dump_bag_metadata(self.files, entries, self.custom_data, self._file_lines)
        try:
            atomic_write(self.path, text, self.mode)
        except OSError as error:
            raise RecordingError(f'cannot write {self.path}: {describe_error(error)}') from error
