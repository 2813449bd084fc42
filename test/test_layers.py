"""The package layers of docs/architecture.md hold in the code: an AST scan of every module.

Every ``import`` of every module under ``src/*/`` is read with :mod:`ast`, those inside
functions included, and mapped to the package graph (one edge per pair of workspace packages).
The graph must have no cycle, no import from a package to one of a higher (or the same) layer,
and every edge must be declared in the importing package's ``package.xml``: ``<depend>`` or
``<exec_depend>`` for its modules, also ``<test_depend>`` for its tests and benchmarks.

The layer order is defined once, in the "Layers" table of docs/architecture.md, which this test
reads. ``python test/test_layers.py`` prints the graph and the function-level imports.

Imports sit at the top of modules, so the dependency graph reads from there: every import
inside a function of a module that is not a test (``src/<package>/`` except its ``test/``,
``bench/``, ``scripts/``) must carry ``# lazy: <why>`` on its line, why it cannot be at the top
(an optional or heavy dependency that a light entry point must not load, e.g.
``import torch  # lazy: torch (seconds), only when a cloned model is used``). Tests
(``src/*/test/``, ``test/``) are out of scope: a test may import what only it needs where it
needs it.
"""

import ast
import collections
import dataclasses
import pathlib
import re
import sys
import xml.etree.ElementTree as ElementTree

import pytest

REPOSITORY = pathlib.Path(__file__).resolve().parents[1]
ARCHITECTURE = REPOSITORY / 'docs' / 'architecture.md'
# A row of the layers table: | 3 | `hrc_agent_node`, `hrc_bag` | what they hold |
LAYER_ROW = re.compile(r'^\|\s*(\d+)\s*\|((?:\s*`\w+`\s*,?)+)\|')
RUNTIME_TAGS = ('depend', 'exec_depend')
TEST_TAGS = RUNTIME_TAGS + ('test_depend',)
# The mark a function-level import needs on its (first) line: ``# lazy: <why>``.
LAZY_MARK = re.compile(r'#\s*lazy:\s*\S')
# Folders of the repository whose modules the function-level rule covers, besides src/<pkg>/.
TOP_LEVEL_FOLDERS = ('bench', 'scripts')
# Files exempt from the function-level rule (none now: the files other helpers changed while
# the rule was set were brought under it at the merge). A path that ends in '/' exempts the
# whole folder.
LAZY_EXEMPT = ()


@dataclasses.dataclass(frozen=True)
class Import:
    """One import statement of a workspace package by a module of another one."""

    path: str                   # relative to the source root's parent, e.g. src/hrc_bag/x.py
    line: int
    importer: str               # package of the module
    imported: str               # package imported
    in_function: bool
    kind: str                   # 'module' | 'test' | 'bench'


def read_layers(text: str) -> dict:
    """Return {package: layer number} of the layers table of docs/architecture.md."""
    layers = {}
    for line in text.splitlines():
        match = LAYER_ROW.match(line.strip())
        if match:
            for package in re.findall(r'`(\w+)`', match.group(2)):
                layers[package] = int(match.group(1))
    return layers


def module_kind(relative: pathlib.Path) -> str:
    """Return 'test', 'bench' or 'module' for a file of src/<package>/."""
    parts = relative.parts[2:]
    if parts and parts[0] in ('test', 'bench'):
        return parts[0]
    return 'module'


def imported_names(node) -> list:
    """Return the absolute module names an import statement loads."""
    if isinstance(node, ast.Import):
        return [alias.name for alias in node.names]
    if isinstance(node, ast.ImportFrom) and not node.level and node.module:
        return [node.module]
    return []


def import_statements(tree) -> list:
    """Return (statement, inside a function) of every import statement of a module's tree."""
    statements = []

    def visit(node, in_function):
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.Import, ast.ImportFrom)):
                statements.append((child, in_function))
            visit(child, in_function or isinstance(child, (ast.FunctionDef,
                                                           ast.AsyncFunctionDef, ast.Lambda)))

    visit(tree, False)
    return statements


