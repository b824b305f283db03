"""SAC on MuJoCo Walker2d-v5 (Haarnoja et al. 2018b, "Soft Actor-Critic Algorithms and
Applications"): TD3's twin critics with a stochastic actor that is paid for its entropy.

Read after td3_walker.py; `diff td3_walker.py sac_walker.py` shows what SAC changes:
  1. the actor is a tanh-squashed Gaussian, reparameterised (Actor.sample, squashed_log_prob);
  2. the soft TD target: min Q' - alpha log pi at a' ~ pi(.|s'), no target actor (td_target);
  3. the actor maximises min(Q1, Q2) + alpha * entropy, every step (compute_loss_actor);
  4. alpha is learned to hold the entropy near -dim(A) (compute_loss_alpha); --alpha fixes it.
It explores with its own samples, not with added noise. The loop in train(), top to bottom:

    act      random for start_steps steps, then a ~ pi(.|s)
    store    (s, a, r, s', terminated) in the buffer; a time-limit truncation still bootstraps
    learn    on a random minibatch, one step each of the critics, the actor and alpha;
             then the target critics move a fraction tau toward the critics
    evaluate every eval_every steps (once in the warm-up): 10 episodes of tanh(mean), no sampling

    python sac_walker.py                          # 1M steps: several hours on a CPU
    python sac_walker.py --resume runs/latest      # continue a stopped or killed run exactly
    python sac_walker.py --eval runs/latest/best.pt --watch    # replay a saved actor

中文导读：SAC（软演员-评论员，soft actor-critic）保留 TD3 的两个评论员，换上随机策略，并把策略的熵算进回报
（最大熵强化学习）。和 TD3 相比有四处不同。一、演员输出高斯分布，采样后用 tanh 压缩到动作范围；
采样用重参数化，梯度能穿过采样传回演员；对数概率要减去 tanh 的雅可比修正。二、软 TD 目标：两个
目标评论员中较小的 Q 减去 α log π(a′|s′)，a′ 从当前策略采样；没有目标演员。三、演员的目标是
让 min(Q1, Q2) 加上 α 倍的熵最大，每一步都更新，不延迟。四、温度系数 α 自动调节，让熵保持在
目标熵 −dim(A) 附近（--alpha 0.2 则把 α 固定下来）。探索靠策略自身的随机性，不另加噪声。建议
先读 DDPG 和 TD3（教程 003，README.zh-CN.md 的路线三和 TD3 一节），再用 diff 对照这几处修改。
"""

import copy
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch
import torch.nn as nn
import torch.nn.functional as F

import checkpoints
import cli
import common
import mujoco_env
import plots
import report
import runlog

SCRIPT = Path(__file__).stem  # names its run folders; saved in its models (it loads no other's)


# ==== Networks ============================================================================
class Actor(nn.Module):
    """pi(a|s): a Gaussian over u, squashed into the action box: a = bias + scale * tanh(u)."""

    LOG_STD_MIN, LOG_STD_MAX = -20.0, 2.0  # log sigma is clipped here (the authors' code)

    def __init__(self, obs_dim, act_dim, hidden, low, high):
        super().__init__()
        self.l1 = nn.Linear(obs_dim, hidden)
        self.l2 = nn.Linear(hidden, hidden)
        self.mean = nn.Linear(hidden, act_dim)
        self.log_std = nn.Linear(hidden, act_dim)
        # tanh gives [-1, 1]; scale and shift it onto [low, high] (Walker2d: [-1, 1] already).
        self.register_buffer("scale", torch.as_tensor((high - low) / 2, dtype=torch.float32))
        self.register_buffer("bias", torch.as_tensor((high + low) / 2, dtype=torch.float32))

    def distribution(self, obs):  # the Gaussian over u, before the squash
        h = F.relu(self.l1(obs))
        h = F.relu(self.l2(h))
        log_std = self.log_std(h).clamp(self.LOG_STD_MIN, self.LOG_STD_MAX)
        return torch.distributions.Normal(self.mean(h), log_std.exp())

    def forward(self, obs):  # the deterministic action: evaluation and --eval
        return self.bias + self.scale * torch.tanh(self.distribution(obs).mean)

    def sample(self, obs):
        """a ~ pi(.|s) and log pi(a|s). rsample: u = mean + sigma * eps, eps ~ N(0, I), so the
        actor's loss sends its gradient through the sample (Haarnoja et al. 2018b, eq. 8)."""
        u_dist = self.distribution(obs)
        u = u_dist.rsample()
        return self.bias + self.scale * torch.tanh(u), squashed_log_prob(u_dist, u, self.scale)


