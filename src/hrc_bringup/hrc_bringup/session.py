"""Session runner: start the hrc graph for one case, supervise it, report at the end.

    hrc session --case 2 --seed 0            # headless, simulated human
    hrc session --case 1 --mode realtime --human auto --subject-id P07

It starts sim, agent, human and recorder as separate processes (the executables ``ros2 run``
starts) with one parameter file composed from ``params/*.yaml`` (see
hrc_common.session_plan), prints a progress line per episode, and stops everything when the
agent finishes, a node dies, or on Ctrl-C / SIGTERM, the recorder last so its bags are closed.
Then it runs the report.

This module prepares the session and ``session_run`` runs it; each other job of the runner has
its module in hrc_bringup: ``session_args`` (the command line), ``session_progress`` (the lines
it prints), ``input_guard`` (a person's input lost: pause), ``practice`` (the person alone
before the condition), ``study_hooks`` (study index, NASA-TLX, owner-only files) and
``session_report``.

Live sessions (hrc_live, docs/live_study.md): ``--display`` also starts the display node (the
person's page and the experimenter's console on localhost); ``--params FILE`` merges a
parameter file such as the one ``hrc joystick setup`` writes; the operator pauses, resumes or
aborts with ``hrc operator ...`` or the console's buttons. An operator abort is a
clean stop: the bags are closed, the runner prints the command that resumes the session from
its last checkpoint (counters continue), and exits with code 3 (EXIT_OPERATOR_ABORT).

The person's time only when needed: in a realtime session the agent runs the training steps
without the person in lockstep (as fast as the graph goes) and switches the sim to realtime
for the episodes with the person (``ResetEpisode.clock_mode``); the runner prints how long the
robot practised alone and when the person joined.

Never a silent stand-in (hrc_bringup.input_guard): in realtime with ``--human device``, ``joy``
or ``auto`` the runner does not start until the input is there, and pauses the session at once
when it is lost; ``--stand-in sim`` asks for the simulated human instead.

Exit codes: 0 done, 1 a node failed, 2 bad arguments, 3 aborted by the operator, 124 timeout,
130/143 SIGINT/SIGTERM.
"""

import json
import os
import pathlib
import sys

from hrc_agent_node.strategies import pretrains_with_population
from hrc_common import paths
from hrc_common.contract import os_error_text
from hrc_common.domains import DomainTaken, SessionOnDomain
from hrc_common.session_claim import claim_session, SessionIdTaken
from hrc_common.session_plan import compose, SessionSettings, write_session_files

from hrc_bringup.compose_nodes import session_composition
from hrc_bringup.session_args import parse_args, person_input
from hrc_bringup.session_run import SessionRun
from hrc_bringup.study_hooks import start_returning_person, warn_out_of_order


def pretrain_if_needed(parameters: dict, run_dir):
    """Pre-train a partners-first session (cases 7, 8); return its agent settings, else None.

    ``hrc_partners.partners_first.prepare_person_session`` for a case that pre-trains; the other
    cases return None without loading torch (1-2 s of every session's start-up before the
    nodes were launched).
    """
    if not pretrains_with_population(parameters['agent']):
        return None
    from hrc_partners.partners_first import prepare_person_session  # lazy: torch
    try:
        return prepare_person_session(parameters, run_dir)
    except (ValueError, OSError) as error:
        raise ValueError(f'pre-training with simulated partners failed: {error}') from error


