"""Agent checkpoints: save, resume a session, load a policy for evaluation. Pure (torch).

A checkpoint is one ``torch.save`` file holding::

    format          'hrc_agent_checkpoint'
    format_version  FORMAT_VERSION (bumped whenever the layout changes)
    config          the AgentParams as a dict, plus the reward preset, case, strategy, dofs
    network         observation size and network shape (checked before loading weights)
    core            AgentCore.state_dict(): policy and value state_dicts, optimizer, generator
                    states (exploration noise, minibatch order), reward scaler, rollout buffer,
                    strategy progress, counters, phase

Written atomically (temporary file, then rename) so a crash never leaves half a checkpoint.
"""

import os
import tempfile

import torch

from hrc_common.params import as_dict

FORMAT = 'hrc_agent_checkpoint'
FORMAT_VERSION = 1


class CheckpointError(ValueError):
    """A checkpoint cannot be read or does not fit this agent; the message says why."""


def network_signature(core) -> dict:
    """Return what the networks' shapes depend on."""
    params = core.params
    return {'observation_size': core.observation_size, 'hidden_size': params.hidden_size,
            'hidden_layers': params.hidden_layers, 'observe_rates': params.observe_rates}


def make_checkpoint(core) -> dict:
    """Return the checkpoint dictionary of an AgentCore between episodes."""
    return {'format': FORMAT, 'format_version': FORMAT_VERSION,
            'config': {'params': as_dict(core.params), 'preset': core.tree.preset,
                       'case': core.case.case_id, 'strategy': core.case.strategy,
                       'robot_dof': core.robot_dof, 'human_dof': core.human_dof,
                       'session_id': core.session_id},
            'network': network_signature(core),
            'core': core.state_dict()}


def save_checkpoint(core, path) -> str:
    """Write ``core``'s checkpoint to ``path`` atomically; return the path."""
    path = os.fspath(path)
    directory = os.path.dirname(os.path.abspath(path))
    os.makedirs(directory, exist_ok=True)
    handle, temporary = tempfile.mkstemp(prefix='.checkpoint-', suffix='.tmp', dir=directory)
    try:
        with os.fdopen(handle, 'wb') as stream:
            torch.save(make_checkpoint(core), stream)
        os.replace(temporary, path)
    except BaseException:
        if os.path.exists(temporary):
            os.unlink(temporary)
        raise
    return path


def read_checkpoint(path) -> dict:
    """Read a checkpoint file and check its format; raise CheckpointError on any problem."""
    path = os.fspath(path)
    try:
        # weights_only=False: the checkpoint holds generator states and plain dicts we wrote.
        checkpoint = torch.load(path, map_location='cpu', weights_only=False)
    except FileNotFoundError:
        raise CheckpointError(f'checkpoint {path} does not exist') from None
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
    if config.get('robot_dof') != core.robot_dof:
        problems.append(f'the policy drives {config.get("robot_dof")!r} but the robot drives '
                        f'{core.robot_dof!r} in case {core.case.case_id}')
    if resume and config.get('case') != core.case.case_id:
        problems.append(f'it belongs to case {config.get("case")}, not case '
                        f'{core.case.case_id}')
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
    except (KeyError, RuntimeError, ValueError) as error:
        raise CheckpointError(f'checkpoint {path} does not load: {type(error).__name__}: '
                              f'{error}') from None
    return checkpoint['config']
