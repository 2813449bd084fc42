"""Contracts written once: no copy of the case table, control period or params lookup.

Scans the project's code that is not a test (packages, their benches, bench/, scripts/): a
copy of a contract that appears again makes the test name the file and line.
"""

import ast
import pathlib
import re

from hrc_common.cases import case_table, paper_case_ids
from hrc_common.study_index import PAPER_CASES

REPOSITORY = pathlib.Path(__file__).resolve().parents[3]


def _sources() -> list:
    """Return the project's Python files that are not tests."""
    files = [path for path in (REPOSITORY / 'src').glob('*/**/*.py')
             if 'test' not in path.relative_to(REPOSITORY / 'src').parts[1:]
             and not path.name.startswith('test_')]
    for folder in ('bench', 'scripts'):
        files += list((REPOSITORY / folder).glob('*.py'))
    assert len(files) > 100   # the scan sees the project
    return sorted(files)


def _hits(pattern: str) -> list:
    expression = re.compile(pattern)
    return [f'{path.relative_to(REPOSITORY)}:{number}: {line.strip()}'
            for path in _sources()
            for number, line in enumerate(path.read_text().splitlines(), 1)
            if expression.search(line)]


def test_the_case_table_is_read_from_params_cases_yaml_only():
    assert _hits(r'range\(1, ?[79]\)|[(\[]1, 2, 3, 4, 5, 6[)\]]') == []
    # the paper's cases come from the case table (no partners-first step), the study's too
    assert paper_case_ids() == tuple(case for case, spec in case_table().items()
                                     if spec.strategy != 'partners_first')
    assert PAPER_CASES == paper_case_ids() == (1, 2, 3, 4, 5, 6)


def test_no_library_signature_defaults_a_control_period():
    """Take the sim's limits (``SimLimits``) instead of assuming 0.2 s."""
    found = []
    for path in _sources():
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                arguments = node.args
                positional = arguments.posonlyargs + arguments.args
                pairs = list(zip(positional[len(positional) - len(arguments.defaults):],
                                 arguments.defaults))
                pairs += [(argument, default) for argument, default
                          in zip(arguments.kwonlyargs, arguments.kw_defaults) if default]
            elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
                pairs = [(node.target, node.value)] if node.value is not None else []
            else:
                continue
            for argument, default in pairs:
                name = getattr(argument, 'arg', None) or getattr(argument, 'id', None)
                if name == 'control_period' and isinstance(default, ast.Constant):
                    found.append(f'{path.relative_to(REPOSITORY)}:{default.lineno}')
    assert found == []


def test_one_params_directory_lookup_and_one_place_for_checkpoint_names():
    assert [hit.split(':')[0] for hit in _hits(r"/ ?'params'")] == \
        ['src/hrc_common/hrc_common/paths.py'] * 2
    assert [hit.split(':')[0] for hit in _hits(r"'(latest|final)\.pt'")] == \
        ['src/hrc_common/hrc_common/session_control.py'] * 2
