"""The supervised run of one session: start the nodes, watch them, stop them, report.

:class:`SessionRun` is the runner's loop (``hrc_bringup.session`` prepares its parameters):
the display and the person's input first when asked, the practice, then the recorder, the sim,
the human and the agent as processes (``Supervisor``); every 0.1 s it spins its own node (the
progress lines, the input guard), and it ends when the agent finishes, a node dies, the
operator aborts, the timeout passes or a SIGINT/SIGTERM arrives; the recorder stops last so
its bags are closed with everything in them.
"""

import pathlib
import re
import signal
import sys
import time

from hrc_agent_node.config import AgentParams
from hrc_common.executables import executable_path
from hrc_common.session_control import EXIT_OPERATOR_ABORT, LATEST_CHECKPOINT
from hrc_common.session_plan import NODES, SessionSettings
import rclpy
from rclpy.context import Context

from hrc_bringup.input_guard import InputGuard, wait_for_input
from hrc_bringup.practice import run_practice
from hrc_bringup.session_args import resume_command
from hrc_bringup.session_progress import Progress
from hrc_bringup.session_report import report
from hrc_bringup.study_hooks import condition_words, index_session, owner_only, wait_for_tlx
from hrc_bringup.supervisor import describe_exit, Supervisor

# CPU niceness of the Foxglove live view: at 0 it raised the realtime period jitter's p99 by
# 1.31x (bench/realtime_jitter.py --compare-foxglove, 2 rounds on 2 cores).
VIEWER_NICENESS = 10
# Seconds the runner waits for the display's address in its log before going on.
DISPLAY_ADDRESS_WAIT_S = 15.0
# Stop order: the actors first, the recorder last so it records everything and closes its bags.
STOP_ORDER = ('agent', 'human', 'sim', 'recorder')
# Seconds the loop waits on its node between two looks at the processes.
LOOP_SPIN_S = 0.1


def now_text() -> str:
    """Return the local time as ISO text (the study index's start times)."""
    return time.strftime('%Y-%m-%dT%H:%M:%S')


