"""The learning configurations of the sessions a report would pool (pure, no rclpy).

Every session's ``session.yaml`` names its learning configuration and holds its content
(``learning: {name, settings}``); sessions recorded before that entry are configuration
``unrecorded``. Table II pools the sessions of a case, so a report over sessions of different
configurations mixes learners: :func:`pooling_refusal` says so unless the user asked for it.
Two sessions are of the same configuration when they have the same name and, for a named one,
the same settings (a configuration file edited between the runs is another configuration).
"""

import json

from hrc_bag.report.session_config import UNRECORDED

POOL_OPTION = '--pool-configurations'


def _settings_key(session) -> str:
    if session.learning == UNRECORDED:   # the agent's parameters differ by seed: name only
        return ''
    return json.dumps(session.learning_settings, sort_keys=True, default=str)


def configurations(sessions) -> dict:
    """Return {configuration label: session count}, labels in order of appearance.

    The label is the configuration's name; a name recorded with different settings is
    labelled ``name (settings 1)``, ``name (settings 2)``, ... in order of appearance.
    """
    variants = {}
    for session in sessions:
        keys = variants.setdefault(session.learning, {})
        keys[_settings_key(session)] = keys.get(_settings_key(session), 0) + 1
    counts = {}
    for name, keys in variants.items():
        if len(keys) == 1:
            counts[name] = next(iter(keys.values()))
            continue
        for number, count in enumerate(keys.values(), 1):
            counts[f'{name} (settings {number})'] = count
    return counts


def describe(counts: dict) -> str:
    """Return e.g. 'sac (10 sessions), unrecorded (1 session)'."""
    return ', '.join(f'{label} ({count} session{"" if count == 1 else "s"})'
                     for label, count in counts.items())


def pooling_refusal(sessions, pool: bool = False) -> str:
    """Return why the sessions may not be pooled ('' when they may).

    They may when they are all of one learning configuration or when ``pool`` is set.
    """
    counts = configurations(sessions)
    if pool or len(counts) <= 1:
        return ''
    return (f'the sessions were run with {len(counts)} learning configurations: '
            f'{describe(counts)}; Table II would pool different learners. Give the sessions '
            f'of one configuration, or {POOL_OPTION} to pool them anyway.')
