"""The session runner prints the report's notices (owned by the bag engineer: hrc_bag's report).

A killed recorder leaves an episode file open; the report says so on stderr, and the runner
used to print the report's stderr only when it failed.
"""

from hrc_testing.bag_traffic import record_in_process, strategy_plan
from hrc_bringup.session_report import report
from hrc_common.session_plan import SessionSettings
import pytest


@pytest.mark.slow
def test_the_runner_prints_the_reports_notices(tmp_path, capsys):
    plan = strategy_plan('learn_together', 1, 0, 1)
    record_in_process(tmp_path / 'bags', 'cut', 5, 'learn_together', 2, plan, steps=4)
    folder = tmp_path / 'bags' / 'cut'
    # as a killed recorder leaves its open episode: not finished, not listed
    (folder / 'metadata.yaml').write_text('- not\n- rosbag2 metadata\n')
    last = folder / 'cut_episode0002.mcap'
    data = last.read_bytes()
    last.write_bytes(data[:len(data) - 600])
    settings = SessionSettings(case=5, session_id='cut', bags_dir=str(tmp_path / 'bags'))
    report(settings, tmp_path / 'run')
    printed = capsys.readouterr()
    assert '| 5 | together | translation | 1 |' in printed.out
    assert '[session] hrc bag report:' in printed.err
    assert 'a file was not closed (recorder killed?)' in printed.err
    assert 'using the MCAP files of the folder' in printed.err
    assert (tmp_path / 'run' / 'report' / 'table2.md').is_file()
