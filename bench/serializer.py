#!/usr/bin/env python3
"""Benchmark: the engine's step with the one serializer against the hand-written encoder.

    python bench/serializer.py                   # from the repository (it reads git)
    python bench/serializer.py --pairs 8 --episodes 3 --case 2

The in-process engine writes five to six messages per control step to its bags. They are
encoded by :mod:`hrc_bag.serializer` (rosbags' typestore); until commit 8c1b998 they were
encoded by a hand-written ``struct`` encoder (``hrc_engine/cdr.py``), kept only because the
library it replaced (mcap-ros2-support's dynamic serializer) cost 0.8 ms per message. That
encoder is loaded here from git (``git show 8c1b998:...``), not kept in the tree.

One run, alternating: each pair runs the same short session (same case and seed, so the same
steps) once with each encoder, in changing order, in this one process, and takes the engine's
own step time (``SessionResult.episode_seconds``: the episodes' steps, without the learner's
updates and checkpoint saves; taken in process CPU time, see ``ProcessClock``) over its
control steps. Printed: the step time of each encoder
(median over the pairs), the median of the pairs' ratios (library / hand-written) and the
encoding cost per message of each, measured alone.
"""

import argparse
import pathlib
import statistics
import subprocess
import sys
import tempfile
import time
import types

from hrc_bag import serializer
from hrc_common.session_plan import SessionSettings
from hrc_engine import messages
from hrc_engine import engine
from hrc_engine.engine import EngineConfig, run_session

BASELINE_COMMIT = '8c1b998'
BASELINE_PATH = 'src/hrc_engine/hrc_engine/cdr.py'
ROOT = pathlib.Path(__file__).resolve().parents[1]


def hand_written_encoder():
    """Return ``encode(type_name, message)`` of the hand-written encoder of BASELINE_COMMIT."""
    source = subprocess.run(['git', '-C', str(ROOT), 'show', f'{BASELINE_COMMIT}:{BASELINE_PATH}'],
                            capture_output=True, text=True, check=True).stdout
    module = types.ModuleType('hand_written_cdr')
    exec(compile(source, f'{BASELINE_COMMIT}:{BASELINE_PATH}', 'exec'), module.__dict__)
    return module.encode


class ProcessClock:
    """The ``time`` module with ``perf_counter`` counting this process's CPU time (s).

    Put in place of the engine's ``time`` while a session runs, so that its
    ``episode_seconds`` count the steps' CPU time: the wall time of a shared machine counts
    the other processes' turns too.
    """

    perf_counter = staticmethod(time.process_time)

    def __getattr__(self, name):
        return getattr(time, name)


def step_seconds(encode, arguments, folder: pathlib.Path, name: str) -> float:
    """Run one session whose bags are encoded by ``encode``; return its step CPU time (s)."""
    library = serializer.encode
    serializer.encode = encode              # what hrc_bag.session_writer calls
    engine.time = ProcessClock()
    try:
        result = run_session(EngineConfig(SessionSettings(
            case=arguments.case, seed=arguments.seed,
            training_episodes=arguments.episodes, evaluation_episodes=0, session_id=name,
            bags_dir=str(folder / 'bags'), runs_dir=str(folder / 'runs')),
            checkpoints=False))
    finally:
        serializer.encode = library
        engine.time = time
    return sum(result.episode_seconds) / result.steps


def per_message_us(encode, count: int = 5000) -> float:
    """Return the mean cost (us) of encoding one step's messages of a short engine session."""
    messages = sample_messages()
    started = time.perf_counter()
    for _ in range(count):
        for type_name, message in messages:
            encode(type_name, message)
    return (time.perf_counter() - started) / count / len(messages) * 1e6


def sample_messages() -> list:
    """Return (type, plain values) of one control step's messages as the engine builds them."""
    header = messages.header(1_500_000_000)
    wrench = {'header': header, 'wrench': {'force': {'x': 1.5, 'y': 0.0, 'z': 0.0},
                                           'torque': {'x': 0.0, 'y': 0.0, 'z': -0.2}}}
    state = {'header': header, 'episode': 3, 'step': 70, 'slider_position': 0.1,
             'slider_velocity': -0.02, 'pendulum_angle': 0.05, 'pendulum_angular_velocity': 0.3,
             'ball_position': 0.12, 'ball_velocity': -0.1, 'applied_force': 1.5,
             'applied_torque': -0.2, 'robot_command_missing': False,
             'human_command_missing': False, 'slice': 0, 'human_applied': [0.1, -0.2],
             'terminated': False, 'truncated': False}
    action = {'header': header, 'episode': 3, 'step': 70, 'command': -0.3, 'dof': 1,
              'source': 2, 'source_detail': 'paper', 'engaged': True}
    step = {'header': header, 'episode': 3, 'step': 69, 'observation_human_action': -0.3,
            'action': 0.4, 'wrench': 1.5, 'subtask_ids': ['T1_1', 'T2_1'],
            'reward_components': [-0.1, -0.05, 0.0], 'reward': -0.15, 'value_estimate': -2.0,
            'log_prob': -0.9, 'deterministic': False}
    return [('hrc_msgs/msg/TaskState', state), ('geometry_msgs/msg/WrenchStamped', wrench),
            ('hrc_msgs/msg/HumanAction', action), ('geometry_msgs/msg/WrenchStamped', wrench),
            ('hrc_msgs/msg/AgentStep', step)]


def parse(argv) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--pairs', type=int, default=6, help='sessions with each encoder')
    parser.add_argument('--episodes', type=int, default=2, help='training episodes a session')
    parser.add_argument('--case', type=int, default=2)
    parser.add_argument('--seed', type=int, default=0)
    arguments = parser.parse_args(argv)
    if arguments.pairs < 1 or arguments.episodes < 1:
        parser.error('--pairs and --episodes must be at least 1')
    return arguments


def main(argv=None) -> int:
    arguments = parse(argv)
    hand_written = hand_written_encoder()
    encoders = {'library': serializer.encode, 'hand-written': hand_written}
    for type_name, message in sample_messages():
        assert encoders['library'](type_name, message) == hand_written(type_name, message)
    times = {name: [] for name in encoders}
    with tempfile.TemporaryDirectory() as folder:
        step_seconds(serializer.encode, arguments, pathlib.Path(folder), 'warm-up')
        for pair in range(arguments.pairs):
            order = list(encoders) if pair % 2 == 0 else list(reversed(encoders))
            for name in order:
                times[name].append(step_seconds(encoders[name], arguments,
                                                pathlib.Path(folder), f'pair{pair}-{name}'))
            print(f'pair {pair}: library {times["library"][-1] * 1e3:.3f} ms, hand-written '
                  f'{times["hand-written"][-1] * 1e3:.3f} ms a step', flush=True)
    ratios = [library / hand for library, hand in zip(times['library'], times['hand-written'])]
    for name in encoders:
        print(f'{name:>12}: step {statistics.median(times[name]) * 1e3:.3f} ms (median of '
              f'{arguments.pairs}), encoding {per_message_us(encoders[name]):.1f} us a message')
    print(f'step ratio library / hand-written: {statistics.median(ratios):.3f} (median of the '
          f'pairs; min {min(ratios):.3f}, max {max(ratios):.3f}); case {arguments.case}, '
          f'{arguments.episodes} episodes a session')
    return 0


if __name__ == '__main__':
    sys.exit(main())
