"""Data files of the wrong shape are refused with a reason, never with a crash.

The task tree and the cases file are rewritten at every path with values of the wrong shape
(a number, a list of lists, a string, null, an empty mapping or list, ...): loading raises
TaskTreeError / CasesError (a reason), never another exception; so do binary files, FIFOs and
directories. At the node, such a file and a
session id that would leave the checkpoint directory end with exit code 2 and the reason.
"""

import copy
import os
import pathlib

import pytest
import torch
import yaml

from hrc_agent_node.agent_core import AgentCore
from hrc_agent_node.checkpoint import FORMAT, FORMAT_VERSION
from hrc_agent_node.config import AgentParams
from hrc_agent_node.strategies import cases_from_dict, CasesError, load_cases
from hrc_agent_node.task_tree import TaskTree, TaskTreeError
from hrc_common.params import checked, ParameterError, with_overrides
from hrc_common.paths import params_dir

PARAMS = pathlib.Path(params_dir())
WRONG_SHAPES = [5, [['slider', 'pendulum']], 'x', None, {}, [], -1, 1.5, True, {'a': [1]}]


def load(name):
    with open(PARAMS / name) as stream:
        return yaml.safe_load(stream)


def paths(node, prefix=()):
    """Yield the path of every value in a parsed YAML document (the root included)."""
    yield prefix
    children = node.items() if isinstance(node, dict) else \
        enumerate(node) if isinstance(node, list) else ()
    for key, value in children:
        yield from paths(value, prefix + (key,))


def replaced(document, path, value):
    """Return a copy of ``document`` with the value at ``path`` replaced."""
    if not path:
        return value
    document = copy.deepcopy(document)
    node = document
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value
    return document


def crashes(build, document, error_type):
    """Return the (path, value, exception) of every replacement that crashes ``build``."""
    found = []
    for path in paths(document):
        for value in WRONG_SHAPES:
            try:
                build(replaced(document, path, value))
            except error_type:
                pass
            except Exception as error:  # noqa: BLE001 - any other exception is the failure
                found.append((path, value, f'{type(error).__name__}: {error}'))
    return found


def test_task_tree_of_any_wrong_shape_is_refused_with_a_reason():
    assert crashes(TaskTree.from_dict, load('task_tree.yaml'), TaskTreeError) == []


def test_cases_of_any_wrong_shape_are_refused_with_a_reason():
    tree = TaskTree.from_file(PARAMS / 'task_tree.yaml')
    assert crashes(lambda document: cases_from_dict(document, tree), load('cases.yaml'),
                   CasesError) == []


@pytest.mark.parametrize('path, value, reason', [
    (('actions',), 5, 'actions must be a list, got int 5'),
    (('subtasks', 0, 'children'), [['slider', 'pendulum']],
     "subtask 'ball': children must be a list of ids, got [['slider', 'pendulum']]"),
])
def test_the_reported_tree_files_give_their_reason(path, value, reason):
    with pytest.raises(TaskTreeError) as error:
        TaskTree.from_dict(replaced(load('task_tree.yaml'), path, value))
    assert reason in str(error.value)


@pytest.mark.parametrize('kind, reason', [
    ('binary', 'is not valid YAML text'), ('fifo', 'is not a regular file'),
    ('directory', 'is not a regular file'), ('missing', 'cannot read'),
    ('deep', 'is not valid YAML text: line 1, column 65: nested more than 64 levels deep'),
])
def test_unreadable_data_files_are_refused_with_a_reason(tmp_path, kind, reason):
    path = tmp_path / 'data.yaml'
    if kind == 'binary':
        path.write_bytes(bytes(range(256)))
    elif kind == 'fifo':
        os.mkfifo(path)        # opening it would block until a writer comes
    elif kind == 'directory':
        path.mkdir()
    elif kind == 'deep':
        path.write_text('[' * 20000 + ']' * 20000)     # a RecursionError in PyYAML
    tree = TaskTree.from_file(PARAMS / 'task_tree.yaml')
    with pytest.raises(TaskTreeError, match=reason):
        TaskTree.from_file(path)
    with pytest.raises(CasesError, match=reason):
        load_cases(path, tree)


@pytest.mark.parametrize('session_id', ['../../x', '/tmp/elsewhere', '.hidden', 'a/b', '-p'])
def test_session_ids_that_name_other_paths_are_refused(session_id):
    with pytest.raises(ParameterError, match='session_id'):
        checked(with_overrides(AgentParams(), session_id=session_id))


def test_derived_and_plain_session_ids_are_accepted():
    assert AgentCore(with_overrides(AgentParams(), case=3, seed=4)).session_id == 'case3-seed4'
    checked(with_overrides(AgentParams(), session_id='case2-seed0-20261130-201500'))


@pytest.fixture
def bad_files(tmp_path):
    """Write a tree file with `actions: 5` and a checkpoint holding only its header."""
    tree = tmp_path / 'tree.yaml'
    tree.write_text(yaml.safe_dump(replaced(load('task_tree.yaml'), ('actions',), 5)))
    header = tmp_path / 'header.pt'
    torch.save({'format': FORMAT, 'format_version': FORMAT_VERSION}, header)
    return {'tree': str(tree), 'header': str(header)}


@pytest.mark.parametrize('parameters, reason', [
    ({'task_tree_file': 'tree'}, 'actions must be a list, got int 5'),
    ({'resume_from': 'header'}, "checkpoint lacks 'network'"),
    ({'session_id': '../../x'}, "session_id '../../x' is not valid"),
])
def test_node_exits_2_with_the_reason(start_node, bad_files, parameters, reason):
    parameters = {name: bad_files.get(value, value) for name, value in parameters.items()}
    agent = start_node('hrc_agent_node', 'agent_node', parameters=parameters)
    assert agent.wait(timeout=60) == 2, agent.output
    assert reason in agent.output and 'Traceback' not in agent.output
