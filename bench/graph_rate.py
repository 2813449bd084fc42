#!/usr/bin/env python3
"""Benchmark: lockstep control steps per second of the engines, measured in one run.

    python bench/graph_rate.py --episodes 3 --case 2 --repeats 3     # from any directory
    python bench/graph_rate.py --case 5 --human-period 0.2 0.02       # both human rates

Measures, within episodes (PPO updates between episodes excluded everywhere), in rounds that
run each variant in turn so that a change of machine load hits them alike:

1. bare: the engine's loop (``hrc_engine.loop``: physics, step protocol, AgentCore, the human
   node's core) alone: the floor, no messages, no bags;
2. engine: the in-process engine (``hrc_engine``: step protocol, messages, bags written);
3. graph: ``session`` (sim, agent, human as separate processes over DDS), no recorder, timed
   by a listener on /hrc/state in this process;
4. graph + recorder: the same with the MCAP recorder.

Prints steps/s (median over episodes) of each, and the ratios of each round (median over the
rounds): graph / engine, graph / bare, recorder overhead (steps/s and nodes' CPU), engine /
bare. The parameters are the session's (params/ of this checkout, else the installed ones).

``--human-period`` (s, one or more): the sim's ``human_period`` for the engine and the graph
(each value measured in turn, in every round). The human acts at that rate only while it is
involved (case 2's first episodes are the robot's alone: use a case whose human acts from the
start, 3-6). The bare loop runs the parameters' own human_period.
"""

import argparse
import os
import pathlib
import queue
import statistics
import subprocess
import sys
import tempfile
import threading
import time

import rclpy
from rclpy.context import Context
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor

from hrc_agent_node.agent_core import AgentCore
from hrc_agent_node.config import AgentParams
from hrc_common import qos, topics
from hrc_common.contract import SimLimits
from hrc_common.executables import executable_path
from hrc_common.params import from_dict
from hrc_common.proc_tree import cpu_between, thread_cpu_ns
from hrc_common.session_plan import SessionSettings
from hrc_engine.engine import compose_parameters, EngineConfig, run_session
from hrc_engine.human import SimulatedHumanSide
from hrc_engine.loop import EpisodeLoop, run_agent_episode
from hrc_msgs.msg import TaskState
from hrc_sim_node.physics import physics_params_of, SliderPendulumBall
from hrc_sim_node.protocol import ProtocolSettings, StepProtocol
from hrc_sim_node.sim_params import SimParams
from hrc_sim_node.stepper import SimStepper


def session_parameters(case: int, seed: int, episodes: int) -> dict:
    """Return the session's composed node parameters (as ``session`` would run them)."""
    _, parameters = compose_parameters(EngineConfig(SessionSettings(
        case=case, seed=seed, training_episodes=episodes + 1, session_id='bench')))
    return parameters


def bare_rate(case: int, episodes: int, seed: int) -> float:
    """Return median steps/s of the engine's loop with nothing recorded."""
    parameters = session_parameters(case, seed, episodes)
    parameters['agent']['checkpoint_dir'] = ''
    limits = SimLimits.of(from_dict(SimParams, parameters['sim']))
    core = AgentCore(from_dict(AgentParams, parameters['agent']), limits=limits)
    human = SimulatedHumanSide.from_parameters(parameters['human'], limits)
    rates = []
    sim_params = from_dict(SimParams, dict(parameters['sim'], mode='lockstep'))
    with SliderPendulumBall(physics_params_of(sim_params)) as sim:
        loop = EpisodeLoop(SimStepper(sim, StepProtocol(ProtocolSettings.of(sim_params))), human)
        for _ in range(episodes):
            start = time.perf_counter()
            result = run_agent_episode(core, loop)
            rates.append(result.steps / (time.perf_counter() - start))
            if core.phase == 'updating':
                core.update()
    return statistics.median(rates)


def engine_rate(case: int, episodes: int, seed: int, work: pathlib.Path,
                human_period: float = None) -> float:
    """Return median steps/s of the in-process engine's episodes (bags written)."""
    result = run_session(EngineConfig(SessionSettings(
        case=case, seed=seed, training_episodes=episodes, evaluation_episodes=0,
        session_id=f'engine-{time.time_ns()}', bags_dir=str(work / 'bags'),
        runs_dir=str(work / 'runs'),
        overrides={} if human_period is None else {'sim.human_period': human_period})))
    steps = [episode['steps'] for episode in result.episodes]
    return statistics.median(step / seconds
                             for step, seconds in zip(steps, result.episode_seconds))


