"""Agent checkpoints: save, resume a session, load a policy for evaluation. Pure (torch).

A checkpoint is one ``torch.save`` file holding::

    format          'hrc_agent_checkpoint'
    format_version  FORMAT_VERSION (bumped whenever the layout changes)
    config          the AgentParams as a dict, plus the reward preset, case, strategy, dofs
    network         observation size and network shape (checked before loading weights)
    core            AgentCore.state_dict(): policy and value state_dicts, optimizer, generator
                    states (exploration noise, minibatch order), reward scaler, rollout buffer,
                    strategy progress, counters, evaluation results so far, phase; under
                    ``algorithm: sac`` the key ``sac`` replaces ``ppo`` (actor, critics,
                    temperature, optimizers, generators, replay buffer: sac.STATE_LAYOUT)

Only tensors and plain containers (dict, list, tuple, str, int, float, bool, None): the file
is read with ``torch.load(weights_only=True)``, whose unpickler builds nothing else, so a
crafted file cannot run code (anything else is refused with the reason). The layout is then
checked against :data:`LAYOUT` (every problem reported at once) before anything is loaded.

Written atomically (temporary file, then rename) so a crash never leaves half a checkpoint.
"""

import io
import os
import pickle
import warnings

import torch

from hrc_agent_node.ppo import BUFFER_FIELDS
from hrc_agent_node.sac import STATE_LAYOUT as SAC_STATE_LAYOUT
from hrc_common.contract import atomic_write
from hrc_common.params import as_dict

FORMAT = 'hrc_agent_checkpoint'
# 2: weights_only layout (tensors in the buffer), judging counters, evaluation results.
FORMAT_VERSION = 2

# The checkpoint's layout: a dict maps keys to layouts, a type is the type of a leaf.
LAYOUT = {
    'format': str, 'format_version': int,
    'config': {'params': dict, 'preset': str, 'case': int, 'strategy': str, 'robot_dof': str,
               'human_dof': str, 'session_id': str},
    'network': {'observation_size': int, 'hidden_size': int, 'hidden_layers': int,
                'observe_rates': bool},
    'core': {
        'ppo': {'policy': dict, 'value': dict, 'optimizer': dict,
                'action_generator': torch.Tensor, 'shuffle_generator': torch.Tensor,
                'updates': int},
        'reward_scaler': {'stats': {'mean': float, 'var': float, 'count': float},
                          'discounted_return': float},
        'buffer': {name: list for name in BUFFER_FIELDS},
        'progress': {'case_id': int, 'step_index': int, 'finished': bool, 'step_history': list},
        'counters': {'episode': int, 'total_episodes': int, 'human_involved_episodes': int,
                     'judging_episodes': int, 'episodes_since_judging': int,
                     'judging_due': bool},
        'evaluation_results': list, 'phase': str},
}


def layout_of(algorithm: str) -> dict:
    """Return :data:`LAYOUT` for the checkpoint of a learner (``ppo`` or ``sac``)."""
    if algorithm != 'sac':
        return LAYOUT
    core = {key: value for key, value in LAYOUT['core'].items() if key != 'ppo'}
    return {**LAYOUT, 'core': {'sac': SAC_STATE_LAYOUT, **core}}


def algorithm_of(checkpoint: dict) -> str:
    """Return the learner a checkpoint was written by (files without the field: ppo)."""
    config = checkpoint.get('config')
    params = config.get('params') if isinstance(config, dict) else None
    return params.get('algorithm', 'ppo') if isinstance(params, dict) else 'ppo'


class CheckpointError(ValueError):
    """A checkpoint cannot be read or does not fit this agent; the message says why."""


def network_signature(core) -> dict:
    """Return what the networks' shapes depend on."""
    params = core.params
    hidden_size = params.sac_hidden_size if params.algorithm == 'sac' else params.hidden_size
    return {'observation_size': core.observation_size, 'hidden_size': hidden_size,
            'hidden_layers': params.hidden_layers, 'observe_rates': params.observe_rates}