class SessionRun:
    """One session's processes from start to report (see the module docstring)."""

    def __init__(self, settings: SessionSettings, options, parameters: dict,
                 params_path: pathlib.Path, run_dir: pathlib.Path, env: dict):
        self.settings, self.options, self.parameters = settings, options, parameters
        self.params_path, self.run_dir, self.env = params_path, run_dir, env
        # A resumed session keeps the logs of the run it continues.
        logs = 'logs' if not settings.resume_from else time.strftime('logs-resumed-%Y%m%d-%H%M%S')
        self.supervisor = Supervisor(run_dir / logs, env)
        self.stop_reason = []
        self.process_of = {}     # node -> the name of its process (sim+human when composed)
        self.started = now_text()

    def run(self, params_dir: pathlib.Path, composed: tuple, live_input: str) -> int:
        """Run the session; return its exit code."""
        settings = self.settings
        print(f'[session] {settings.session_id}: case {settings.case}, seed {settings.seed}, '
              f'{settings.mode}, human input {settings.human_input}; logs and parameters in '
              f'{self.run_dir}' + (f', bags in {pathlib.Path(settings.bags_dir) / settings.session_id}'  # noqa: E501
                                   if settings.record else ''), flush=True)
        previous = {sig: signal.signal(sig, self._on_signal)
                    for sig in (signal.SIGINT, signal.SIGTERM)}
        self.context = Context()
        rclpy.init(context=self.context, domain_id=self.options.domain_id,
                   signal_handler_options=rclpy.signals.SignalHandlerOptions.NO)
        agent = self.parameters['agent']
        self.progress = Progress(self.context, sys.stdout.isatty(),
                                 max_training_episodes=agent.get('max_training_episodes'),
                                 evaluation_episodes=agent.get(
                                     'evaluation_episodes', AgentParams.evaluation_episodes))
        self.executor = rclpy.executors.SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.progress.node)
        self.guard = (InputGuard(self.progress.node, live_input,
                                 self.parameters['human'].get('device', ''),
                                 self.options.link_timeout)
                      if live_input and self.options.stand_in == 'none' else None)
        if self.guard is not None:
            self.progress.paused_for_input = lambda: self.guard.lost
        self.start = time.monotonic()
        try:
            early = self._before_the_nodes(params_dir, live_input)
            if early is None:
                self._start_nodes(composed)
                code = self._watch()
        finally:
            exits = self._stop()
            for sig, handler in previous.items():
                signal.signal(sig, handler)
        if early is not None:       # no input, or the practice failed: no session ran
            return early
        return self._finish(code, exits)

    def _on_signal(self, signum, frame):
        self.stop_reason.append(signal.Signals(signum).name)

    def _before_the_nodes(self, params_dir: pathlib.Path, live_input: str):
        """Run the display, wait for the person's input, run the practice; an exit code to stop."""
        options = self.options
        if options.display:
            # served from the start (the waiting-for-the-joystick screen included)
            self.supervisor.start('display', display_command(options, params_dir, self.run_dir,
                                                             self.settings))
            print_display_address(self.supervisor.processes['display'], self.executor,
                                  self.stop_reason)
        if options.foxglove:
            # a viewer yields the CPU to the control loop (it drops samples, never holds one)
            self.supervisor.start('foxglove', live_node_command('foxglove', params_dir,
                                                                options.foxglove_port),
                                  niceness=VIEWER_NICENESS)
        if live_input and not wait_for_input(
                self.guard or InputGuard(self.progress.node, live_input,
                                         self.parameters['human'].get('device', '')),
                self.executor, options.input_wait, self.stop_reason):
            return 2
        if options.practice:
            practice_started = now_text()
            practice_code = run_practice(self.settings, options, params_dir, self.env,
                                         self.progress, self.executor, self.stop_reason)
            index_session(self.settings, options, 'practice', practice_started, practice_code)
            if practice_code != 0:
                return practice_code
            self.progress.restart()
            self.started = now_text()
        return None

    def _start_nodes(self, composed: tuple) -> None:
        """Start the recorder (it sees the first state), the sim, the human, then the agent.

        Composed nodes (``HRC_COMPOSE``) share one process.
        """
        remote = self.options.remote_nodes
        for node in ('recorder', 'sim', 'human', 'agent'):
            if node not in self.parameters or node in remote or node in self.process_of:
                continue
            together = [name for name in composed if name in self.parameters
                        and name not in remote] if node in composed else []
            if len(together) > 1:
                # one process, one executor (hrc_bringup.compose_nodes), named sim+human...
                self.supervisor.start('+'.join(together), [
                    sys.executable, '-m', 'hrc_bringup.compose_nodes', *together, '--ros-args',
                    '--params-file', str(self.params_path)])
                self.process_of.update((name, '+'.join(together)) for name in together)
                continue
            package, executable, _ = NODES[node]
            self.supervisor.start(node, [str(executable_path(package, executable)), '--ros-args',
                                         '--params-file', str(self.params_path)],
                                  niceness=self.options.recorder_niceness
                                  if node == 'recorder' else 0)
            self.process_of[node] = node

    def _watch(self) -> int:
        """Spin until the session ends; return its exit code."""
        while True:
            self.executor.spin_once(timeout_sec=LOOP_SPIN_S)
            if self.stop_reason:
                print(f'[session] {self.stop_reason[0]} received: stopping the session',
                      flush=True)
                return 130 if self.stop_reason[0] == 'SIGINT' else 143
            code = self._guard_tick()
            if code == 'continue':
                continue
            if code is not None:
                return code
            code = self._on_exits()
            if code == 'continue':
                continue
            if code is not None:
                return code
            if self.options.timeout and time.monotonic() - self.start > self.options.timeout:
                print(f'[session] timeout of {self.options.timeout:.0f} s reached: stopping',
                      file=sys.stderr, flush=True)
                return 124

    def _guard_tick(self):
        """Tick the person's input guard (the agent holds a lost input itself): None."""
        if self.guard is not None:
            self.guard.tick()
        return None

    def _on_exits(self):
        """Handle a node that exited: the exit code, 'continue', or None (none exited)."""
        finished = self.supervisor.exited()
        if not finished:
            return None
        first = finished[0]
        if first.name == 'agent' and first.returncode == 0:
            print('[session] the agent finished the session', flush=True)
            if self.options.tlx:
                wait_for_tlx(self.run_dir / 'tlx.yaml', self.settings.session_id, self.executor,
                             self.options.tlx_wait, self.stop_reason)
            return 0
        if first.name == 'agent' and first.returncode == EXIT_OPERATOR_ABORT:
            message = self.progress.status.message if self.progress.status else ''
            print(f'[session] the operator aborted the session ({message}); stopping '
                  f'the other nodes and closing the bags', flush=True)
            return EXIT_OPERATOR_ABORT
        print(f'[session] node {first.name} stopped unexpectedly '
              f'({describe_exit(first.returncode)}); stopping the session. Last '
              f'output of {first.name}:\n{first.tail()}', file=sys.stderr, flush=True)
        return 1

    def _stop(self) -> dict:
        """Stop every process (the recorder last) and the runner's node; return the exits."""
        # a composed process stops where its last node would (the recorder still last)
        order = []
        for node in reversed(STOP_ORDER):
            if self.process_of.get(node, node) not in order:
                order.append(self.process_of.get(node, node))
        exits = self.supervisor.stop_all(order[::-1])
        # Let the last episode summaries arrive before closing.
        self.progress.close()
        self.executor.shutdown()
        rclpy.shutdown(context=self.context)
        return exits

    def _finish(self, code: int, exits: dict) -> int:
        """Say how the nodes ended, how to resume, report and index; return the exit code."""
        settings, parameters = self.settings, self.parameters
        print(f'[session] stopped after {time.monotonic() - self.start:.1f} s: ' + ', '.join(
            f'{name} {describe_exit(returncode)}' for name, returncode in exits.items()),
            flush=True)
        recorder_exit = next((returncode for name, returncode in exits.items()
                              if 'recorder' in name.split('+')), 0)
        if recorder_exit not in (0, None) and code in (0, EXIT_OPERATOR_ABORT):
            print('[session] the recorder did not exit cleanly: check its log', file=sys.stderr)
            code = 1
        if code in (EXIT_OPERATOR_ABORT, 1):     # aborted, or a node failed: say how on
            checkpoint = (pathlib.Path(parameters['agent']['checkpoint_dir'])
                          / settings.session_id / LATEST_CHECKPOINT)
            if checkpoint.is_file():
                print('[session] to resume from the last finished episode (counters continue):'
                      f'\n  {resume_command(self.options, settings.session_id, checkpoint)}',
                      flush=True)
            else:
                print('[session] no episode had finished: there is no checkpoint to resume '
                      'from', flush=True)
        if settings.record and self.options.report and (code == 0 or self.progress.episodes):
            if report(settings, self.run_dir) and code == 0:
                print('[session] the bags miss part of what the session ran (above): exit 1',
                      file=sys.stderr, flush=True)
                code = 1
        index_session(settings, self.options, 'condition', self.started, code)
        if settings.subject_id:
            owner_only(settings, parameters)
        return code


