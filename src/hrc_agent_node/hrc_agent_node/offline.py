"""A whole session in one process, without ROS: physics + partner + AgentCore + strategy.

The same :class:`~hrc_agent_node.agent_core.AgentCore` calls as the agent node, in the same
order (see agent_core.py), with the physics core stepped directly. It is the in-process
baseline of the benchmark "full graph over DDS vs the same pure components in one process", the
learning test's loop, and the tool for "episodes to convergence per case".

A partner is a callable ``partner(state, subtasks) -> command in [-1, 1]`` on the human's
degree of freedom (``ScriptedPartner``, or ``SimulatedHumanPartner``: hrc_joystick_node's
simulated human, one person or a population). A partner with a ``start_episode(episode)``
method is told each episode's index before it starts. When the current training step does not
involve the human its command is 0 and it is not called.

Command line::

    python -m hrc_agent_node.offline --case 2 --preset tuned --episodes 60 --seed 0
    python -m hrc_agent_node.offline --case 2 --preset tuned --partner human:paper \
        --population-every 1     # a new simulated person every episode (population training)
"""

import argparse
import json
import sys
import time

import yaml

from hrc_agent_node.agent_core import AgentCore
from hrc_agent_node.checkpoint import load_into, save_checkpoint
from hrc_agent_node.config import AgentParams
from hrc_agent_node.partners import person_period, ScriptedPartner, SimulatedHumanPartner
from hrc_common.contract import SimLimits
from hrc_common.params import with_overrides
from hrc_joystick_node.human_profile import load_profile
from hrc_sim_node.commands import wrench_on
from hrc_sim_node.physics import PhysicsParams, SliderPendulumBall
from hrc_sim_node.protocol import ProtocolSettings, StepProtocol
from hrc_sim_node.stepper import SimStepper


def run_episode(core: AgentCore, sim, partner, on_step=None):
    """Run one episode of ``core`` on ``sim`` (a SliderPendulumBall); return its EpisodeResult.

    The sim's step protocol in lockstep, as the in-process engine runs it
    (``hrc_sim_node.stepper.SimStepper.run_period``): the partner answers the period's state
    and, at the human's rate (``sim.params.human_period``), each state within the period; the
    robot's action holds for the period. ``on_step(state, decision, human_action)`` is called
    after each decision, if given (the partner's answer to the period's state).
    """
    plan = core.start_episode()
    if hasattr(partner, 'start_episode'):
        partner.start_episode(plan.episode)
    params = sim.params
    limits = SimLimits.of(params)
    protocol = StepProtocol(ProtocolSettings(
        control_period=params.control_period, max_force=params.max_force,
        max_torque=params.max_torque, robot_dof=core.robot_dof,
        human_period=params.human_period))
    protocol.set_roles(core.robot_dof, plan.human_involved)
    stepper = SimStepper(sim, protocol)
    human_subtasks, human_dof = core.human_subtasks, core.human_dof
    human_scale, robot_scale = limits.full_scale(human_dof), limits.full_scale(core.robot_dof)

    def human_command(state) -> float:
        if not plan.human_involved or partner is None:
            return 0.0
        return float(partner(state, human_subtasks))

    advanced = stepper.start_episode(plan.episode, plan.seed)
    while not advanced.episode_over:
        state = advanced.state
        human_action = human_command(state)
        decision = core.act(advanced.observed,
                            human_action if core.needs_human_action else None)
        if on_step is not None:
            on_step(state, decision, human_action)
        advanced = stepper.run_period(
            wrench_on(core.robot_dof, decision.action * robot_scale),
            wrench_on(human_dof, human_action * human_scale),
            lambda middle: wrench_on(human_dof, human_command(middle.state) * human_scale))
    return core.end_episode(advanced.observed)


def run_session(core: AgentCore, sim, partner, checkpoint_path=None, on_episode=None,
                max_episodes=None) -> dict:
    """Run ``core`` until phase ``done`` (or ``max_episodes`` more episodes); return a summary.

    After every episode: the PPO update when due, a checkpoint when ``checkpoint_path`` is
    given, then ``on_episode(result, update_stats)``. The core takes the control period and
    the limits from ``sim`` (a SliderPendulumBall), as the agent node takes the reset response's.
    """
    core.set_limits(SimLimits.of(sim.params))
    started = time.perf_counter()
    update_seconds = []
    convergence = {}
    episodes_run = 0
    while core.phase != 'done' and (max_episodes is None or episodes_run < max_episodes):
        result = run_episode(core, sim, partner)
        episodes_run += 1
        if result.event in ('advanced', 'training_finished') and result.converged:
            convergence[f'step{result.training_step}'] = core.total_episodes
        stats = core.update() if core.phase == 'updating' else None
        if stats is not None:
            update_seconds.append(stats['seconds'])
        if checkpoint_path is not None:
            save_checkpoint(core, checkpoint_path)
        if on_episode is not None:
            on_episode(result, stats)
    summary = {'case': core.case_id, 'strategy': core.strategy,
               'preset': core.preset, 'seed': core.seed,
               'training_episodes': core.total_episodes,
               'judging_episodes': core.judging_episodes,
               'human_involved_episodes': core.human_involved_episodes,
               'converged': core.converged,
               'episodes_to_step_end': convergence,
               'updates': len(update_seconds),
               'mean_update_seconds': (sum(update_seconds) / len(update_seconds)
                                       if update_seconds else 0.0),
               'wall_seconds': time.perf_counter() - started}
    summary['evaluation'] = core.evaluation_summary()
    return summary