def make_checkpoint(core) -> dict:
    """Return the checkpoint dictionary of an AgentCore between episodes."""
    return {'format': FORMAT, 'format_version': FORMAT_VERSION,
            'config': {'params': as_dict(core.params), 'preset': core.preset,
                       'case': core.case_id, 'strategy': core.strategy,
                       'robot_dof': core.robot_dof, 'human_dof': core.human_dof,
                       'session_id': core.session_id},
            'network': network_signature(core),
            'core': core.state_dict()}


def remove_stale_temporaries(directory) -> list:
    """Remove the temporary files a killed checkpoint write left in ``directory``; list them.

    ``atomic_write`` writes ``.<name>.<random>.tmp`` beside the checkpoint and renames it; a
    SIGKILL between the two leaves it (about 0.5 MiB each). Only the session's own agent
    writes its checkpoint folder (its id is claimed), so at its start none is in progress.
    """
    removed = []
    if not os.path.isdir(directory):
        return removed
    for name in sorted(os.listdir(directory)):
        if name.startswith(('.latest.pt.', '.final.pt.')) and name.endswith('.tmp'):
            os.unlink(os.path.join(directory, name))
            removed.append(name)
    return removed


def save_checkpoint(core, path) -> str:
    """Write ``core``'s checkpoint to ``path`` atomically and durably; return the path."""
    path = os.fspath(path)
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    buffer = io.BytesIO()
    torch.save(make_checkpoint(core), buffer)
    atomic_write(path, buffer.getvalue())
    return path


def layout_problems(value, layout, where: str = 'checkpoint') -> list:
    """Return every way ``value`` departs from ``layout`` (see :data:`LAYOUT`), or []."""
    if isinstance(layout, dict):
        if not isinstance(value, dict):
            return [f'{where} must be a mapping, got {type(value).__name__}']
        problems = [f'{where} lacks {key!r}' for key in layout if key not in value]
        for key, inner in layout.items():
            if key in value:
                problems += layout_problems(value[key], inner, f'{where}.{key}')
        return problems
    if layout is float:
        fits = isinstance(value, (int, float)) and not isinstance(value, bool)
    elif layout is int:
        fits = isinstance(value, int) and not isinstance(value, bool)
    else:
        fits = isinstance(value, layout)
    return [] if fits else [f'{where} must be {layout.__name__}, got {type(value).__name__}']


def read_checkpoint(path) -> dict:
    """Read a checkpoint file and check its layout; raise CheckpointError on any problem."""
    path = os.fspath(path)
    try:
        # weights_only=True: tensors and plain containers only; no object of the file's
        # choosing is built, so no code from the file runs.
        with warnings.catch_warnings():   # torch warns about pickle protocols it reads anyway
            warnings.simplefilter('ignore', UserWarning)
            checkpoint = torch.load(path, map_location='cpu', weights_only=True)
    except FileNotFoundError:
        raise CheckpointError(f'checkpoint {path} does not exist') from None
    except pickle.UnpicklingError as error:
        lines = str(error).strip().splitlines()
        detail = next((line.strip() for line in lines if 'Unsupported' in line),
                      lines[0] if lines else '')
        detail = detail.split('. Please')[0].replace('WeightsUnpickler error: ', '')
        if 'GLOBAL' not in detail:   # no object reference: a damaged or foreign file
            raise CheckpointError(f'checkpoint {path} cannot be read (UnpicklingError: '
                                  f'{detail})') from None
        raise CheckpointError(
            f'checkpoint {path} refused: it holds objects other than tensors and plain '
            f'containers, which are never loaded (code could run from them; checkpoints of '
            f'format version 1 held numpy arrays and are refused too): {detail}') from None
    except Exception as error:  # torch raises many kinds for a damaged or foreign file
        raise CheckpointError(f'checkpoint {path} cannot be read ({type(error).__name__}: '
                              f'{error})') from None
    if not isinstance(checkpoint, dict) or checkpoint.get('format') != FORMAT:
        raise CheckpointError(f'{path} is not an hrc agent checkpoint (no format '
                              f'{FORMAT!r})')
    version = checkpoint.get('format_version')
    if version != FORMAT_VERSION:
        raise CheckpointError(f'checkpoint {path} has format version {version}; this agent '
                              f'reads version {FORMAT_VERSION}')
    problems = layout_problems(checkpoint, layout_of(algorithm_of(checkpoint)))
    if problems:
        raise CheckpointError(f'checkpoint {path} is malformed: ' + '; '.join(problems))
    return checkpoint


