"""Read hrc bags: single MCAP files or session folders, finished or cut short (pure, no rclpy).

A finished file (footer, summary, indexes) is read through its chunk index. A file whose writer
was killed (no summary, no footer) is scanned record by record from the start; the scan stops at
the first incomplete record, so everything up to the last complete chunk is returned and the file
is reported as incomplete. Decoding uses the ``ros2msg`` schemas stored in the files
(mcap-ros2-support), so no ROS installation is needed to analyse bags.
"""

from dataclasses import dataclass, field
import io
import pathlib
import stat
import struct
import typing

from mcap.exceptions import McapError
from mcap.reader import SeekingReader
from mcap.records import Channel, Message, Metadata, Schema
from mcap.stream_reader import StreamReader
from mcap_ros2.decoder import DecoderFactory
import yaml

from hrc_bag.format import END_FILE_SUFFIX, episode_file_key, METADATA_FILE
from hrc_bag.qos_yaml import load_yaml
from hrc_common import bounded_yaml

MCAP_MAGIC = b'\x89MCAP0\r\n'

# What a truncated record may raise while being parsed or decompressed.
TRUNCATION_ERRORS = (McapError, EOFError, ValueError, struct.error, MemoryError)
try:  # zstandard raises its own error on a cut compressed frame
    import zstandard
    TRUNCATION_ERRORS += (zstandard.ZstdError,)
except ImportError:  # pragma: no cover - zstandard is a dependency of the writer
    pass


@dataclass(frozen=True)
class BagMessage:
    """One recorded message: raw CDR bytes plus where and when it was recorded."""

    topic: str
    type_name: str              # e.g. hrc_msgs/msg/TaskState (the schema name)
    data: bytes                 # CDR serialized message, as published
    log_time: int               # ns since the epoch, when the recorder received it
    publish_time: int           # ns since the epoch, the publisher's source timestamp
    sequence: int
    channel_metadata: typing.Mapping = field(default_factory=dict, compare=False)
    schema_text: str = field(default='', compare=False, repr=False)


@dataclass
class FileScan:
    """What a scan of one file found."""

    path: pathlib.Path
    complete: bool              # the file has its footer (it was closed properly)
    messages: list              # BagMessage, in log-time order
    metadata: dict              # MCAP metadata records: name -> dict (the last one of a name)
    error: str = ''             # why a scan stopped early (incomplete files)


def is_complete(path) -> bool:
    """Return True when the file ends with an MCAP footer and magic (it was closed)."""
    path = pathlib.Path(path)
    try:
        with open(path, 'rb') as stream:
            stream.seek(0, io.SEEK_END)
            if stream.tell() < 2 * len(MCAP_MAGIC) + 29:
                return False
            stream.seek(-len(MCAP_MAGIC), io.SEEK_END)
            return stream.read() == MCAP_MAGIC
    except OSError:
        return False


class _MessageFactory:
    """Build BagMessages, converting each schema and channel once per file."""

    def __init__(self):
        self._schema_texts = {}
        self._channel_metadata = {}

    def __call__(self, schema, channel, message) -> BagMessage:
        key = None if schema is None else (schema.id, schema.name)
        text = self._schema_texts.get(key)
        if text is None:
            text = '' if schema is None else bytes(schema.data).decode()
            self._schema_texts[key] = text
        metadata = self._channel_metadata.get(channel.id)
        if metadata is None:
            metadata = self._channel_metadata[channel.id] = dict(channel.metadata)
        return BagMessage(
            topic=channel.topic,
            type_name=schema.name if schema is not None else '',
            data=bytes(message.data),
            log_time=message.log_time,
            publish_time=message.publish_time,
            sequence=message.sequence,
            channel_metadata=metadata,
            schema_text=text)


def _wanted(topic, topics) -> bool:
    return topics is None or topic in topics


def scan_records(path):
    """Read a file record by record up to its end or its first cut (a killed writer).

    Returns (schemas, channels, messages, metadata, error): schemas and channels by id, the raw
    Message records in file order, the metadata records as dicts, and '' if the file was read
    to its end, else what stopped the reading.
    """
    schemas, channels, messages, metadata = {}, {}, [], {}
    error = ''
    with open(path, 'rb') as stream:
        try:
            for record in StreamReader(stream).records:
                if isinstance(record, Schema):
                    schemas[record.id] = record
                elif isinstance(record, Channel):
                    channels[record.id] = record
                elif isinstance(record, Metadata):
                    metadata[record.name] = dict(record.metadata)
                elif isinstance(record, Message):
                    messages.append(record)
        except TRUNCATION_ERRORS as exception:
            error = f'{type(exception).__name__}: {exception}'.rstrip(': ') or 'truncated'
    return schemas, channels, messages, metadata, error


