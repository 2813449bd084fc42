"""Joystick set-up helper: find the device, watch it live, pick the axis, write the human's YAML.

    hrc joystick setup --list
    hrc joystick setup /dev/input/js0 --output joystick.yaml      # guided
    hrc joystick setup /dev/input/js0 --non-interactive --detect 5

Guided (a terminal): a refreshed line shows every axis and button at every step; the operator
pushes the chosen stick in the direction that should mean "+" (slider up, right end of the
pendulum up), lets go (the largest deviation at rest gives the deadzone), and presses the
deadman button if one is wanted. Each step can be kept or redone; a last step shows the command
the human node would send while the operator moves the stick, and any one step can be redone
from there before the file is written.
``--non-interactive`` does the same from what the device reports during ``--detect`` seconds:
the axis moved most, its direction (inversion), its first value (the rest), the button held.
Flags (``--axis``, ``--invert``, ``--deadzone``, ``--enable-button``) override any detection.

The result is a parameter file for the human node (``human:`` / ``ros__parameters:`` with
``input: device``, ``device``, ``axis``, ``invert``, ``deadzone``, ``enable_button``), checked
against the human node's own parameter rules. The device is read with the human node's reader
(:mod:`hrc_joystick_node.js_event`), so a FIFO or a file carrying js_event records works too.
The devices and the detection rules live in :mod:`hrc_live.joystick_watch`, the guided steps in
:mod:`hrc_live.joystick_guided`; this module is the command and the file it writes.
"""

import argparse
from dataclasses import dataclass
import os
import sys

import yaml

from hrc_common.contract import atomic_write
from hrc_common.params import as_dict, from_dict, ParameterError
from hrc_live.joystick_guided import Console, GuidedSetup, watch_until
from hrc_live.joystick_watch import (chosen_axis, chosen_button, deadzone_from_rest,
                                     DEVICE_PATTERN, device_info, inversion, JoystickWatcher,
                                     list_devices, MIN_DEFLECTION)


@dataclass
class JoystickSettings:
    """What the human node needs to read the joystick."""

    device: str
    axis: int
    invert: bool
    deadzone: float
    enable_button: int

    def parameters(self) -> dict:
        """Return the human node's parameters (``input: device`` and the five settings)."""
        return {'input': 'device', 'device': self.device, 'axis': self.axis,
                'invert': self.invert, 'deadzone': self.deadzone,
                'enable_button': self.enable_button}


def settings_yaml(settings: JoystickSettings, detected: str = '') -> str:
    """Return the parameter file text for the human node."""
    document = {'human': {'ros__parameters': settings.parameters()}}
    header = ['# Joystick settings for the human node (written by hrc_live joystick_setup).',
              '# Use: session --human device --params <this file>, or',
              '#      ros2 run hrc_joystick_node human_node --ros-args --params-file <this file>']
    if detected:
        header.append(f'# {detected}')
    return '\n'.join(header) + '\n' + yaml.safe_dump(document, sort_keys=False)


def check_settings(settings: JoystickSettings) -> None:
    """Raise ParameterError if the human node would refuse these settings."""
    from hrc_joystick_node.human_core import HumanParams  # lazy: numpy (0.1 s), not for --help
    from_dict(HumanParams, {**as_dict(HumanParams()), **settings.parameters()})


def write_settings(path: str, settings: JoystickSettings, detected: str = '') -> None:
    """Check the settings and write them (atomically) to ``path``."""
    check_settings(settings)
    directory = os.path.dirname(os.path.abspath(path))
    os.makedirs(directory, exist_ok=True)
    atomic_write(path, settings_yaml(settings, detected))


# ---------------------------------------------------------------------------- the command

def guided(watcher: JoystickWatcher, options, console: Console) -> tuple:
    """Interactive: ask the operator step by step (:class:`GuidedSetup`); flags skip steps."""
    return GuidedSetup(watcher, options, console).run()


def detect(watcher: JoystickWatcher, options, console: Console) -> tuple:
    """Non-interactive: detect from ``--detect`` seconds of events; flags override."""
    watcher.start()
    console.say(f'watching {watcher.device.path} for {options.detect} s: push the stick in '
                f'its "+" direction (and hold the enable button, if one is wanted)')
    watch_until(watcher, console, seconds=options.detect, show=options.show_values)
    watch = watcher.watch
    axis = options.axis if options.axis is not None else chosen_axis(watch)
    if axis is None:
        moved = ', '.join(f'{number}: {trace.deflection:.2f}'
                          for number, trace in sorted(watch.axes.items())) or 'none reported'
        raise RuntimeError(f'no axis moved by {MIN_DEFLECTION} or more within '
                           f'{options.detect} s (deflections {moved}): give --axis, or move '
                           f'the stick during the detection')
    trace = watch.axes.get(axis)
    invert = options.invert
    if invert is None:
        invert = inversion(trace) if trace is not None and trace.deflection > 0 else False
    deadzone = options.deadzone
    if deadzone is None:
        deadzone = deadzone_from_rest(trace.first if trace is not None else 0.0)
    enable_button = options.enable_button
    if enable_button is None:
        enable_button = chosen_button(watcher.held_buttons())
    notes = (f'detected from {watch.events} events in {options.detect} s: axis {axis} moved '
             f'{trace.deflection if trace else 0:.2f} from {trace.first if trace else 0:+.2f}')
    return axis, invert, deadzone, enable_button, notes


