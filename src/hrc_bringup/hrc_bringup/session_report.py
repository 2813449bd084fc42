"""The report at the end of a session: the report CLI on its bags, Table II printed."""

import pathlib
import subprocess
import sys

from hrc_bag.report.loading import RECORDER_MISSED
from hrc_common.executables import executable_path
from hrc_common.session_plan import SessionSettings

from hrc_bringup.supervisor import describe_exit


def report(settings: SessionSettings, run_dir: pathlib.Path) -> list:
    """Run the report CLI on the session's bags and print its Table II.

    Returns the report's notices of what the recorder missed (episodes or states not in the
    bags): the session then did not record what it ran.
    """
    bag_dir = pathlib.Path(settings.bags_dir) / settings.session_id
    out_dir = run_dir / 'report'
    result = subprocess.run([str(executable_path('hrc_bringup', 'hrc')), 'bag', 'report',
                             str(bag_dir), '--out', str(out_dir)], capture_output=True, text=True)
    print(result.stdout, end='')
    for line in result.stderr.splitlines():     # the report's notices and reasons
        print(f'[session] {line}', file=sys.stderr, flush=True)
    if result.returncode != 0:
        print(f'[session] report failed ({describe_exit(result.returncode)})', file=sys.stderr)
        return []
    print(f'[session] bags: {bag_dir}   report and figures: {out_dir}', flush=True)
    return [line for line in result.stderr.splitlines() if RECORDER_MISSED in line]