def print_display_address(display, executor, stop_reason: list) -> None:
    """Print the addresses of the person's page and the console once the display serves.

    Read from the display's log line; its port may be chosen by the system (0).
    """
    deadline = time.monotonic() + DISPLAY_ADDRESS_WAIT_S
    while time.monotonic() < deadline and not stop_reason:
        found = re.search(r'serving the display on (http://\S+?/) ', display.tail(lines=50))
        if found:
            print(f"[session] the person's page: {found.group(1)}   the experimenter's "
                  f'console: {found.group(1)}console', flush=True)
            return
        if display.returncode is not None:
            break
        executor.spin_once(timeout_sec=0.1)
    print(f'[session] the display did not say its address within {DISPLAY_ADDRESS_WAIT_S:.0f} '
          f's: see {display.log_path}', file=sys.stderr, flush=True)


def live_node_command(node: str, params_dir: pathlib.Path, port) -> list:
    """Return the command line of a live node of hrc_live (``display`` or ``foxglove``).

    Its parameters from ``params_dir``/<node>.yaml when there, ``port`` given when not None.
    """
    command = [str(executable_path('hrc_live', f'{node}_node')), '--ros-args']
    params_file = params_dir / f'{node}.yaml'
    if params_file.is_file():
        command += ['--params-file', str(params_file)]
    if port is not None:
        command += ['-p', f'port:={port}']
    return command


def display_command(options, params_dir: pathlib.Path, run_dir: pathlib.Path,
                    settings: SessionSettings) -> list:
    """Return the command line of the display node of this session (subject: the console)."""
    command = live_node_command('display', params_dir, options.display_port)
    if options.tlx:
        command += ['-p', f'tlx_file:={(run_dir / "tlx.yaml").resolve()}']
    if options.gamepad:
        command += ['-p', 'gamepad:=true']
    if settings.subject_id:
        command += ['-p', f'subject_id:={settings.subject_id}',
                    '-p', f'condition:={condition_words(settings, options)}']
    return command
