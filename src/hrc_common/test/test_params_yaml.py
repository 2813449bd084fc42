"""hrc_common.params_yaml: a ROS 2 parameter file rendered from a parameter dataclass."""

from dataclasses import dataclass

import yaml

from hrc_common.params import load_yaml, param
from hrc_common.params_yaml import drift, render, value_text, write


@dataclass
class BaseParams:
    """Physical parameters of a made-up :class:`Plant`."""

    period: float = param(0.2, 'control period (s)', low=0.01, high=1.0)
    rate: float = param(1e-07, 'learning rate, a float YAML must not read as a string', low=0.0)


@dataclass
class ExampleParams(BaseParams):
    """Parameters of a made-up node: the ``BaseParams`` plus these."""

    mode: str = param('lockstep', 'clock mode; a long description that goes on and on about '
                      'what each mode means so that it has to be wrapped on more than one line '
                      'of the comment', choices=('lockstep', 'realtime'))
    actors: list = param(['robot', 'human'], 'actors to wait for', choices=('robot', 'human'))
    names: list = param([''], "node names ([''] = none)")
    label: str = param('', 'free text')
    number_text: str = param('10', 'a string that looks like a number')
    gain: float = param(1.0, 'gain', low=0.0, read_only=False)


def test_the_file_reads_back_as_the_defaults_with_their_types(tmp_path):
    path = tmp_path / 'example.yaml'
    path.write_text(render(ExampleParams, 'example', 'Generated for a test.'))
    assert load_yaml(ExampleParams, path, 'example') == ExampleParams()
    values = yaml.safe_load(path.read_text())['example']['ros__parameters']
    assert list(values) == ['period', 'rate', 'mode', 'actors', 'names', 'label', 'number_text',
                            'gain']
    assert type(values['rate']) is float and values['number_text'] == '10'


def test_comments_are_the_docs_with_ranges_and_choices_and_fit_the_width():
    text = render(ExampleParams, 'example', 'Generated for a test.')
    lines = text.splitlines()
    assert lines[:2] == ['# Parameters of a made-up node: the BaseParams plus these.',
                         '# Generated for a test.']
    assert lines[2:4] == ['example:', '  ros__parameters:']
    assert '    # --- BaseParams: Physical parameters of a made-up Plant.' in lines
    assert '    # control period (s). Range [0.01, 1].' in lines
    assert '    # learning rate, a float YAML must not read as a string. At least 0.' in lines
    assert '    # actors to wait for. Items among: robot, human.' in lines
    assert '    # gain. At least 0. May change at run time (ros2 param set).' in lines
    mode = lines.index('    mode: lockstep')
    assert lines[mode - 1].endswith(' of the comment. One of: lockstep, realtime.')
    assert lines[mode - 2].startswith('    # clock mode; a long description')
    assert max(len(line) for line in lines) <= 99


def test_values_are_one_line_of_flow_yaml():
    assert [value_text(value) for value in (0.2, 20, True, '', 'paper', ['robot', 'human'],
                                            [''], [], 1e-07, 'yes')] == \
        ['0.2', '20', 'true', "''", 'paper', '[robot, human]', "['']", '[]', '1.0e-07', "'yes'"]


def test_drift_names_changed_and_missing_files_and_write_mends_them(tmp_path):
    texts = {'a.yaml': render(ExampleParams, 'a', 'A.'), 'b.yaml': render(BaseParams, 'b', 'B.')}
    assert drift(texts, tmp_path) == ['a.yaml', 'b.yaml']
    assert write(texts, tmp_path) == ['a.yaml', 'b.yaml']
    assert drift(texts, tmp_path) == [] and write(texts, tmp_path) == []
    (tmp_path / 'b.yaml').write_text(texts['b.yaml'].replace('0.2', '0.3'))
    assert drift(texts, tmp_path) == ['b.yaml']
