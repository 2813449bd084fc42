"""Compose the parameters of every node of a session (pure, no rclpy).

Used by the session runner and the experiment (``hrc_bringup``) and by the in-process engine
(``hrc_engine``), so it lives below both.

A session is one paper case run with one seed. The plan starts from each node's parameter file
(``params/<node>.yaml``), applies the user's overrides (``--set node.name=value``), then the
session-level settings so that every node agrees (case, seed, roles, clock mode, session id,
human input; the sim's limits and control period are not copied: the actors read them from the
sim at run time): an override those settings overrule is refused with the option to use
(``--set agent.seed=3`` -> ``--seed``). It writes one ROS 2 parameter file with a section per
node plus a ``session.yaml`` describing the whole session (it travels in every bag).
"""

from dataclasses import asdict, dataclass, fields
import datetime
import pathlib
import subprocess

import yaml

from hrc_common import bounded_yaml
from hrc_common.cases import case_problem, case_table
from hrc_common.contract import atomic_write, id_problem, make_session_id, PERSONAL_FILE_MODE
from hrc_common.params import field_problems, param
from hrc_common.paths import params_dir as default_params_dir

# Node name -> (package, executable, parameter file). The node name is the section of the file.
NODES = {
    'sim': ('hrc_sim_node', 'sim_node', 'sim.yaml'),
    'agent': ('hrc_agent_node', 'agent_node', 'agent.yaml'),
    'human': ('hrc_joystick_node', 'human_node', 'human.yaml'),
    'recorder': ('hrc_bag', 'recorder_node', 'recorder.yaml'),
}

# The learning configurations: params/learning/<name>.yaml, each a ROS 2 parameter file of the
# agent node (so `ros2 run hrc_agent_node agent_node --ros-args --params-file` takes it too). The
# default is the one the study measured best for the person's time; its file says why.
LEARNING_DIR = 'learning'
DEFAULT_LEARNING = 'sac'


LEARNING_HELP = ('learning configuration: params/learning/<name>.yaml (default '
                 f"{DEFAULT_LEARNING}, the study's best for the person's time; ppo: the "
                 "paper's algorithm with the study's rules; paper: Table I literally; "
                 'partner_aware: sac observing a model of its partner)')


# The person's episodes a robot trained with others learns from by default (--adapt-from): 3
# (2 minutes) brought every held-out partner within 1.5x of the robot trained for them
# (docs/partners/held_out.md).
ADAPT_EPISODES = 3


def add_adapt_option(parser) -> None:
    """Add ``--adapt-from CHECKPOINT`` (one help for the graph's and the engine's session)."""
    parser.add_argument('--adapt-from', default='', metavar='CHECKPOINT',
                        help='a robot trained with other people (e.g. a partners-first '
                        "session's final.pt) meets a new person: it starts from that policy "
                        "and learns from each of the person's episodes, --episodes of them "
                        f'(default {ADAPT_EPISODES}), no judging; then the evaluation')


def add_learning_option(parser) -> None:
    """Add ``--learning NAME`` (one help for every command that runs sessions)."""
    parser.add_argument('--learning', default=DEFAULT_LEARNING, metavar='NAME',
                        help=LEARNING_HELP)


def learning_names(params_dir: pathlib.Path) -> list:
    """Return the names of the learning configurations in ``params_dir/learning/``."""
    return sorted(path.stem for path in (pathlib.Path(params_dir) / LEARNING_DIR).glob('*.yaml'))


def load_learning(params_dir: pathlib.Path, name: str) -> dict:
    """Return the agent parameters of the learning configuration ``name``.

    Raises ValueError naming the configurations there are when ``name`` is not one of them,
    or when the file is not an agent parameter file.
    """
    path = pathlib.Path(params_dir) / LEARNING_DIR / f'{name}.yaml'
    if not isinstance(name, str) or not name or '/' in name or not path.is_file():
        names = ', '.join(learning_names(params_dir)) or 'none'
        raise ValueError(f'learning configuration {name!r} not found in '
                         f'{pathlib.Path(params_dir) / LEARNING_DIR} (there are: {names})')
    document = bounded_yaml.load_file(path) or {}
    nodes = set(document) if isinstance(document, dict) else {'?'}
    section = document.get('agent') if isinstance(document, dict) else None
    values = section.get('ros__parameters') if isinstance(section, dict) else None
    if nodes != {'agent'} or not isinstance(values, dict):
        raise ValueError(f'{path}: a learning configuration holds one section, '
                         f'agent: ros__parameters: {{...}} (found {sorted(map(str, nodes))})')
    return dict(values)


# The settings a session owns that are not one node's parameter: checked here, not by a node.
SESSION_MODES = ('lockstep', 'realtime')


