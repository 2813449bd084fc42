"""The agent's parameters: one dataclass for the node, the offline loop and the checkpoints. Pure.

Defaults are the paper's where it gives them (Table I: PPO; section IV: reward, 40 s episodes)
and documented choices where it does not: the learning configuration ``paper``. A session
applies a named learning configuration over them (``params/learning/<name>.yaml``; the
default, ``sac``, is what the study measured best for the person's time). ``params/agent.yaml``
is generated from this dataclass (``python -m hrc_bringup.params_files --write``).
"""

from dataclasses import dataclass

from hrc_common.contract import id_problem, make_session_id, REALTIME_SWITCH_INTERVAL_S
from hrc_common.paths import params_file
from hrc_common.params import param

PACKAGE = 'hrc_agent_node'
TREE_FILE_NAME = 'task_tree.yaml'
CASES_FILE_NAME = 'cases.yaml'
# Parameters that once chose an earlier behaviour, and the commit that still has it: a file or
# an option that names one is told so (hrc_common.params.from_dict).
RETIRED_PARAMETERS = {
    'update_rule': 'PPO always updates after horizon samples or at an episode end, whichever '
                   'comes first (episode_end_after_horizon: git 8c1b998)',
    'judging_rule': 'a judging episode that meets the step is always followed by another '
                    '(in_a_row; spaced: git 8c1b998)',
    'convergence_judged_on': 'convergence is always judged on judging episodes (training: '
                             'git 8c1b998)',
}


