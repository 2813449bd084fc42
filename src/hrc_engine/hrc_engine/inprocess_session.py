"""``hrc session --engine inprocess``: one headless session in one process, no DDS.

The same session as ``hrc session --mode lockstep`` (the graph) (same parameter files,
same ``--set`` overrides, same bags and report), computed in one process from the nodes'
cores: several times faster, and nothing to start or stop. A person at a joystick, realtime,
live display or replay need the graph.
"""

import json
import sys

from hrc_common.contract import os_error_text
from hrc_common.params import ParameterError
from hrc_common.session_claim import claim_session, SessionIdTaken
from hrc_common.session_plan import new_session_id, parse_overrides, SessionSettings

from hrc_engine.inprocess_args import build_parser


def parse_args(argv=None) -> tuple:
    """Return (EngineConfig, print as JSON) of the command line (exit 2 with every reason)."""
    parser = build_parser()
    options = parser.parse_args(argv)

    reasons, overrides = [], {}
    try:
        overrides = parse_overrides(options.set)
    except ValueError as error:
        reasons.append(str(error))
    if options.human_input not in ('sim', 'model', 'script'):
        reasons.append(f'--human {options.human_input}: the in-process engine runs the '
                       'simulated human, a cloned model or a scripted stick only (--human sim, '
                       'model or script); use --engine graph')
    if options.mode != 'lockstep':
        reasons.append(f'--mode {options.mode}: the in-process engine runs lockstep only; '
                       'use --engine graph')
    if options.episodes < 0:
        reasons.append(f'--episodes must be >= 0, got {options.episodes}')
    if reasons:
        parser.exit(2, ''.join(f'hrc session --engine inprocess: {reason}\n'
                                for reason in reasons))
    settings = SessionSettings(
        case=options.case, seed=options.seed, mode=options.mode,
        human_input=options.human_input, human_profile=options.human_profile,
        learning=options.learning, training_episodes=options.episodes,
        evaluation_episodes=options.eval_episodes,
        session_id=options.session_id, bags_dir=options.bags_dir, runs_dir=options.runs_dir,
        record=not options.no_record, resume_from=options.resume_from,
        start_from=options.start_from, adapt_from=options.adapt_from,
        overrides=overrides)
    # the engine loads the cores, torch among them (seconds): --help and usage errors answer
    # without it
    from hrc_engine.engine import EngineConfig  # lazy: torch (seconds), see above
    return EngineConfig(settings, checkpoints=not options.no_checkpoints,
                        params_dir=options.params_dir, quiet=options.json), options.json


def main(argv=None) -> int:
    """Run the session; print its result; exit 0, or 2 for bad parameters."""
    config, as_json = parse_args(argv)
    from hrc_engine.engine import run_session  # lazy: torch, as in parse_args (loaded by now)
    settings = config.settings
    generated = not settings.session_id
    settings.session_id = settings.session_id or new_session_id(settings)
    try:
        notice = claim_session(settings, generated) if settings.record else ''
    except (SessionIdTaken, OSError) as error:
        print(f'hrc session --engine inprocess: {error}', file=sys.stderr)
        return 2
    if notice:
        print(f'[inprocess_session] {notice}', file=sys.stderr, flush=True)
    try:
        result = run_session(config)
    except (ParameterError, ValueError) as error:
        print(f'hrc session --engine inprocess: {error}', file=sys.stderr)
        return 2
    except OSError as error:        # a write failed (a full disk): not the user's parameters
        print(f'hrc session --engine inprocess: {os_error_text(error)}', file=sys.stderr)
        return 1
    if as_json:
        print(json.dumps(vars(result), indent=2, default=str))
        return 0
    metrics = ', '.join(f'{name} {value:.4f}' if isinstance(value, float) else f'{name} {value}'
                        for name, value in result.evaluation.items())
    print(f'[inprocess_session] {result.session_id}: case {result.case} ({result.strategy}), '
          f'seed {result.seed}: {result.training_episodes} training episodes '
          f'({result.human_involved_episodes} with the human), '
          f'{"converged" if result.converged else "not converged"}, {result.steps} steps in '
          f'{result.wall_seconds:.1f} s ({result.steps / result.wall_seconds:.0f} steps/s)')
    print(f'[inprocess_session] evaluation: {metrics or "none"}')
    if result.bag_dir:
        print(f'[inprocess_session] bags in {result.bag_dir}; report: hrc bag report '
              f'{result.bag_dir}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