def scan_file(path: pathlib.Path, root: pathlib.Path, packages: set) -> list:
    """Return [Import of another package] of one module of src/<package>/."""
    relative = path.relative_to(root.parent)
    importer = relative.parts[1]
    kind = module_kind(relative)
    found = []
    for statement, in_function in import_statements(ast.parse(path.read_text(),
                                                              filename=str(path))):
        for name in imported_names(statement):
            package = name.split('.')[0]
            if package in packages and package != importer:
                found.append(Import(str(relative), statement.lineno, importer, package,
                                    in_function, kind))
    return found


def scan(root: pathlib.Path) -> tuple:
    """Return ([Import], packages) of the tree ``root`` (a src/ folder)."""
    packages = {path.parent.name for path in root.glob('*/package.xml')}
    imports = []
    for path in sorted(root.glob('*/**/*.py')):
        if any(part in ('build', 'install') for part in path.relative_to(root).parts):
            continue
        imports += scan_file(path, root, packages)
    return imports, packages


def modules_not_tests(repository: pathlib.Path) -> list:
    """Return the .py files the function-level rule covers (relative paths), tests left out.

    src/<package>/ except its test/ folder (the package's modules, its benches, setup.py),
    and every file under the folders of TOP_LEVEL_FOLDERS.
    """
    paths = []
    for path in sorted((repository / 'src').glob('*/**/*.py')):
        parts = path.relative_to(repository).parts
        if parts[2] != 'test' and not {'build', 'install'} & set(parts):
            paths.append(path)
    for folder in TOP_LEVEL_FOLDERS:
        paths += sorted((repository / folder).glob('**/*.py'))
    return [path.relative_to(repository) for path in paths]


def function_level_imports(repository: pathlib.Path) -> dict:
    """Return {relative path: [(line, text of its first line)]} of every function-level import."""
    result = {}
    for relative in modules_not_tests(repository):
        text = (repository / relative).read_text()
        lines = text.splitlines()
        inner = [(statement.lineno, lines[statement.lineno - 1].strip())
                 for statement, in_function in import_statements(ast.parse(text, str(relative)))
                 if in_function]
        if inner:
            result[relative.as_posix()] = inner
    return result


def exempt(path: str, exemptions=LAZY_EXEMPT) -> bool:
    """Tell whether ``path`` is (in) an entry of the exemption list."""
    return any(path.startswith(entry) if entry.endswith('/') else path == entry
               for entry in exemptions)


def declared(root: pathlib.Path, package: str) -> dict:
    """Return {tag: {dependency}} of ``package``'s package.xml."""
    document = ElementTree.parse(root / package / 'package.xml').getroot()
    result = collections.defaultdict(set)
    for element in document:
        result[element.tag].add((element.text or '').strip())
    return result


def find_cycle(edges: set):
    """Return one cycle of the package graph as a list of packages, or None."""
    graph = collections.defaultdict(set)
    for importer, imported in edges:
        graph[importer].add(imported)
    state = {}

    def visit(node, path):
        state[node] = 'open'
        for successor in sorted(graph[node]):
            if state.get(successor) == 'open':
                return path[path.index(successor):] + [successor]
            if successor not in state:
                cycle = visit(successor, path + [successor])
                if cycle:
                    return cycle
        state[node] = 'done'
        return None

    for node in sorted(graph):
        if node not in state:
            cycle = visit(node, [node])
            if cycle:
                return cycle
    return None


