"""The session runner starts the nodes without loading torch, unless the case pre-trains.

Measured (quiet machine): importing the runner took 1.7 s, 1.4 s of it torch (the
partners-first pre-training, imported for every case), before a single node was launched. Only
cases 7 and 8 pre-train in the runner's process.
"""

import json
import pathlib
import subprocess
import sys

from hrc_agent_node.strategies import pretrains_with_population
from hrc_bringup.session import pretrain_if_needed
from hrc_common.session_plan import compose, SessionSettings
import pytest

PARAMS_DIR = pathlib.Path(__file__).resolve().parents[3] / 'params'


CHECK = """
import json, sys
from hrc_bringup.session import pretrain_if_needed
from hrc_common.session_plan import compose, SessionSettings
import pathlib
parameters = compose(SessionSettings(case=2, seed=0), pathlib.Path({params!r}))
start = pretrain_if_needed(parameters, {run_dir!r})
print(json.dumps({{'start': start, 'torch': 'torch' in sys.modules}}))
"""


def test_the_runner_prepares_a_case_without_pretraining_without_loading_torch(tmp_path):
    check = CHECK.format(params=str(PARAMS_DIR), run_dir=str(tmp_path / 'run'))
    result = subprocess.run([sys.executable, '-c', check], capture_output=True, text=True,
                            timeout=120)
    assert result.returncode == 0, result.stderr
    assert json.loads(result.stdout.splitlines()[-1]) == {'start': None, 'torch': False}


def test_a_bad_cases_file_is_a_value_error_for_the_runner(tmp_path):
    bad = tmp_path / 'cases.yaml'
    bad.write_text('cases: {2: {strategy: nowhere, robot_action: rotation}}\n')
    parameters = compose(SessionSettings(case=2, seed=0), PARAMS_DIR)
    parameters['agent']['cases_file'] = str(bad)
    with pytest.raises(ValueError, match='nowhere'):
        pretrain_if_needed(parameters, tmp_path / 'run')


@pytest.mark.parametrize('case, pretrains', [(1, False), (2, False), (3, False), (4, False),
                                             (5, False), (6, False), (7, True), (8, True)])
def test_only_the_partners_first_cases_pretrain(case, pretrains):
    parameters = compose(SessionSettings(case=case, seed=0), PARAMS_DIR)
    assert pretrains_with_population(parameters['agent']) is pretrains