def prepare_parameters(settings: SessionSettings, options, params_dir: pathlib.Path,
                       run_dir: pathlib.Path, live_input: str) -> dict:
    """Compose the nodes' parameters of the session and what the runner adds to them.

    Raises ValueError (or OSError) with the reason when the session cannot start.
    """
    parameters = compose(settings, params_dir)
    for node in ('sim', 'human', 'recorder'):
        if node in parameters and node not in options.remote_nodes:
            # this runner stops them in its order (the recorder last), not the agent's "done"
            parameters[node]['exit_after_session'] = False
    if settings.record:
        parameters['recorder']['session_config'] = str(run_dir / 'session.yaml')
    if live_input:
        # Never a silent stand-in: the simulated human only when the operator asked for it.
        parameters['human']['on_input_lost'] = 'sim' if options.stand_in == 'sim' else 'pause'
    if 'human' in options.remote_nodes:
        # The station's human node is started by hand, possibly long after this runner: the
        # agent waits for it (wait_for_subscribers) as long as the runner waits for its input.
        agent = parameters['agent']
        agent['reset_timeout'] = max(float(agent['reset_timeout']), float(options.input_wait))
    if not (settings.resume_from or settings.start_from or settings.adapt_from):
        # Partners first (cases 7, 8): the robot alone and with the simulated population in
        # this process first (no person: minutes), then the graph from that checkpoint.
        start = pretrain_if_needed(parameters, run_dir)
        if start is not None:
            parameters['agent'].update(start)
            print_pretraining(json.loads((run_dir / 'pretrain.json').read_text()),
                              start['resume_from'])
    return parameters


def print_pretraining(record: dict, checkpoint: str) -> None:
    """Say what the partners-first pre-training did and where the session continues."""
    print(f'[session] pre-trained with simulated partners (no person): '
          f'{record["episodes"]} episodes, {record["population_episodes"]} of them '
          f'with the population, in {record["wall_seconds"]:.0f} s; the session '
          f'continues from {checkpoint}', flush=True)
    if not record['reached_person_step']:
        print("[session] the pre-training ran out of episodes before the person's "
              'step (the robot alone did not converge): the person joins only for '
              'the evaluation; give more --episodes', flush=True)


def run_session(settings: SessionSettings, options) -> int:
    """Run one session; return the exit code (0 = the agent finished the session)."""
    params_dir = pathlib.Path(options.params_dir) if options.params_dir else paths.params_dir()
    composed, problems = session_composition()     # HRC_COMPOSE
    if problems:
        print('\n'.join(f'session: {problem}' for problem in problems), file=sys.stderr)
        return 2
    if settings.subject_id:
        # with a subject id everything the session writes is owner-only (files 0600, folders
        # 0700): the nodes inherit the mask (checkpoints, run and bag folders)
        os.umask(0o077)
    env = dict(os.environ)
    if options.domain_id is not None:
        env['ROS_DOMAIN_ID'] = str(options.domain_id)
    try:    # held until this process ends (the runner is the session); before any write
        domain = SessionOnDomain(int(env.get('ROS_DOMAIN_ID') or 0), settings.session_id)
    except DomainTaken as error:
        print(f'session: {error}', file=sys.stderr)
        return 2
    try:
        notice = claim_session(settings, generated=not options.session_id)
    except (SessionIdTaken, OSError) as error:
        print(f'session: {error}', file=sys.stderr)
        return 2
    if notice:
        print(f'[session] {notice}', flush=True)
    run_dir = pathlib.Path(settings.runs_dir) / settings.session_id
    warn_out_of_order(settings, options)
    start_returning_person(settings, options)
    live_input = person_input(settings, options)
    try:
        parameters = prepare_parameters(settings, options, params_dir, run_dir, live_input)
    except (ValueError, OSError) as error:
        print(f'session: {error}', file=sys.stderr)
        return 2
    try:
        params_path, _ = write_session_files(settings, parameters, run_dir, params_dir)
    except OSError as error:    # a full or read-only runs folder: not the user's parameters
        print(f'session: cannot write the session files: {os_error_text(error)}',
              file=sys.stderr)
        return 1
    env.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    run = SessionRun(settings, options, parameters, params_path, run_dir, env)
    try:
        return run.run(params_dir, composed, live_input)
    finally:
        domain.release()


def main(argv=None) -> int:
    """Entry point of ``hrc session``."""
    settings, options = parse_args(argv)
    return run_session(settings, options)


if __name__ == '__main__':
    sys.exit(main())