def squashed_log_prob(u_dist, u, scale):
    """log pi(a|s) of a = bias + scale * tanh(u), u ~ u_dist: the Gaussian's log density minus
    log da/du, by the change of variables (Haarnoja et al. 2018b, appendix C, eq. 26):
        log pi(a|s) = sum_i [log N(u_i; mean_i, sigma_i) - log(scale_i * (1 - tanh(u_i)^2))]
    log(1 - tanh(u)^2) as 2 * (log 2 - u - softplus(-2u)): no log(0) in float32 once |u| > ~9."""
    log_slope = torch.log(scale) + 2 * (math.log(2) - u - F.softplus(-2 * u))
    return (u_dist.log_prob(u) - log_slope).sum(-1)  # (B,): one number per action vector


class Critic(nn.Module):
    """Q(s, a), as TD3's, two of them; soft: it counts the later steps' entropy (td_target)."""

    def __init__(self, obs_dim, act_dim, hidden):
        super().__init__()
        self.l1 = nn.Linear(obs_dim, hidden)
        self.l2 = nn.Linear(hidden + act_dim, hidden)
        self.l3 = nn.Linear(hidden, 1)

    def forward(self, obs, action):
        q = F.relu(self.l1(obs))
        q = F.relu(self.l2(torch.cat([q, action], dim=-1)))
        return self.l3(q).squeeze(-1)  # (B,): squeeze so Q never broadcasts against (B,) targets


# ==== Hyperparameters: each once, here; --help shows the string under each =============
@dataclass
class Config(cli.CheckpointFlags):
    """The algorithm's settings; the flags all scripts share and --resume: cli.CheckpointFlags."""
    # --- experiment ---
    env_id: str = "Walker2d-v5"
    """gymnasium id of a MuJoCo env (Walker2d-v5, Hopper-v5, HalfCheetah-v5, InvertedPendulum-v5)"""
    seed: int = 0
    """seeds torch and the env: same seed, same machine => same evaluations.csv on the CPU"""
    total_timesteps: int = 1_000_000
    """env steps to train for (td3_walker.py and ddpg_walker.py: 1M)"""
    start_steps: int = 25_000
    """random actions for this many steps, then the actor acts and learns (>= batch_size)"""
    # --- SAC (Haarnoja et al. 2018b, table 1) ---
    batch_size: int = 256
    """transitions per update (the SAC paper: 256)"""
    gamma: float = 0.99
    """discount factor (0.98 .. 0.995)"""
    tau: float = 0.005
    """the target critics move this fraction toward the critics at every step (0.001 .. 0.01)"""
    actor_lr: float = 3e-4
    """Adam step size of the actor (the SAC paper: 3e-4 for all)"""
    critic_lr: float = 3e-4
    """Adam step size of the two critics (3e-4)"""
    hidden: int = 256
    """units in each of the two hidden layers (the SAC paper: 256)"""
    buffer_size: int = 1_000_000
    """replay buffer capacity; the oldest transitions are overwritten"""
    eval_every: int = 5000
    """env steps between evaluations of tanh(mean), which save model.pt (tutorial 003: 5000)"""
    # --- the temperature alpha, the entropy's weight (section 5 of the paper) ---
    alpha: float | None = None
    """none: learned, from 1, toward target_entropy (the paper); > 0: fixed there (SAC v1: 0.2)"""
    alpha_lr: float = 3e-4
    """Adam step size of log alpha, when alpha is learned (3e-4)"""
    target_entropy: float | None = None
    """the entropy alpha steers the policy toward; none: -dim(A) (the paper; Walker2d: -6)"""

    def __post_init__(self):
        super().__post_init__()  # the shared flags' checks
        mujoco_env.check_mujoco(self.env_id)
        cli.check_ranges(
            self, total_timesteps="> 0", batch_size="> 0", hidden="> 0", buffer_size="> 0",
            eval_every="> 0", actor_lr="> 0", critic_lr="> 0", alpha_lr="> 0",
            gamma="(0, 1]", tau="(0, 1]", alpha="> 0 or none")
        cli.check(self.start_steps >= self.batch_size,
                  f"--start-steps must be at least --batch-size ({self.batch_size}), "
                  f"got {self.start_steps}")
        cli.check(self.resume or self.total_timesteps > self.start_steps,
                  f"--total-timesteps ({self.total_timesteps}) must exceed --start-steps "
                  f"({self.start_steps}): learning starts after the warm-up")


