"""Parameters of the sim node (pure, no ROS): the physics plus the step protocol's settings."""

from dataclasses import dataclass

from hrc_common.dof import DOFS, TRANSLATION
from hrc_common.params import param
from hrc_sim_node.commands import ACTORS, HUMAN, ROBOT
from hrc_sim_node.physics_params import PhysicsParams

LOCKSTEP = 'lockstep'
REALTIME = 'realtime'
CLOCK_MODES = (LOCKSTEP, REALTIME)


@dataclass
class SimParams(PhysicsParams):
    """Parameters of the sim node: the physics (PhysicsParams, inherited) plus these."""

    mode: str = param('lockstep', 'lockstep: advance when the commands of the step arrived; '
                      'realtime: advance every control_period of wall time (a reset may switch '
                      'it: ResetEpisode.clock_mode)', choices=CLOCK_MODES)
    expected_actors: list = param(
        [ROBOT, HUMAN], 'actors whose command the sim waits for (lockstep) and reports missing;'
        ' [] = run free', choices=ACTORS)
    lockstep_timeout: float = param(
        1.0, 'lockstep: wall seconds to wait for the commands of a step before counting the '
        'missing ones as zero', low=0.001, high=600.0)
    await_recorder: bool = param(
        False, 'lockstep: publish no state more than a window of periods ahead of the '
        "recorder's /hrc/recorder/progress (hrc_sim_node.recorder_gate), so a stalled recorder "
        'misses nothing; hrc session sets it when it records')
    recorder_timeout: float = param(
        60.0, 'lockstep, await_recorder: exit (code 3) when a step has waited this long (wall '
        's) for a recorder that acknowledges nothing', low=1.0, high=3600.0)
    command_timeout: float = param(
        0.5, 'realtime: a command older than this (wall s) counts as zero and is reported',
        low=0.01, high=60.0)
    auto_reset: bool = param(False, 'start the next episode by itself after the last state '
                             '(standalone runs); false = hold until /hrc/sim/reset')
    start_on_launch: bool = param(False, 'start episode 0 at launch instead of waiting for '
                                  '/hrc/sim/reset (standalone runs)')
    robot_dof: str = param(TRANSLATION, 'degree of freedom the robot drives until /hrc/session '
                           'says otherwise; the human drives the other', choices=DOFS)
    seed: int = param(0, 'seed of the initial states when a reset asks for none (-1)',
                      low=0, high=2 ** 31 - 1)
    max_episodes: int = param(0, 'exit (code 0) after this many finished episodes; 0 = never',
                              low=0, high=10 ** 9)
    camera_rate: float = param(0.0, 'rate (Hz, wall time) of the rendered image on '
                               '/hrc/sim/image; 0 = off', low=0.0, high=60.0)
    image_width: int = param(320, 'width of the rendered image (px)', low=16, high=1920)
    image_height: int = param(240, 'height of the rendered image (px)', low=16, high=1080)
    marker_rate: float = param(10.0, 'rate (Hz, wall time) of /hrc/sim/markers; 0 = off',
                               low=0.0, high=60.0)
    gui: bool = param(False, 'open the PyBullet GUI window (needs a display); default: '
                      'headless (DIRECT)')
    exit_after_session: bool = param(
        True, 'exit once the agent says the session is done (phase done on /hrc/session), as a '
        'node started by hand should; hrc session turns it off for the nodes it stops itself')

    def check(self) -> list:
        """Return the reasons why the fields do not fit together (empty if they do)."""
        reasons = list(super().check())
        if len(set(self.expected_actors)) != len(self.expected_actors):
            reasons.append(f'expected_actors {self.expected_actors} lists an actor twice')
        return reasons