@dataclass
class SessionSettings:
    """What a user chooses for one session: the one session configuration.

    The graph runner (``hrc session``), the in-process engine (``hrc_engine.engine``), the
    experiment's tasks (``hrc_bringup.experiment_task``) and the Gymnasium environment
    (``hrc_gym``: case, seed, profile, overrides) all take one of these; everything else comes
    from the parameter files (``params/<node>.yaml``) through :func:`compose`. Each field is
    documented with :func:`hrc_common.params.param`; :meth:`check` returns every reason at once.
    """

    case: int = param(2, 'Case of params/cases.yaml (the only case table): strategy and which '
                         "degree of freedom the robot drives; 1..6 the paper's, 7-8 partners "
                         'first')
    seed: int = param(0, 'Session seed, given to the sim, the agent and the human', low=0)
    mode: str = param('lockstep', 'Clock: lockstep (the sim waits for both commands) or '
                                  'realtime (wall-clock periods; a person at a device)',
                      choices=SESSION_MODES)
    human_input: str = param('sim', "The human node's input (human.yaml's input: sim, model, "
                                    'script, device, joy, auto; the human node checks it)')
    human_profile: str = param('', "Simulated-human profile of params/sim_human.yaml ('' = "
                                   "human.yaml's)")
    learning: str = param(DEFAULT_LEARNING, 'Learning configuration: params/learning/<name>'
                                            '.yaml (sac, the default; ppo; paper; partner_aware)')
    training_episodes: int = param(0, "Max training episodes (0 = the learning "
                                      "configuration's or agent.yaml's "
                                      'max_training_episodes)', low=0)
    evaluation_episodes: int = param(-1, "Evaluation episodes (-1 = agent.yaml's)", low=-1)
    session_id: str = param('', "Session id, names the bag and run folders ('' = "
                                'case<N>-seed<S>-<time>)')
    bags_dir: str = param('bags', 'Bags land in <bags_dir>/<session_id>/')
    runs_dir: str = param('runs', 'session.yaml in <runs_dir>/<session_id>/, checkpoints in '
                                  '<runs_dir>/checkpoints/<session_id>/')
    record: bool = param(True, 'Record the session (the recorder node; the engine writes the '
                               'same bags)')
    resume_from: str = param('', "A checkpoint to continue from ('' = a new agent)")
    start_from: str = param('', "A finished session's checkpoint whose policy a new session "
                                "starts from (a returning person; '' = a new policy)")
    adapt_from: str = param('', "A checkpoint of a robot trained with other people (e.g. a "
                                "partners-first session's final.pt) that a new person's session "
                                "starts from, learning from each of the person's episodes "
                                f'(training_episodes of them, {ADAPT_EPISODES} by default; no '
                                "judging); '' = none")
    subject_id: str = param('', "The person's study id (kept in session.yaml, owner-only; never "
                                'in a file name)')
    notes: str = param('', 'Free text kept in session.yaml (owner-only)')
    overrides: dict = param({}, "Node parameters over the files: {'node.name': value} (--set "
                                'node.name=value, YAML values)')

    def check(self) -> list:
        """Return every reason these settings are unusable at once (empty if fine)."""
        reasons = []
        for dataclass_field in fields(self):
            if dataclass_field.name in ('case', 'mode', 'seed'):
                continue   # their own reasons below (the case from the case table)
            reasons += field_problems(dataclass_field, getattr(self, dataclass_field.name))
        problem = case_problem(self.case)
        if problem:
            reasons.append(problem)
        if self.mode not in SESSION_MODES:
            reasons.append(f"mode must be 'lockstep' or 'realtime', got {self.mode!r}")
        if isinstance(self.seed, bool) or not isinstance(self.seed, int):
            reasons.append(f'seed must be an integer >= 0, got {self.seed!r}')
        elif self.seed < 0:
            reasons.append(f'seed must be >= 0, got {self.seed}')
        if self.resume_from and self.start_from:
            reasons.append('--resume-from continues a session, --start-from starts a new one '
                           "from a finished session's policy: give one")
        if self.adapt_from and (self.resume_from or self.start_from):
            reasons.append('--adapt-from starts a new session from a robot trained with others; '
                           'it cannot be combined with --resume-from or --start-from')
        for value, option in ((self.start_from, '--start-from'), (self.adapt_from,
                                                                  '--adapt-from')):
            if value and not pathlib.Path(str(value)).is_file():
                reasons.append(f'{option} {value}: no such checkpoint file')
        for key in self.overrides if isinstance(self.overrides, dict) else ():
            if key.split('.', 1)[0] not in NODES:
                reasons.append(f'--set {key}: the node must be one of {sorted(NODES)}')
        for value, what in ((self.session_id, 'session id'), (self.subject_id, 'subject id')):
            problem = isinstance(value, str) and value and id_problem(value, what)
            if problem:
                reasons.append(problem)
        return reasons


