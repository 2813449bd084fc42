"""Draw a task decomposition tree as a figure (PNG/SVG), in the style of the paper's Fig. 2/4.

Levels are rows (level 1 on top), actions are the bottom row, task-task connections are solid
lines, task-action connections dashed (thick for the direct action). For a case, actions are
coloured by their executor and the subtasks of the robot's reward in a training step are filled.
Pure (matplotlib with the Agg backend, no display needed).
"""

import matplotlib

matplotlib.use('Agg')
import matplotlib.pyplot as plt  # noqa: E402

ROBOT_COLOUR = '#4c72b0'
HUMAN_COLOUR = '#dd8452'
ACTIVE_FILL = '#c6dbef'
HUMAN_FILL = '#fde0c5'


def draw_tree(tree, path, case=None, step_index=None, title=None, dpi=120) -> str:
    """Draw ``tree`` to ``path``; with ``case`` (and a step), show roles and active subtasks."""
    executors = case.executors if case is not None else {}
    step = case.steps[step_index] if case is not None and step_index is not None else None
    rows = list(tree.levels) + ['actions']
    positions = {}
    for row_index, row in enumerate(rows):
        ids = list(tree.actions) if row == 'actions' else tree.subtasks_at(row)
        for column, identifier in enumerate(ids):
            x = (column + 1) / (len(ids) + 1)
            y = 1.0 - row_index / max(len(rows) - 1, 1)
            positions[identifier] = (x, y)
    figure, axes = plt.subplots(figsize=(7.5, 1.6 + 1.5 * len(rows)))
    axes.set_xlim(0, 1)
    axes.set_ylim(-0.2, 1.2)
    axes.axis('off')
    for subtask in tree.subtasks.values():
        x0, y0 = positions[subtask.id]
        for child in subtask.children:
            x1, y1 = positions[child]
            axes.annotate('', (x1, y1 + 0.08), (x0, y0 - 0.08),
                          arrowprops={'arrowstyle': '-', 'color': 'black', 'lw': 1.5})
        for action_id in subtask.actions:
            x1, y1 = positions[action_id]
            direct = action_id == subtask.direct_action
            axes.annotate('', (x1, y1 + 0.08), (x0, y0 - 0.08),
                          arrowprops={'arrowstyle': '-', 'color': 'grey',
                                      'lw': 2.2 if direct else 0.8, 'linestyle': '--'})
    for subtask in tree.subtasks.values():
        x, y = positions[subtask.id]
        fill = 'white'
        if step is not None and subtask.id in step.robot_subtasks:
            fill = ACTIVE_FILL
        elif step is not None and subtask.id in step.human_subtasks:
            fill = HUMAN_FILL
        shape = tree.shapes[subtask.id]
        label = (f'{subtask.paper_symbol or subtask.id}: {subtask.id}\n'
                 f'{subtask.state_variable} -> {shape.mu:g} {subtask.unit}\n'
                 f'a={shape.alpha:g} s={shape.sigma:g}')
        axes.text(x, y, label, ha='center', va='center', fontsize=8,
                  bbox={'boxstyle': 'round', 'facecolor': fill, 'edgecolor': 'black'})
    for action_id in tree.actions:
        x, y = positions[action_id]
        executor = executors.get(action_id, '')
        colour = {'robot': ROBOT_COLOUR, 'human': HUMAN_COLOUR}.get(executor, 'black')
        label = f'action: {action_id}' + (f'\n({executor})' if executor else '')
        axes.text(x, y, label, ha='center', va='center', fontsize=8, color='white',
                  bbox={'boxstyle': 'square', 'facecolor': colour, 'edgecolor': colour})
    for row_index, row in enumerate(rows):
        y = 1.0 - row_index / max(len(rows) - 1, 1)
        axes.text(0.0, y, f'level {row}' if row != 'actions' else 'actions', ha='left',
                  va='center', fontsize=9, style='italic')
    if title is None:
        title = f'task decomposition tree (preset {tree.preset})'
        if case is not None:
            title = f'case {case.case_id} ({case.strategy}), robot: {case.robot_dof}'
            if step is not None:
                title += (f'\nstep {step.index + 1}: {step.name}; blue fill = robot reward, '
                          f'orange = human only')
    axes.set_title(title, fontsize=10)
    figure.tight_layout()
    figure.savefig(path, dpi=dpi)
    plt.close(figure)
    return str(path)
