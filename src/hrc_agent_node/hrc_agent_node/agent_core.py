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

PPO updates after ``horizon`` samples or at an episode's end, whichever comes first, inside an
episode at a defined step boundary of :meth:`act` (``agent_updates``: the update schedule and
the learner modes). SAC learns inside :meth:`act` itself (``sac_update_at``).

The class is split by job: this module the episode loop and the strategy's judging;
``agent_observation`` what the robot observes of the human; ``agent_updates`` when the learner
updates; ``agent_operator`` pause, resume, abort and the status and summary;
``agent_state`` the checkpoint state.

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

import numpy as np

from hrc_agent_node.agent_observation import HumanObservation
from hrc_agent_node.agent_operator import OperatorControls
from hrc_agent_node.agent_state import CheckpointState
from hrc_agent_node.agent_updates import UpdateSchedule
from hrc_agent_node.config import AgentParams
from hrc_agent_node.episode_records import Decision, EpisodePlan, EpisodeResult, StepRecord
from hrc_agent_node.learner import make_learner
from hrc_agent_node.observation import derive_seed
from hrc_agent_node.partner_model import FEATURE_SIZE, PartnerModel
from hrc_agent_node.ppo import PPO, RewardScaler, RolloutBuffer
from hrc_agent_node.sac import SAC
from hrc_agent_node.strategies import session_case, StrategyProgress
from hrc_agent_node.task_tree import TaskTree
from hrc_common.contract import Phase, SimLimits
from hrc_common.params import checked
from hrc_common.smoothness import reversals_per_second


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
    commands_missing: int = 0       # periods whose robot's or (involved) human's command was late
    error_sums: dict = field(default_factory=dict)
    states_reached: int = 0
    pending: StepRecord = None
    next_step: int = 0
    segment_start: int = 0   # first sample not handed to the buffer yet (a rollout cut inside)


class AgentCore(HumanObservation, UpdateSchedule, OperatorControls, CheckpointState):
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
        self.observation_size = (7 if p.observe_rates else 4) + (
            FEATURE_SIZE if p.partner_inference else 0)
        self.partner_model = PartnerModel() if p.partner_inference else None
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

    # ------------------------------------------------------------------ episode

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
        if self.partner_model is not None:
            self.partner_model.reset()      # the partner may be another person now
        return plan

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
            converged, event = self._count_and_judge(plan, errors, log.commands_missing == 0)
        human = log.human_slices or log.human_actions    # at the human's rate when known
        seconds = steps * self.limits.control_period
        result = EpisodeResult(
            plan.episode, plan.training_step, plan.human_involved, plan.evaluation, steps,
            terminated, bool(final_state.truncated), float(sum(log.rewards)), errors,
            float(np.var(log.robot_actions)) if log.robot_actions else 0.0,
            float(np.var(human)) if human else 0.0, converged, event, last,
            judging=plan.judging,
            robot_reversals=reversals_per_second(log.robot_actions, seconds),
            human_reversals=reversals_per_second(human, seconds),
            commands_missing=log.commands_missing)
        if plan.evaluation:
            self.evaluation_results.append(result)
            if self.evaluation_finished():
                self.phase = Phase.DONE
                result.event = 'evaluation_finished'
        self._log = None
        self.episode += 1
        result.phase_after = self.phase
        return result

    def _count_and_judge(self, plan: EpisodePlan, errors: dict, complete: bool) -> tuple:
        """Count a training or judging episode, judge the step; return (converged, event).

        A judging episode with a command missing (``complete`` False: the sim applied zero for
        a late one) judges nothing: the next episode judges the same policy again.
        """
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
        judged = plan.judging and complete
        converged, event = self.progress.record(errors) if judged else (False, '')
        if plan.judging and not complete:
            self.judging_due = True
        elif plan.judging and event == '' and self.progress.last_episode_met():
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
        # smoothness: minus action_rate_cost x the squared change of the normalized action
        change = record.action - (log.robot_actions[-2] if len(log.robot_actions) > 1
                                  else record.action)
        reward -= self.params.action_rate_cost * change * change
        record.subtask_ids = tuple(subtasks)
        record.reward_components = tuple(components)
        record.reward = reward
        log.rewards.append(reward)
        log.train_rewards.append(self.reward_scaler.scale(reward,
                                                          learn=not log.plan.deterministic))
        for subtask_id in self.tree.subtasks:
            log.error_sums[subtask_id] += self.tree.error(subtask_id, reached)
        log.states_reached += 1
        # the sim applied zero for a late command (TaskState; the engine's states never miss)
        log.commands_missing += int(bool(getattr(reached, 'robot_command_missing', False)) or (
            log.plan.human_involved and bool(getattr(reached, 'human_command_missing', False))))
        log.pending = None
        return record