def new_session_id(settings: SessionSettings, now=None) -> str:
    """Return a session id: case, seed and start time (no personal data)."""
    return make_session_id(settings.case, settings.seed, now)


def parse_override(text: str):
    """Parse ``node.name=value`` (value in YAML syntax) into (node, name, value)."""
    if '=' not in text or '.' not in text.split('=', 1)[0]:
        raise ValueError(f'--set {text!r}: expected node.parameter=value, e.g. agent.horizon=256')
    key, raw = text.split('=', 1)
    node, name = key.split('.', 1)
    return node, name, bounded_yaml.load(raw, f'--set {key}') if raw != '' else ''


def parse_overrides(texts) -> dict:
    """Return {'node.name': value} of ``--set`` texts (a later one wins).

    Raises ValueError with the reason of every text that is not ``node.parameter=value``.
    """
    overrides, reasons = {}, []
    for text in texts:
        try:
            node, name, value = parse_override(text)
        except ValueError as error:
            reasons.append(str(error))
            continue
        overrides[f'{node}.{name}'] = value
    if reasons:
        raise ValueError('; '.join(reasons))
    return overrides


def override_arguments(overrides: dict) -> list:
    """Return ``overrides`` ({'node.name': value}) as ``['--set', 'node.name=value', ...]``.

    Each value in YAML flow syntax, so :func:`parse_overrides` reads back the same value.
    """
    arguments = []
    for key, value in overrides.items():
        text = yaml.safe_dump(value, default_flow_style=True, width=float('inf'))
        text = text[:-len('...\n')] if text.endswith('\n...\n') else text
        arguments += ['--set', f'{key}={text.strip()}']
    return arguments


def load_node_parameters(params_dir: pathlib.Path, node: str) -> dict:
    """Return the ``ros__parameters`` of ``node`` in its parameter file."""
    path = params_dir / NODES[node][2]
    document = bounded_yaml.load_file(path) or {}
    return dict((document.get(node) or {}).get('ros__parameters') or {})


def package_version() -> str:
    """Return the version of the code: the git commit if known, else the package version."""
    try:
        commit = subprocess.run(['git', 'describe', '--always', '--dirty'], capture_output=True,
                                text=True, timeout=5, cwd=pathlib.Path(__file__).parent)
        if commit.returncode == 0 and commit.stdout.strip():
            return 'git ' + commit.stdout.strip()
    except (OSError, subprocess.TimeoutExpired):
        pass
    return '0.1.0'


def compose(settings: SessionSettings, params_dir: pathlib.Path) -> dict:
    """Return {node: parameters} for a session; raise ValueError with every reason if bad."""
    reasons = settings.check()
    if reasons:
        raise ValueError('session settings rejected: ' + '; '.join(reasons))
    nodes = [node for node in NODES if settings.record or node != 'recorder']
    parameters = {node: load_node_parameters(params_dir, node) for node in nodes}
    parameters['agent'].update(load_learning(params_dir, settings.learning))
    for key, value in settings.overrides.items():
        node, name = key.split('.', 1)
        if node in parameters:
            parameters[node][name] = value
    _apply_settings(settings, parameters)
    # What the session sets itself wins over --set (the nodes must agree); a --set it overrules
    # is refused with the option to use, never dropped silently.
    reasons = []
    for key, value in settings.overrides.items():
        node, name = key.split('.', 1)
        if node in parameters and parameters[node].get(name) != value:
            reasons.append(f'--set {key}={value!r}: the session sets {key} itself '
                           f'({parameters[node].get(name)!r})'
                           + (f'; use {SETTING_OPTIONS[name]}' if name in SETTING_OPTIONS
                              else ''))
    if reasons:
        raise ValueError('session settings rejected: ' + '; '.join(reasons))
    return parameters


# The session-level option that sets a node parameter the session owns (for the refusal).
SETTING_OPTIONS = {'seed': '--seed', 'mode': '--mode', 'case': '--case', 'input': '--human',
                   'profile': '--profile', 'robot_dof': '--case', 'dof': '--case',
                   'session_id': '--session-id', 'max_training_episodes': '--episodes',
                   'evaluation_episodes': '--eval-episodes', 'resume_from': '--resume-from',
                   'start_from': '--start-from or --adapt-from',
                   'start_from_judged': '--adapt-from',
                   'checkpoint_dir': '--runs-dir', 'output_dir': '--bags-dir',
                   'practice_episodes': '--practice'}