def layer_problems(imports: list, layers: dict, packages: set) -> list:
    """Return every reason the imports break the layers (unknown packages included)."""
    problems = [f'{package}: not in the layers table of docs/architecture.md'
                for package in sorted(packages - set(layers))]
    for item in imports:
        if item.importer in layers and item.imported in layers \
                and layers[item.imported] >= layers[item.importer]:
            problems.append(f'{item.path}:{item.line}: {item.importer} (layer '
                            f'{layers[item.importer]}) imports {item.imported} (layer '
                            f'{layers[item.imported]})')
    cycle = find_cycle({(item.importer, item.imported) for item in imports})
    if cycle:
        problems.append('package cycle: ' + ' -> '.join(cycle))
    return problems


def declaration_problems(imports: list, root: pathlib.Path) -> list:
    """Return every import of a package that the importer's package.xml does not declare."""
    problems = []
    tags_of = {}
    for item in imports:
        if item.importer not in tags_of:
            tags_of[item.importer] = declared(root, item.importer)
        tags = RUNTIME_TAGS if item.kind == 'module' else TEST_TAGS
        if not any(item.imported in tags_of[item.importer][tag] for tag in tags):
            problems.append(f'{item.path}:{item.line}: imports {item.imported}, which '
                            f'{item.importer}/package.xml does not declare as '
                            f'{" or ".join(f"<{tag}>" for tag in tags)}')
    return problems


def unmarked_function_imports(function_level: dict, exemptions=LAZY_EXEMPT) -> list:
    """Return 'path:line: text' of every function-level import without ``# lazy: <why>``."""
    return [f'{path}:{line}: {text}' for path, found in sorted(function_level.items())
            if not exempt(path, exemptions)
            for line, text in found if not LAZY_MARK.search(text)]


# ------------------------------------------------------------------------------------ tests

@pytest.fixture(scope='module')
def workspace():
    imports, packages = scan(REPOSITORY / 'src')
    return imports, packages, read_layers(ARCHITECTURE.read_text())


def test_the_layers_table_names_every_package(workspace):
    _, packages, layers = workspace
    assert set(layers) == packages


def test_no_cycle_and_no_import_of_a_higher_layer(workspace):
    imports, packages, layers = workspace
    assert layer_problems(imports, layers, packages) == []


def test_every_import_of_another_package_is_declared(workspace):
    imports, _, _ = workspace
    assert declaration_problems(imports, REPOSITORY / 'src') == []


def test_imports_are_at_the_top_or_say_why_they_are_lazy():
    # every module that is not a test: packages, their benches, bench/, scripts/
    assert unmarked_function_imports(function_level_imports(REPOSITORY)) == []


def test_each_exemption_names_an_existing_file_or_folder():
    assert [entry for entry in LAZY_EXEMPT if not (REPOSITORY / entry).exists()] == []


def write_package(root: pathlib.Path, name: str, depends=(), files=None) -> None:
    (root / name / name).mkdir(parents=True)
    (root / name / 'package.xml').write_text(
        '<package format="3"><name>' + name + '</name>'
        + ''.join(f'<{tag}>{dependency}</{tag}>' for tag, dependency in depends)
        + '</package>')
    for relative, text in (files or {}).items():
        path = root / name / relative
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)


def test_the_scan_finds_a_hidden_cycle_an_upward_import_and_a_missing_declaration(tmp_path):
    # low imports high inside a function (hidden from the top of the module), high imports
    # low at the top but declares it only for tests
    root = tmp_path / 'src'
    write_package(root, 'low', files={'low/core.py': 'def f():\n    import high.tool\n'})
    write_package(root, 'high', depends=[('test_depend', 'low')],
                  files={'high/tool.py': 'from low import core\n',
                         'test/test_tool.py': 'from low.core import f\n'})
    imports, packages = scan(root)
    layers = read_layers('| 1 | `low` | x |\n| 2 | `high` | y |\n')
    assert layers == {'low': 1, 'high': 2}
    problems = layer_problems(imports, layers, packages)
    assert problems == ['src/low/low/core.py:2: low (layer 1) imports high (layer 2)',
                        'package cycle: high -> low -> high']
    assert declaration_problems(imports, root) == [
        'src/high/high/tool.py:1: imports low, which high/package.xml does not declare as '
        '<depend> or <exec_depend>',
        'src/low/low/core.py:2: imports high, which low/package.xml does not declare as '
        '<depend> or <exec_depend>']
    assert layer_problems(imports, {'low': 1}, packages)[0] == \
        'high: not in the layers table of docs/architecture.md'


