#!/usr/bin/env python3
"""The main job of `make run`: one headless session with the simulated human.

Runs `hrc session` for case 2 (the paper's "learn the task first" case with the robot on
rotation), lockstep, seed 0, on a private ROS domain, with the default learning configuration
(params/learning/sac.yaml: what the study measured best for the person's time), then prints its
Table II row and where the bags and figures are. Extra arguments are passed to `hrc session`
and win over these, e.g. `make run ARGS="--case 4 --learning ppo"` (or `ARGS="--engine
inprocess"`: the same session in one process).
"""

import os
import sys

from hrc_bringup import cli


def main() -> int:
    """Run the session with the main job's defaults (overridable on the command line)."""
    os.environ.setdefault('ROS_DOMAIN_ID', '77')
    defaults = ['--case', '2', '--seed', '0', '--mode', 'lockstep', '--human', 'sim']
    return cli.main(['session', *defaults, *sys.argv[1:]])


if __name__ == '__main__':
    sys.exit(main())
