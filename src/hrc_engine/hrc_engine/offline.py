"""A whole session in one process with a partner, without ROS: the engine's loop, no bags.

The in-process loop of the engine (:mod:`hrc_engine.loop`: the sim's step protocol, the
``AgentCore`` calls in the agent node's order) with an offline partner
(:mod:`hrc_engine.partners`) as the human side instead of the human node's core, and
nothing recorded. It is the learning tests' loop, the tool for "episodes to convergence per
case", and the partner tools' (training with a population, evaluating a frozen agent with a
partner, cross-play).

When the current training step does not involve the human the partner is not called (the
human sends nothing; its command counts as 0).

Command line::

    python -m hrc_engine.offline --case 2 --episodes 60 --seed 0
    python -m hrc_engine.offline --case 2 --partner human:paper \
        --population-every 1     # a new simulated person every episode (population training)
"""

import argparse
from dataclasses import fields
import json
import sys
import time

from hrc_common import bounded_yaml

from hrc_agent_node.agent_core import AgentCore
from hrc_agent_node.checkpoint import load_into, read_checkpoint, save_checkpoint
from hrc_agent_node.config import AgentParams
from hrc_common.paths import params_dir
from hrc_common.session_plan import add_learning_option, load_learning
from hrc_common.contract import SimLimits
from hrc_common.params import from_dict, with_overrides
from hrc_engine.loop import EpisodeLoop, LoopObserver, PartnerSide, run_agent_episode, \
    run_agent_session
from hrc_engine.partners import make_partner as partner_of_spec, ScriptedPartner, \
    SimulatedHumanPartner
from hrc_joystick_node.human_profile import load_profile
from hrc_sim_node.physics import PhysicsParams, SliderPendulumBall


def partner_loop(core: AgentCore, sim, partner) -> EpisodeLoop:
    """Return the engine's loop on ``sim`` (a SliderPendulumBall) with ``partner`` as the human.

    The sim's step protocol in lockstep with both actors, as the engine runs it; ``partner``
    None: a human who answers zero.
    """
    return EpisodeLoop.on_physics(sim, PartnerSide(partner, SimLimits.of(sim.params)),
                                  core.robot_dof)


class _StepObserver(LoopObserver):
    """Calls ``on_step(state, decision, human_action)`` after each decision."""

    def __init__(self, on_step):
        self.on_step = on_step

    def decided(self, advanced, decision, answer, robot_wrench) -> None:
        self.on_step(advanced.state, decision, answer.command if answer is not None else 0.0)


def run_episode(core: AgentCore, sim, partner, on_step=None, loop: EpisodeLoop = None):
    """Run one episode of ``core`` on ``sim`` (a SliderPendulumBall); return its EpisodeResult.

    ``on_step(state, decision, human_action)`` is called after each decision, if given (the
    partner's answer to the period's state). ``loop``: the loop to run it on (default: a new
    :func:`partner_loop`, whose clock starts at 0).
    """
    loop = loop or partner_loop(core, sim, partner)
    return run_agent_episode(core, loop, _StepObserver(on_step) if on_step else None)


class _SessionObserver(LoopObserver):
    """The offline session's bookkeeping after each episode: checkpoint, report."""

    def __init__(self, core, checkpoint_path, on_episode):
        self.core = core
        self.checkpoint_path = checkpoint_path
        self.on_episode = on_episode
        self.update_seconds = []
        self.convergence = {}

    def after_episode(self, result, stats) -> None:
        if result.event in ('advanced', 'training_finished') and result.converged:
            self.convergence[f'step{result.training_step}'] = self.core.total_episodes
        if stats is not None:
            self.update_seconds.append(stats['seconds'])
        if self.checkpoint_path is not None:
            save_checkpoint(self.core, self.checkpoint_path)
        if self.on_episode is not None:
            self.on_episode(result, stats)


