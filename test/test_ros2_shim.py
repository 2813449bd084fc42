"""Commands as written run here: `source scripts/env.sh` from any directory, then `ros2 run`.

The pip-based set-up has no ROS 2 CLI; env.sh then puts hrc's shim (scripts/bin/ros2) on PATH,
which finds executables with the ament-index lookup of the real `ros2 run`. Every shell below
starts from a minimal environment (as a new terminal would), in /tmp, and sources this
checkout's env.sh.
"""

import os
import pathlib
import re
import shlex
import shutil
import signal
import subprocess
import time

import pytest

REPOSITORY = pathlib.Path(__file__).resolve().parents[1]
ENV_SH = REPOSITORY / 'scripts' / 'env.sh'
SHIM_NOTICE = 'this is the hrc shim'


def fresh_shell(command: str, timeout: float = 120) -> subprocess.CompletedProcess:
    """Run ``command`` in a new bash started in /tmp after sourcing env.sh (no inherited venv)."""
    env = {'HOME': os.environ.get('HOME', '/root'), 'PATH': '/usr/local/bin:/usr/bin:/bin',
           'LANG': 'C.UTF-8'}
    script = f'cd /tmp && source {shlex.quote(str(ENV_SH))} && {command}'
    return subprocess.run(['bash', '-c', script], capture_output=True, text=True, env=env,
                          timeout=timeout)


def readme_ros2_run_commands() -> list:
    """Return every `ros2 run <package> <executable>` of README.md, in order, without repeats."""
    found = []
    for line in (REPOSITORY / 'README.md').read_text().splitlines():
        for package, executable in re.findall(r'ros2 run ([A-Za-z0-9_]+) ([A-Za-z0-9_]+)', line):
            if (package, executable) not in found:
                found.append((package, executable))
    return found


@pytest.mark.slow
def test_env_sh_from_another_directory_gives_ros2_run():
    result = fresh_shell('command -v ros2 && ros2 run hrc_sim_node sim_node --help')
    assert result.returncode == 0, result.stderr
    assert 'usage: ros2 run <package> sim_node' in result.stdout
    ros2 = result.stdout.splitlines()[0]
    if ros2 == str(REPOSITORY / 'scripts' / 'bin' / 'ros2'):
        assert result.stderr.count(SHIM_NOTICE) == 1, result.stderr


def test_the_shim_notice_comes_once_per_shell_and_env_sh_says_it_needs_bash():
    """The notice came on every ``ros2`` call, and env.sh failed under ``sh``."""
    result = fresh_shell(f'ros2 pkg prefix hrc_live && ros2 pkg prefix hrc_sim_node && '
                         f'source {shlex.quote(str(ENV_SH))} && ros2 pkg prefix hrc_live && '
                         f'bash -c "ros2 pkg prefix hrc_live"')
    assert result.returncode == 0, result.stderr
    assert len(result.stdout.splitlines()) == 4, result.stdout
    if f'{REPOSITORY}/scripts/bin' in fresh_shell('echo $PATH').stdout:
        assert result.stderr.count(SHIM_NOTICE) == 1, result.stderr
    for shell in ('sh', 'dash'):
        if shutil.which(shell) is None:
            continue
        refused = subprocess.run([shell, '-c', f'. {shlex.quote(str(ENV_SH))} || echo refused'],
                                 capture_output=True, text=True, timeout=60, cwd='/tmp')
        assert refused.stdout.strip() == 'refused', (shell, refused.stdout, refused.stderr)
        assert refused.stderr.strip() == (
            "scripts/env.sh needs bash (this shell is not bash): run 'bash', then "
            "'source scripts/env.sh'"), (shell, refused.stderr)


@pytest.mark.slow
def test_shim_errors_are_clear():
    result = fresh_shell('ros2 run hrc_nothing some_node; echo "code $?"; '
                         'ros2 run hrc_sim_node some_node; echo "code $?"; '
                         'ros2 topic list; echo "code $?"')
    if f'{REPOSITORY}/scripts/bin' not in fresh_shell('echo $PATH').stdout:
        pytest.skip('a real ROS 2 CLI is installed: the shim is not on PATH')
    assert "Package 'hrc_nothing' not found" in result.stderr
    assert "package 'hrc_sim_node' has no executable 'some_node' (it has: sim_node)" \
        in result.stderr
    assert "'topic' is not available" in result.stderr
    assert [line for line in result.stdout.splitlines() if line.startswith('code')] == [
        'code 1', 'code 1', 'code 2']


@pytest.mark.slow
def test_every_ros2_run_of_the_readme_runs():
    commands = readme_ros2_run_commands()
    assert len(commands) >= 6, commands   # the nodes; every other command is a verb of hrc
    script = ' && '.join(f'ros2 run {package} {executable} --help >/dev/null'
                         for package, executable in commands)
    result = fresh_shell(script, timeout=600)
    assert result.returncode == 0, result.stderr