def test_a_function_level_import_needs_a_lazy_reason_on_its_line(tmp_path):
    write_package(tmp_path / 'src', 'solo', files={
        'solo/plot.py': ('import json\n'                              # top: fine
                         'def f():\n'
                         '    import matplotlib  # lazy: 1 s, only for a figure\n'
                         '    from matplotlib import (  # lazy: as above\n'
                         '        pyplot)\n'
                         '    import yaml  # a comment that is not a reason\n'
                         '    # lazy: the line above does not count\n'
                         '    import numpy\n'
                         '    import torch  # lazy:\n'                # no reason given
                         'class C:\n'
                         '    import os\n'                            # class body: top level
                         '    def g(self):\n'
                         '        class D:\n'
                         '            from os import path\n'),       # nested in a method
        'test/test_plot.py': 'def test_f():\n    import matplotlib\n',  # tests: out of scope
        'setup.py': 'def f():\n    import setuptools\n'})
    for folder, name in (('bench', 'rate.py'), ('scripts', 'tool.py'), ('test', 'test_x.py')):
        (tmp_path / folder).mkdir()
        (tmp_path / folder / name).write_text('def main():\n    import rclpy\n')
    (tmp_path / 'bench' / 'other.py').write_text('def main():\n    import rclpy\n')
    function_level = function_level_imports(tmp_path)
    assert sorted(function_level) == ['bench/other.py', 'bench/rate.py', 'scripts/tool.py',
                                      'src/solo/setup.py', 'src/solo/solo/plot.py']
    assert unmarked_function_imports(function_level, exemptions=('bench/other.py',)) == [
        'bench/rate.py:2: import rclpy',
        'scripts/tool.py:2: import rclpy',
        'src/solo/setup.py:2: import setuptools',
        'src/solo/solo/plot.py:6: import yaml  # a comment that is not a reason',
        'src/solo/solo/plot.py:8: import numpy',
        'src/solo/solo/plot.py:9: import torch  # lazy:',
        'src/solo/solo/plot.py:14: from os import path']
    assert unmarked_function_imports(function_level, exemptions=(
        'bench/', 'scripts/tool.py', 'src/solo/')) == []


def main() -> int:
    """Print the package graph and the function-level imports of the modules (not tests)."""
    imports, packages = scan(REPOSITORY / 'src')
    layers = read_layers(ARCHITECTURE.read_text())
    edges = collections.Counter((item.importer, item.imported) for item in imports)
    for (importer, imported), count in sorted(edges.items()):
        print(f'{importer} ({layers.get(importer, "?")}) -> {imported} '
              f'({layers.get(imported, "?")}): {count}')
    function_level = function_level_imports(REPOSITORY)
    counts = collections.defaultdict(collections.Counter)   # place -> {kind: imports}
    for path, found in function_level.items():
        parts = path.split('/')
        place = parts[1] if parts[0] == 'src' else parts[0]
        for _, text in found:
            kind = ('exempt' if exempt(path) else 'lazy' if LAZY_MARK.search(text)
                    else 'unmarked')
            counts[place][kind] += 1
    print('function-level imports (modules that are not tests): '
          f'{sum(len(found) for found in function_level.values())}')
    for place, kinds in sorted(counts.items()):
        print(f'  {place}: {sum(kinds.values())} ('
              + ', '.join(f'{kind} {count}' for kind, count in sorted(kinds.items())) + ')')
    for line in unmarked_function_imports(function_level):
        print('  unmarked: ' + line)
    return 0


if __name__ == '__main__':
    sys.exit(main())