# ==== Replay buffer and update ============================================================
class ReplayBuffer:
    """A ring of the last `max_size` transitions, one tensor per field, on the training device."""

    def __init__(self, obs_dim, act_dim, max_size, device):
        self.obs = torch.zeros(max_size, obs_dim, device=device)       # s   (max_size, obs_dim)
        self.action = torch.zeros(max_size, act_dim, device=device)    # a   (max_size, act_dim)
        self.reward = torch.zeros(max_size, device=device)             # r   (max_size,)
        self.next_obs = torch.zeros(max_size, obs_dim, device=device)  # s'  (max_size, obs_dim)
        self.not_done = torch.zeros(max_size, device=device)           # 1 - terminated  (max_size,)
        self.max_size, self.ptr, self.size = max_size, 0, 0  # ptr: the next slot (tutorial 003)

    def add(self, obs, action, reward, next_obs, terminated):
        i = self.ptr
        self.obs[i] = torch.as_tensor(obs)
        self.action[i] = torch.as_tensor(action)
        self.reward[i] = float(reward)
        self.next_obs[i] = torch.as_tensor(next_obs)
        # not_done = 0 only if the episode really ended: a time-limit truncation still bootstraps
        self.not_done[i] = 0.0 if terminated else 1.0
        self.ptr = (self.ptr + 1) % self.max_size  # wrap around: overwrite the oldest
        self.size = min(self.size + 1, self.max_size)

    def state_dict(self):
        """For checkpoint.pt: the filled rows of every tensor field, and where the ring is."""
        return dict(ptr=self.ptr, size=self.size, **{key: x[:self.size].cpu().clone()
                                                     for key, x in vars(self).items()
                                                     if torch.is_tensor(x)})

    def load_state_dict(self, state):
        """--resume. A run extended by --total-timesteps may get a larger buffer: it fills on."""
        for key, x in vars(self).items():
            if torch.is_tensor(x):
                x[:state["size"]] = state[key].to(x.device)
        full = state["size"] == self.max_size
        self.ptr, self.size = (state["ptr"] if full else state["size"]), state["size"]

    def sample(self, batch_size):
        """A uniformly random minibatch of stored transitions:
        obs (B, obs_dim), action (B, act_dim), reward (B,), next_obs (B, obs_dim), not_done (B,)."""
        idx = torch.randint(0, self.size, (batch_size,), device=self.obs.device)
        return (self.obs[idx], self.action[idx], self.reward[idx], self.next_obs[idx],
                self.not_done[idx])


def store_and_advance(env, buffer, obs, action, reward, next_obs, terminated, truncated):
    """Store (s, a, r, s', terminated); return s', or a new episode's first obs after the end."""
    buffer.add(obs, action, reward, next_obs, terminated)
    if terminated or truncated:  # the episode is over either way: the next one starts afresh
        next_obs, _ = env.reset()  # one env, reset by hand: no autoreset
    return next_obs  # obs = next_obs: the transition is stored; the next action starts here


@torch.no_grad()
def soft_update(target, source, tau):
    """theta' <- tau * theta + (1 - tau) * theta'  (Lillicrap et al. 2016, Algorithm 1)."""
    for p_target, p in zip(target.parameters(), source.parameters()):
        p_target.mul_(1 - tau).add_(tau * p)


class Temperature(nn.Module):
    """alpha, kept as log alpha to stay positive: learned from 1 (the authors' code) or fixed."""

    def __init__(self, alpha=None):
        super().__init__()
        self.log_alpha = nn.Parameter(torch.tensor(0.0 if alpha is None else math.log(alpha)),
                                      requires_grad=alpha is None)

    def forward(self):
        return self.log_alpha.exp()