class CpuMarks:
    """Samples a process tree's threads' CPU (``thread_cpu_ns``) on request, in its own thread.

    ``mark(label)`` ('first' or 'end') returns at once (the listener that calls it is not held
    up by reading /proc); ``marks`` holds (label, {(pid, tid): ns}, processes alive) in order.
    """

    def __init__(self, root_pid: int):
        self.root_pid = root_pid
        self.marks = []
        self.names = {}   # pid -> process_label
        self._requests = queue.Queue()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def mark(self, label) -> None:
        self._requests.put(label)

    def _run(self):
        while (label := self._requests.get()) is not None:
            cpu = thread_cpu_ns(self.root_pid)
            self.marks.append((label, cpu, len({pid for pid, _ in cpu})))
            for pid, _ in cpu:
                if pid not in self.names:
                    self.names[pid] = process_label(pid, self.root_pid)

    def close(self) -> None:
        """Finish the pending samples."""
        self._requests.put(None)
        self._thread.join(timeout=10)

    def running_cpu(self) -> float:
        """Return the CPU (s) from the 'first' mark to the last one with every process alive.

        A mark sampled after a node exited would lose that node's time, so the last mark that
        saw as many processes as the first is the end; nan without such a pair.
        """
        window = self._window()
        return cpu_between(*window) if window else float('nan')

    def running_cpu_by_process(self) -> dict:
        """Return {process label: CPU s} over the window of :meth:`running_cpu` ({} without)."""
        window = self._window()
        if not window:
            return {}
        start, end = window
        by_process = {}
        for pid in {pid for pid, _ in end}:
            threads = {key: ns for key, ns in end.items() if key[0] == pid}
            label = self.names.get(pid, str(pid))
            by_process[label] = by_process.get(label, 0.0) + cpu_between(start, threads)
        return by_process

    def _window(self):
        """Return (first mark's CPU, last full 'end' mark's CPU), or None."""
        first = [(cpu, alive) for label, cpu, alive in self.marks if label == 'first']
        if not first:
            return None
        start, alive_then = first[0]
        ends = [cpu for label, cpu, alive in self.marks if label == 'end' and alive >= alive_then]
        return (start, ends[-1]) if ends else None


def process_label(pid: int, root_pid: int) -> str:
    """Name a session's process: 'runner' for the root, else its executable ('sim_node', ...).

    A composed process (``python -m hrc_bringup.compose_nodes sim human``) is named after its
    nodes ('sim+human').
    """
    if pid == root_pid:
        return 'runner'
    try:
        with open(f'/proc/{pid}/cmdline', 'rb') as cmdline:
            words = cmdline.read().decode(errors='replace').split('\0')
    except OSError:
        return str(pid)
    head = [word for word in (words[:words.index('--ros-args')] if '--ros-args' in words
                              else words[:2]) if word]
    if 'hrc_bringup.compose_nodes' in head:
        label = '+'.join(head[head.index('hrc_bringup.compose_nodes') + 1:])
    else:
        label = pathlib.Path(head[-1]).name if head else ''
    return label if label and not label.startswith('-') else str(pid)


class StateTimer:
    """Records the receive time of every /hrc/state message on a domain (own thread).

    ``cpu``: a CpuMarks to mark at the first state received ('first') and at every episode's
    last state ('end'): the session's CPU while the episodes run, start-up and shutdown left
    out.
    """

    def __init__(self, domain_id: int):
        self.cpu = None
        self.context = Context()
        rclpy.init(context=self.context, domain_id=domain_id)
        self.node = rclpy.create_node('bench_state_timer', context=self.context)
        self.samples = []  # (episode, step, receive time)
        self.node.create_subscription(TaskState, topics.STATE, self._on_state, qos.STATE_QOS)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.thread = threading.Thread(target=self._spin, daemon=True)
        self.thread.start()

    def _on_state(self, state):
        self.samples.append((state.episode, state.step, time.perf_counter()))
        if self.cpu is not None:
            if len(self.samples) == 1:
                self.cpu.mark('first')
            elif state.terminated or state.truncated:
                self.cpu.mark('end')

    def _spin(self):
        try:
            while self.context.ok():
                self.executor.spin_once(timeout_sec=0.1)
        except ExternalShutdownException:
            pass

    def episode_rates(self) -> list:
        """Return steps/s of every complete episode (first to last state received)."""
        by_episode = {}
        for episode, step, stamp in self.samples:
            by_episode.setdefault(episode, []).append((step, stamp))
        rates = []
        for samples in by_episode.values():
            steps = [step for step, _ in samples]
            if len(samples) > 100:
                times = [stamp for _, stamp in samples]
                rates.append((max(steps) - min(steps)) / (max(times) - min(times)))
        return rates

    def close(self):
        """Stop the listener."""
        rclpy.shutdown(context=self.context)
        self.thread.join(timeout=5)


