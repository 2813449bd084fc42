"""The agent's ``agent: learner`` status on /diagnostics, and its update log line.

Pure: reads an :class:`hrc_agent_node.agent_core.AgentCore`; levels and thresholds are
:func:`hrc_common.diagnostics.learner_level`'s.
"""

from hrc_common.diagnostics import learner_level, status


def update_line(stats: dict, when: str, algorithm: str) -> str:
    """Return the log line of one update's statistics."""
    return (f'{algorithm.upper()} update {stats["update"]} ({when}): {stats["samples"]} samples '
            f'in {stats["seconds"]:.2f} s, policy loss {stats["policy_loss"]:.4f}, value loss '
            f'{stats["value_loss"]:.4f}, approx kl {stats["approx_kl"]:.5f}, action std '
            f'{stats["action_std"]:.3f}')


class LearnerHealth:
    """What the agent's learner did last; its DiagnosticStatus."""

    def __init__(self):
        self.last_update = None     # the newest update's statistics (None: none yet)

    def on_update(self, stats: dict) -> None:
        """Take the statistics of an update that finished."""
        self.last_update = dict(stats)

    def status(self, core, break_s: float):
        """Return the ``agent: learner`` status of ``core`` (``break_s``: s between episodes)."""
        level, words = learner_level(self.last_update, break_s)
        last = self.last_update or {}
        busy = (core.policy_learner.pending_updates > 0 if core.off_policy
                else core.learner.busy)
        values = {'algorithm': core.params.algorithm, 'mode': core.learner_mode,
                  'phase': core.phase, 'updating': 'yes' if busy or core.phase == 'updating'
                  else 'no', 'updates': last.get('update', 0),
                  'last_update_s': f'{last["seconds"]:.3f}' if last else 'n/a',
                  'samples': core.buffered_samples}
        if core.off_policy:
            values['gradient_steps_owed'] = core.policy_learner.pending_updates
        for name in ('policy_loss', 'value_loss'):
            if name in last:
                values[name] = f'{last[name]:.4g}'
        return status('agent: learner', f'hrc agent {core.session_id}', level, words, values)
