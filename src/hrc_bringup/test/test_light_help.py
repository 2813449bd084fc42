"""Every verb's `--help` prints without loading torch, PyBullet, ray, matplotlib or scipy.

Each verb whose runner's module loads them answers --help from its parser built in a light
module (hrc_bringup.cli.Verb.help), with the same text.

Each case runs in a fresh interpreter (a module loaded by an earlier test would hide it).
"""

import importlib
import json
import subprocess
import sys

from hrc_bringup import cli
import pytest

HEAVY = ('torch', 'pybullet', 'ray', 'matplotlib', 'scipy')

CHECK = """
import contextlib, io, json, sys
from hrc_bringup import cli
printed = io.StringIO()
with contextlib.redirect_stdout(printed):
    code = cli.main(sys.argv[1:])
heavy = sorted(name for name in {heavy!r} if name in sys.modules)
print(json.dumps({{'code': code, 'heavy': heavy, 'help': printed.getvalue()}}))
""".format(heavy=HEAVY)

ARGUMENTS = [verb.name.split() for verb in cli.VERBS] + [['session', '--engine', 'inprocess']]


def help_in_a_fresh_interpreter(arguments: list) -> dict:
    """Return {code, heavy (the heavy modules loaded), help} of ``hrc ARGUMENTS --help``."""
    result = subprocess.run([sys.executable, '-c', CHECK, *arguments, '--help'],
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout.splitlines()[-1])


@pytest.mark.parametrize('arguments', ARGUMENTS, ids=' '.join)
def test_help_loads_no_heavy_library(arguments):
    answer = help_in_a_fresh_interpreter(arguments)
    assert answer['code'] == 0
    assert answer['help'].startswith(f'usage: hrc {arguments[0]}'), answer['help']
    assert answer['heavy'] == [], f'hrc {" ".join(arguments)} --help loaded {answer["heavy"]}'


@pytest.mark.parametrize('name, arguments, module, parse', [
    ('session', [], 'hrc_bringup.session', 'parse_args'),
    ('session', ['--engine', 'inprocess'], 'hrc_engine.inprocess_session', 'parse_args'),
    ('experiment', [], 'hrc_bringup.experiment', 'parse_args'),
    ('results', [], 'hrc_study.results_cli', 'parse_arguments'),
    ('partners train', [], 'hrc_partners.training', 'main')])
def test_the_light_help_is_the_help_of_the_verb_itself(capsys, name, arguments, module, parse):
    """The verb's own module, parsing ``--help``, prints the very text of the light help."""
    verb = next(verb for verb in cli.VERBS if verb.name == name)
    with pytest.raises(SystemExit) as exit_:
        verb.help(arguments + ['--help'])
    assert exit_.value.code == 0
    light = capsys.readouterr().out
    with pytest.raises(SystemExit):
        getattr(importlib.import_module(module), parse)(['--help'])
    assert capsys.readouterr().out == light != ''


def test_partners_train_description_is_the_first_paragraph_of_its_module():
    from hrc_partners import training, training_args

    assert training_args.DESCRIPTION == training.__doc__.split('\n\n')[0]