def _scan_stream(path, topics) -> FileScan:
    """Read a file record by record; stop quietly at a truncated record."""
    schemas, channels, records, metadata, error = scan_records(path)
    make_message = _MessageFactory()
    messages = []
    for record in records:
        channel = channels.get(record.channel_id)
        if channel is not None and _wanted(channel.topic, topics):
            messages.append(make_message(schemas.get(channel.schema_id), channel, record))
    messages.sort(key=lambda message: message.log_time)
    return FileScan(pathlib.Path(path), not error, messages, metadata, error)


def scan_file(path, topics=None) -> FileScan:
    """Return every message (optionally of some ``topics``) and metadata record of a file."""
    path = pathlib.Path(path)
    topics = None if topics is None else set(topics)
    if not is_complete(path):
        return _scan_stream(path, topics)
    with open(path, 'rb') as stream:
        reader = SeekingReader(stream)
        try:
            summary = reader.get_summary()
        except TRUNCATION_ERRORS:
            summary = None
        if summary is None:
            return _scan_stream(path, topics)
        make_message = _MessageFactory()
        messages = [make_message(schema, channel, message)
                    for schema, channel, message in reader.iter_messages(
                        topics=None if topics is None else sorted(topics),
                        log_time_order=True)]
        metadata = {record.name: dict(record.metadata) for record in reader.iter_metadata()}
    return FileScan(path, True, messages, metadata)


def read_metadata(path) -> dict:
    """Return the MCAP metadata records of a file (name -> dict), complete or not."""
    return scan_file(path, topics=()).metadata


class BagError(ValueError):
    """Paths given as bags are not (not MCAP, empty, not a regular file): a reason a line."""


def file_problem(path) -> typing.Optional[str]:
    """Return why ``path`` is not an MCAP file that can be read, or None.

    Checked without opening anything but regular files (a FIFO would block the reader): the
    file must exist, be a regular file, be readable, and start with the MCAP magic.
    """
    path = pathlib.Path(path)
    try:
        status = path.stat()
    except OSError as error:
        return f'{path}: {error.strerror or error}'
    if not stat.S_ISREG(status.st_mode):
        kind = ('a FIFO' if stat.S_ISFIFO(status.st_mode) else
                'a folder' if stat.S_ISDIR(status.st_mode) else
                'a device' if stat.S_ISCHR(status.st_mode) or stat.S_ISBLK(status.st_mode)
                else 'a socket' if stat.S_ISSOCK(status.st_mode) else 'not a regular file')
        return f'{path}: is {kind}, not an MCAP file'
    if status.st_size == 0:
        return f'{path}: is empty, not an MCAP file'
    try:
        with open(path, 'rb') as stream:
            start = stream.read(len(MCAP_MAGIC))
    except OSError as error:
        return f'{path}: cannot be read: {error.strerror or error}'
    if start != MCAP_MAGIC[:len(start)] or len(start) < len(MCAP_MAGIC):
        return f'{path}: is not an MCAP file (it does not start with the MCAP magic bytes)'
    return None


def bag_problems(path) -> list:
    """Return the reasons why a file or session folder cannot be read as a bag (all of them)."""
    path = pathlib.Path(path)
    if not path.exists():
        return [f'{path}: does not exist']
    if path.is_dir():
        if not is_session_folder(path):
            return [f'{path}: holds neither metadata.yaml nor .mcap files']
        return [problem for problem in map(file_problem, session_files(path)) if problem]
    problem = file_problem(path)
    return [problem] if problem else []


def check_bag(path) -> None:
    """Raise BagError with every reason why ``path`` is not a readable bag."""
    problems = bag_problems(path)
    if problems:
        raise BagError('\n'.join(problems))


def bag_metadata_yaml(folder) -> tuple:
    """Return (``rosbag2_bagfile_information`` or {}, problem) of a folder's metadata.yaml.

    ``problem`` is '' when the file is missing (a folder of MCAP files only) or fine, else why
    it cannot be used (unreadable, not YAML, a list or a string, fields of the wrong shape);
    the bag tools then read the MCAP files of the folder instead.
    """
    path = pathlib.Path(folder) / METADATA_FILE
    if not path.is_file():
        return {}, ''
    try:
        document = load_yaml(path.read_text())
    except (OSError, UnicodeDecodeError) as error:
        return {}, f'{path} cannot be read ({error}): using the MCAP files of the folder'
    except yaml.YAMLError as error:
        return {}, (f'{path} is not YAML ({bounded_yaml.describe(error)}): using the MCAP '
                    'files of the folder')
    if document is None:
        return {}, ''
    information = (document.get('rosbag2_bagfile_information')
                   if isinstance(document, dict) else None)
    if not isinstance(information, dict):
        shape = (type(document).__name__ if not isinstance(document, dict)
                 else 'a mapping without rosbag2_bagfile_information')
        return {}, (f'{path} is not rosbag2 metadata ({shape}): using the MCAP files of '
                    f'the folder')
    files = information.get('relative_file_paths') or []
    if not isinstance(files, list) or not all(isinstance(name, str) for name in files):
        return {}, (f'{path}: relative_file_paths is not a list of names: using the MCAP '
                    f'files of the folder')
    return information, ''


