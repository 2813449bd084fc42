"""What the report reads of a session's ``session.yaml`` (the ``hrc_session`` record of its bags).

The configuration travels as YAML text in every bag (:mod:`hrc_bag.report.loading` parses it);
these readers pick the values the study needs and say what stands in for a value that sessions
recorded before it existed do not have.
"""

import math

# The learning configuration of sessions recorded before session.yaml named it.
UNRECORDED = 'unrecorded'


def nested(config: dict, *keys, default=None):
    """Return ``config[keys[0]][keys[1]]...``, or ``default`` when a level is missing."""
    value = config
    for key in keys:
        if not isinstance(value, dict) or key not in value:
            return default
        value = value[key]
    return value


def profile_of(config: dict) -> str:
    """Return the simulated-human profile of a session config ('paper' when not given)."""
    for path in (('human_profile',), ('settings', 'human_profile'),
                 ('parameters', 'human', 'profile'), ('human', 'profile')):
        value = nested(config, *path)
        if value:
            return str(value)
    return 'paper'


def person_of(config: dict) -> int:
    """Return the simulated person drawn for the session (-1: the profile itself)."""
    for path in (('parameters', 'human', 'person'), ('human', 'person'), ('person',)):
        value = nested(config, *path)
        if isinstance(value, int):
            return value
    return -1


def limits_of(config: dict) -> dict:
    """Return the command limits the session's sim was given {dof: N or N*m} (may be empty).

    Sims started without them use the sim's defaults (:func:`hrc_bag.report.records.
    default_limits`).
    """
    limits = {}
    for dof, name in (('translation', 'max_force'), ('rotation', 'max_torque')):
        for path in (('parameters', 'sim', name), ('sim', name)):
            value = nested(config, *path)
            if isinstance(value, (int, float)) and value > 0:
                limits[dof] = float(value)
                break
    return limits


def episode_seconds_of(config: dict) -> float:
    """Return the session's episode duration (s of simulated time; NaN when not said)."""
    for path in (('parameters', 'sim', 'episode_duration'), ('sim', 'episode_duration')):
        value = nested(config, *path)
        if isinstance(value, (int, float)) and value > 0:
            return float(value)
    return math.nan


def episode_limit_of(config: dict) -> int:
    """Return the session's max training episodes (0 when the config does not say)."""
    for path in (('parameters', 'agent', 'max_training_episodes'),
                 ('agent', 'max_training_episodes'), ('max_training_episodes',),
                 ('settings', 'training_episodes')):
        value = nested(config, *path)
        if isinstance(value, (int, float)) and value > 0:
            return int(value)
    return 0


def learning_of(config: dict) -> tuple:
    """Return (name, settings) of the session's learning configuration.

    ``session.yaml``'s ``learning: {name, settings}``; a session recorded before that entry is
    configuration :data:`UNRECORDED`, with the agent's parameters of its session.yaml (or {})
    as its settings.
    """
    learning = config.get('learning')
    if isinstance(learning, dict) and learning.get('name'):
        settings = learning.get('settings')
        return str(learning['name']), settings if isinstance(settings, dict) else {}
    agent = nested(config, 'parameters', 'agent', default=None)
    if not isinstance(agent, dict):
        agent = nested(config, 'agent', default={})
    return UNRECORDED, dict(agent) if isinstance(agent, dict) else {}
