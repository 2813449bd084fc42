"""Command line: print a task tree as text and draw it as a PNG (for reports and the README)."""

import argparse
import sys

from hrc_agent_node.config import CASES_FILE_NAME, share_file, TREE_FILE_NAME
from hrc_agent_node.strategies import CasesError, load_cases
from hrc_agent_node.task_tree import TaskTree, TaskTreeError

SUMMARY = ('usage: hrc tree [--tree FILE] [--cases FILE] [--preset NAME] [--case N] '
           '[--step K] [--png FILE]\n\nPrint the task decomposition tree (validated) as text and '
           'optionally draw it as a PNG; with --case, show the roles and the training steps.')


def main(argv=None) -> int:
    """Validate, print and draw a task tree; exit 1 with the reasons if it is invalid."""
    parser = argparse.ArgumentParser(prog='hrc tree', usage=SUMMARY.splitlines()[0][7:],
                                     description=SUMMARY.split('\n\n', 1)[1])
    parser.add_argument('--tree', default=None, help='task tree YAML (default: installed)')
    parser.add_argument('--cases', default=None, help='cases YAML (default: installed)')
    parser.add_argument('--preset', default=None, help="reward preset (default: the file's)")
    parser.add_argument('--case', type=int, default=None,
                        help="a case of the cases file (installed: the paper's 1..6, partners "
                             'first 7-8)')
    parser.add_argument('--step', type=int, default=1, help='training step of the case, from 1')
    parser.add_argument('--png', default=None, help='draw the tree into this PNG file')
    args = parser.parse_args(argv)
    try:
        tree = TaskTree.from_file(args.tree or share_file(TREE_FILE_NAME), args.preset)
        case = None
        if args.case is not None:
            cases = load_cases(args.cases or share_file(CASES_FILE_NAME), tree)
            if args.case not in cases:
                raise CasesError(f'case {args.case} is not defined ({sorted(cases)})')
            case = cases[args.case]
            if not 1 <= args.step <= len(case.steps):
                raise CasesError(f'case {args.case} has steps 1..{len(case.steps)}')
    except (TaskTreeError, CasesError) as error:
        print(f'error: {error}', file=sys.stderr)
        return 1
    step = case.steps[args.step - 1] if case is not None else None
    print(tree.render_text(case.executors if case else None,
                           step.robot_subtasks if step else None))
    if case is not None:
        print(f'\ncase {case.case_id}: {case.strategy} ({case.description}); robot '
              f'{case.robot_dof}, human {case.human_dof}')
        for item in case.steps:
            human = (f'involved, holds {list(item.human_subtasks)}' if item.human_involved
                     else 'not involved')
            print(f'  step {item.index + 1} "{item.name}": robot reward '
                  f'{list(item.robot_subtasks)}, human {human}, advance when {item.advance} '
                  f'on {list(item.watch)}')
    if args.png:
        from hrc_agent_node.tree_figure import draw_tree  # lazy: matplotlib (1 s), --png only
        draw_tree(tree, args.png, case, args.step - 1 if case is not None else None)
        print(f'\nwrote {args.png}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