def check_compatible(checkpoint: dict, core, path='checkpoint', resume: bool = True) -> None:
    """Raise CheckpointError when the checkpoint does not fit ``core``.

    The network shape and the robot's degree of freedom must always match; resuming a session
    also needs the same case (strategy progress and counters belong to it).
    """
    problems = []
    expected = network_signature(core)
    for key, value in expected.items():
        if checkpoint['network'].get(key) != value:
            problems.append(f'{key} is {checkpoint["network"].get(key)!r} in the checkpoint '
                            f'but {value!r} here')
    config = checkpoint['config']
    if algorithm_of(checkpoint) != core.params.algorithm:
        problems.append(f'it was written by the {algorithm_of(checkpoint)} learner but this '
                        f'agent runs {core.params.algorithm} (algorithm)')
    if config.get('robot_dof') != core.robot_dof:
        problems.append(f'the policy drives {config.get("robot_dof")!r} but the robot drives '
                        f'{core.robot_dof!r} in case {core.case_id}')
    if resume and config.get('case') != core.case_id:
        problems.append(f'it belongs to case {config.get("case")}, not case '
                        f'{core.case_id}')
    if problems:
        raise CheckpointError(f'checkpoint {path} is incompatible: ' + '; '.join(problems))


def load_into(core, path, resume: bool = True) -> dict:
    """Load a checkpoint into ``core``: resume a session, or (``resume=False``) the policy only.

    Returns the checkpoint's config. Raises CheckpointError if unreadable or incompatible.
    """
    checkpoint = read_checkpoint(path)
    check_compatible(checkpoint, core, path, resume)
    try:
        core.load_state_dict(checkpoint['core'], policy_only=not resume)
    except (KeyError, RuntimeError, ValueError, TypeError, IndexError) as error:
        raise CheckpointError(f'checkpoint {path} does not load: {type(error).__name__}: '
                              f'{error}') from None
    return checkpoint['config']


def load_session_start(core) -> str:
    """Load what ``core``'s parameters start the session from; return it in words ('' if none).

    ``resume_from``: the session continues (or, with ``evaluation_only``, its policy is
    evaluated); ``start_from``: a new session with a finished session's policy (a returning
    person, :meth:`AgentCore.start_after`). Raises CheckpointError naming the parameter.
    """
    params = core.params
    if params.start_from:
        try:
            load_into(core, params.start_from, resume=False)
        except CheckpointError as error:
            raise CheckpointError(f'start_from rejected: {error}') from None
        core.start_after()
        if params.start_from_judged:
            return (f'started from the policy of {params.start_from} (a returning person): the '
                    'last training step, its first episode judges that policy')
        return (f'started from the policy of {params.start_from} (adapting to a new person): '
                "the last training step, learning from each of the person's episodes")
    if not params.resume_from:
        return ''
    try:
        load_into(core, params.resume_from, resume=not params.evaluation_only)
    except CheckpointError as error:
        raise CheckpointError(f'resume_from rejected: {error}') from None
    return (f'loaded {params.resume_from} '
            f'({"policy for evaluation" if params.evaluation_only else "session"}): '
            f'{core.total_episodes} training episodes done, next episode {core.episode}')
