"""The session state a checkpoint holds: :meth:`CheckpointState.state_dict` and its inverse.

A mixin of :class:`hrc_agent_node.agent_core.AgentCore`; the file format around it (layout,
version, compatibility checks) is ``hrc_agent_node.checkpoint``'s.
"""

from hrc_agent_node.episode_records import EpisodeResult
from hrc_common.contract import Phase

class CheckpointState:
    def state_dict(self) -> dict:
        """Return everything needed to continue the session (see checkpoint.py)."""
        if self._log is not None:
            raise RuntimeError('checkpoints are taken between episodes, not during one')
        if self.learner.busy:
            raise RuntimeError('an update is running: checkpoints follow update()')
        return {self.params.algorithm: self.policy_learner.state_dict(),   # 'ppo' or 'sac'
                'reward_scaler': self.reward_scaler.state_dict(),
                'buffer': self.buffer.state_dict(), 'progress': self.progress.state_dict(),
                'counters': {'episode': self.episode, 'total_episodes': self.total_episodes,
                             'human_involved_episodes': self.human_involved_episodes,
                             'population_episodes': self.population_episodes,
                             'judging_episodes': self.judging_episodes,
                             'episodes_since_judging': self.episodes_since_judging,
                             'judging_due': self.judging_due},
                # a session resumed in evaluation runs only the evaluation episodes left
                'evaluation_results': [result.to_plain() for result in self.evaluation_results],
                # a paused session resumes in the phase it was paused in (saved as its
                # label: the checkpoint format of before)
                'phase': self.activity_phase.label}

    def load_state_dict(self, state: dict, policy_only: bool = False) -> None:
        """Continue from :meth:`state_dict` (``policy_only``: networks and counters only)."""
        self.policy_learner.load_state_dict(state[self.params.algorithm],
                                            policy_only=policy_only)
        counters = state['counters']
        self.episode = int(counters['episode'])
        self.total_episodes = int(counters['total_episodes'])
        self.human_involved_episodes = int(counters['human_involved_episodes'])
        self.population_episodes = int(counters.get('population_episodes', 0))  # older: none
        self.judging_episodes = int(counters['judging_episodes'])
        if policy_only:
            return
        self.episodes_since_judging = int(counters['episodes_since_judging'])
        self.judging_due = bool(counters['judging_due'])
        self.reward_scaler.load_state_dict(state['reward_scaler'])
        self.buffer.load_state_dict(state['buffer'])
        self.progress.load_state_dict(state['progress'])
        self.evaluation_results = [EpisodeResult.from_plain(data)
                                   for data in state['evaluation_results']]
        try:
            phase = Phase.from_label(state['phase'])
        except ValueError:       # not a phase: start training, as for paused or aborted
            phase = Phase.TRAINING
        # A session stopped while an update was due does the update first when resumed; one
        # stopped in its evaluation runs the evaluation episodes it has not run yet (a finished
        # one stays done).
        if phase == Phase.EVALUATION and self.evaluation_finished():
            phase = Phase.DONE
        self.phase = phase if phase in (Phase.TRAINING, Phase.UPDATING, Phase.EVALUATION,
                                        Phase.DONE) else Phase.TRAINING

    def start_after(self) -> None:
        """Start a new session with the policy just loaded from a finished one (start_from).

        A returning person: the counters from zero, the strategy at its last step (the one
        with the person), whose first episode judges the policy it starts with
        (``start_from_judged``; otherwise it trains from the first episode).
        """
        self.episode = self.total_episodes = self.human_involved_episodes = 0
        self.population_episodes = self.judging_episodes = 0
        previous = self.progress.step
        while not self.progress.is_last_step:
            self.progress.skip()
        self._start_step(previous)
        self.judging_due = self.params.start_from_judged

    def evaluation_finished(self) -> bool:
        """Return whether the evaluation has its episodes: ``evaluation_episodes`` complete ones.

        An evaluation episode with a command missing is run again (Table II is computed over
        the complete ones), up to ``evaluation_episodes`` more: then the session ends with what
        it has, and the report says how many were incomplete.
        """
        wanted = self.params.evaluation_episodes
        complete = sum(1 for result in self.evaluation_results if not result.commands_missing)
        return complete >= wanted or len(self.evaluation_results) >= 2 * wanted
