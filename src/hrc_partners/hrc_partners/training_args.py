"""The command line of ``hrc partners train``: its parser, light to import.

``hrc partners train --help`` is answered from here without loading torch or PyBullet (the
training loads them); ``hrc_partners.training.main`` checks the values.
"""

import argparse

# the first paragraph of hrc_partners.training's docstring (a test checks they stay the same)
DESCRIPTION = ('Train the agents that cross-play compares: one simulated person vs a '
               'population (offline).')


def build_parser() -> argparse.ArgumentParser:
    """Return the parser of ``hrc partners train`` (its flags and help)."""
    parser = argparse.ArgumentParser(prog='hrc partners train',
                                     description=DESCRIPTION)
    parser.add_argument('--out', default='runs/partners', help='folder for the checkpoints')
    parser.add_argument('--case', type=int, default=2, help='paper case of the agents')
    parser.add_argument('--seeds', nargs='+', type=int, default=[0], help='an agent per seed')
    parser.add_argument('--episodes', type=int, default=250, help='max training episodes')
    parser.add_argument('--profile', default='paper',
                        help='simulated-human profile of the person or the population')
    parser.add_argument('--preset', default='tuned', help='reward preset of the task tree')
    parser.add_argument('--population-every', type=int, default=1,
                        help='population: a new simulated person every N episodes')
    parser.add_argument('--kinds', nargs='+', default=['one', 'population'],
                        choices=['one', 'population', 'mixture'],
                        help='agents to train: with one simulated person, a population, a '
                             'mixture of partners')
    parser.add_argument('--mixture', nargs='*', default=[], metavar='SPEC',
                        help='kind mixture: partner specs drawn from every --population-every '
                             'episodes (profile:, person:, population:, model:)')
    return parser
