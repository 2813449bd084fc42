"""The session runner's command line: ``hrc session`` flags into (SessionSettings, options)."""

import argparse
import pathlib
import shlex
import sys

from hrc_common import bounded_yaml
from hrc_common.session_plan import (add_adapt_option, add_learning_option, NODES, new_session_id,
                                     parse_overrides, SessionSettings)
from hrc_live.study import consent_problem, load_registry, StudyError
import yaml

# The largest ROS_DOMAIN_ID: the RTPS port of domain d is 7400 + 250 d + offsets, and
# 232 is the last id whose ports fit in 16 bits (ROS 2 docs, "The ROS_DOMAIN_ID").
MAX_DOMAIN_ID = 232


def build_parser() -> argparse.ArgumentParser:
    """Return the parser of ``hrc session`` (the graph; its flags and help)."""
    parser = argparse.ArgumentParser(
        prog='hrc session', description='Run one hrc session (one case, one seed): sim, agent, '
        'human and recorder as supervised processes, then the report.')
    parser.add_argument('--case', type=int, default=2,
                        help="case 1..8: the paper's six, 7-8 partners first (default 2)")
    parser.add_argument('--seed', type=int, default=0, help='session seed (default 0)')
    parser.add_argument('--engine', choices=('graph',), default='graph',
                        help='graph (default): the nodes as processes over DDS; for one '
                        'process see: hrc session --engine inprocess --help')
    parser.add_argument('--mode', choices=('lockstep', 'realtime'), default='lockstep',
                        help='lockstep: as fast as the graph allows (headless); realtime: '
                        'every 0.2 s of wall time (a person at the joystick)')
    parser.add_argument('--human', dest='human_input', default='sim',
                        choices=('sim', 'auto', 'device', 'joy', 'gamepad', 'model', 'script'),
                        help='human input (default sim: the simulated human; gamepad: any '
                        "gamepad through the person's page, the browser's Gamepad API, implies "
                        '--display; model: a cloned human model, --set human.model_file=PATH; '
                        'script: a scripted stick in simulation time, --set '
                        'human.script_file=PATH)')
    parser.add_argument('--profile', dest='human_profile', default='',
                        help='simulated-human profile (params/sim_human.yaml)')
    add_learning_option(parser)
    parser.add_argument('--episodes', dest='training_episodes', type=int, default=0,
                        help='max training episodes (default: the learning configuration)')
    parser.add_argument('--eval-episodes', dest='evaluation_episodes', type=int, default=-1,
                        help='evaluation episodes (default: params/agent.yaml)')
    parser.add_argument('--session-id', default='', help='default: case<N>-seed<S>-<time>')
    parser.add_argument('--bags-dir', default='bags', help='bags go to <bags-dir>/<session>')
    parser.add_argument('--runs-dir', default='runs',
                        help='logs, parameters, checkpoints and report go to <runs-dir>')
    parser.add_argument('--params-dir', default=None, help='default: ./params or installed')
    parser.add_argument('--no-record', dest='record', action='store_false',
                        help='do not start the recorder')
    parser.add_argument('--resume-from', default='', help='agent checkpoint to resume')
    parser.add_argument('--start-from', default='', metavar='CHECKPOINT',
                        help="a finished session's final.pt: a new session starts from its "
                        "policy at the strategy's last step (with --study-dir found by itself "
                        'for a subject back for a case they finished); its first episode '
                        'judges that policy (--adapt-from for a new person: it learns from '
                        'the first)')
    add_adapt_option(parser)
    parser.add_argument('--fresh-start', action='store_true',
                        help='with --study-dir: a new robot even for a subject back for a case '
                        'they finished')
    parser.add_argument('--subject-id', default='', help='pseudonymous subject id (bag metadata)')
    parser.add_argument('--notes', default='', help='free-text notes (bag metadata)')
    parser.add_argument('--set', dest='overrides', action='append', default=[],
                        metavar='NODE.PARAM=VALUE', help='override a node parameter (repeatable)')
    parser.add_argument('--params', dest='params_files', action='append', default=[],
                        metavar='FILE', help='a ROS 2 parameter file whose node sections '
                        'override params/*.yaml, e.g. the joystick_setup output (repeatable; '
                        '--set wins)')
    add_person_options(parser)
    add_process_options(parser)
    return parser


