"""The session runner starts the nodes without loading torch, unless the case pre-trains.

Measured (issue 24, quiet machine): importing the runner took 1.7 s, 1.4 s of it torch (the
partners-first pre-training, imported for every case), before a single node was launched. Only
cases 7 and 8 pre-train in the runner's process.
"""

import json
import pathlib
import subprocess
import sys

from hrc_bringup.session import needs_pretraining
from hrc_common.session_plan import compose, SessionSettings
import pytest

PARAMS_DIR = pathlib.Path(__file__).resolve().parents[3] / 'params'


def test_the_session_runner_module_loads_no_torch():
    check = ('import json, sys; import hrc_bringup.session; '
             "print(json.dumps('torch' in sys.modules))")
    result = subprocess.run([sys.executable, '-c', check], capture_output=True, text=True,
                            timeout=120)
    assert result.returncode == 0, result.stderr
    assert json.loads(result.stdout.splitlines()[-1]) is False


@pytest.mark.parametrize('case, pretrains', [(1, False), (2, False), (3, False), (4, False),
                                             (5, False), (6, False), (7, True), (8, True)])
def test_only_the_partners_first_cases_pretrain(case, pretrains):
    parameters = compose(SessionSettings(case=case, seed=0), PARAMS_DIR)
    assert needs_pretraining(parameters) is pretrains
