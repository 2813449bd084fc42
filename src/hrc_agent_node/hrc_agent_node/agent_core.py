"""The robot's whole per-step and per-episode logic, without ROS: :class:`AgentCore`.

The agent node and the offline loop (``offline.py``) call the same methods in the same order,
so they cannot diverge::

    core = AgentCore(params, limits=SimLimits.of(<the sim's reset response or PhysicsParams>))
                                                 # or load_into(core, checkpoint) to resume
    while core.phase != Phase.DONE:
        plan = core.start_episode()              # index, seed, kind (training / judging /
        state = <reset the sim with plan.seed>   #   evaluation), human involved or not
        while not (state.truncated or state.terminated):
            answer = <the human's answer to state> if core.needs_human_action else None
            decision = core.act(state, answer)   # robot action for this state (an update due
                                                 #   inside the episode runs here first)
            state = <step the sim with decision.action and the human's command>
        result = core.end_episode(state)          # reward of the last step, metrics, strategy
        if core.phase == Phase.UPDATING:
            core.update()                         # PPO at the episode's end, when due
        <save core.state_dict() (checkpoint.save_checkpoint)>

Phases (one place, :attr:`phase`, a ``hrc_common.contract.Phase``; on the wire its code, in logs
its label): ``training`` -> (``updating`` -> ``training``)* -> ``evaluation`` -> ``done``; the
operator may put ``paused`` between two episodes (:meth:`pause`, :meth:`resume`) or end the
session as ``aborted`` (:meth:`abort`).
Training ends when the strategy's last step converges or after ``max_training_episodes``
episodes (judging episodes included); evaluation runs the frozen deterministic policy for
``evaluation_episodes`` episodes in the last training step's setting (human involved as there).

Three kinds of episode (:class:`EpisodePlan`):

* **training**: the stochastic policy explores; its samples go to the rollout buffer;
* **judging**: one deterministic episode of the current policy after each update
  (``judging_interval: 0``) or after every N training episodes, in the current step's setting;
  the step's advance condition is judged on these episodes only. They are not learned from,
  but they count in :attr:`total_episodes` and, when the human acts in them, in
  :attr:`human_involved_episodes` (the person's time is the burden the paper measures). A
  judging episode that met the step's condition is followed by another one of the same policy
  until the window is full (the floor of the rule: strategies.py);
* **evaluation**: the frozen policy after training (Table II); not counted in the totals.

PPO updates after ``horizon`` samples or at an episode's end, whichever comes first. Inside an
episode the update runs in :meth:`act` at a defined step boundary (see :meth:`_step_boundary`),
so every loop gets it without a call of its own. The learner (``hrc_agent_node.learner``) runs
it synchronously (deterministic) unless :meth:`set_learner_mode` chose ``background`` (the agent
node's realtime episodes). SAC learns inside :meth:`act` itself (``sac_update_at``).

When a step advances to a step with another reward, the rollout buffer (samples of the old
reward) and the reward scaler's statistics are reset, so the first update of the new step
learns only from the new reward.

The sim owns the control period and the force/torque limits (``hrc_common.contract.SimLimits``):
the core scales its normalized action to a wrench and reads the human's applied command with
them, so it takes them from the sim (``limits=`` or :meth:`set_limits`; the agent node passes
the reset response's) and never from its own parameters.

Reward timing: the reward of the action taken in state s_k is computed from the state reached,
s_k+1 (eq. 3-5 on S_x, P_z, B_y of s_k+1). So the record of step k (``StepRecord``) is complete
when s_k+1 arrives: :meth:`act` returns it for the previous step, :meth:`end_episode` for the
last one.

The records it plans and returns are in ``episode_records``; what the robot observes (and the
episodes' seeds) in ``observation``.
"""

from dataclasses import dataclass, field
import math

import numpy as np

