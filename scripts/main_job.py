#!/usr/bin/env python3
"""The main job of `make run`: one headless session with the simulated human.

Runs `hrc session` for case 2 (the paper's "learn the task first" case with
the robot on rotation), lockstep, seed 0, on a private ROS domain, with the study's learning
settings (``hrc_common.session_plan.STUDY_LEARNING``: updates at the horizon or an episode's
end, judging in a row, the `graded` reward preset, 10 epochs, clip 0.2; the paper's Table I
rules and sigma = 1 give almost no learning signal: see src/hrc_agent_node/README.md) and at
most 300 training episodes, then prints its Table II row and where the bags and figures are.
Extra arguments are passed to `hrc session` and win over these, e.g. `make run ARGS="--case 4
--set agent.preset=paper"` (or `ARGS="--engine inprocess"`: the same session in one process).
Before issue 22's settings the main job ran `--set agent.preset=tuned` alone:
`make run ARGS="--set agent.update_rule=episode_end_after_horizon --set agent.judging_rule=spaced
--set agent.judging_interval=0 --set agent.preset=tuned --set agent.epochs=3 --set
agent.clip_coef=0.05"` runs it again.
"""

import os
import sys

from hrc_bringup import cli
from hrc_common.session_plan import study_learning_arguments


def main() -> int:
    """Run the session with the main job's defaults (overridable on the command line)."""
    os.environ.setdefault('ROS_DOMAIN_ID', '77')
    defaults = ['--case', '2', '--seed', '0', '--mode', 'lockstep', '--human', 'sim',
                '--episodes', '300', '--eval-episodes', '5', *study_learning_arguments()]
    return cli.main(['session', *defaults, *sys.argv[1:]])


if __name__ == '__main__':
    sys.exit(main())