def adapting_agent_parameters(episodes: int) -> dict:
    """Return the agent parameters of a robot, started from a policy, adapting to a new person.

    It learns from each of the person's ``episodes`` (its budget), and no judging episode falls
    due before the budget ends: the judge would keep an inherited policy that merely meets the
    step, however much better a robot trained for the person is (docs/partners/held_out.md).
    """
    return {'start_from_judged': False, 'max_training_episodes': int(episodes),
            'judging_interval': int(episodes)}


def _apply_settings(settings: SessionSettings, parameters: dict) -> None:
    """Write what the session settings decide into the nodes' parameters (in place)."""
    sim, agent, human = parameters['sim'], parameters['agent'], parameters['human']

    # One value for what several nodes must agree on (seeds and modes come from the settings).
    # The sim's control period and limits are not copied: the agent takes them from the reset
    # response and the human node from the sim's parameters, so --set sim.max_force=3 reaches
    # both at run time.
    for node in (sim, agent, human):
        node['seed'] = settings.seed
    sim['mode'] = agent['mode'] = settings.mode
    # The agent announces the roles on /hrc/session; the start values agree with it.
    case = case_table()[settings.case]
    sim['robot_dof'] = case.robot_dof
    human['dof'] = case.human_dof
    agent['case'] = settings.case
    # A session's agent runs the condition; the practice before it is the runner's --practice
    # (hrc_bringup.practice sets practice_episodes on the practice's own agent).
    agent['practice_episodes'] = 0
    agent['session_id'] = settings.session_id
    agent['checkpoint_dir'] = str(pathlib.Path(settings.runs_dir) / 'checkpoints')
    if settings.training_episodes > 0:
        agent['max_training_episodes'] = settings.training_episodes
    if settings.evaluation_episodes >= 0:
        agent['evaluation_episodes'] = settings.evaluation_episodes
    if settings.resume_from:
        agent['resume_from'] = settings.resume_from
    if settings.start_from:
        agent['start_from'] = settings.start_from
    if settings.adapt_from:
        # adapting to a new person as docs/partners/held_out.md measured best
        agent['start_from'] = settings.adapt_from
        agent.update(adapting_agent_parameters(settings.training_episodes or ADAPT_EPISODES))
    human['input'] = settings.human_input
    if settings.human_profile:
        human['profile'] = settings.human_profile
    # Before the first episode the agent waits until these listen to the states and have the
    # session's announcement: the human node (else it may answer the first states with its
    # default roles) and the recorder (else it misses the first state).
    agent['wait_for_subscribers'] = ['human']
    if settings.record:
        recorder = parameters['recorder']
        recorder['session_id'] = settings.session_id
        recorder['output_dir'] = settings.bags_dir
        agent['wait_for_subscribers'] = ['human', 'recorder']
        # lockstep runs no further ahead of the recorder than the writers' histories hold
        parameters['sim']['await_recorder'] = True


def write_session_files(settings: SessionSettings, parameters: dict, session_dir: pathlib.Path,
                        params_dir: pathlib.Path = None):
    """Write ``parameters.yaml`` (for --params-file) and ``session.yaml`` (the session config).

    ``params_dir``: where the learning configuration was read (default: ``params_dir()``).

    ``session.yaml`` holds the subject id and notes, so it is created owner-only (0600).

    Returns (parameters_path, session_config_path).
    """
    session_dir.mkdir(parents=True, exist_ok=True)
    params_path = session_dir / 'parameters.yaml'
    atomic_write(params_path, yaml.safe_dump(
        {node: {'ros__parameters': values} for node, values in parameters.items()},
        sort_keys=False))
    case = case_table()[settings.case]
    config = {
        'session_id': settings.session_id,
        'case': settings.case,
        'strategy': case.strategy,
        'robot_dof': case.robot_dof,
        'human_dof': case.human_dof,
        'seed': settings.seed,
        'mode': settings.mode,
        'human_input': settings.human_input,
        # the learning configuration by name and in full (what the agent ran with; hrc results
        # pools only sessions of one configuration unless told)
        'learning': {'name': settings.learning,
                     'settings': load_learning(params_dir or default_params_dir(),
                                               settings.learning)},
        'subject_id': settings.subject_id,
        'notes': settings.notes,
        'version': package_version(),
        'started': datetime.datetime.now().isoformat(timespec='seconds'),
        'settings': {key: value for key, value in asdict(settings).items()},
        'parameters': parameters,
    }
    config_path = session_dir / 'session.yaml'
    # It holds the subject id and the notes: owner-only.
    atomic_write(config_path, yaml.safe_dump(config, sort_keys=False), PERSONAL_FILE_MODE)
    return params_path, config_path