def read_bag_metadata_yaml(folder) -> dict:
    """Return ``rosbag2_bagfile_information`` of a session folder's metadata.yaml (or {})."""
    return bag_metadata_yaml(folder)[0]


def is_session_folder(path) -> bool:
    """Return True for a folder that holds a metadata.yaml or MCAP files."""
    path = pathlib.Path(path)
    return path.is_dir() and ((path / METADATA_FILE).is_file() or any(path.glob('*.mcap')))


def session_files(path) -> list:
    """Return the MCAP files of a session folder in recording order (or ``[path]``).

    The files listed by metadata.yaml come first, in its order; files it does not list (an
    episode that was open when the recorder died, or all of them when metadata.yaml is
    missing or unusable) follow, by episode number, the end file last.
    """
    path = pathlib.Path(path)
    if path.is_file():
        return [path]
    if not path.is_dir():
        raise FileNotFoundError(f'no bag at {path}')
    listed = [path / pathlib.PurePath(name).name
              for name in read_bag_metadata_yaml(path).get('relative_file_paths', []) or []]
    listed = [file for file in listed if file.is_file()]
    unlisted = sorted(set(path.glob('*.mcap')) - set(listed), key=recording_order)
    return listed + unlisted


def recording_order(path) -> tuple:
    """Return a sort key of episode files: by episode number, the end file last."""
    stem = pathlib.Path(path).stem
    key = episode_file_key(stem)
    if key is not None:
        return (0, *key, stem)
    return (2 if stem.endswith(END_FILE_SUFFIX) else 1, 0, 0, stem)


def iter_messages(path, topics=None) -> typing.Iterator[BagMessage]:
    """Yield the messages of a file or session folder, file after file, in log-time order."""
    for file in session_files(path):
        yield from scan_file(file, topics).messages


class MessageDecoder:
    """Decode BagMessage CDR data into Python objects using the schemas stored in the bag.

    A schema with no text (a writer that left it out) would decode every message as an empty
    object; such a type is decoded with its installed definition instead (the report says so:
    :func:`without_schema`), or refused (BagError) when none is installed.
    """

    def __init__(self):
        self._factory = DecoderFactory()
        self._decoders = {}

    def decode(self, message: BagMessage):
        """Return the decoded message (attributes named as the .msg fields)."""
        key = (message.type_name, message.schema_text)
        decoder = self._decoders.get(key)
        if decoder is None:
            # the factory caches decoders by schema id: one id per distinct schema
            schema = Schema(id=len(self._decoders) + 1, name=message.type_name,
                            encoding='ros2msg',
                            data=self._schema_text(message).encode())
            decoder = self._factory.decoder_for('cdr', schema)
            if decoder is None:
                raise BagError(f'cannot decode {message.type_name} on {message.topic}')
            self._decoders[key] = decoder
        return decoder(message.data)

    def _schema_text(self, message: BagMessage) -> str:
        if message.schema_text.strip():
            return message.schema_text
        from hrc_bag import msgdefs  # lazy: the ament index, only for a bag without a schema
        where = f'{message.topic} ({message.type_name or "no type name"})'
        try:
            text = msgdefs.full_definition(message.type_name)
        except (msgdefs.DefinitionNotFound, ValueError):
            raise BagError(f'{where}: the bag holds no schema of the type and none is '
                           'installed: its messages cannot be read') from None
        return text


def without_schema(messages) -> list:
    """Return a notice per topic of ``messages`` whose bag holds no schema text of its type."""
    topics = sorted({(message.topic, message.type_name) for message in messages
                     if not message.schema_text.strip()})
    return [f'{topic} ({type_name or "no type name"}): the bag holds no schema of the type: '
            'decoded with the installed definition' for topic, type_name in topics]


@dataclass(frozen=True)
class TopicInfo:
    """A recorded topic: its type and the channel metadata (offered QoS, type hash)."""

    topic: str
    type_name: str
    channel_metadata: typing.Mapping


def file_topics(path) -> dict:
    """Return {topic: TopicInfo} of one file (from its summary, or a scan if unfinished)."""
    path = pathlib.Path(path)
    summary = None
    if is_complete(path):
        with open(path, 'rb') as stream:
            try:
                summary = SeekingReader(stream).get_summary()
            except TRUNCATION_ERRORS:
                summary = None
    if summary is not None:
        schemas, channels = summary.schemas, summary.channels
    else:
        schemas, channels, _, _, _ = scan_records(path)     # a file left open
    topics = {}
    for channel in channels.values():
        schema = schemas.get(channel.schema_id)
        topics.setdefault(channel.topic, TopicInfo(
            channel.topic, schema.name if schema is not None else '', dict(channel.metadata)))
    return topics


def bag_topics(path) -> dict:
    """Return {topic: TopicInfo} over every file of a file or session folder."""
    topics = {}
    for file in session_files(path):
        for topic, info in file_topics(file).items():
            topics.setdefault(topic, info)
    return topics
