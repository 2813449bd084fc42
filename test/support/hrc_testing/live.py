"""Helpers of the live-session tests: the operator CLI, a FIFO joystick, a loose task tree."""

import os
import pathlib
import re
import subprocess

from hrc_common.executables import executable_path
from hrc_common.paths import params_dir
from hrc_joystick_node.js_event import JS_EVENT_AXIS, JS_EVENT_INIT, pack_event


def operator(domain_id, command):
    """Run ``hrc operator <command>``; return (exit code, output)."""
    result = subprocess.run([str(executable_path('hrc_bringup', 'hrc')), 'operator', command,
                             '--domain-id', str(domain_id), '--timeout', '30'],
                            capture_output=True, text=True, timeout=120)
    return result.returncode, result.stdout + result.stderr


def loose_task_tree(folder) -> str:
    """Write the task tree with every tolerance 10 (each step converges at once); its path."""
    source = params_dir() / 'task_tree.yaml'
    path = pathlib.Path(folder) / 'loose_task_tree.yaml'
    path.write_text(re.sub(r'tolerance: .*', 'tolerance: 10.0', source.read_text()))
    return str(path)


def js_bytes(event_type, number, value, init=False):
    """Return one js_event of the kernel's joystick interface."""
    return pack_event(0, value, event_type | (JS_EVENT_INIT if init else 0), number)


def plug_in(fifo, stick=-16384):
    """Open the FIFO as the joystick (O_RDWR never blocks) and send its INIT state."""
    writer = os.open(fifo, os.O_RDWR)
    os.write(writer, js_bytes(JS_EVENT_AXIS, 0, 0, init=True)
             + js_bytes(JS_EVENT_AXIS, 1, stick, init=True))
    return writer