@dataclass
class AgentParams:
    """The agent's parameters (node ``agent``): Table I; a session applies params/learning/."""

    # --- session
    session_id: str = param('', 'Session id stamped on every message and checkpoint; empty = '
                                'derived from case and seed (case<N>_seed<S>)')
    case: int = param(1, "Case 1..8 (params/cases.yaml: 1-6 the paper's, 7-8 partners first): "
                         'strategy and role assignment', low=1, high=8)
    seed: int = param(0, 'Session seed: network init, exploration noise, episode seeds',
                      low=0, high=2**31 - 1)
    mode: str = param('lockstep', 'Clock mode of the sim: with human_action_source same_step, '
                                  'lockstep waits for the human action of each step (up to '
                                  'human_action_timeout) and realtime uses the latest one',
                      choices=('lockstep', 'realtime'))
    max_training_episodes: int = param(60, 'Training ends after this many training and judging '
                                           'episodes if the last training step has not '
                                           'converged',
                                       low=1, high=100000)
    evaluation_episodes: int = param(5, 'Episodes of the frozen deterministic policy after '
                                        'training (Table II metrics)', low=0, high=10000)
    evaluation_only: bool = param(False, 'Skip training: load resume_from and evaluate it')
    task_tree_file: str = param('', 'Task tree YAML; empty = share/hrc_agent_node/params/'
                                    'task_tree.yaml')
    cases_file: str = param('', 'Strategies and cases YAML; empty = share/hrc_agent_node/'
                                'params/cases.yaml')
    action_rate_cost: float = param(0.0, "Smoothness: the robot's reward loses this times "
                                         'the squared change of its normalized action from '
                                         "the step before (0 = the paper's reward)", low=0.0,
                                    high=100.0)
    preset: str = param('paper', 'Reward preset of the task tree file (paper = alpha 10, '
                                 'sigma 1, mu 0; tuned = sigma scaled to each range; graded = '
                                 'sigma half the distance from the goal to the stops, a slope '
                                 'from the stops to the goal)')
    checkpoint_dir: str = param('runs/checkpoints', 'Directory of checkpoints '
                                                    '(<dir>/<session_id>/latest.pt, final.pt); '
                                                    'empty = no checkpoints')
    resume_from: str = param('', 'Checkpoint to resume (counters continue); empty = fresh start')
    start_from: str = param('', "Checkpoint of a finished session whose policy this one starts "
                                'from (a returning person): counters from zero, the '
                                "strategy's last step, its first episode judges the policy; "
                                'empty = a new policy')
    start_from_judged: bool = param(
        True, "start_from: the session's first episode judges the inherited policy (the "
        "paper's rule: a policy that already meets the step trains no more); false = it "
        'trains from the first episode (adapting to a new person for max_training_episodes; '
        'judging_interval decides the judging after)')
    human_action_source: str = param(
        'applied', "What the robot observes as the human action a_h: applied = the human's "
        'command the sim applied in the last control period (read from the state: the two act '
        'at the same time, as at a real joystick; deterministic, no waiting); same_step = the '
        "human's answer to the same state (lockstep waits for it)",
        choices=('applied', 'same_step'))
    human_action_timeout: float = param(1.0, 'Lockstep: wall seconds to wait for the human '
                                             'action of a step before acting with 0 (reported)',
                                        low=0.0, high=60.0)
    reset_timeout: float = param(30.0, 'Wall seconds to wait for the sim reset service before '
                                       'the session aborts', low=0.1, high=3600.0)
    wait_for_subscribers: list = param(
        [''], 'Node names that must subscribe to /hrc/state and /hrc/session (every session '
              'reader matched) before the first episode starts (the session runner puts the '
              'recorder and the human node here, so the first state is recorded and answered '
              'with the session roles whatever the start-up order or the network); [""] = '
              'none. Waits at most reset_timeout')
    episode_break: float = param(3.0, 'Realtime only: wall seconds from the end of an episode '
                                      'to the next reset, so the person rests and sees the '
                                      'result and a countdown (the PPO update runs within it); '
                                      'lockstep never waits', low=0.0, high=600.0)
    practice_episodes: int = param(0, 'Run this many practice episodes of the person alone '
                                      "instead of a session (the session runner's --practice): "
                                      'the robot does not act or learn, the sim runs realtime, '
                                      'episode_break apart; then exit 0 (practice.py). 0 = a '
                                      'session', low=0, high=1000)
    torch_threads: int = param(1, 'torch intra-op threads (the sim and the human share the 2 '
                                  'cores)', low=1, high=64)
    # --- strategy criteria (the paper does not define them; see strategies.py)
    convergence_window: int = param(3, "converged: the step's robot subtasks satisfied in each "
                                       'of this many last judged episodes of the step',
                                    low=1, high=1000)
    satisfied_window: int = param(3, 'lower_levels_satisfied: level-2 subtasks satisfied in each '
                                     'of this many last judged episodes of the step',
                                  low=1, high=1000)
    judging_interval: int = param(0, 'Judging episodes (deterministic, of the current policy; '
                                     'the step is judged on them alone): 0 = one after each '
                                     'update; N = one after every N training episodes. One '
                                     'that meets the step is followed by another until '
                                     'convergence_window are met in a row',
                                  low=0, high=100000)
    # --- PPO (Table I unless noted)
    gamma: float = param(0.995, 'Discount factor (Table I)', low=0.0, high=1.0)
    gae_lambda: float = param(0.95, 'GAE factor (Table I)', low=0.0, high=1.0)
    horizon: int = param(512, 'Experience horizon (Table I): PPO updates after this many '
                              "samples or at an episode's end, whichever comes first "
                              "(MATLAB's PPO agent); inside an episode the rollout is cut at "
                              'that step and bootstrapped from V of its state',
                         low=2, high=1000000)
    learner_niceness: int = param(
        10, "Realtime episodes (the learner thread: PPO's updates, SAC's gradient steps): how "
        "much lower the learner "
        "thread's scheduling priority (nice) is than the node's, so that on a machine with few "
        "cores the control steps of the sim, the person and the agent run first; 0 = the same "
        'priority', low=0, high=19)
    learner_switch_interval: float = param(
        REALTIME_SWITCH_INTERVAL_S, "Realtime episodes: the interpreter's thread switch "
        'interval (s) while the learner thread runs, about the longest the '
        "control thread waits for the interpreter lock; 0 = leave Python's (5 ms unless "
        'HRC_REALTIME_PRIORITY set 0.5 ms)', low=0.0, high=0.1)
    minibatch_size: int = param(64, 'Minibatch size (Table I)', low=1, high=1000000)
    epochs: int = param(3, 'Epochs per update (Table I)', low=1, high=100)
    learning_rate: float = param(0.001, 'Adam learning rate (Table I)', low=1e-7, high=1.0)
    clip_coef: float = param(0.05, 'PPO clip factor (Table I)', low=0.0, high=1.0)
    entropy_coef: float = param(0.02, 'Entropy loss weight (Table I)', low=0.0, high=10.0)
    value_coef: float = param(0.5, 'Value loss weight (not in the paper; CleanRL/SB3 default)',
                              low=0.0, high=100.0)
    max_grad_norm: float = param(0.5, 'Global gradient-norm clip (CleanRL/SB3 default)',
                                 low=0.0, high=100.0)
    hidden_size: int = param(64, 'Units per hidden layer of the policy and value networks',
                             low=1, high=4096)
    hidden_layers: int = param(2, 'Hidden layers (tanh) of each network', low=1, high=8)
    initial_log_std: float = param(-0.5, 'Initial log standard deviation of the Gaussian policy '
                                         '(state-independent, learned)', low=-5.0, high=2.0)
    normalize_advantages: bool = param(True, 'Normalize advantages per minibatch')
    normalize_rewards: bool = param(True, 'Divide rewards by the running std of the discounted '
                                          'return for training (reported rewards stay raw)')
    # --- learner: PPO (the paper's) or SAC (sac.py; the sac_* fields apply to it alone)
    algorithm: str = param('ppo', "Learner: ppo = the paper's PPO (Table I fields above); sac = "
                                  'Soft Actor-Critic with DroQ critics (sac_* fields; '
                                  'hidden_layers, the reward and the judging rule shared)',
                           choices=('ppo', 'sac'))
    sac_update_at: str = param('step', 'SAC: step = learn as each transition arrives (inside '
                                       'the act/end_episode call of the step; delays that '
                                       "step's action in realtime); episode_end = the episode's "
                                       'owed gradient steps run in the update between episodes',
                               choices=('step', 'episode_end'))
    sac_updates_per_step: int = param(10, 'SAC: critic gradient steps per stored transition '
                                          '(update-to-data ratio; DroQ: 20, halved for the 2 '
                                          'shared cores); one actor step follows them',
                                      low=1, high=1000)
    sac_batch_size: int = param(128, 'SAC: transitions per gradient step (DroQ: 256)', low=1,
                                high=100000)
    sac_replay_size: int = param(100000, 'SAC: replay buffer capacity (transitions; 500 '
                                         'episodes of 200 steps)', low=1, high=10000000)
    sac_learning_starts: int = param(200, 'SAC: stored transitions before the first gradient '
                                          'step (one 40 s episode)', low=1, high=10000000)
    sac_learning_rate: float = param(0.0003, 'SAC: Adam learning rate of actor, critics and '
                                             'temperature (DroQ)', low=1e-7, high=1.0)
    sac_gamma: float = param(0.99, 'SAC: discount factor (PPO keeps gamma)', low=0.0,
                             high=1.0)
    sac_reward_scale: float = param(0.1, "SAC: the task's reward times this is learned from "
                                         '(fixed; normalize_rewards is for PPO); 0.1 keeps a '
                                         'step below 1.2', low=1e-6, high=1e6)
    sac_tau: float = param(0.005, 'SAC: target critics move this fraction toward the critics '
                                  'each gradient step', low=0.0, high=1.0)
    sac_critics: int = param(2, 'SAC: Q-functions in the ensemble (targets take their '
                                'minimum)', low=1, high=20)
    sac_dropout: float = param(0.01, 'SAC: dropout probability in the critics (DroQ: 0.01)',
                               low=0.0, high=0.9)
    sac_hidden_size: int = param(64, 'SAC: units per hidden layer of actor and critics (ReLU; '
                                     'critics add dropout and layer norm; DroQ: 256)', low=1,
                                 high=4096)
    sac_initial_temperature: float = param(0.1, 'SAC: initial entropy temperature (then '
                                                'learned toward entropy -1)', low=1e-6,
                                           high=100.0)
    # --- observation {B_y, P_z, S_x, a_h} (+ rates), each divided by its scale
    observe_rates: bool = param(True, "Add dB_y/dt, dP_z/dt, dS_x/dt to the paper's "
                                      'observation (the state is not Markov without them)')
    partner_inference: bool = param(False, 'Add what the robot infers about its partner from '
                                           'the last seconds of the episode: their predicted '
                                           'next action, gains, persistence, bias and noise '
                                           '(partner_model.py; 7 more inputs)')
    ball_position_scale: float = param(0.25, 'm: B_y / this enters the observation',
                                       low=1e-6, high=1e6)
    pendulum_angle_scale: float = param(0.5, 'rad: P_z / this enters the observation',
                                        low=1e-6, high=1e6)
    slider_position_scale: float = param(0.1, 'm: S_x / this enters the observation',
                                         low=1e-6, high=1e6)
    ball_velocity_scale: float = param(0.5, 'm/s: dB_y/dt / this enters the observation',
                                       low=1e-6, high=1e6)
    pendulum_velocity_scale: float = param(1.0, 'rad/s: dP_z/dt / this enters the observation',
                                           low=1e-6, high=1e6)
    slider_velocity_scale: float = param(0.2, 'm/s: dS_x/dt / this enters the observation',
                                         low=1e-6, high=1e6)

    def check(self):
        """Conditions across fields."""
        reasons = []
        # The id names the checkpoint directory: '../../x' or '/abs' would leave it.
        problem = id_problem(self.session_id, 'session_id') if self.session_id else None
        if problem:
            reasons.append(problem)
        if self.minibatch_size > self.horizon:
            reasons.append(f'minibatch_size: {self.minibatch_size} exceeds horizon '
                           f'{self.horizon}')
        if self.algorithm == 'sac' and self.sac_learning_starts > self.sac_replay_size:
            reasons.append(f'sac_learning_starts: {self.sac_learning_starts} exceeds '
                           f'sac_replay_size {self.sac_replay_size} (SAC would never learn)')
        if self.start_from and (self.resume_from or self.evaluation_only):
            reasons.append('start_from: a new session from a finished one; resume_from and '
                           'evaluation_only continue or evaluate a checkpoint: give one')
        if self.evaluation_only and not self.resume_from:
            reasons.append('evaluation_only: needs resume_from (the policy to evaluate)')
        if self.evaluation_only and self.evaluation_episodes == 0:
            reasons.append('evaluation_only: needs evaluation_episodes of at least 1')
        return reasons

    @property
    def effective_session_id(self) -> str:
        """Return session_id, or the id derived from case and seed when it is empty."""
        return self.session_id or make_session_id(self.case, self.seed, timestamped=False)


def share_file(name: str) -> str:
    """Return the data file ``params/<name>`` (``hrc_common.paths.params_file``)."""
    return str(params_file(name))


AgentParams.RETIRED_PARAMETERS = RETIRED_PARAMETERS
