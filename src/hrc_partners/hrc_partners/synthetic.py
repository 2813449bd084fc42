"""Recordings of simulated people with known parameters, made with the in-process engine.

For tests and demonstrations of cloning: each person is a simulated-human profile (a
``HumanProfile`` with some fields changed) written to a profiles file, and one short session
per (person, seed) is run by :func:`hrc_engine.engine.run_session` with the human node's
``profiles_file``/``profile`` parameters, so the bags are the engine's real bags (the same
files the recorder writes), driven by ``SOURCE_SIMULATED``.
"""

import dataclasses
import pathlib
import typing

from hrc_common.session_plan import SessionSettings
from hrc_engine.engine import compose_parameters, EngineConfig, run_session
from hrc_joystick_node.human_profile import load_profile
import yaml

FAST_SLOW_DELAYS = {'fast': 0.1, 'slow': 0.6}   # s: reaction delays of the demonstration pair


def write_profiles(path, people: typing.Dict[str, dict], base: str = 'skilled') -> str:
    """Write a profiles file: each person = profile ``base`` with the fields given changed."""
    template = load_profile(base)
    profiles = {}
    for name, changes in people.items():
        person = dataclasses.replace(template, **changes)
        values = dataclasses.asdict(person)
        values['description'] = f'{base} with {changes}'
        profiles[name] = values
    path = pathlib.Path(path)
    path.write_text(yaml.safe_dump({'profiles': profiles}, sort_keys=False))
    return str(path)


def fast_and_slow(path) -> str:
    """Write the demonstration pair: a fast and a slow person, otherwise alike and steady.

    ``skilled`` with only the reaction delay changed, no delay compensation (``prediction`` 0),
    no lapses, no learning curve and no fatigue, so the delay is the one difference.
    """
    steady = dict(prediction=0.0, lapse_probability=0.0, untrained_factor=1.0,
                  fatigue_delay_ceiling=0.0, fatigue_noise_ceiling=0.0,
                  fatigue_lapse_ceiling=0.0)
    return write_profiles(path, {name: dict(steady, reaction_delay=delay)
                                 for name, delay in FAST_SLOW_DELAYS.items()})


def record_sessions(bags_dir, runs_dir, profiles_file, people, seeds, case: int = 3,
                    episodes: int = 4, seconds: float = 16.0,
                    human_period: float = 0.2) -> typing.List[str]:
    """Run one short in-process session per (person, seed); return the session folders.

    Case 3 (level-guided, robot on translation) puts the person on the rotation from the first
    episode. ``episodes`` training episodes of ``seconds`` s of simulation, no evaluation, no
    checkpoints. By default the person acts once a control period (``human_period`` 0.2 s: one
    command a step, the rate a clone acts at); at a shorter ``human_period`` (the default
    session's 0.02 s) the bags carry every command applied (``TaskState.human_applied``),
    which a clone learns from (``hrc_partners.cloning``, targets ``applied``).
    """
    folders = []
    for person in people:
        for seed in seeds:
            result = run_session(EngineConfig(SessionSettings(
                case=case, seed=int(seed), training_episodes=int(episodes),
                evaluation_episodes=0, session_id=f'{person}-seed{seed}',
                bags_dir=str(bags_dir), runs_dir=str(runs_dir), human_profile=person,
                overrides={'sim.episode_duration': float(seconds),
                           'sim.human_period': float(human_period),
                           'human.profiles_file': str(profiles_file)}), checkpoints=False))
            folders.append(result.bag_dir)
    return folders


def record_with_model(bags_dir, runs_dir, model_file, seed: int = 0, case: int = 3,
                      episodes: int = 1, seconds: float = 8.0) -> str:
    """Run one short in-process session whose human is a cloned model; return its bag folder.

    The engine's human side is the human node's core with ``input: model`` (the session's
    composed parameters, with the human's input switched to the model).
    """
    config = EngineConfig(SessionSettings(
        case=case, seed=int(seed), training_episodes=int(episodes), evaluation_episodes=0,
        session_id=f'model-seed{seed}', bags_dir=str(bags_dir), runs_dir=str(runs_dir),
        overrides={'sim.episode_duration': float(seconds)}), checkpoints=False)
    _, parameters = compose_parameters(config)
    parameters['human'].update(input='model', model_file=str(model_file))
    config.parameters = parameters
    return run_session(config).bag_dir