def add_person_options(parser: argparse.ArgumentParser) -> None:
    """Add the flags of a session with a person: pages, questionnaire, practice, input."""
    parser.add_argument('--display', action='store_true',
                        help='also start the display node (hrc_live): the page for the person '
                        'on http://127.0.0.1:<port>/ and the console on /console '
                        '(params/display.yaml)')
    parser.add_argument('--display-port', type=int, default=None, metavar='PORT',
                        help='port of the pages (default: params/display.yaml; 0 = any free)')
    parser.add_argument('--foxglove', action='store_true',
                        help='also serve the session live to Foxglove (hrc_live foxglove_node: '
                        'the 3D scene, errors, reward, actions, status on ws://127.0.0.1:8766; '
                        'layout params/foxglove/hrc_layout.json; params/foxglove.yaml)')
    parser.add_argument('--foxglove-port', type=int, default=None, metavar='PORT',
                        help='port of the Foxglove server (default: params/foxglove.yaml; 0 = '
                        'any free, logged)')
    parser.add_argument('--tlx', action='store_true',
                        help='with --display: ask the raw NASA-TLX on the page when the '
                        'session is done; stored in <runs-dir>/<session>/tlx.yaml (0600)')
    parser.add_argument('--tlx-wait', type=float, default=600.0, metavar='S',
                        help='with --tlx: keep the page up this long for the answer after the '
                        'session (default 600 s)')
    parser.add_argument('--stand-in', choices=('none', 'sim'), default='none',
                        help='realtime with --human device|joy|auto: what drives the human side '
                        'when the input is lost: none (default) = the session pauses until '
                        'the operator resumes; sim = the simulated human (its episodes are '
                        'marked simulated in the bags)')
    parser.add_argument('--practice', type=int, default=0, metavar='N',
                        help='before the condition: N practice episodes of the person alone on '
                        'their degree of freedom (realtime, no robot), recorded as the session '
                        '<session-id>-practice and counted apart (default 0)')
    parser.add_argument('--study-dir', default='',
                        help='the study folder (hrc study): the subject must be '
                        'registered there with consent yes; the session is added to its '
                        'per-subject index')
    parser.add_argument('--remote', dest='remote_nodes', action='append', default=[],
                        choices=('human',), help='a node that runs on another host and is not '
                        "started here: 'human' = the person's station runs the human node with "
                        "this session's parameters.yaml (docs/two_hosts.md)")
    parser.add_argument('--link-timeout', type=float, default=1.0, metavar='S',
                        help='realtime with a person: states run but no answer from the '
                        "person's side for this long (a network link to the station down, the "
                        'human node stalled) pauses the session as a lost joystick does '
                        '(default 1.0 s = 5 control periods)')
    parser.add_argument('--input-wait', type=float, default=120.0, metavar='S',
                        help='realtime with --human device|joy|auto: wait this long for the input '
                        'before refusing to start (default 120 s)')


def add_process_options(parser: argparse.ArgumentParser) -> None:
    """Add the flags of how the session's processes run: domain, report, priority, timeout."""
    parser.add_argument('--domain-id', type=int, default=None,
                        help='ROS_DOMAIN_ID of the session (default: the environment)')
    parser.add_argument('--no-report', dest='report', action='store_false',
                        help='skip the report at the end')
    parser.add_argument('--recorder-niceness', type=int, default=10, choices=range(0, 20),
                        metavar='0..19', help='run the recorder at this lower CPU priority '
                        '(default 10): it buffers and catches up between episodes, so it does '
                        'not slow the control loop; 0 = same priority as the nodes')
    parser.add_argument('--timeout', type=float, default=0.0,
                        help='stop the session after this many wall seconds (0 = none)')


