"""hrc_common.executables: the ament-index lookup of ``ros2 run``."""

import os

from ament_index_python.packages import get_package_prefix
import pytest

from hrc_common.executables import (executable_path, ExecutableNotFound, find_executable,
                                    package_executables, package_prefix)


def make_prefix(root, package, executables=()):
    """Create an install prefix that registers ``package`` with the given executables."""
    index = root / 'share' / 'ament_index' / 'resource_index' / 'packages'
    index.mkdir(parents=True, exist_ok=True)
    (index / package).write_text('')
    lib = root / 'lib' / package
    lib.mkdir(parents=True, exist_ok=True)
    for name in executables:
        (lib / name).write_text('#!/bin/sh\necho ran\n')
        (lib / name).chmod(0o755)
    return root


def test_same_prefix_as_ament_index_python(tmp_path, monkeypatch):
    first = make_prefix(tmp_path / 'a', 'demo', ['talker'])
    second = make_prefix(tmp_path / 'b', 'demo', ['listener'])
    monkeypatch.setenv('AMENT_PREFIX_PATH', os.pathsep.join([str(first), str(second)]))
    assert package_prefix('demo') == first
    assert str(package_prefix('demo')) == get_package_prefix('demo')
    assert find_executable('demo', 'talker') == first / 'lib' / 'demo' / 'talker'
    assert executable_path('demo', 'x') == first / 'lib' / 'demo' / 'x'


def test_clear_errors(tmp_path, monkeypatch):
    prefix = make_prefix(tmp_path, 'demo', ['talker'])
    (prefix / 'lib' / 'demo' / 'notes.txt').write_text('not executable')
    monkeypatch.setenv('AMENT_PREFIX_PATH', str(prefix))
    assert package_executables('demo') == ['talker']
    with pytest.raises(ExecutableNotFound, match="Package 'nothere' not found"):
        find_executable('nothere', 'talker')
    with pytest.raises(ExecutableNotFound, match=r"no executable 'notes.txt' \(it has: talker\)"):
        find_executable('demo', 'notes.txt')
