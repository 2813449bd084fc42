"""What the operator and the reports ask of a session: pause, resume, abort, status, summary.

A mixin of :class:`hrc_agent_node.agent_core.AgentCore` (between episodes only; a pause or an
abort is kept as the phase, the interrupted phase beside it).
"""

import numpy as np

from hrc_common.contract import Phase
from hrc_common.episode_numbers import episode_number

class OperatorControls:
    def status_line(self) -> str:
        """Return one line saying where the session is (for logs and SessionStatus)."""
        step = self.training_step
        return (f'case {self.case.case_id} ({self.case.strategy}), phase {self.phase}, '
                f'step {step.index + 1}/{len(self.case.steps)} "{step.name}": robot '
                f'{self.robot_dof} rewarded on {list(step.robot_subtasks)}, human '
                f'{"involved on " + str(list(step.human_subtasks)) if step.human_involved else "not involved"}; '  # noqa: E501
                f'episode {episode_number(self.episode)}'
                f'{" (judging)" if self._next_is_judging() else ""}, '
                f'{self.total_episodes} episodes ({self.human_involved_episodes} with the '
                f'human, {self.judging_episodes} judging)')

    def population_step_problem(self) -> str:
        """Return why the next episode cannot run here ('' if it can).

        A strategy's population step (partners first) is run only by a caller that supplies
        the simulated population (``population_partner``); any other runner must start the
        session from the pre-trained checkpoint, which stands at the person's step.
        """
        step = self.training_step
        if step.partner != 'population' or self.population_partner \
                or self.phase not in (Phase.TRAINING, Phase.EVALUATION):
            return ''
        return (f'case {self.case_id} step {step.index + 1} "{step.name}" trains with a '
                'simulated population before the person joins: pre-train it first (hrc '
                'session does; by hand: python -m hrc_partners.partners_first --case '
                f'{self.case_id}) and start this session from its checkpoint (resume_from)')

    def pause(self) -> None:
        """Pause between two episodes: no episode starts until :meth:`resume`."""
        if self._log is not None:
            raise RuntimeError(f'episode {self.episode} is running: pause at its end')
        if self.phase not in (Phase.TRAINING, Phase.EVALUATION):
            raise RuntimeError(f'cannot pause in phase {self.phase.label!r}')
        self._interrupted_phase, self.phase = self.phase, Phase.PAUSED

    def resume(self) -> None:
        """Continue a paused session in the phase it was paused in."""
        if self.phase != Phase.PAUSED:
            raise RuntimeError(f'cannot resume in phase {self.phase.label!r}: not paused')
        self.phase, self._interrupted_phase = self._interrupted_phase, None

    def abort(self) -> None:
        """End the session now; a running episode is dropped (not learned from, not counted).

        The last checkpoint taken at an episode end stays the one to resume from.
        """
        if self.phase != Phase.ABORTED:
            self._interrupted_phase = self.activity_phase
        self._log = None
        self.phase = Phase.ABORTED

    def evaluation_summary(self) -> dict:
        """Return the Table II metrics averaged over the evaluation episodes.

        Over the complete ones (every command arrived) when there are any; ``incomplete``
        counts the others.
        """
        results = [r for r in self.evaluation_results if not r.commands_missing] \
            or self.evaluation_results
        if not results:
            return {}
        summary = {f'{subtask_id}_error': float(np.mean([r.errors[subtask_id] for r in results]))
                   for subtask_id in self.tree.subtasks}
        summary.update(
            total_error=float(np.mean([r.total_error for r in results])),
            robot_effort=float(np.mean([r.robot_effort for r in results])),
            human_effort=float(np.mean([r.human_effort for r in results])),
            robot_reversals=float(np.mean([r.robot_reversals for r in results])),
            human_reversals=float(np.mean([r.human_reversals for r in results])),
            episode_return=float(np.mean([r.episode_return for r in results])),
            episodes=len(results), training_episodes=self.total_episodes,
            incomplete=sum(1 for r in self.evaluation_results if r.commands_missing),
            judging_episodes=self.judging_episodes,
            human_involved_episodes=self.human_involved_episodes,
            human_involved_percentage=(100.0 * self.human_involved_episodes
                                       / self.total_episodes if self.total_episodes else 0.0))
        if self.population_episodes:     # partners-first: with the simulated population
            summary['population_episodes'] = self.population_episodes
        return summary
