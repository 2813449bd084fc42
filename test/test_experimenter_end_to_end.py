"""The experimenter's whole day, end to end: plan, two conditions, the TLX on the page, the report.

As a lab runs a subject: ``hrc study register``, ``assign`` and ``plan`` print the sessions'
commands; the first two conditions run as printed (with a joystick parameters file naming a
FIFO that this test writes in the kernel's js_event format, and short realtime episodes so that
the test takes minutes). The first condition is aborted by the operator while the person acts
and resumed with the command the runner prints; the second has its joystick unplugged in the
middle of the person's episode and plugged in again before the operator resumes. After each
condition the person answers the raw NASA-TLX on their page in Chromium. Then
``hrc bag report --study-dir`` gives one row per condition with its attempts, its outcome
(converged or stopped at the cap) and the TLX.
"""

import csv
import os
import pathlib
import re
import shlex
import subprocess
import sys

from hrc_common.executables import executable_path
from hrc_common.session_control import EXIT_OPERATOR_ABORT
from hrc_testing.live import loose_task_tree, operator, plug_in
from hrc_testing.nodes import wait_for
import yaml

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / 'src' / 'hrc_live'
                       / 'test'))
from browser import open_browser  # noqa: E402

SHORT = ['--set', 'sim.episode_duration=3.0', '--set', 'agent.horizon=64',
         '--set', 'agent.episode_break=0.5', '--set', 'agent.convergence_window=1',
         '--eval-episodes', '1', '--practice', '0', '--no-report', '--display-port', '0',
         '--input-wait', '120', '--tlx-wait', '300']
TLX = {'mental': 40, 'physical': 10, 'temporal': 30, 'performance': 20, 'effort': 50,
       'frustration': 15}


def hrc(*args, cwd, timeout=120) -> subprocess.CompletedProcess:
    return subprocess.run([str(executable_path('hrc_bringup', 'hrc')), *args], cwd=cwd,
                          capture_output=True, text=True, timeout=timeout)


class Runner:
    """One ``hrc session`` process with its output in a file."""

    started = []        # every runner of the test, stopped at its end (a failed test too)

    def __init__(self, command: list, cwd: pathlib.Path, log: pathlib.Path):
        self.log = open(log, 'w+')
        self.process = subprocess.Popen(command, cwd=cwd, stdout=self.log,
                                        stderr=subprocess.STDOUT, text=True)
        Runner.started.append(self)

    def stop(self) -> None:
        """SIGTERM a runner still running: it stops its nodes (a SIGKILL would orphan them)."""
        if self.process.poll() is None:
            self.process.terminate()
            try:
                self.process.wait(timeout=60)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()

    def output(self) -> str:
        self.log.seek(0)
        return self.log.read()

    def wait_for_output(self, pattern: str, timeout: float = 180.0) -> re.Match:
        found = []

        def seen():
            match = re.search(pattern, self.output())
            if match:
                found.append(match)
            return bool(found) or self.process.poll() is not None
        assert wait_for(seen, timeout, 0.2), self.output()
        assert found, f'{pattern!r} never said; exit {self.process.poll()}:\n{self.output()}'
        return found[0]

    def finish(self, timeout: float = 300.0) -> int:
        try:
            return self.process.wait(timeout=timeout)
        finally:
            if self.process.poll() is None:
                self.process.kill()
                self.process.wait()


def answer_tlx(browser, page: str) -> None:
    """Answer the NASA-TLX on the person's page as they would; wait for the thank-you."""
    browser.get(page)
    form = browser.find_element('id', 'tlx')
    assert wait_for(form.is_displayed, 120, 0.2), browser.find_element('tag name', 'body').text
    for name, value in TLX.items():
        browser.find_element('css selector', f'input[name="{name}"][value="{value}"]').click()
    browser.find_element('id', 'tlx-send').click()
    banner = browser.find_element('id', 'banner')
    assert wait_for(lambda: banner.text == 'Thank you, your answers are saved', 30, 0.2)


def planned_commands(folder: pathlib.Path) -> list:
    """Register, assign and plan subject P01; return the printed commands of its conditions."""
    for args in (('register', 'P01', '--consent', 'yes'), ('assign',)):
        result = hrc('study', *args, cwd=folder)
        assert result.returncode == 0, result.stdout + result.stderr
    result = hrc('study', 'plan', 'P01', '--episodes', '6', cwd=folder)
    assert result.returncode == 0, result.stdout + result.stderr
    commands = [shlex.split(line) for line in result.stdout.splitlines()
                if line.startswith('hrc session ')]
    assert len(commands) == 6 and all('--params' in command for command in commands), \
        result.stdout
    return commands