def td_target(reward, not_done, next_q1, next_q2, next_logp, alpha, gamma):
    """The soft TD target, a' ~ the current pi(.|s'), no future after a termination (not_done = 0):
        y = r + gamma * (min(Q1', Q2')(s', a') - alpha log pi(a'|s'))
    (Haarnoja et al. 2018b, eqs. 2-3: the soft value V(s') = E[Q(s', a') - alpha log pi(a'|s')];
    the min: section 6). -log pi(a'|s') is one sample of the entropy at s': randomness pays."""
    return reward + gamma * not_done * (torch.min(next_q1, next_q2) - alpha * next_logp)


def compute_loss_actor(actor, critic, critic2, obs, alpha):
    """J_pi = mean [alpha * log pi(a|s) - min(Q1(s, a), Q2(s, a))], a ~ pi(.|s) reparameterised
    (Haarnoja et al. 2018b, eq. 9, with section 6's min): higher Q and entropy both lower it.
    Returns the loss and log pi(a|s) (B,), which the temperature's loss reuses."""
    action, logp = actor.sample(obs)
    q = torch.min(critic(obs, action), critic2(obs, action))
    return (alpha * logp - q).mean(), logp


def compute_loss_alpha(temperature, logp, target_entropy):
    """J(alpha) = mean [-alpha * (log pi(a|s) + H_target)], log pi detached (Haarnoja et al.
    2018b, eq. 18): entropy below its target makes the bracket positive; descent raises alpha."""
    return -(temperature() * (logp.detach() + target_entropy)).mean()


def update_critics(nets, batch, cfg):
    """One step of both critics on a minibatch toward the soft TD target."""
    obs, action, reward, next_obs, not_done = batch
    with torch.no_grad():  # targets are constants: no gradient flows into them
        next_action, next_logp = nets["actor"].sample(next_obs)  # a' ~ pi(.|s'): no target actor
        y = td_target(reward, not_done, nets["critic_target"](next_obs, next_action),
                      nets["critic2_target"](next_obs, next_action), next_logp,
                      nets["temperature"](), cfg.gamma)
    # L = mean (y - Q1(s, a))^2 + mean (y - Q2(s, a))^2  (Haarnoja et al. 2018b, eq. 5, less 1/2)
    critic_loss = (F.mse_loss(nets["critic"](obs, action), y)
                   + F.mse_loss(nets["critic2"](obs, action), y))
    nets["critic_opt"].zero_grad()
    critic_loss.backward()
    nets["critic_opt"].step()
    return critic_loss.detach()


def update_actor_and_targets(nets, obs, target_entropy, cfg):
    """One actor step, one of alpha (if learned), then the target critics move a fraction tau
    (Haarnoja et al. 2018b, Algorithm 1). Returns the actor's loss and -mean log pi(a|s)."""
    alpha = nets["temperature"]().detach()  # a number in the actor's loss
    actor_loss, logp = compute_loss_actor(nets["actor"], nets["critic"], nets["critic2"], obs,
                                          alpha)
    nets["actor_opt"].zero_grad()
    actor_loss.backward(inputs=list(nets["actor"].parameters()))  # gradients for the actor only
    nets["actor_opt"].step()

    if cfg.alpha is None:  # learned: descend J(alpha); fixed (--alpha): alpha stays
        alpha_loss = compute_loss_alpha(nets["temperature"], logp, target_entropy)
        nets["alpha_opt"].zero_grad()
        alpha_loss.backward()
        nets["alpha_opt"].step()

    soft_update(nets["critic_target"], nets["critic"], cfg.tau)
    soft_update(nets["critic2_target"], nets["critic2"], cfg.tau)
    return actor_loss.detach(), -logp.detach().mean()


