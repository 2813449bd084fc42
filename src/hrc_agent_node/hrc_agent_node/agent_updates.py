"""When and how the robot's learner updates: the part of :class:`AgentCore` that runs updates.

PPO updates after ``horizon`` samples or at an episode's end, whichever comes first. Inside an
episode the update runs at a defined step boundary, before the action for the state where the
horizon is reached (:meth:`UpdateSchedule._step_boundary`), so every loop that calls
``AgentCore.act`` gets it without a call of its own. The learner (``hrc_agent_node.learner``)
runs it synchronously (deterministic) unless :meth:`UpdateSchedule.set_learner_mode` chose
``background`` (the agent node's realtime episodes). SAC learns inside ``act`` itself
(``sac_update_at``; sac.py) and its episode-end update here.

A mixin of :class:`hrc_agent_node.agent_core.AgentCore`: it reads and writes the core's
buffer, learner, phase and judging state.
"""

from hrc_agent_node.learner import make_learner
from hrc_agent_node.ppo import RolloutBuffer
from hrc_common.contract import Phase

class UpdateSchedule:
    @property
    def update_due(self) -> bool:
        """Return True when an update is due at this episode end.

        PPO: the buffer holds any sample, or a background update started inside the episode has
        not been swapped in yet.
        """
        if self.off_policy:
            return self.policy_learner.update_due    # SAC: see sac.py
        return len(self.buffer) > 0 or self.learner.busy

    @property
    def learner_mode(self) -> str:
        """Return 'synchronous' (update at once, deterministic) or 'background' (realtime)."""
        if self.off_policy:
            return 'background' if self.policy_learner.background is not None else 'synchronous'
        return self.learner.mode

    def set_learner_mode(self, mode: str) -> None:
        """Run the next updates synchronously or in the background (between episodes only).

        The agent node runs its realtime episodes with ``background`` so learning inside an
        episode never delays a control step (PPO: the update in a learner thread; SAC: its
        per-step gradient steps in a learner thread, ``sac_background``); everything else is
        ``synchronous``.
        """
        if self._log is not None:
            raise RuntimeError(f'episode {self.episode} is running: change the learner between '
                               'episodes')
        if mode not in ('synchronous', 'background'):
            raise ValueError(f"learner mode {mode!r} is not 'synchronous' or 'background'")
        if self.off_policy:
            self.policy_learner.set_background(mode == 'background', self.params.learner_niceness,
                                               self.params.learner_switch_interval)
            return
        if mode == self.learner.mode:
            return
        self._settle_learner()
        self.learner = make_learner(mode, self.ppo, self.params.learner_niceness,
                                    self.params.learner_switch_interval)

    def _step_boundary(self, log, observation) -> dict:
        """Before the action for a state of a training episode: the updates due inside it.

        First a background update that has
        finished is swapped in (its weights act from this state on). Then, when the buffer and
        the episode's samples not yet in it hold ``horizon`` samples, the rollout is cut here
        and the update starts: synchronously it runs now, so this state's action already comes
        from the new weights (a defined step: sessions stay deterministic); in the background
        the old weights keep acting until a later boundary. The cut segment is truncated, not
        terminated: it bootstraps from V(this state) of the weights that collected it. Returns
        the statistics of the update that took over at this step, or None.
        """
        if log.plan.deterministic:
            return None
        swapped = self.learner.poll()
        if swapped is not None:
            self._updated(swapped)
        if self.learner.busy:
            return swapped
        waiting = len(self.buffer) + len(log.train_rewards) - log.segment_start
        if waiting < self.params.horizon:
            return swapped
        self._hand_over_segment(log, self.ppo.value_of(observation), terminated=False)
        started = self._start_update()
        return started if started is not None else swapped

    def _hand_over_segment(self, log, final_value: float, terminated: bool):
        """Add the episode's samples since the last cut to the buffer (GAE computed now).

        ``final_value``: V of the state after the segment's last sample (ignored when
        ``terminated``).
        """
        start, end = log.segment_start, len(log.train_rewards)
        if end > start:
            self.buffer.add_episode(log.observations[start:end], log.raw_actions[start:end],
                                    log.log_probs[start:end], log.values[start:end],
                                    log.train_rewards[start:end], final_value, terminated,
                                    self.params.gamma, self.params.gae_lambda)
        log.segment_start = end

    def _start_update(self):
        """Hand the buffer to the learner (a fresh buffer collects on); return its stats or None.

        None: a background update started; its statistics come when it is swapped in.
        """
        rollout, self.buffer = self.buffer, RolloutBuffer()
        stats = self.learner.start(rollout)
        if stats is not None:
            self._updated(stats)
        return stats

    def _updated(self, stats: dict) -> None:
        """Note an update whose weights act from now on."""
        self.last_update = stats
        if self.params.judging_interval == 0:
            self.judging_due = True

    def _settle_learner(self):
        """Wait for a background update still running and swap it in; return its stats or None."""
        stats = self.learner.wait()
        if stats is not None:
            self._updated(stats)
        return stats

    def update(self) -> dict:
        """Run the PPO update on the buffer (phase ``updating``), then go back to training.

        With ``judging_interval: 0`` the next episode judges the updated policy. This is the
        update at the episode's end (of the samples since the last one inside it, after
        swapping in a background update still running); returns the statistics of the last
        update run.
        """
        if self.phase != Phase.UPDATING:
            raise RuntimeError(f'no update is due in phase {self.phase.label!r}')
        if self.off_policy:
            self.last_update = stats = self.policy_learner.update()
            self.phase = Phase.TRAINING
            if self.params.judging_interval == 0:
                self.judging_due = True
            return stats
        # A background update started inside the episode first; then the samples since.
        stats = self._settle_learner()
        if len(self.buffer) > 0:
            stats = self._start_update()
            if stats is None:        # background learner: between episodes nothing acts
                stats = self._settle_learner()
        self.phase = Phase.TRAINING
        return stats
