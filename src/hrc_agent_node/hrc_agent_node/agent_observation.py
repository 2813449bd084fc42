"""What the robot observes of the human in a state: the part of :class:`AgentCore` that reads it.

By ``human_action_source``: ``applied``, the human's command the sim applied in the last period
(read from the state), or ``same_step``, the human's answer to the same state. A mixin of
:class:`hrc_agent_node.agent_core.AgentCore`; the pure functions are in ``observation``.
"""

import math

import numpy as np

from hrc_agent_node.observation import applied_command, observation_of

class HumanObservation:
    def observation(self, state, human_action: float) -> np.ndarray:
        """Return the normalized observation {B_y, P_z, S_x, a_h} (+ the three rates).

        With ``partner_inference``, then the partner model's features after this state's
        action of the partner (``partner_model.PartnerModel``: updated once per step).
        """
        values = observation_of(self.params, state, human_action)
        if self.partner_model is None:
            return values
        features = self.partner_model.update(int(state.step), values[:3], human_action)
        return np.concatenate([values, features])

    @property
    def needs_human_action(self) -> bool:
        """Return True when act() needs the human's answer to the same state."""
        return self.params.human_action_source == 'same_step' and self.human_involved

    def applied_human_action(self, state) -> float:
        """Return the human's normalized command the sim applied in the last control period.

        Each degree of freedom has one actor, so the state's applied force (torque) on the
        human's degree of freedom is the human's command, after the sim's clamping and with a
        missing command as 0.
        """
        return applied_command(state, self.human_dof, self.limits)

    def observed_human_action(self, state, human_action=None) -> float:
        """Return the human action a_h the robot observes in ``state`` (normalized, [-1, 1]).

        By ``human_action_source``: ``applied``, the human's command the sim applied in the
        last period, read from ``state`` (then ``human_action`` must be None: it would not be
        used); ``same_step``, ``human_action``, the human's answer to this same state (required
        while the human is involved). 0 while the human is not involved (then ``human_action``
        must be None); a non-finite answer is observed as 0. Raises ValueError otherwise.
        """
        involved = self._require_episode().plan.human_involved
        if human_action is not None and not (involved and
                                             self.params.human_action_source == 'same_step'):
            why = ('the human is not involved in this episode' if not involved else
                   'human_action_source is applied: the observed action comes from the state')
            raise ValueError(f'a human action was given but would not be used: {why}')
        if not involved:
            return 0.0
        if self.params.human_action_source == 'applied':
            human_action = self.applied_human_action(state)
        elif human_action is None:
            raise ValueError("human_action_source is same_step: act() needs the human's answer "
                             'to this state')
        if not math.isfinite(human_action):
            return 0.0
        return min(1.0, max(-1.0, float(human_action)))

    def _collect_human_slices(self, log, state) -> None:
        """Keep the human's commands the sim applied within the period that led to ``state``.

        At the human's own rate a state carries several (``human_applied``, N or N*m, one per
        slice of the period; TaskState and the engine's states alike): the human's effort is
        then their variance (normalized), the person's real input, not that of the period
        means the robot observes. One value per period (the human acts once a period): the
        observed actions, as before.
        """
        applied = getattr(state, 'human_applied', None)
        if applied is not None and len(applied) > 1:
            scale = self.limits.full_scale(self.human_dof)
            log.human_slices.extend(float(value) / scale for value in applied)