def build(obs_dim, act_dim, low, high, cfg, device):
    """Actor, the two critics (critic is Q1, critic2 is Q2), their targets and optimizers."""
    actor = Actor(obs_dim, act_dim, cfg.hidden, low, high).to(device)
    critic = Critic(obs_dim, act_dim, cfg.hidden).to(device)
    critic2 = Critic(obs_dim, act_dim, cfg.hidden).to(device)  # its own initial weights
    # The target critics start equal to the critics, then lag behind them. No target actor.
    critic_target, critic2_target = copy.deepcopy(critic), copy.deepcopy(critic2)
    temperature = Temperature(cfg.alpha).to(device)
    # fused=True: torch's one-kernel Adam step for all parameters (a standard option).
    actor_opt = torch.optim.Adam(actor.parameters(), lr=cfg.actor_lr, fused=True)
    critic_opt = torch.optim.Adam([*critic.parameters(), *critic2.parameters()],
                                  lr=cfg.critic_lr, fused=True)  # one step for both critics
    alpha_opt = torch.optim.Adam(temperature.parameters(), lr=cfg.alpha_lr)  # unused if fixed
    return dict(actor=actor, critic=critic, critic2=critic2, critic_target=critic_target,
                critic2_target=critic2_target, temperature=temperature, actor_opt=actor_opt,
                critic_opt=critic_opt, alpha_opt=alpha_opt)


# evaluations.csv's own columns, once: (progress-line format, picture label)
LOGGED = dict(q_estimate=(None, "critic: Q1(s, tanh(mean))"), q_states=(None, "states averaged"),
              discounted_return=(None, "what pi obtained: sum of gamma^k r from s"),
              entropy=(None, "-mean log pi(a|s), last minibatch"), target_entropy=(None, "target"),
              alpha=(None, "alpha, the entropy's weight"))
PICTURES = dict(inside=[[plots.lines("q_estimate", "discounted_return", title="each evaluation",
                                     ylabel="discounted return from s, mean over the states")],
                        [plots.lines("entropy", "target_entropy", ylabel="entropy of pi (nats)"),
                         plots.lines("alpha", log="wide")]])
SMOKE = dict(env_id="InvertedPendulum-v5", total_timesteps=300, start_steps=200,  # the tests':
             eval_every=150, eval_episodes=1, batch_size=64, hidden=64)  # seconds, every file


