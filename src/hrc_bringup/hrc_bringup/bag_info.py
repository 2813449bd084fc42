"""``hrc bag info`` (what a bag holds) and ``hrc bag replay`` (the replay node, started).

A bag is one episode file (``.mcap``) or a session folder of them (hrc_bag's format,
src/hrc_bag/README.md). ``info`` reads the summary section of each finished file (no message
is decoded; an unfinished file, left open by a stopped recorder, is scanned instead) and
prints its episodes, topics with types and message counts, and the recorded time span.
"""

import argparse
import collections
import os
import pathlib
import sys

from hrc_bag.bag_reader import bag_problems, file_topics, is_complete, scan_file, session_files
from mcap.reader import SeekingReader

NS_PER_S = 1e9


def file_counts(path: pathlib.Path) -> tuple:
    """Return ({topic: message count}, first ns, last ns, finished) of one MCAP file."""
    counts = collections.Counter()
    if is_complete(path):
        with open(path, 'rb') as stream:
            summary = SeekingReader(stream).get_summary()
        if summary is not None and summary.statistics is not None:
            statistics = summary.statistics
            for channel_id, count in statistics.channel_message_counts.items():
                counts[summary.channels[channel_id].topic] += count
            return counts, statistics.message_start_time, statistics.message_end_time, True
    times = []
    for message in scan_file(path).messages:    # a file left open: read it through
        counts[message.topic] += 1
        times.append(message.log_time)
    return counts, min(times, default=0), max(times, default=0), False


def describe(path) -> list:
    """Return the lines ``hrc bag info`` prints for a file or session folder."""
    files = session_files(path)
    counts, types, start, end, unfinished = collections.Counter(), {}, None, None, []
    for file in files:
        file_count, first, last, finished = file_counts(file)
        counts.update(file_count)
        for topic, info in file_topics(file).items():
            types.setdefault(topic, info.type_name)
        if file_count:
            start = first if start is None else min(start, first)
            end = last if end is None else max(end, last)
        if not finished:
            unfinished.append(file.name)
    size = sum(file.stat().st_size for file in files)
    lines = [f'bag:       {path}',
             f'files:     {len(files)} ({size / 1e6:.1f} MB)'
             + (f', unfinished: {", ".join(unfinished)}' if unfinished else ''),
             f'messages:  {sum(counts.values())}']
    if start is not None:
        lines.append(f'duration:  {(end - start) / NS_PER_S:.1f} s (recording time)')
    lines.append('topics:')
    width = max((len(topic) for topic in types), default=0)
    lines += [f'  {topic:<{width}}  {counts.get(topic, 0):7d}  {types[topic]}'
              for topic in sorted(types)]
    return lines


def main(argv=None) -> int:
    """Entry point of ``hrc bag info``: exit 0, or 2 with every reason a path is not a bag."""
    parser = argparse.ArgumentParser(
        prog='hrc bag info', description='Print what a bag holds: its files, the topics with '
        'their types and message counts, the recorded time span.')
    parser.add_argument('paths', nargs='+', metavar='BAG',
                        help='an episode file (.mcap) or a session folder')
    options = parser.parse_args(argv)
    problems = [problem for path in options.paths for problem in bag_problems(path)]
    if problems:
        for problem in problems:
            print(f'hrc bag info: {problem}', file=sys.stderr)
        return 2
    for index, path in enumerate(options.paths):
        if index:
            print()
        print('\n'.join(describe(path)), flush=True)
    return 0


def replay_arguments(argv) -> list:
    """Return the replay node's ``--ros-args`` for ``hrc bag replay``'s flags."""
    parser = argparse.ArgumentParser(
        prog='hrc bag replay', description='Play a recorded episode or session back on its '
        'topics with the recorded QoS (the replay node of hrc_bag; it stops at the end).')
    parser.add_argument('path', metavar='BAG', help='an episode file (.mcap) or a session '
                        'folder')
    parser.add_argument('--rate', type=float, default=None, help='speed factor (2 = twice as '
                        'fast; default 1)')
    parser.add_argument('--loop', action='store_true', help='start again at the end')
    parser.add_argument('--clock', action='store_true', help='also publish /clock with the '
                        'recording time (use_sim_time for the listeners)')
    parser.add_argument('--topics', nargs='+', default=None, metavar='TOPIC',
                        help='play only these topics (default: every recorded one)')
    parser.add_argument('--start-offset', type=float, default=None, metavar='S',
                        help='skip this many seconds of the recording at its start')
    options = parser.parse_args(argv)
    problems = bag_problems(options.path)
    if problems:
        parser.exit(2, ''.join(f'hrc bag replay: {problem}\n' for problem in problems))
    arguments = ['--ros-args', '-p', f'path:={pathlib.Path(options.path).resolve()}']
    if options.rate is not None:
        arguments += ['-p', f'rate:={options.rate!r}']
    if options.loop:
        arguments += ['-p', 'loop:=true']
    if options.clock:
        arguments += ['-p', 'clock:=true']
    if options.topics:
        arguments += ['-p', f'topics:=[{", ".join(repr(topic) for topic in options.topics)}]']
    if options.start_offset is not None:
        arguments += ['-p', f'start_offset:={options.start_offset!r}']
    return arguments


def replay(argv, executable: pathlib.Path) -> int:
    """Run the replay node in this process's place (its parameters check the values)."""
    command = [str(executable), *replay_arguments(argv)]
    sys.stdout.flush()
    sys.stderr.flush()
    os.execv(command[0], command)