from hrc_agent_node.config import AgentParams
from hrc_agent_node.episode_records import Decision, EpisodePlan, EpisodeResult, StepRecord
from hrc_agent_node.learner import make_learner
from hrc_agent_node.observation import applied_command, derive_seed, observation_of
from hrc_agent_node.ppo import PPO, RewardScaler, RolloutBuffer
from hrc_agent_node.sac import SAC
from hrc_agent_node.strategies import session_case, StrategyProgress
from hrc_agent_node.task_tree import TaskTree
from hrc_common.contract import Phase, SimLimits
from hrc_common.params import checked


class PopulationStepRefused(ValueError):
    """A population step reached by a runner that has no simulated population to give."""


@dataclass
class _EpisodeLog:
    """Samples and metrics of the running episode."""

    plan: EpisodePlan
    observations: list = field(default_factory=list)
    raw_actions: list = field(default_factory=list)
    log_probs: list = field(default_factory=list)
    values: list = field(default_factory=list)
    train_rewards: list = field(default_factory=list)
    rewards: list = field(default_factory=list)
    robot_actions: list = field(default_factory=list)
    human_actions: list = field(default_factory=list)
    human_slices: list = field(default_factory=list)   # normalized, at the human's rate
    error_sums: dict = field(default_factory=dict)
    states_reached: int = 0
    pending: StepRecord = None
    next_step: int = 0
    segment_start: int = 0   # first sample not handed to the buffer yet (a rollout cut inside)