# ==== Training ============================================================================
def train(cfg: Config):
    """Train SAC with `cfg`, or continue the run cfg.resume; returns report.finish_evaluations()."""
    if cfg.resume:
        cfg = checkpoints.config_to_resume(cfg, SCRIPT)  # the saved run's settings
    # --- seeding and setup ---
    torch.set_num_threads(cfg.threads)  # also for reproducibility: threads change float sums
    torch.manual_seed(cfg.seed)  # the networks' init
    device = torch.device("cuda" if cfg.cuda and torch.cuda.is_available() else "cpu")
    env = common.make_continuous_env(cfg.env_id)  # one env, as in the paper and tutorial 003
    obs_dim, act_dim = int(env.observation_space.shape[0]), int(env.action_space.shape[0])
    low, high = env.action_space.low.astype(np.float64), env.action_space.high.astype(np.float64)
    nets = build(obs_dim, act_dim, low, high, cfg, device)
    actor = nets["actor"]
    untrained = copy.deepcopy(actor)  # before.gif is drawn from these weights after training
    torch.manual_seed(cfg.seed)  # pi's samples and the minibatches: not shifted by the init
    env.action_space.seed(cfg.seed)  # the random warm-up actions
    buffer = ReplayBuffer(obs_dim, act_dim, min(cfg.buffer_size, cfg.total_timesteps), device)
    target_entropy = -act_dim if cfg.target_entropy is None else cfg.target_entropy
    obs, _ = env.reset(seed=cfg.seed)
    run = runlog.EvaluationLog(SCRIPT, cfg, device, LOGGED, cfg.start_steps, cfg.eval_every)
    actor_info = dict(obs_dim=obs_dim, act_dim=act_dim, low=low.tolist(), high=high.tolist())
    in_checkpoint = dict(nets, buffer=buffer, env=mujoco_env.MujocoEnvState(env),
                         rng=checkpoints.RandomState(env, device), log=run)
    first_step = 0
    if cfg.resume:  # where the run stopped: its step and the loop's obs
        first_step, obs = checkpoints.resume(run.dir, SCRIPT, cfg, in_checkpoint)
    global_step, losses = first_step, None
    entropy = torch.tensor(float("nan"))  # -log pi at the last update: evaluations.csv

    with checkpoints.CtrlC() as ctrl_c:
        for global_step in range(first_step + 1, cfg.total_timesteps + 1):
            learning = global_step > cfg.start_steps  # after the random warm-up
            # --- act ---
            if not learning:
                action = env.action_space.sample()  # a random warm-up fills the buffer widely
            else:
                with torch.no_grad():  # a ~ pi(.|s): SAC explores with its own samples
                    a, _ = actor.sample(torch.as_tensor(obs, dtype=torch.float32, device=device))
                    action = a.cpu().numpy()  # inside the box by the squash: no clip
            next_obs, reward, terminated, truncated, info = env.step(action)

            # --- store (s, a, r, s', terminated), then move on to s' (or a new episode's s) ---
            obs = store_and_advance(env, buffer, obs, action, reward, next_obs, terminated,
                                    truncated)
            if terminated or truncated:
                run.episode_ended(global_step, info["episode"]["r"])  # its return, episodes.csv

            # --- learn: one step of the critics, the actor and alpha per env step (Algorithm 1) ---
            if learning:
                batch = buffer.sample(cfg.batch_size)
                critic_loss = update_critics(nets, batch, cfg)
                actor_loss, entropy = update_actor_and_targets(nets, batch[0], target_entropy,
                                                               cfg)  # [0]: the states
                losses = dict(critic_loss=critic_loss, actor_loss=actor_loss,  # progress line's
                              alpha=nets["temperature"]().detach())
            run.progress(global_step, losses, nets.values())  # nan/inf: stop

            # --- evaluate tanh(mean), no sampling, every eval_every steps; in the warm-up once ---
            if global_step % cfg.eval_every == 0 and (learning or not run.evaluations):
                seen = []  # the evaluation's states and rewards: Q1(s, a) against the return
                returns = common.evaluate(cfg.env_id, common.deterministic(actor, device),
                                          cfg.eval_episodes, cfg.eval_seed, trajectories=seen)
                q, g, n = common.q_against_return(seen, actor, nets["critic"], cfg.gamma, device)
                best = run.evaluation(  # a row of evaluations.csv, with SAC's own columns
                    global_step, returns, q_estimate=q, discounted_return=g, q_states=n,
                    entropy=entropy.item(), target_entropy=float(target_entropy),
                    alpha=nets["temperature"]().item())
                report.after_evaluation(run, actor, best, device, actor_info, PICTURES,
                                        mujoco_env.GIF)  # model.pt, best.pt, the pictures
            if (global_step % cfg.checkpoint_every == 0 or global_step == cfg.total_timesteps
                    or ctrl_c.pressed):  # (a larger --total-timesteps can extend a run)
                checkpoints.save(run.dir / "checkpoint.pt", SCRIPT, cfg, global_step, obs,
                                 in_checkpoint, say=not ctrl_c.pressed)
                run.clock_from(global_step)  # steps/s: learning, not the write
            if ctrl_c.pressed:  # stop where the step is whole (its checkpoint is written)
                break
    env.close()
    return report.finish_evaluations(run, global_step, ctrl_c.pressed, untrained, actor, device,
                                     actor_info, mujoco_env.GIF)


def main(argv=None):
    """python sac_walker.py [flags]: train (then --watch), --resume a run, or --eval an actor."""
    cfg = cli.parse_config(Config, argv, description=__doc__.split("\n\n")[0])
    with cli.clear_exit():  # bad input: one line, exit 2; Ctrl-C: one line, exit 130
        saved = cfg.eval or report.saved_model(train(cfg))  # after a Ctrl-C: exit 130
        if cfg.eval or cfg.watch:  # play the saved actor (in a window with --watch)
            actor, env_id = checkpoints.load_model(saved, SCRIPT, "actor", lambda ckpt: Actor(
                ckpt["obs_dim"], ckpt["act_dim"], ckpt["config"]["hidden"],
                np.array(ckpt["low"]), np.array(ckpt["high"])))
            mean = [("eval_returns", "tanh(mean)", lambda _: common.deterministic(actor, "cpu"))]
            report.play(cfg, saved, env_id, mean, mujoco_env.GIF, mujoco_env.watch_camera)


if __name__ == "__main__":
    main()