def parse_args(argv=None):
    """Parse the command line."""
    parser = argparse.ArgumentParser(
        prog='hrc joystick setup', description='Set up the joystick for the human node: list '
        'devices, watch axes and buttons live, pick the axis, inversion, deadzone and enable '
        'button, and write the parameter file the human node reads.')
    parser.add_argument('device', nargs='?', default=None,
                        help='joystick device, or a FIFO/file with its js_event stream '
                        '(default: the first of /dev/input/js*)')
    parser.add_argument('--list', action='store_true', help='list the joystick devices, exit')
    parser.add_argument('--devices', default=DEVICE_PATTERN,
                        help=f'where to look for devices (default {DEVICE_PATTERN})')
    parser.add_argument('--output', '-o', default='joystick.yaml',
                        help='parameter file to write (default ./joystick.yaml)')
    parser.add_argument('--axis', type=int, default=None, help='use this axis (no detection)')
    inversion_group = parser.add_mutually_exclusive_group()
    inversion_group.add_argument('--invert', dest='invert', action='store_true', default=None,
                                 help='invert the axis')
    inversion_group.add_argument('--no-invert', dest='invert', action='store_false',
                                 help='do not invert the axis')
    parser.add_argument('--deadzone', type=float, default=None,
                        help='deadzone in [0, 0.9) (default: from the rest position)')
    parser.add_argument('--enable-button', type=int, default=None,
                        help='deadman button index, -1 = none (default: the button held)')
    parser.add_argument('--non-interactive', action='store_true',
                        help='no questions: detect from --detect seconds of events')
    parser.add_argument('--detect', type=float, default=5.0,
                        help='seconds to watch in non-interactive mode (default 5)')
    parser.add_argument('--show', dest='show_values', action='store_true',
                        help='non-interactive: print the live values while detecting')
    parser.add_argument('--open-timeout', type=float, default=5.0,
                        help='seconds to wait for the device (a FIFO: for its writer)')
    options = parser.parse_args(argv)
    if options.deadzone is not None and not 0.0 <= options.deadzone < 0.9:
        parser.error(f'--deadzone must be in [0, 0.9), got {options.deadzone}')
    if options.detect <= 0:
        parser.error('--detect must be > 0')
    return options


def main(argv=None) -> int:
    """Entry point of ``hrc joystick setup``; 0 = file written, 1 = failed."""
    options = parse_args(argv)
    console = Console()
    if options.list:
        devices = list_devices(options.devices)
        if not devices:
            console.say(f'no joystick devices ({options.devices}); a FIFO or a file carrying '
                        f'js_event records can be given as the device')
            return 1
        for info in devices:
            console.say(info.describe())
        return 0
    path = options.device
    if path is None:
        devices = [info for info in list_devices(options.devices) if not info.problem]
        if not devices:
            console.say(f'no usable joystick device ({options.devices}): plug one in or give '
                        f'the device path')
            return 1
        path = devices[0].path
    info = device_info(path)
    console.say(f'device {info.describe()}')
    watcher = JoystickWatcher(path)
    if not watcher.open(options.open_timeout):
        console.say(f'cannot use {path}: {watcher.device.status}')
        return 1
    interactive = not options.non_interactive and sys.stdin.isatty()
    try:
        chooser = guided if interactive else detect
        axis, invert, deadzone, enable_button, notes = chooser(watcher, options, console)
    except RuntimeError as error:
        console.say(f'set-up failed: {error}')
        return 1
    except KeyboardInterrupt:
        console.say('set-up cancelled: nothing written')
        return 130
    finally:
        watcher.close()
    # The human node may run in another directory: write the absolute path.
    settings = JoystickSettings(os.path.abspath(path), int(axis), bool(invert), float(deadzone),
                                int(enable_button))
    try:
        write_settings(options.output, settings, notes)
    except (ParameterError, OSError) as error:
        console.say(f'not written: {error}')
        return 1
    console.say(f'wrote {options.output}: device {path}, axis {settings.axis}'
                f'{" inverted" if settings.invert else ""}, deadzone {settings.deadzone}, '
                f'enable button {settings.enable_button} ({notes})')
    console.say(f'use it: session --mode realtime --human device --params {options.output}')
    return 0


if __name__ == '__main__':
    sys.exit(main())