class AgentCore:
    """Task tree, reward, strategy progress, PPO learner and counters of one session."""

    def __init__(self, params: AgentParams = None, tree: TaskTree = None, cases: dict = None,
                 limits: SimLimits = None):
        self.params = checked(params or AgentParams())
        self._limits = None
        if limits is not None:
            self.set_limits(limits)
        p = self.params
        self.tree, self.case = session_case(p, tree, cases)
        self.progress = StrategyProgress(self.case, self.tree, p.convergence_window,
                                         p.satisfied_window)
        self.observation_size = 7 if p.observe_rates else 4
        # algorithm: the policy learner acts and learns; PPO learns from self.buffer (rollouts)
        # through self.learner (synchronous or background updates), SAC from its own replay
        # buffer inside act() (sac.py). self.ppo names the PPO learner (None under SAC).
        self.off_policy = p.algorithm == 'sac'
        self.policy_learner = SAC(self.observation_size, p, p.seed) if self.off_policy \
            else PPO(self.observation_size, p, p.seed)
        self.ppo = None if self.off_policy else self.policy_learner
        self.reward_scaler = RewardScaler(p.gamma, p.normalize_rewards)
        self.buffer = RolloutBuffer()
        # Runs the PPO updates: synchronous (deterministic) unless set_learner_mode('background').
        self.learner = make_learner('synchronous', self.ppo)
        self.phase = Phase.EVALUATION if p.evaluation_only else Phase.TRAINING
        self.episode = 0                    # index of the current (or next) episode
        self.total_episodes = 0             # training and judging episodes finished
        self.human_involved_episodes = 0    # of which the person took part
        self.population_episodes = 0        # of which a simulated population partner acted
        # Set by the caller that supplies a simulated population as the human in the
        # strategy's population steps (hrc_partners.partners_first): no other runner may run
        # them, lest the person of the last step be trained with as the "population".
        self.population_partner = False
        self.judging_episodes = 0           # judging episodes finished (in total_episodes)
        self.judging_due = False            # the next training-phase episode is a judging one
        self.episodes_since_judging = 0     # training episodes since the last judging episode
        self.evaluation_results = []        # EpisodeResult of this session's evaluation
        self.last_update = None             # statistics of the last PPO update
        self._log = None
        self._interrupted_phase = None      # the phase a pause or an abort interrupted

    # ------------------------------------------------------------------ the session right now

    @property
    def case_id(self) -> int:
        """Return the paper case of the session (1..6)."""
        return self.case.case_id

    @property
    def strategy(self) -> str:
        """Return the case's learning strategy."""
        return self.case.strategy

    @property
    def training_step_count(self) -> int:
        """Return how many training steps the case's strategy has."""
        return len(self.case.steps)

    @property
    def converged(self) -> bool:
        """Return True once the strategy's last step has met its condition."""
        return self.progress.finished

    @property
    def buffered_samples(self) -> int:
        """Return how many training samples wait for the next PPO update (SAC: replay size)."""
        return len(self.policy_learner.replay) if self.off_policy else len(self.buffer)

    @property
    def preset(self) -> str:
        """Return the task tree's reward preset."""
        return self.tree.preset

    @property
    def seed(self) -> int:
        """Return the session seed."""
        return self.params.seed

    @property
    def robot_dof(self) -> str:
        """Return the degree of freedom the robot drives."""
        return self.case.robot_dof

    @property
    def human_dof(self) -> str:
        """Return the degree of freedom the human drives."""
        return self.case.human_dof

    @property
    def activity_phase(self) -> Phase:
        """Return the phase, or while paused/aborted the phase that was interrupted."""
        if self.phase in (Phase.PAUSED, Phase.ABORTED) and self._interrupted_phase is not None:
            return self._interrupted_phase
        return self.phase

    @property
    def training_step(self):
        """Return the TrainingStep in force (the last one in evaluation)."""
        if self.activity_phase in (Phase.EVALUATION, Phase.DONE) or self.progress.finished:
            return self.case.steps[-1]
        return self.progress.step

    @property
    def human_involved(self) -> bool:
        """Return whether the human acts now."""
        return self.training_step.human_involved

    @property
    def robot_subtasks(self) -> tuple:
        """Return the subtask ids in the robot's reward now."""
        return self.training_step.robot_subtasks

    @property
    def human_subtasks(self) -> tuple:
        """Return the subtask ids the human is asked to hold now."""
        return self.training_step.human_subtasks

    @property
    def session_id(self) -> str:
        """Return the session id."""
        return self.params.effective_session_id

    @property
    def in_episode(self) -> bool:
        """Return True between start_episode() and end_episode()."""
        return self._log is not None

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
        return self.learner.mode

    def set_learner_mode(self, mode: str) -> None:
        """Run the next updates synchronously or in the background (between episodes only).

        The agent node runs its realtime episodes with ``background`` so an update inside an
        episode never delays a control step; everything else is ``synchronous``.
        """
        if self._log is not None:
            raise RuntimeError(f'episode {self.episode} is running: change the learner between '
                               'episodes')
        if mode == self.learner.mode or self.off_policy:
            return       # SAC learns inside act() itself (sac_update_at), never in a thread
        self._settle_learner()
        self.learner = make_learner(mode, self.ppo, self.params.learner_niceness,
                                    self.params.learner_switch_interval)

    @property
    def limits(self) -> SimLimits:
        """The sim's control period and force/torque limits (raises until they are known)."""
        if self._limits is None:
            raise RuntimeError("the sim's limits are not known yet: set_limits() with the sim's "
                               'reset response (or SimLimits.of(PhysicsParams)) first')
        return self._limits

    @property
    def limits_known(self) -> bool:
        """Return True once :meth:`set_limits` was called."""
        return self._limits is not None

    def set_limits(self, limits: SimLimits) -> bool:
        """Take the sim's limits; return True if they differ from those known before.

        Raises ValueError with every reason when a value is not a finite number > 0.
        """
        problems = limits.problems()
        if problems:
            raise ValueError("the sim's limits are unusable: " + '; '.join(problems))
        changed = self._limits is not None and limits != self._limits
        self._limits = limits
        return changed

    def wrench_of(self, action: float) -> float:
        """Return the force (N) or torque (N*m) of a normalized robot action."""
        return float(action) * self.limits.full_scale(self.robot_dof)

    def status_line(self) -> str:
        """Return one line saying where the session is (for logs and SessionStatus)."""
        step = self.training_step
        return (f'case {self.case.case_id} ({self.case.strategy}), phase {self.phase}, '
                f'step {step.index + 1}/{len(self.case.steps)} "{step.name}": robot '
                f'{self.robot_dof} rewarded on {list(step.robot_subtasks)}, human '
                f'{"involved on " + str(list(step.human_subtasks)) if step.human_involved else "not involved"}; '  # noqa: E501
                f'episode {self.episode}{" (judging)" if self._next_is_judging() else ""}, '
                f'{self.total_episodes} episodes ({self.human_involved_episodes} with the '
                f'human, {self.judging_episodes} judging)')

    # ------------------------------------------------------------------ episode

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

    def start_episode(self) -> EpisodePlan:
        """Begin the next episode and return its plan."""
        if self.phase not in (Phase.TRAINING, Phase.EVALUATION):
            raise RuntimeError(f'cannot start an episode in phase {self.phase.label!r}')
        if self._log is not None:
            raise RuntimeError(f'episode {self.episode} is still running')
        step = self.training_step
        problem = self.population_step_problem()
        if problem:
            raise PopulationStepRefused(problem)
        plan = EpisodePlan(self.episode, derive_seed(self.params.seed, self.episode),
                           self.phase == Phase.EVALUATION, step.index,
                           self.human_involved, self._next_is_judging(), step.partner)
        self._log = _EpisodeLog(plan, error_sums={subtask_id: 0.0
                                                  for subtask_id in self.tree.subtasks})
        self.reward_scaler.start_episode()
        return plan

    def observation(self, state, human_action: float) -> np.ndarray:
        """Return the normalized observation {B_y, P_z, S_x, a_h} (+ the three rates)."""
        return observation_of(self.params, state, human_action)

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

    def act(self, state, human_action=None) -> Decision:
        """Return the robot's action for a non-final state of the running episode.

        ``human_action``: the human's answer to this state, given exactly when
        :attr:`needs_human_action` (see :meth:`observed_human_action`).
        """
        log = self._require_episode()
        if state.truncated or state.terminated:
            raise ValueError('the final state of an episode needs no action: call end_episode')
        if int(state.step) < log.next_step:
            raise ValueError(f'expected the state of step {log.next_step} or later, got step '
                             f'{state.step} again')
        # A later step than expected means states were lost: the pending step's reward comes
        # from the state that did arrive (a gap, reported by the caller), and the episode goes on.
        human_action = self.observed_human_action(state, human_action)
        previous = self._close_pending(state) if log.next_step > 0 else None
        plan = log.plan
        observation = self.observation(state, human_action)
        update = None
        if self.off_policy:
            if previous is not None and not plan.deterministic:
                # SAC: the previous step's transition is complete; under sac_update_at step
                # it learns from it here, before choosing this step's action.
                self.policy_learner.observe(log.observations[-1], log.robot_actions[-1],
                                            log.rewards[-1], observation, terminated=False)
        else:
            update = self._step_boundary(log, observation)
        raw, action, log_prob, value = self.policy_learner.act(
            observation, deterministic=plan.deterministic)
        record = StepRecord(plan.episode, int(state.step), human_action, action, raw,
                            self.wrench_of(action), value, log_prob, plan.deterministic)
        log.pending = record
        log.observations.append(observation)
        log.raw_actions.append(raw)
        log.log_probs.append(log_prob)
        log.values.append(value)
        log.robot_actions.append(action)
        log.human_actions.append(human_action)
        self._collect_human_slices(log, state)
        log.next_step = int(state.step) + 1
        return Decision(action, record.wrench, record, previous, update)

    def _collect_human_slices(self, log: _EpisodeLog, state) -> None:
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

    def _step_boundary(self, log: _EpisodeLog, observation) -> dict:
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

    def _hand_over_segment(self, log: _EpisodeLog, final_value: float, terminated: bool):
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

    def end_episode(self, final_state, human_action=None) -> EpisodeResult:
        """Close the running episode at its final state; update counters and the strategy.

        ``human_action``: as for :meth:`act`, the human's answer to the final state under
        ``same_step`` (None there: the last observed one, or 0, stands in); it enters only the
        observation of the final state that a truncated episode's value is bootstrapped from.
        """
        log = self._require_episode()
        if not (final_state.truncated or final_state.terminated):
            raise ValueError('end_episode needs the final state (truncated or terminated)')
        plan = log.plan
        if human_action is None and self.needs_human_action:
            human_action = log.human_actions[-1] if log.human_actions else 0.0
        final_human_action = self.observed_human_action(final_state, human_action)
        self._collect_human_slices(log, final_state)
        last = self._close_pending(final_state) if log.pending is not None else None
        terminated = bool(final_state.terminated)
        steps = len(log.rewards)
        errors = {subtask_id: (total / log.states_reached if log.states_reached else 0.0)
                  for subtask_id, total in log.error_sums.items()}
        converged, event = False, ''
        if not plan.evaluation:
            if not plan.judging and steps and self.off_policy:
                # SAC: the last transition; truncation bootstraps from the final state.
                self.policy_learner.observe(log.observations[-1], log.robot_actions[-1],
                                            log.rewards[-1],
                                            self.observation(final_state, final_human_action),
                                            terminated)
            elif not plan.judging and steps > log.segment_start:
                # Truncation (time limit) bootstraps from V(final state), observed with the
                # human action of the final state; termination from 0. The samples since the
                # last cut inside the episode (all of them when there was none) go to the buffer.
                final_value = 0.0 if terminated else self.ppo.value_of(
                    self.observation(final_state, final_human_action))
                self._hand_over_segment(log, final_value, terminated)
            converged, event = self._count_and_judge(plan, errors)
        result = EpisodeResult(
            plan.episode, plan.training_step, plan.human_involved, plan.evaluation, steps,
            terminated, bool(final_state.truncated), float(sum(log.rewards)), errors,
            float(np.var(log.robot_actions)) if log.robot_actions else 0.0,
            float(np.var(log.human_slices)) if log.human_slices
            else float(np.var(log.human_actions)) if log.human_actions else 0.0,
            converged, event, last, judging=plan.judging)
        if plan.evaluation:
            self.evaluation_results.append(result)
            if len(self.evaluation_results) >= self.params.evaluation_episodes:
                self.phase = Phase.DONE
                result.event = 'evaluation_finished'
        self._log = None
        self.episode += 1
        result.phase_after = self.phase
        return result

    def _count_and_judge(self, plan: EpisodePlan, errors: dict) -> tuple:
        """Count a training or judging episode, judge the step; return (converged, event)."""
        self.total_episodes += 1
        self.human_involved_episodes += int(plan.with_person)
        self.population_episodes += int(plan.human_involved and not plan.with_person)
        if plan.judging:
            self.judging_episodes += 1
            self.judging_due = False
            self.episodes_since_judging = 0
        else:
            self.episodes_since_judging += 1
            interval = self.params.judging_interval
            if interval > 0 and self.episodes_since_judging >= interval:
                self.judging_due = True
        converged, event = self.progress.record(errors) if plan.judging else (False, '')
        if plan.judging and event == '' and self.progress.last_episode_met():
            # Judge the same frozen policy again on the next episode, until the window is full
            # (no training, no update in between) or an episode fails.
            self.judging_due = True
        if event == 'advanced':
            self._start_step(self.case.steps[plan.training_step])
        if event == 'finished' or self.total_episodes >= self.params.max_training_episodes:
            event = 'training_finished'
            self._settle_learner()   # as a synchronous update would have been: already in
            self.buffer.clear()  # the converged (or last) policy is the one evaluated
            self.judging_due = False
            self.phase = Phase.EVALUATION if self.params.evaluation_episodes > 0 else Phase.DONE
        elif self.update_due:
            self.phase = Phase.UPDATING
        return converged, event

    def skip_step(self) -> None:
        """End the current training step between episodes, its condition unmet.

        For a runner whose budget for a step ran out (the partners-first pre-training, whose
        population may be harder than the person: hrc_partners.partners_first); the next step
        starts as after an advance. Only in phase training and before the last step.
        """
        if self._log is not None or self.phase != Phase.TRAINING:
            raise RuntimeError(f'a step is skipped between episodes in phase training, not in '
                               f'phase {self.phase.label!r}')
        previous = self.progress.step
        self.progress.skip()
        self._settle_learner()
        self._start_step(previous)

    def _start_step(self, previous_step) -> None:
        """Begin the step after ``previous_step``: forget samples and scales of another reward."""
        if tuple(previous_step.robot_subtasks) != tuple(self.progress.step.robot_subtasks):
            self.buffer.clear()
            self.reward_scaler.reset()
            if self.off_policy:
                self.policy_learner.clear_replay()
        # judge_first: the policy the step starts with may already meet it (trained before the
        # person joined): judge it on the step's first episode instead of training first.
        self.judging_due = self.progress.step.judge_first
        self.episodes_since_judging = 0

    def _next_is_judging(self) -> bool:
        """Return True when the next episode of the training phase is a judging episode."""
        return self.judging_due and self.activity_phase == Phase.TRAINING \
            and not self.progress.finished

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

    # ------------------------------------------------------------------ operator

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
        """Return the Table II metrics averaged over the evaluation episodes."""
        results = self.evaluation_results
        if not results:
            return {}
        summary = {f'{subtask_id}_error': float(np.mean([r.errors[subtask_id] for r in results]))
                   for subtask_id in self.tree.subtasks}
        summary.update(
            total_error=float(np.mean([r.total_error for r in results])),
            robot_effort=float(np.mean([r.robot_effort for r in results])),
            human_effort=float(np.mean([r.human_effort for r in results])),
            episode_return=float(np.mean([r.episode_return for r in results])),
            episodes=len(results), training_episodes=self.total_episodes,
            judging_episodes=self.judging_episodes,
            human_involved_episodes=self.human_involved_episodes,
            human_involved_percentage=(100.0 * self.human_involved_episodes
                                       / self.total_episodes if self.total_episodes else 0.0))
        if self.population_episodes:     # partners-first: with the simulated population
            summary['population_episodes'] = self.population_episodes
        return summary

    # ------------------------------------------------------------------ internals

    def _require_episode(self) -> _EpisodeLog:
        if self._log is None:
            raise RuntimeError('no episode is running: call start_episode() first')
        return self._log

    def _close_pending(self, reached) -> StepRecord:
        """Fill in the reward of the pending step from the state it reached."""
        log = self._log
        record = log.pending
        subtasks = self.robot_subtasks
        components, reward = self.tree.reward(reached, subtasks)
        record.subtask_ids = tuple(subtasks)
        record.reward_components = tuple(components)
        record.reward = reward
        log.rewards.append(reward)
        log.train_rewards.append(self.reward_scaler.scale(reward,
                                                          learn=not log.plan.deterministic))
        for subtask_id in self.tree.subtasks:
            log.error_sums[subtask_id] += self.tree.error(subtask_id, reached)
        log.states_reached += 1
        log.pending = None
        return record

    # ------------------------------------------------------------------ checkpoints

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
        if phase == Phase.EVALUATION \
                and len(self.evaluation_results) >= self.params.evaluation_episodes:
            phase = Phase.DONE
        self.phase = phase if phase in (Phase.TRAINING, Phase.UPDATING, Phase.EVALUATION,
                                        Phase.DONE) else Phase.TRAINING
