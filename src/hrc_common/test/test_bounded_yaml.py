"""hrc_common.bounded_yaml: hostile YAML is refused in one line, hrc's own files load as before."""

import pathlib

import pytest
import yaml

from hrc_common import bounded_yaml
from hrc_common.paths import params_dir

# The three ways a safe-loaded YAML still hurts, each a few kilobytes of text.
DEEP = '[' * 20000 + ']' * 20000                            # RecursionError in PyYAML
LONG_INTEGER = 'agent:\n  ros__parameters:\n    seed: ' + '9' * 5000 + '\n'   # int() limit
LAUGHS = 'l0: &l0 [ha, ha]\n' + ''.join(                    # 2**41 values once expanded
    f'l{level}: &l{level} [*l{level - 1}, *l{level - 1}]\n' for level in range(1, 41))


@pytest.mark.parametrize('text, reason, line', [
    (DEEP, 'nested more than 64 levels deep', 1),
    (LONG_INTEGER, 'an integer of 5000 digits', 3),
    (LAUGHS, 'values with its aliases (*name) expanded', 18),
    ('a: 0x' + 'f' * 200, 'an integer of 202 digits', 1),
    ('a: !!int "' + '1' * 200 + '"', 'an integer of 200 digits', 1),
])
def test_hostile_documents_are_refused_with_the_reason_and_line(text, reason, line):
    with pytest.raises(bounded_yaml.YamlLimitError) as caught:
        bounded_yaml.load(text, 'hostile.yaml')
    message = str(caught.value)
    assert message.startswith(f'hostile.yaml (line {line}): ') and reason in message, message
    assert '\n' not in message and len(message) < 300, message
    # every handler of broken YAML (yaml.YAMLError) or of bad values (ValueError) takes it
    assert isinstance(caught.value, yaml.YAMLError) and isinstance(caught.value, ValueError)
    assert bounded_yaml.describe(caught.value).startswith(f'line {line}, column ')


def test_a_file_too_large_is_refused_before_it_is_read(tmp_path):
    path = tmp_path / 'large.yaml'
    path.write_text('a: ' + 'x' * 200)
    with pytest.raises(bounded_yaml.YamlLimitError, match='203 bytes, more than the 100'):
        bounded_yaml.load_file(path, max_bytes=100)
    with pytest.raises(bounded_yaml.YamlLimitError, match='more than the 4194304'):
        bounded_yaml.load('a: ' + 'x' * bounded_yaml.MAX_BYTES)


def test_ordinary_documents_load_as_pyyaml_loads_them():
    text = ('a: &shared {b: [1, 2.5, "3"], c: 0x1f, d: 1_000}\n'
            'e: *shared\nf: "' + '9' * 500 + '"\ng: ' + '7' * 100 + '\n')
    assert bounded_yaml.load(text) == yaml.safe_load(text)
    assert bounded_yaml.load(text.encode()) == yaml.safe_load(text)
    assert bounded_yaml.load('') is None


def test_every_shipped_yaml_file_is_within_the_bounds():
    files = sorted(pathlib.Path(params_dir()).rglob('*.yaml'))
    assert len(files) >= 10, files
    for path in files:
        assert bounded_yaml.load_file(path) == yaml.safe_load(path.read_text()), path


def test_a_parse_error_is_described_in_one_line_without_the_path():
    with pytest.raises(yaml.YAMLError) as caught:
        bounded_yaml.load('a: [1, 2\n', 'broken.yaml')
    assert bounded_yaml.describe(caught.value) == (
        "line 2, column 1: did not find expected ',' or ']'")


def test_brief_quotes_at_most_the_limit():
    assert bounded_yaml.brief('short') == "'short'"
    quoted = bounded_yaml.brief('x' * 1000, 20)
    assert quoted.startswith("'" + 'x' * 19) and quoted.endswith('(1002 characters)')
