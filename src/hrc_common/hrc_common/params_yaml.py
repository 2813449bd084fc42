"""Write a node's ROS 2 parameter file from its parameter dataclass (pure, no ROS).

A node's parameters are declared once, in its dataclass (:func:`hrc_common.params.param`); its
file ``params/<node>.yaml`` is generated from it, as generate_parameter_library generates a
node's parameter code from one YAML: every field with its default, and above it the field's
description, range or choices as the comment. :func:`render` returns the file's text and
:func:`drift` the files that differ from it. ``python -m hrc_bringup.params_files --write``
(the table of the nodes and their dataclasses) rewrites them and a test fails on drift.
"""

from dataclasses import fields
import pathlib
import re
import textwrap

import yaml

from hrc_common.params import default_of, spec_of

WIDTH = 99                  # columns of the comments, as the code's line length
INDENT = '    '             # a parameter's indentation under <node>: ros__parameters:
# reStructuredText markup of docstrings, shown plain in a comment: :class:`X`, ``x``
MARKUP = re.compile(r':\w+:`([^`]*)`|``([^`]*)``')


def value_text(value) -> str:
    """Return ``value`` in YAML flow syntax, as one line (``[robot, human]``, ``''``, ``0.2``)."""
    text = yaml.safe_dump(value, default_flow_style=True, width=float('inf'))
    return text[:-len('...\n')].strip() if text.endswith('\n...\n') else text.strip()


def _number(bound) -> str:
    """Return a bound as written in a range: integers without a decimal point."""
    return str(int(bound)) if float(bound).is_integer() and abs(bound) < 1e15 else repr(bound)


def accepts_text(dataclass_field) -> str:
    """Return what the field accepts besides its type: range, choices, run-time changes."""
    spec = spec_of(dataclass_field)
    parts = []
    if spec.choices:
        many = isinstance(default_of(dataclass_field), list)
        parts.append(('Items among: ' if many else 'One of: ')
                     + ', '.join(str(choice) for choice in spec.choices) + '.')
    if spec.low is not None and spec.high is not None:
        parts.append(f'Range [{_number(spec.low)}, {_number(spec.high)}].')
    elif spec.low is not None:
        parts.append(f'At least {_number(spec.low)}.')
    elif spec.high is not None:
        parts.append(f'At most {_number(spec.high)}.')
    if not spec.read_only:
        parts.append('May change at run time (ros2 param set).')
    return ' '.join(parts)


def comment(text: str, indent: str = '') -> list:
    """Return ``text`` as comment lines of at most WIDTH columns."""
    return textwrap.wrap(text, WIDTH, initial_indent=indent + '# ',
                         subsequent_indent=indent + '# ', break_on_hyphens=False,
                         break_long_words=False)


def plain(text: str) -> str:
    """Return docstring text without its reStructuredText markup."""
    return MARKUP.sub(lambda match: match.group(1) or match.group(2), text).strip()


def sentence(text: str) -> str:
    """Return ``text`` ending with a full stop (unless it ends with one, '?' or '!')."""
    return text if not text or text[-1] in '.?!' else text + '.'


def field_lines(dataclass_field) -> list:
    """Return the comment and the ``name: default`` line of one field.

    What the field accepts (range, choices) ends the comment, on its last line if it fits.
    """
    lines = comment(sentence(plain(spec_of(dataclass_field).description)), INDENT)
    accepts = accepts_text(dataclass_field)
    if accepts and lines and len(lines[-1]) + 1 + len(accepts) <= WIDTH:
        lines[-1] += ' ' + accepts
    elif accepts:
        lines += comment(accepts, INDENT)
    return lines + [f'{INDENT}{dataclass_field.name}: {value_text(default_of(dataclass_field))}']


def first_line(cls) -> str:
    """Return the first line of a class's docstring ('' without one)."""
    return plain((cls.__doc__ or '').strip().splitlines()[0]) if cls.__doc__ else ''


def groups(params_cls) -> list:
    """Return [(class, [fields])] in declaration order, by the class that declares the fields.

    A dataclass that extends another (the sim's node parameters over the physics) lists the
    fields of each base under its own heading.
    """
    declared_by = {}
    for cls in reversed(params_cls.__mro__):
        for name in getattr(cls, '__annotations__', {}):
            declared_by.setdefault(name, cls)
    result = []
    for dataclass_field in fields(params_cls):
        cls = declared_by.get(dataclass_field.name, params_cls)
        if not result or result[-1][0] is not cls:
            result.append((cls, []))
        result[-1][1].append(dataclass_field)
    return result


def render(params_cls, node_name: str, notice: str) -> str:
    """Return the parameter file of ``node_name`` for ``params_cls`` (a ROS 2 parameter file).

    Its header: the dataclass's first docstring line, then ``notice`` (how the file is made).
    """
    lines = comment(sentence(first_line(params_cls) or f'Parameters of the node {node_name}'))
    lines += comment(notice) + [f'{node_name}:', '  ros__parameters:']
    parts = groups(params_cls)
    for cls, members in parts:
        if len(parts) > 1:
            lines += comment(f'--- {cls.__name__}: {sentence(first_line(cls))}', INDENT)
        for dataclass_field in members:
            lines += field_lines(dataclass_field)
    return '\n'.join(lines) + '\n'


def drift(texts: dict, folder: pathlib.Path) -> list:
    """Return the names of ``texts`` ({file name: rendered text}) whose file in ``folder`` differs.

    A missing file counts as drift.
    """
    return [name for name, text in texts.items()
            if not (pathlib.Path(folder) / name).is_file()
            or (pathlib.Path(folder) / name).read_text() != text]


def write(texts: dict, folder: pathlib.Path) -> list:
    """Write the files of ``texts`` ({file name: text}) that differ; return their names."""
    changed = drift(texts, folder)
    for name in changed:
        (pathlib.Path(folder) / name).write_text(texts[name])
    return changed