def make_partner(core: AgentCore, noise: float = 0.0, seed: int = 0, kind: str = 'scripted',
                 population_every: int = 0, limits: SimLimits = None, period: str = 'human'):
    """Return the partner on the human's degree of freedom of ``core``'s case.

    ``limits``: the sim's control period and limits the partner acts with (default: those of
    the default physics, ``PhysicsParams()``, which the offline tools run).

    ``kind``: ``scripted`` (the PD partner, ``noise`` = std of its command) or
    ``human:<profile>`` (the simulated human of that profile; ``population_every`` N > 0 draws
    a new person from the profile's population every N episodes; ``period``: how often that
    person acts, :data:`~hrc_agent_node.partners.PERSON_PERIODS`).
    """
    if limits is None:
        limits = SimLimits.of(PhysicsParams())
    if kind == 'scripted':
        return ScriptedPartner(core.human_dof, max_torque=limits.max_torque, noise=noise,
                               seed=seed)
    if not kind.startswith('human:'):
        raise ValueError(f"partner {kind!r}: expected 'scripted' or 'human:<profile>'")
    return SimulatedHumanPartner(load_profile(kind.split(':', 1)[1]), core.human_dof, seed,
                                 person_period(limits, period), population_every)


def main(argv=None) -> int:
    """Run one offline session and print its summary as JSON."""
    parser = argparse.ArgumentParser(description='Run an hrc agent session in one process '
                                                 '(physics + scripted PD partner), no ROS.')
    parser.add_argument('--case', type=int, default=1)
    parser.add_argument('--seed', type=int, default=0)
    parser.add_argument('--preset', default='paper')
    parser.add_argument('--episodes', type=int, default=60, help='max training episodes')
    parser.add_argument('--evaluation-episodes', type=int, default=3)
    parser.add_argument('--partner', default='scripted',
                        help='scripted (PD partner) or human:<profile> (simulated human)')
    parser.add_argument('--partner-noise', type=float, default=0.0,
                        help="std of the scripted partner's command noise")
    parser.add_argument('--population-every', type=int, default=0,
                        help="human partner: draw a new person from the profile's population "
                             'every N episodes (0: the profile itself throughout)')
    parser.add_argument('--threads', type=int, default=1)
    parser.add_argument('--checkpoint', default=None, help='save a checkpoint here each episode')
    parser.add_argument('--resume', default=None, help='resume from this checkpoint')
    parser.add_argument('--quiet', action='store_true')
    parser.add_argument('--set', nargs='*', default=[], metavar='NAME=VALUE',
                        help='other AgentParams overrides (YAML values)')
    args = parser.parse_args(argv)

    overrides = {name: yaml.safe_load(value) for name, value in
                 (item.split('=', 1) for item in args.set)}
    params = with_overrides(AgentParams(), case=args.case, seed=args.seed, preset=args.preset,
                            max_training_episodes=args.episodes,
                            evaluation_episodes=args.evaluation_episodes,
                            torch_threads=args.threads, **overrides)
    physics_params = PhysicsParams()
    core = AgentCore(params, limits=SimLimits.of(physics_params))
    if args.resume:
        load_into(core, args.resume)
    try:
        partner = make_partner(core, args.partner_noise, args.seed, args.partner,
                               args.population_every, SimLimits.of(physics_params))
    except (ValueError, KeyError) as error:
        print(f'offline: {error}', file=sys.stderr)
        return 2

    def report(result, stats):
        if args.quiet:
            return
        errors = ' '.join(f'{name}={value:.4f}' for name, value in result.errors.items())
        update = f' update {stats["seconds"]:.2f}s std={stats["action_std"]:.3f}' \
            if stats else ''
        kind = 'eval ' if result.evaluation else 'judge ' if result.judging else ''
        print(f'episode {result.episode:3d} {kind}step '
              f'{result.training_step} return {result.episode_return:8.2f} {errors} '
              f'robot_effort={result.robot_effort:.3f}{" converged" if result.converged else ""}'
              f' {result.event}{update}', file=sys.stderr, flush=True)

    with SliderPendulumBall(physics_params) as sim:
        summary = run_session(core, sim, partner, args.checkpoint, report)
    print(json.dumps(summary, indent=2))
    return 0


if __name__ == '__main__':
    sys.exit(main())