def session_command(planned: list, domain_id: int, session_id: str, folder) -> list:
    """Return the planned command as run here: the installed hrc, a domain, short episodes.

    A loose task tree (every tolerance 10) makes each training step converge after its first
    judging episode, so that the person joins after a few of the robot's episodes.
    """
    return ([str(executable_path('hrc_bringup', 'hrc'))] + planned[1:]
            + ['--domain-id', str(domain_id), '--session-id', session_id,
               '--set', f'agent.task_tree_file={loose_task_tree(folder)}'] + SHORT)


def test_an_experimenter_runs_two_conditions_with_an_abort_and_an_unplug(tmp_path,
                                                                         ros_domain_id):
    fifo = tmp_path / 'js0'
    os.mkfifo(fifo)
    (tmp_path / 'joystick.yaml').write_text(yaml.safe_dump({'human': {'ros__parameters': {
        'device': str(fifo), 'reopen_period': 0.2}}}))
    commands = planned_commands(tmp_path)
    browser = open_browser(1280, 720)
    writer = plug_in(str(fifo))
    try:
        # Condition 1: aborted by the operator while the person acts, then resumed.
        first = Runner(session_command(commands[0], ros_domain_id, 'cond1', tmp_path), tmp_path,
                       tmp_path / 'cond1.log')
        first.wait_for_output(r'the person joins|human yes', 240)
        code, said = operator(ros_domain_id, 'abort')
        assert code == 0, said
        assert first.finish() == EXIT_OPERATOR_ABORT, first.output()
        resume = re.search(r'(hrc session .*--resume-from \S+)', first.output())
        assert resume, first.output()
        resumed = Runner([str(executable_path('hrc_bringup', 'hrc'))]
                         + shlex.split(resume.group(1))[1:], tmp_path, tmp_path / 'cond1b.log')
        page = resumed.wait_for_output(r"the person's page: (http://127\.0\.0\.1:\d+/)").group(1)
        resumed.wait_for_output(r'waiting up to \d+ s for the NASA-TLX', 300)
        answer_tlx(browser, page)
        assert resumed.finish() == 0, resumed.output()

        # Condition 2: the joystick unplugged mid-episode and plugged in again, then resumed.
        second = Runner(session_command(commands[1], ros_domain_id, 'cond2', tmp_path), tmp_path,
                        tmp_path / 'cond2.log')
        page = second.wait_for_output(r"the person's page: (http://127\.0\.0\.1:\d+/)").group(1)
        second.wait_for_output(r'human yes', 240)
        os.close(writer)
        writer = None
        second.wait_for_output(r'joystick disconnected', 60)
        writer = plug_in(str(fifo))
        second.wait_for_output(r'the joystick is connected again', 60)
        # as the console shows it: the agent's own paused status says the joystick is back
        assert wait_for(lambda: 'connected again' in operator(ros_domain_id, 'status')[1],
                        60, interval=0.5)
        code, said = operator(ros_domain_id, 'resume')
        assert code == 0 and 'resumed' in said, said
        second.wait_for_output(r'waiting up to \d+ s for the NASA-TLX', 300)
        answer_tlx(browser, page)
        assert second.finish() == 0, second.output()
    finally:
        browser.quit()
        if writer is not None:
            os.close(writer)
        for runner in Runner.started:   # their nodes would stay on the test's domain
            runner.stop()
        Runner.started.clear()

    # The report of the study: one row per condition, its attempts, outcome and TLX.
    result = hrc('bag', 'report', '--study-dir', 'study', '--out', 'report', cwd=tmp_path,
                 timeout=300)
    assert result.returncode == 0, result.stdout + result.stderr
    with open(tmp_path / 'report' / 'by_subject.csv') as stream:
        rows = [row for row in csv.DictReader(stream) if row['kind'] == 'condition']
    assert [(row['subject_id'], row['case'], row['position']) for row in rows] == [
        ('P01', commands[0][commands[0].index('--case') + 1], '1'),
        ('P01', commands[1][commands[1].index('--case') + 1], '2')], rows
    assert [row['attempts'] for row in rows] == ['3 0', '0'], rows
    assert all(row['outcome'] in ('converged', 'stopped at the cap') for row in rows), rows
    raw = sum(TLX.values()) / len(TLX)
    assert all(abs(float(row['raw_tlx']) - raw) < 0.01 for row in rows), rows