def run_session(core: AgentCore, sim, partner, checkpoint_path=None, on_episode=None,
                max_episodes=None) -> dict:
    """Run ``core`` until phase ``done`` (or ``max_episodes`` more episodes); return a summary.

    After every episode: the policy update when due, a checkpoint when ``checkpoint_path`` is
    given, then ``on_episode(result, update_stats)``. The core takes the control period and
    the limits from ``sim`` (a SliderPendulumBall), as the agent node takes the reset response's.
    """
    core.set_limits(SimLimits.of(sim.params))
    started = time.perf_counter()
    observer = _SessionObserver(core, checkpoint_path, on_episode)
    run_agent_session(core, partner_loop(core, sim, partner), observer, max_episodes)
    update_seconds = observer.update_seconds
    summary = {'case': core.case_id, 'strategy': core.strategy,
               'preset': core.preset, 'seed': core.seed,
               'training_episodes': core.total_episodes,
               'judging_episodes': core.judging_episodes,
               'human_involved_episodes': core.human_involved_episodes,
               'converged': core.converged,
               'episodes_to_step_end': observer.convergence,
               'updates': len(update_seconds),
               'mean_update_seconds': (sum(update_seconds) / len(update_seconds)
                                       if update_seconds else 0.0),
               'wall_seconds': time.perf_counter() - started}
    summary['evaluation'] = core.evaluation_summary()
    return summary


def make_partner(core: AgentCore, noise: float = 0.0, seed: int = 0, kind: str = 'scripted',
                 population_every: int = 0, limits: SimLimits = None):
    """Return the partner on the human's degree of freedom of ``core``'s case.

    ``limits``: the sim's control period and limits the partner acts with (default: those of
    the default physics, ``PhysicsParams()``, which the offline tools run).

    ``kind``: ``scripted`` (the PD partner, ``noise`` = std of its command) or
    ``human:<profile>`` (the simulated human of that profile; ``population_every`` N > 0 draws
    a new person from the profile's population every N episodes; the person acts at the sim's
    human period, as the engine's person).
    """
    if limits is None:
        limits = SimLimits.of(PhysicsParams())
    if kind == 'scripted':
        return ScriptedPartner(core.human_dof, max_torque=limits.max_torque, noise=noise,
                               seed=seed)
    if not kind.startswith('human:'):
        raise ValueError(f"partner {kind!r}: expected 'scripted' or 'human:<profile>'")
    return SimulatedHumanPartner(load_profile(kind.split(':', 1)[1]), core.human_dof, seed,
                                 limits.human_step, population_every)


def evaluation_core(checkpoint, seed: int, episodes: int, overrides: dict = None):
    """Return an AgentCore that evaluates ``checkpoint``'s frozen policy (``episodes``, seed)."""
    config = read_checkpoint(checkpoint)['config']
    settings = dict(seed=int(seed), evaluation_only=True, resume_from=str(checkpoint),
                    evaluation_episodes=int(episodes), checkpoint_dir='', torch_threads=1)
    settings.update(overrides or {})
    # Checkpoints written before the sim's limits left AgentParams still hold max_force and
    # max_torque among their params: those are the sim's now (run_session gives them).
    known = {field.name for field in fields(AgentParams)}
    trained = from_dict(AgentParams, {name: value for name, value in config['params'].items()
                                      if name in known})
    core = AgentCore(with_overrides(trained, **settings))
    load_into(core, checkpoint, resume=False)
    return core


def evaluate(checkpoint, spec, seed: int, episodes: int, physics_overrides: dict = None,
             profiles_file=None) -> float:
    """Return the mean total error of ``checkpoint``'s frozen policy with ``spec`` (one seed).

    ``spec``: a :class:`hrc_engine.partners.PartnerSpec`.
    """
    physics = with_overrides(PhysicsParams(), **(physics_overrides or {}))
    core = evaluation_core(checkpoint, seed, episodes)
    partner = partner_of_spec(spec, core.human_dof, seed, SimLimits.of(physics), profiles_file)
    with SliderPendulumBall(physics) as sim:
        return float(run_session(core, sim, partner)['evaluation']['total_error'])


def main(argv=None) -> int:
    """Run one offline session and print its summary as JSON."""
    parser = argparse.ArgumentParser(description='Run an hrc agent session in one process '
                                                 '(physics + scripted PD partner), no ROS.')
    parser.add_argument('--case', type=int, default=1)
    parser.add_argument('--seed', type=int, default=0)
    add_learning_option(parser)
    parser.add_argument('--episodes', type=int, default=0,
                        help="max training episodes (default: the learning configuration's)")
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

    try:
        learning = load_learning(params_dir(), args.learning)
    except ValueError as error:
        print(f'offline: {error}', file=sys.stderr)
        return 2
    if args.episodes > 0:
        learning['max_training_episodes'] = args.episodes
    overrides = {name: bounded_yaml.load(value, f'--set {name}') for name, value in
                 (item.split('=', 1) for item in args.set)}
    params = with_overrides(AgentParams(), case=args.case, seed=args.seed,
                            evaluation_episodes=args.evaluation_episodes,
                            torch_threads=args.threads, **dict(learning, **overrides))
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