def readme_hrc_verbs() -> list:
    """Return the verb of every `hrc ...` command of README.md, without repeats.

    A command is inline code that starts with ``hrc `` or a line of a code block that does
    (after an optional ``$ ``); every one must name a verb, except placeholders (``hrc <verb>``),
    ``hrc --help`` and the README's example of a misspelt verb.
    """
    from hrc_bringup.cli import find_verb
    found, in_code = [], False
    for line in (REPOSITORY / 'README.md').read_text().splitlines():
        if line.startswith('```'):
            in_code = not in_code
            continue
        stripped = line.strip().removeprefix('$ ')
        commands = re.findall(r'`hrc ([^`]*)`', line) + (
            [stripped[4:]] if in_code and stripped.startswith('hrc ') else [])
        for command in commands:
            if command.startswith(('<', '-', 'sesion ')):
                continue
            words = re.match(r'[a-z]+(?: [a-z]+)?', command)
            verb, _, problem = find_verb(words.group(0).split() if words else [command])
            assert verb is not None, f'README.md: {line.strip()}: {problem}'
            if verb.name not in found:
                found.append(verb.name)
    return found


@pytest.mark.slow
def test_every_hrc_verb_of_the_readme_runs_from_a_fresh_shell():
    """`hrc` is on PATH after `source scripts/env.sh` (any folder); every verb's --help runs."""
    verbs = readme_hrc_verbs()
    assert len(verbs) >= 10, verbs
    script = 'command -v hrc && hrc --help >/dev/null && ' + ' && '.join(
        f'hrc {verb} --help | grep -q "^example:"' for verb in verbs)
    result = fresh_shell(script, timeout=600)
    assert result.returncode == 0, result.stderr
    assert result.stdout.splitlines()[0].endswith('/lib/hrc_bringup/hrc'), result.stdout


@pytest.mark.slow
def test_the_resume_command_the_runner_prints_runs(tmp_path):
    from hrc_bringup import session_args
    argv = ['--case', '3', '--seed', '2', '--episodes', '4', '--session-id', 'old']
    _, options = session_args.parse_args(argv)
    command = session_args.resume_command(options, 'case3-seed2-x', tmp_path / 'latest.pt')
    words = shlex.split(command)
    assert words[:2] == ['hrc', 'session']
    settings, _ = session_args.parse_args(words[2:])
    assert (settings.case, settings.seed) == (3, 2)
    assert settings.resume_from == str(tmp_path / 'latest.pt')
    assert settings.session_id == 'case3-seed2-x'
    result = fresh_shell(command + ' --help')
    assert result.returncode == 0, result.stderr
    assert 'usage: hrc session' in result.stdout


def readme_node_lines() -> list:
    """Return the README's `ros2 run ... --ros-args ...` lines that name no placeholder."""
    lines = []
    for line in (REPOSITORY / 'README.md').read_text().splitlines():
        line = line.strip().removeprefix('$ ')
        if line.startswith('ros2 run ') and '--ros-args' in line and '<' not in line:
            lines.append(re.split(r'\s+#', line)[0])
    return lines


def test_the_readme_node_commands_start(ros_env, tmp_path):
    """Each node command of the README, run as written in a folder with the params/, starts.

    It must keep running: a bad parameter file or name would exit with code 2 at once. (A copy
    of params/ in a temporary folder, so the bags and checkpoints land there.)
    """
    shutil.copytree(REPOSITORY / 'params', tmp_path / 'params')
    lines = readme_node_lines()
    assert len(lines) >= 4, lines
    env = dict(ros_env)
    processes = []
    try:
        for line in lines:
            script = f'source {shlex.quote(str(ENV_SH))} && exec {line}'
            log = open(tmp_path / f'{len(processes)}.log', 'w+')
            processes.append((line, log, subprocess.Popen(
                ['bash', '-c', script], stdout=log, stderr=subprocess.STDOUT, env=env,
                cwd=tmp_path, start_new_session=True)))
        deadline = time.monotonic() + 8
        while time.monotonic() < deadline and all(p.poll() is None for _, _, p in processes):
            time.sleep(0.2)
        for line, log, process in processes:
            log.seek(0)
            assert process.poll() is None, f'{line}\nexited {process.returncode}:\n{log.read()}'
    finally:
        for _, log, process in processes:
            if process.poll() is None:
                os.killpg(process.pid, signal.SIGINT)
                try:
                    process.wait(timeout=10)
                except subprocess.TimeoutExpired:
                    os.killpg(process.pid, signal.SIGKILL)
                    process.wait()
            log.close()