def graph_rate(case: int, episodes: int, seed: int, record: bool, domain_id: int,
               work: pathlib.Path, human_period: float = None, settings=()) -> dict:
    """Run a session and return {'rate': median steps/s, 'cpu': child CPU s, 'wall': s, ...}.

    'cpu' is the whole session's (start-up included); 'running_cpu' the session's CPU (s; the
    runner and its nodes) from the first state to the last episode's last state and
    'cpu_per_step' that per state received (nan when no state or no last state was seen);
    'cpu_per_step_by_process' the same split by process ({process_label: s}, {} without).

    ``settings``: more ``NODE.PARAM=VALUE`` overrides (``hrc session --set``). The result also
    names the session (``session_id``; its logs are in ``work/runs/<session_id>/logs``).
    """
    timer = StateTimer(domain_id)
    name = f'graph-{time.time_ns()}'
    command = [str(executable_path('hrc_bringup', 'hrc')), 'session', '--case', str(case),
               '--seed', str(seed), '--episodes', str(episodes), '--eval-episodes', '0',
               '--domain-id', str(domain_id), '--no-report', '--bags-dir', str(work / 'bags'),
               '--runs-dir', str(work / 'runs'), '--session-id', name]
    if not record:
        command.append('--no-record')
    if human_period is not None:
        command += ['--set', f'sim.human_period={human_period}']
    for setting in settings:
        command += ['--set', setting]
    before = os.times()
    start = time.perf_counter()
    session = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               text=True, cwd=work)
    timer.cpu = CpuMarks(session.pid)
    stdout, stderr = session.communicate()
    wall = time.perf_counter() - start
    after = os.times()
    time.sleep(0.5)
    timer.close()
    timer.cpu.close()
    if session.returncode != 0:
        raise RuntimeError(f'session failed:\n{stdout}\n{stderr}')
    rates = timer.episode_rates()
    # The session's CPU (the runner and its nodes) from the first state to the last episode's
    # last state, per step: the running cost without the start-up and the shutdown (which
    # dominate a short session).
    steps = len(timer.samples)
    running = timer.cpu.running_cpu()
    return {'rate': statistics.median(rates) if rates else float('nan'), 'episodes': len(rates),
            'cpu': (after.children_user + after.children_system)
            - (before.children_user + before.children_system), 'wall': wall,
            'running_cpu': running, 'cpu_per_step': running / max(steps - 1, 1),
            'cpu_per_step_by_process': {label: seconds / max(steps - 1, 1) for label, seconds
                                        in timer.cpu.running_cpu_by_process().items()},
            'session_id': name}


def main() -> int:
    """Run the measurements in rounds and print them with their ratios."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--case', type=int, default=2)
    parser.add_argument('--episodes', type=int, default=3)
    parser.add_argument('--seed', type=int, default=0)
    parser.add_argument('--domain-id', type=int, default=91)
    parser.add_argument('--repeats', type=int, default=3, help='rounds of the four runs')
    parser.add_argument('--human-period', type=float, nargs='+', default=[None],
                        help="the sim's human_period (s) for the engine and the graph; "
                             'several: each is measured in every round (default: params/)')
    args = parser.parse_args()

    load = os.getloadavg()[0]
    print(f'machine: {os.cpu_count()} cores, load {load:.1f}, python {sys.version.split()[0]}; '
          f'case {args.case}, {args.episodes} episodes of 200 steps per measurement, '
          f'{args.repeats} rounds (bare, engine, graph, graph + recorder in turn)', flush=True)
    results = {period: [] for period in args.human_period}
    with tempfile.TemporaryDirectory(prefix='hrc-bench-') as folder:
        work = pathlib.Path(folder)
        for index in range(args.repeats):
            bare = bare_rate(args.case, args.episodes, args.seed)
            for period in args.human_period:
                engine = engine_rate(args.case, args.episodes, args.seed, work, period)
                graph = graph_rate(args.case, args.episodes, args.seed, False, args.domain_id,
                                   work, period)
                recorded = graph_rate(args.case, args.episodes, args.seed, True,
                                      args.domain_id, work, period)
                results[period].append((bare, engine, graph, recorded))
                print(f'round {index + 1}, human_period {period or "(params)"}: bare '
                      f'{bare:5.0f} | engine {engine:5.0f} | graph {graph["rate"]:5.0f} '
                      f'(nodes CPU {graph["cpu"]:.1f} s) | graph + recorder '
                      f'{recorded["rate"]:5.0f} steps/s (nodes CPU {recorded["cpu"]:.1f} s)',
                      flush=True)
    median = statistics.median
    for period, rounds in results.items():
        print(f'-- human_period {period or "(params)"} s')
        print(f'median bare physics + policy + human: {median(r[0] for r in rounds):6.0f} '
              f'steps/s')
        print(f'median in-process engine (bags)     : {median(r[1] for r in rounds):6.0f} '
              f'steps/s')
        print(f'median graph over DDS               : '
              f'{median(r[2]["rate"] for r in rounds):6.0f} steps/s')
        print(f'median graph over DDS + recorder    : '
              f'{median(r[3]["rate"] for r in rounds):6.0f} steps/s')
        print(f'ratio graph / engine                : '
              f'{median(r[2]["rate"] / r[1] for r in rounds):.2f}')
        print(f'ratio graph / bare                  : '
              f'{median(r[2]["rate"] / r[0] for r in rounds):.2f}')
        print(f'ratio engine / bare                 : {median(r[1] / r[0] for r in rounds):.2f}')
        print(f'recorder overhead (steps/s)         : '
              f'{median(1 - r[3]["rate"] / r[2]["rate"] for r in rounds) * 100:+.1f}%')
        print(f'recorder overhead (nodes CPU)       : '
              f'{median(r[3]["cpu"] / r[2]["cpu"] - 1 for r in rounds) * 100:+.1f}%')
    print(f'load average at the end             : {os.getloadavg()[0]:.1f}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
