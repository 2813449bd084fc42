#!/usr/bin/env python3
"""Trace one partners-first session offline: every episode's subtask errors, step by step.

Runs case 7 or 8 as the experiment runner does (the study's settings, ``--set`` more): the
pre-training of ``hrc_partners.partners_first.pretrain`` (robot alone, then the population),
then the person's step with the session's person (person ``seed`` of the ``paper``
population, ``hrc_engine.partners.SimulatedHumanPartner`` acting at the sim's
``human_period`` as the engine's person does) in the offline loop, and prints
one line per episode: step, partner, kind (train / judge), the mean |error| of each subtask
(m or rad) with a ``*`` where it exceeds its tolerance (``params/task_tree.yaml``), and the
step's event. The offline loop runs the same cores as the engine; the person's step here is
a diagnosis, not the engine's session (the engine's numbers come from ``hrc experiment``).

    OMP_NUM_THREADS=1 python bench/partners_first_trace.py --case 7 --seed 0 [--set agent.x=v]
"""

import argparse
import collections
import sys
import time

import torch

from hrc_agent_node.agent_core import AgentCore
from hrc_agent_node.config import AgentParams
from hrc_common.contract import Phase, SimLimits
from hrc_common.params import from_dict
from hrc_common.paths import params_dir
from hrc_common.session_plan import (add_learning_option, compose, parse_overrides,
                                     SessionSettings)
from hrc_engine.offline import partner_loop, run_episode
from hrc_engine.partners import MixturePartner, parse_specs, SimulatedHumanPartner
from hrc_joystick_node.human_profile import load_profile
from hrc_joystick_node.population import sample_person
from hrc_partners import partners_first
from hrc_sim_node.physics import physics_params_of, SliderPendulumBall
from hrc_sim_node.sim_params import SimParams


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--case', type=int, default=7)
    parser.add_argument('--seed', type=int, default=0)
    parser.add_argument('--set', action='append', default=[], metavar='NODE.PARAM=VALUE')
    add_learning_option(parser)
    parser.add_argument('--person-episodes', type=int, default=12,
                        help="episodes of the person's step at most")
    args = parser.parse_args(argv)
    torch.set_num_threads(1)
    settings = SessionSettings(case=args.case, seed=args.seed, session_id='trace',
                               learning=args.learning, overrides=parse_overrides(args.set))
    parameters = compose(settings, params_dir())
    agent = from_dict(AgentParams, dict(parameters['agent'], checkpoint_dir='', resume_from=''))
    physics = physics_params_of(from_dict(SimParams, parameters['sim']))
    limits = SimLimits.of(physics)
    core = AgentCore(agent, limits=limits)
    tolerances = {node.id: node.tolerance for node in core.tree.subtasks.values()} \
        if hasattr(core, 'tree') else {}
    settings = partners_first.population_settings(agent.cases_file)
    mixture = MixturePartner(parse_specs(settings.population()), core.human_dof, core.seed,
                             limits, 1)
    person = sample_person(load_profile('paper'), args.seed)
    own = SimulatedHumanPartner(person, core.human_dof, args.seed, limits.human_step)
    person_step = core.case.first_person_step
    in_step, person_episodes = 0, 0
    started = time.perf_counter()
    met = collections.Counter()
    with SliderPendulumBall(physics) as sim:
        core.set_limits(limits)
        # each partner on its own loop, so each person's clock runs on (fatigue, rest)
        loops = {name: partner_loop(core, sim, partner)
                 for name, partner in (('mixture', mixture), ('own', own))}
        while core.phase not in (Phase.DONE, Phase.EVALUATION):
            step = core.progress.step_index
            population_step = core.training_step.partner == 'population'
            core.population_partner = population_step
            partner = mixture if population_step else own
            result = run_episode(core, sim, partner,
                                 loop=loops['mixture' if population_step else 'own'])
            if core.phase == 'updating':
                core.update()
            who = mixture.spec.text if population_step else 'the person' \
                if step >= person_step else '-'
            errors = ' '.join(
                f'{name} {value:.3f}{"*" if value > tolerances.get(name, 1e9) else " "}'
                for name, value in sorted(result.errors.items()))
            print(f'ep {result.episode:3d} step {step} {who:22s} '
                  f'{"judge" if result.judging else "train"} {errors} {result.event}',
                  flush=True)
            if population_step:
                met[who.split(':')[1]] += 1
                in_step = in_step + 1 if core.progress.step_index == step else 0
                if settings.budget and in_step >= settings.budget and core.phase == Phase.TRAINING:
                    core.skip_step()
                    print('population budget spent: step skipped', flush=True)
                    in_step = 0
            if step >= person_step:
                person_episodes += 1
                if person_episodes >= args.person_episodes:
                    break
    print(f'person episodes {core.human_involved_episodes}, population episodes '
          f'{core.population_episodes}, profiles met {dict(met)}, '
          f'{time.perf_counter() - started:.0f} s')
    return 0


if __name__ == '__main__':
    sys.exit(main())
