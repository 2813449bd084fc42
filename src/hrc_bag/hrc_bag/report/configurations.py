"""The learning configurations of the sessions a report would pool (pure, no rclpy).

Every session's ``session.yaml`` names its learning configuration and holds its content
(``learning: {name, settings}``); sessions recorded before that entry are configuration
``unrecorded``. Table II pools the sessions of a case, so a report over sessions of different
configurations mixes learners: :func:`pooling_refusal` says so unless the user asked for it.
Two sessions are of the same configuration when they have the same name and, for a named one,
the same settings (a configuration file edited between the runs is another configuration).
"""

import json

from hrc_bag.report.counting import episodes_before
from hrc_bag.report.metrics import human_time
from hrc_bag.report.records import record_kind
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


def input_of(session) -> str:
    """Return who acted as the person: the input source of most engaged steps, or 'nobody'."""
    bag_session = session.extra.get('bag_session')
    if bag_session is None:
        return ''                       # a record without its bags (a CSV): not known
    sources = {source: entry['engaged_steps'] for source, entry in
               human_time(bag_session).items() if entry['engaged_steps']}
    return max(sources, key=sources.get) if sources else 'nobody'


def _differ(what: str, labels: dict) -> list:
    """Return the reason when the sessions have more than one ``what`` ({label: [ids]})."""
    if len(labels) <= 1:
        return []
    return [f'the sessions differ in {what}: ' + '; '.join(
        f'{label} ({len(ids)}: {", ".join(sorted(ids)[:3])}{", ..." if len(ids) > 3 else ""})'
        for label, ids in labels.items())]


def pooling_problems(sessions, strict: bool = True) -> list:
    """Return every reason why the sessions may not be pooled into one Table II (or []).

    Always: different learning configurations. ``strict`` (pooling many sessions as seeds, as
    ``hrc results`` does) also: who acted as the person, the episode limits, practice-only
    sessions and repeats of one case with one person.
    """
    reasons = []
    counts = configurations(sessions)
    if len(counts) > 1:
        reasons.append(f'the sessions were run with {len(counts)} learning configurations: '
                       f'{describe(counts)}; Table II would pool different learners')
    if not strict or len(sessions) < 2:
        return reasons
    by_input, by_limit, by_person = {}, {}, {}
    for session in sessions:
        source = input_of(session)
        if source:
            by_input.setdefault(source, []).append(session.session_id)
        if session.episode_limit:
            # the session's own budget: a partners-first session's limit also holds the
            # episodes of its pre-training, run before the person joined
            budget = session.episode_limit - episodes_before(session)
            by_limit.setdefault(f'at most {budget} training episodes',
                                []).append(session.session_id)
        subject = session.extra.get('subject_id') or ''
        person = (session.case_id, session.profile, session.seed,
                  session.extra.get('person', -1), subject)
        by_person.setdefault(person, []).append(session.session_id)
    reasons += _differ("the person's input (who acted as the person)", by_input)
    reasons += _differ('their episode limits', by_limit)
    practice_only = sorted(session.session_id for session in sessions if session.episodes and
                           all(record_kind(episode) == 'practice'
                               for episode in session.episodes))
    if practice_only:
        reasons.append(f'practice only (no training episode): {", ".join(practice_only)}')
    for (case_id, profile, seed, _, subject), ids in by_person.items():
        if len(ids) > 1:
            who = f'subject {subject}' if subject else f'profile {profile} seed {seed}'
            reasons.append(f'case {case_id} with {who} is there {len(ids)} times '
                           f'({", ".join(sorted(ids))}): counted once per person, a repeat '
                           'is not another seed')
    return reasons


def pooling_refusal(sessions, pool: bool = False, strict: bool = False) -> str:
    """Return why the sessions may not be pooled, a reason a line ('' when they may).

    They may when the problems of :func:`pooling_problems` are none or ``pool`` is set.
    """
    reasons = [] if pool else pooling_problems(sessions, strict)
    if not reasons:
        return ''
    return '\n'.join(reasons + [f'give sessions that agree, or {POOL_OPTION} to pool them '
                                 'anyway'])