def parse_args(argv=None):
    """Parse the command line into (SessionSettings, options)."""
    parser = build_parser()
    options = parser.parse_args(argv)
    options.argv = list(sys.argv[1:] if argv is None else argv)
    # a gamepad through the page: the display publishes it on /joy, the human node reads /joy
    options.gamepad = options.human_input == 'gamepad'
    if options.gamepad:
        options.human_input, options.display = 'joy', True
    overrides = {}
    for path in options.params_files:
        try:
            overrides.update(file_overrides(path))
        except (OSError, ValueError, yaml.YAMLError) as error:
            reason = bounded_yaml.describe(error) if isinstance(error, yaml.YAMLError) else error
            parser.error(f'--params {path}: {reason}')
    try:
        overrides.update(parse_overrides(options.overrides))
    except ValueError as error:
        parser.error(str(error))
    if options.gamepad:     # the display publishes the stick the person chose as /joy axis 0
        overrides.setdefault('human.axis', 0)
    settings = SessionSettings(
        case=options.case, seed=options.seed, mode=options.mode,
        human_input=options.human_input, human_profile=options.human_profile,
        learning=options.learning, training_episodes=options.training_episodes,
        evaluation_episodes=options.evaluation_episodes, session_id=options.session_id,
        bags_dir=options.bags_dir, runs_dir=options.runs_dir, record=options.record,
        resume_from=options.resume_from, start_from=options.start_from,
        adapt_from=options.adapt_from,
        subject_id=options.subject_id, notes=options.notes,
        overrides=overrides)
    if not settings.session_id:
        settings.session_id = new_session_id(settings)
    reasons = settings.check()
    if settings.human_input == 'model' and not overrides.get('human.model_file'):
        reasons.append('--human model needs --set human.model_file=PATH (a cloned human '
                       'model, hrc partners clone)')
    if settings.human_input == 'script' and not overrides.get('human.script_file'):
        reasons.append('--human script needs --set human.script_file=PATH (a stick script, '
                       'CSV "time,axis[,enable]")')
    if settings.subject_id and settings.subject_id.lower() in settings.session_id.lower():
        # Bag and run folders are named after the session id: no personal data in file names.
        reasons.append('the session id must not contain the subject id (it names files)')
    if options.tlx and not options.display:
        reasons.append('--tlx needs --display (the questionnaire is on the page)')
    # An id outside DDS's range is refused before anything starts
    if options.domain_id is not None and not 0 <= options.domain_id <= MAX_DOMAIN_ID:
        reasons.append(f'--domain-id {options.domain_id} is outside the range of DDS domain '
                       f'ids 0..{MAX_DOMAIN_ID} (higher ids give UDP ports above 65535)')
    if options.input_wait < 0:
        reasons.append('--input-wait must be >= 0')
    if not options.link_timeout > 0:
        reasons.append('--link-timeout must be > 0')
    if options.practice < 0:
        reasons.append('--practice must be >= 0')
    if options.practice and settings.mode != 'realtime':
        reasons.append('--practice needs --mode realtime (the person practises at the '
                       'control rate)')
    if options.study_dir:
        if not settings.subject_id:
            reasons.append('--study-dir needs --subject-id (the registered pseudonym)')
        else:
            try:
                problem = consent_problem(load_registry(options.study_dir),
                                          settings.subject_id)
            except StudyError as error:
                problem = str(error)
            if problem:
                reasons.append(problem)
    if reasons:
        parser.error('; '.join(reasons))
    return settings, options


def person_input(settings: SessionSettings, options) -> str:
    """Return 'device', 'joy' or 'auto' when a person's input must be there, else ''.

    ``auto`` takes the device, else /joy, and never the simulated human (the human node).
    """
    if settings.mode == 'realtime' and settings.human_input in ('device', 'joy', 'auto'):
        return settings.human_input
    return ''


def file_overrides(path) -> dict:
    """Return {'node.name': value} of the node sections of a ROS 2 parameter file."""
    document = bounded_yaml.load_file(path) or {}
    if not isinstance(document, dict):
        raise ValueError('not a parameter file (a mapping of node sections)')
    overrides = {}
    for node, section in document.items():
        if node not in NODES:
            raise ValueError(f'section {node!r} is not one of the nodes {sorted(NODES)}')
        values = (section or {}).get('ros__parameters') or {}
        overrides.update({f'{node}.{name}': value for name, value in values.items()})
    return overrides


def resume_command(options, session_id: str, checkpoint: pathlib.Path) -> str:
    """Return the command line that resumes this session from ``checkpoint``."""
    args, skip = [], False
    for arg in options.argv:
        if skip:
            skip = False
            continue
        if arg in ('--resume-from', '--session-id'):
            skip = True
            continue
        if arg.startswith(('--resume-from=', '--session-id=')):
            continue
        args.append(arg)
    return shlex.join(['hrc', 'session', *args, '--session-id',
                       session_id, '--resume-from', str(checkpoint)])
