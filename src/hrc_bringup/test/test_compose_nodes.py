"""hrc_bringup.compose_nodes: several nodes in one process; HRC_COMPOSE for `hrc session`.

(The composed session's equivalence with the engine: test/test_engine_equivalence.py.)
"""

import subprocess
import sys

import pytest

from hrc_bringup.compose_nodes import names_problems, session_composition


def test_unset_means_every_node_its_own_process():
    assert session_composition({}) == ([], [])
    assert session_composition({'HRC_COMPOSE': ' '}) == ([], [])
    assert session_composition({'HRC_COMPOSE': 'sim, human'}) == (['sim', 'human'], [])


@pytest.mark.parametrize('value, reason', [
    ('sim,agent', "'agent' is not a node that can be composed (sim, human, recorder)"),
    ('sim', 'name two or more nodes'),
    ('sim,sim', 'a node is named twice'),
    ('sim,humna', "'humna' is not a node"),
])
def test_a_bad_composition_says_why(value, reason):
    names, problems = session_composition({'HRC_COMPOSE': value})
    assert problems and all(text.startswith(f'HRC_COMPOSE={value!r}: ') for text in problems)
    assert any(reason in text for text in problems), problems


def test_the_container_takes_any_two_nodes_and_refuses_unknown_ones_with_exit_2():
    assert names_problems(['sim', 'agent']) == []
    result = subprocess.run([sys.executable, '-m', 'hrc_bringup.compose_nodes', 'sim', 'joy',
                             'sim'], capture_output=True, text=True, timeout=60)
    assert result.returncode == 2, result.stderr
    assert "'joy' is not a node that can be composed" in result.stderr
    assert 'a node is named twice' in result.stderr
    assert 'Traceback' not in result.stderr
    help_text = subprocess.run([sys.executable, '-m', 'hrc_bringup.compose_nodes', '--help'],
                               capture_output=True, text=True, timeout=60)
    assert help_text.returncode == 0 and 'one process on one executor' in help_text.stdout


def test_hrc_session_refuses_a_bad_composition_with_exit_2(tmp_path, monkeypatch, capsys):
    from hrc_bringup import session

    monkeypatch.setenv('HRC_COMPOSE', 'sim,agent')
    code = session.main(['--no-report', '--runs-dir', str(tmp_path / 'runs'),
                         '--bags-dir', str(tmp_path / 'bags')])
    assert code == 2
    assert "session: HRC_COMPOSE='sim,agent': 'agent' is not a node" in capsys.readouterr().err
    assert not (tmp_path / 'runs').exists()
