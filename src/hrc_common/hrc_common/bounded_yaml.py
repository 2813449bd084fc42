"""YAML from files a user or someone else wrote, loaded within bounds (pure, no rclpy).

PyYAML's safe loader runs no code, but a hostile or broken file still reaches it: 20,000
nested brackets end ``yaml.safe_load`` in a ``RecursionError``, a 5,000-digit integer in a
``ValueError`` from Python's integer-string limit, and a few lines of aliases ("billion
laughs") build a document whose walk or dump takes exponential time and memory. So a first
pass over libyaml's event stream (iterative: no depth overflows it) checks the size, the
nesting, the number of values with aliases expanded and the integer scalars before anything
is constructed. The error it raises is a ``yaml.YAMLError`` (every caller that reports broken
YAML reports this too) and a ``ValueError``; its message is one line: source, line, reason.

The limits are far above any file hrc writes or reads (a parameters file nests 4 deep, a
session's ``metadata.yaml`` of 1,000 episodes is a few hundred KiB, no file of hrc uses an
alias) and far below what hurts.
"""

import pathlib
import re

import yaml

# libyaml's parser and constructor when PyYAML has them (the pure-Python ones cost ms per file)
LOADER = getattr(yaml, 'CSafeLoader', yaml.SafeLoader)

MAX_BYTES = 4 * 1024 * 1024     # text size (characters) of one document
MAX_DEPTH = 64                  # nested mappings and sequences
MAX_NODES = 1_000_000           # values of one document with its aliases expanded
MAX_INT_DIGITS = 100            # characters of a plain scalar that resolves to an integer
QUOTE_CHARACTERS = 200          # characters of a value quoted in a message

# The YAML 1.1 integer forms PyYAML resolves (sexagesimal ones included); a plain scalar
# matching one is converted with int(), which Python refuses beyond 4,300 digits.
_INTEGER = re.compile(r'[-+]?(0b[01_]+|0x[0-9a-fA-F_]+|0o?[0-7_]+|[0-9][0-9_]*(:[0-5]?[0-9])*)')

_INT_TAG = 'tag:yaml.org,2002:int'
_OPENING = (yaml.MappingStartEvent, yaml.SequenceStartEvent)
_CLOSING = (yaml.MappingEndEvent, yaml.SequenceEndEvent)


class YamlLimitError(yaml.YAMLError, ValueError):
    """A YAML text beyond the bounds of this module (too big, too deep, an integer too long).

    ``problem`` and ``problem_mark`` as PyYAML's parse errors have them, for the callers
    that print "line L, column C: problem".
    """

    def __init__(self, source: str, problem: str, mark=None):
        line = f' (line {mark.line + 1})' if mark is not None else ''
        super().__init__(f'{source}{line}: {problem}')
        self.problem = problem
        self.problem_mark = mark


def brief(value, limit: int = QUOTE_CHARACTERS) -> str:
    """Return ``repr(value)`` cut to ``limit`` characters (a message quotes, never floods)."""
    text = repr(value)
    if len(text) <= limit:
        return text
    return f'{text[:limit]}... ({len(text)} characters)'


def describe(error: Exception) -> str:
    """Return why ``error`` (a YAML or decoding error) refused a file, in one line, no path.

    "line L, column C: problem" when the error knows where (PyYAML's parse errors and
    YamlLimitError), else the first line of its text; for callers that name the file.
    """
    mark = getattr(error, 'problem_mark', None)
    problem = getattr(error, 'problem', None)
    if problem and mark is not None:
        return f'line {mark.line + 1}, column {mark.column + 1}: {problem}'
    if problem:
        return problem
    return (str(error).splitlines() or [type(error).__name__])[0]


def _resolves_to_integer(event) -> bool:
    if event.tag == _INT_TAG:
        return True
    return event.tag is None and event.implicit[0] and bool(_INTEGER.fullmatch(event.value))


def check_bounds(text, source: str = 'YAML', *, max_bytes: int = MAX_BYTES) -> None:
    """Raise YamlLimitError if ``text`` is beyond the bounds; parse errors raise YAMLError."""
    if len(text) > max_bytes:
        raise YamlLimitError(source, f'{len(text)} characters, more than the {max_bytes} a '
                             'YAML file here may have')
    # nodes the document would have with every alias expanded, and each anchor's share
    expanded = 0
    anchor_sizes = {}
    open_nodes = []     # (expanded when the node opened, its anchor)
    for event in yaml.parse(text, Loader=LOADER):
        if isinstance(event, _OPENING):
            expanded += 1
            open_nodes.append((expanded - 1, event.anchor))
            if len(open_nodes) > MAX_DEPTH:
                raise YamlLimitError(source, f'nested more than {MAX_DEPTH} levels deep',
                                     event.start_mark)
        elif isinstance(event, _CLOSING):
            opened_at, anchor = open_nodes.pop()
            if anchor is not None:
                anchor_sizes[anchor] = expanded - opened_at
        elif isinstance(event, yaml.AliasEvent):
            expanded += anchor_sizes.get(event.anchor, 1)
        elif isinstance(event, yaml.ScalarEvent):
            expanded += 1
            if event.anchor is not None:
                anchor_sizes[event.anchor] = 1
            if len(event.value) > MAX_INT_DIGITS and _resolves_to_integer(event):
                raise YamlLimitError(source, f'an integer of {len(event.value)} digits '
                                     f'({brief(event.value, 40)}), more than {MAX_INT_DIGITS}',
                                     event.start_mark)
        if expanded > MAX_NODES:
            raise YamlLimitError(source, f'more than {MAX_NODES} values with its aliases '
                                 '(*name) expanded', event.start_mark)


def load(text, source: str = 'YAML', *, max_bytes: int = MAX_BYTES):
    """Return the document of ``text`` (str or UTF-8 bytes, safe types only) within bounds."""
    check_bounds(text, source, max_bytes=max_bytes)
    return yaml.load(text, Loader=LOADER)


def load_file(path, *, max_bytes: int = MAX_BYTES):
    """Return the document of the file at ``path``; the file is named in every error.

    A file larger than ``max_bytes`` is refused before it is read whole.
    """
    path = pathlib.Path(path)
    size = path.stat().st_size
    if size > max_bytes:
        raise YamlLimitError(str(path), f'{size} bytes, more than the {max_bytes} a YAML '
                             'file here may have')
    return load(path.read_text(), str(path), max_bytes=max_bytes)
