"""PPO-clip with a Gaussian policy on MuJoCo Reacher-v5 (Schulman et al. 2017): a two-joint arm
reaching for a target, the kind of task tutorial 002's series is about, with 002's update.

Read beside tutorial 002 (compute_loss_pi, compute_loss_v, update()) and after ppo_cartpole.py,
whose loop this one keeps. pi(a|s) is a Gaussian N(mu(s), sigma^2) (PolicyNetwork), log pi(a|s)
summed over the action's dimensions (gaussian_log_prob). 002's buf.store -> RolloutBuffer.store,
finish_path(last_val) -> common.gae, buf.get -> batch_of. The loop in train():

    collect  num_steps x num_envs transitions, a ~ N(mu(s), sigma^2)
    GAE      advantages A_t and value targets R_t = A_t + V(s_t)   (common.gae)
    update   tutorial 002's update(): up to train_pi_iters full-batch policy steps, stopped
             once approx_kl > 1.5 x target_kl, then train_v_iters value steps
             (--update minibatch: ppo_cartpole.py's epochs of shuffled minibatches)
    evaluate the mean action mu(s), clipped, after the update reaching each eval_every steps

    python ppo_reacher.py                       # 1M steps: 7 to 26 minutes on a 2-core CPU
    python ppo_reacher.py --eval runs/latest --watch      # the trained arm in a window

Unlike 002 (docs/why.md): normalised observations (--norm-obs), orthogonal init, the sample
clipped to the box at the env (Reacher's control cost is on it), V bootstrapped at a time limit.

中文导读：连续动作的 PPO-clip，任务是 MuJoCo 的 Reacher-v5：两节机械臂把指尖伸向目标点，和教程 002
所在专栏（“实现机械臂reach某点之PPO算法实现”）是同类任务。策略是高斯分布 N(mu(s), sigma^2)，
对数概率在动作的各维上求和；更新即教程 002 的 update()：整批数据上最多 train_pi_iters 次策略
更新，approx_kl 超过 1.5 倍 target_kl 就早停，再做 train_v_iters 次价值网络更新。教程 002 的
buf.store、finish_path、buf.get 分别对应 RolloutBuffer.store、common.gae、batch_of。
"""

import copy
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch
import torch.nn as nn
from torch.distributions import Normal

import checkpoints
import cli
import common
import mujoco_env
import plots
import report
import runlog

SCRIPT = Path(__file__).stem  # names its run folders; saved in its models (it loads no other's)


# ==== Networks ============================================================================
def layer_init(layer, gain=np.sqrt(2)):
    """Orthogonal weights, zero bias: the init of the PPO reference code (baselines)."""
    nn.init.orthogonal_(layer.weight, gain)
    nn.init.zeros_(layer.bias)
    return layer


def mlp(sizes, last_gain):
    """Linear layers with tanh between them (Spinning Up's and the PPO paper's networks)."""
    layers = []
    for n_in, n_out in zip(sizes[:-2], sizes[1:-1]):
        layers += [layer_init(nn.Linear(n_in, n_out)), nn.Tanh()]
    return nn.Sequential(*layers, layer_init(nn.Linear(*sizes[-2:]), last_gain))


def gaussian_log_prob(mu, log_std, act):
    """log pi(a|s) of a diagonal Gaussian: the dimensions are independent, so their log
    densities add up (what Normal(mu, sigma).log_prob(a).sum(-1) computes):
        log pi(a|s) = sum_i [-(a_i - mu_i)^2 / (2 sigma_i^2) - log sigma_i - log(2 pi) / 2]
    With mu = 0, sigma = 1, a = (1, 0): (-1/2 - 0 - 0.919) + (-0.919) = -2.338 in all.

    >>> gaussian_log_prob(torch.zeros(1, 2), torch.zeros(2), torch.tensor([[1., 0.]]))
    tensor([-2.3379])
    """
    z = (act - mu) / log_std.exp()
    return (-0.5 * z ** 2 - log_std - 0.5 * np.log(2 * np.pi)).sum(-1)  # (B,)


class PolicyNetwork(nn.Module):
    """pi(a|s) = N(mu(s), diag(sigma^2)): a network gives the mean; log sigma is a parameter of
    its own, one per action dimension, the same in every state (Spinning Up's MLPGaussianActor,
    the PPO paper's MuJoCo policy). Exploration then shrinks as the update lowers sigma for
    all states at once; a sigma of each state's own could collapse where the batch is thin."""

    def __init__(self, obs_dim, act_dim, hidden, log_std_init):
        super().__init__()
        self.mu_net = mlp([obs_dim, hidden, hidden, act_dim], last_gain=0.01)  # mu near 0
        self.log_std = nn.Parameter(torch.full((act_dim,), float(log_std_init)))

    def forward(self, obs, act=None):
        """Tutorial 002's ac.pi(obs, act): the distribution pi(.|s), and log pi(a|s) of `act`."""
        pi = Normal(self.mu_net(obs), self.log_std.exp())
        return pi, None if act is None else gaussian_log_prob(pi.mean, self.log_std, act)


class ValueNetwork(nn.Module):
    """V(s): observation -> expected discounted return from s."""

    def __init__(self, obs_dim, hidden):
        super().__init__()
        self.v_net = mlp([obs_dim, hidden, hidden, 1], last_gain=1.0)

    def forward(self, obs):
        return self.v_net(obs).squeeze(-1)  # (B,): a stray (B, 1) would broadcast against targets


class MeanActor(nn.Module):
    """The policy as evaluations, GIFs and --eval run it: mu(normalized obs), clipped to the box."""

    def __init__(self, obs_norm, policy, low, high):
        super().__init__()
        self.obs_norm, self.policy = obs_norm, policy
        self.register_buffer("low", torch.as_tensor(low, dtype=torch.float32))
        self.register_buffer("high", torch.as_tensor(high, dtype=torch.float32))

    def forward(self, obs):
        return torch.clamp(self.policy.mu_net(self.obs_norm(obs)), self.low, self.high)


# ==== Hyperparameters: each once, here; --help shows the string under each =============
@dataclass
class Config(cli.CheckpointFlags):
    """The algorithm's settings (tutorial 002's: Spinning Up's PPO defaults); shared flags: cli."""
    # --- experiment ---
    env_id: str = "Reacher-v5"
    """gymnasium id of a MuJoCo env (Reacher-v5; Walker2d-v5 with the settings of docs/results)"""
    seed: int = 0
    """seeds torch and the envs: same seed, same machine => same evaluations.csv on the CPU"""
    total_timesteps: int = 1_000_000
    """env steps to train for (all envs together; the autoreset steps count)"""
    print_every: int = 4000
    """print a progress line every this many env steps (4000: one a rollout, after its update)"""
    eval_every: int = 10_000
    """evaluate mu(s) (and save model.pt) after the update reaching each multiple of this"""
    # --- collection ---
    num_envs: int = 1
    """parallel envs (Spinning Up and tutorial 002: 1; must divide --print-every)"""
    num_steps: int = 4000
    """steps per env per rollout (tutorial 002's steps_per_epoch: 4000; 1000 .. 8000)"""
    gamma: float = 0.99
    """discount factor (0.98 .. 0.999)"""
    lam: float = 0.97
    """GAE lambda (tutorial 002 and Spinning Up: 0.97; CleanRL: 0.95)"""
    # --- the update ---
    update: str = "full_batch"
    """full_batch: tutorial 002's update(); minibatch: ppo_cartpole.py's (CleanRL's) epochs"""
    clip_ratio: float = 0.2
    """epsilon of the clipped surrogate (0.1 .. 0.3)"""
    pi_lr: float = 3e-4
    """Adam step size of the policy (tutorial 002: 3e-4)"""
    vf_lr: float = 1e-3
    """Adam step size of the value network (tutorial 002: 1e-3)"""
    train_pi_iters: int = 80
    """full_batch: most policy steps per batch (tutorial 002: 80)"""
    train_v_iters: int = 80
    """full_batch: value steps per batch (tutorial 002: 80)"""
    target_kl: float | None = 0.01
    """stop a batch's policy steps once approx_kl > kl_stop_factor x this (002: 0.01); none=never"""
    kl_stop_factor: float = 1.5
    """the 1.5 of tutorial 002's early stop"""
    update_epochs: int = 10
    """minibatch: passes over each batch (CleanRL: 10)"""
    num_minibatches: int = 32
    """minibatch: minibatches per pass (CleanRL: 32)"""
    max_grad_norm: float = 0.0
    """clip each network's gradient norm to this (0 = off, as in tutorial 002; CleanRL: 0.5)"""
    anneal_lr: bool = False
    """decay both step sizes linearly to 0 over total_timesteps (CleanRL: on)"""
    hidden: int = 64
    """units in each of the two tanh hidden layers of both networks (tutorial 002: 64)"""
    log_std_init: float = -0.5
    """log sigma at the start: sigma = 0.61 (Spinning Up: -0.5)"""
    # --- normalisation (named options) ---
    norm_obs: bool = True
    """feed pi and V (obs - mean) / std clipped to +-10, stats fixed in a rollout; in model.pt"""
    norm_reward: bool = False
    """divide rewards by the running std of the discounted return; saved in checkpoint.pt"""

    def __post_init__(self):
        super().__post_init__()  # the shared flags' checks
        mujoco_env.check_mujoco(self.env_id)
        cli.check_ranges(self, total_timesteps="> 0", eval_every="> 0", num_envs="> 0",
                         num_steps="> 0", hidden="> 0", pi_lr="> 0", vf_lr="> 0", gamma="(0, 1]",
                         train_pi_iters="> 0", train_v_iters="> 0", update_epochs="> 0",
                         num_minibatches="> 0", lam="[0, 1]", clip_ratio="> 0",
                         kl_stop_factor="> 0", target_kl="> 0 or none", max_grad_norm=">= 0")
        cli.check(self.update in ("full_batch", "minibatch"),
                  f"--update is full_batch or minibatch, got {self.update}")
        batch = self.num_envs * self.num_steps
        cli.check(self.num_minibatches <= batch,
                  f"--num-minibatches ({self.num_minibatches}) exceeds the batch size ({batch})")
        cli.check(self.resume or self.total_timesteps >= batch, f"--total-timesteps "
                  f"({self.total_timesteps}) is less than one rollout ({batch} steps)")
        cli.check(self.print_every % self.num_envs == 0,
                  f"--num-envs ({self.num_envs}) must divide --print-every ({self.print_every})")


# ==== Rollout buffer, losses, update ======================================================
class RolloutBuffer:
    """num_steps x num_envs transitions as (T, N, ...) numpy arrays: the obs as the env gave
    it, the action as sampled (unclipped), each env's discounted return so far (--norm-reward)."""

    def __init__(self, T, N, obs_dim, act_dim):
        self.obs = np.zeros((T, N, obs_dim), dtype=np.float32)
        self.actions = np.zeros((T, N, act_dim), dtype=np.float32)
        self.rewards = np.zeros((T, N), dtype=np.float32)
        self.terminated = np.zeros((T, N), dtype=bool)
        self.truncated = np.zeros((T, N), dtype=bool)
        self.valid = np.ones((T, N), dtype=bool)  # False at a vector-env autoreset step
        self.discounted = np.zeros((T, N), dtype=np.float64)

    def store(self, t, obs, action, reward, terminated, truncated, valid, discounted):
        self.obs[t], self.actions[t], self.rewards[t] = obs, action, reward
        self.terminated[t], self.truncated[t], self.valid[t] = terminated, truncated, valid
        self.discounted[t] = discounted

    def get_batch(self, device):
        """Every field as a tensor on `device`, still shaped (T, N, ...)."""
        return {name: torch.as_tensor(array, device=device) for name, array in vars(self).items()}


def compute_loss_pi(policy, data, clip_ratio):
    """Tutorial 002's compute_loss_pi: the clipped surrogate on `data`, and pi_info (kl, ent, cf).
    The ratio is of the sampled, unclipped action: the density that drew it. The env's clip to
    the box is part of the env; log pi of the clipped action would not be the probability of
    what pi did (the box's edge holds a whole tail of the Gaussian)."""
    obs, act, adv, logp_old = data["obs"], data["act"], data["adv"], data["logp"]
    pi, logp = policy(obs, act)
    ratio = torch.exp(logp - logp_old)  # r_t = pi(a|s) / pi_old(a|s)
    # L_CLIP = E[min(r*A, clip(r, 1-eps, 1+eps)*A)]  (Schulman et al. 2017, eq. 7); minimize -L_CLIP
    clip_adv = torch.clamp(ratio, 1 - clip_ratio, 1 + clip_ratio) * adv
    loss_pi = -(torch.min(ratio * adv, clip_adv)).mean()
    # Useful extra info (tutorial 002): approx_kl = E[log pi_old - log pi], as 002 writes it
    approx_kl = (logp_old - logp).mean().item()
    ent = pi.entropy().sum(-1).mean().item()  # all dimensions' (002's mean: per dimension)
    clipfrac = (ratio.gt(1 + clip_ratio) | ratio.lt(1 - clip_ratio)).float().mean().item()
    return loss_pi, dict(kl=approx_kl, ent=ent, cf=clipfrac, ratio=ratio.detach())


def compute_loss_v(value_net, data):
    """Tutorial 002's compute_loss_v: L_VF = E[(V(s_t) - R_t)^2]  (Schulman et al. 2017, eq. 9)."""
    obs, ret = data["obs"], data["ret"]
    return ((value_net(obs) - ret) ** 2).mean()


def step(optimizer, loss, net, max_grad_norm):
    """One Adam step of `net` on `loss` (its gradient norm clipped if max_grad_norm > 0)."""
    optimizer.zero_grad()
    loss.backward()
    if max_grad_norm > 0:
        nn.utils.clip_grad_norm_(net.parameters(), max_grad_norm)
    optimizer.step()


def update(policy, value_net, pi_optimizer, vf_optimizer, data, cfg):
    """Tutorial 002's update(), line for line: up to train_pi_iters policy steps on the whole
    batch, stopped before the step at which approx_kl exceeds kl_stop_factor * target_kl;
    then train_v_iters value steps, whatever the policy did. Returns the log's numbers."""
    pi_l_old, pi_info_old = compute_loss_pi(policy, data, cfg.clip_ratio)
    pi_l_old, v_l_old = pi_l_old.item(), compute_loss_v(value_net, data).item()
    stop_iter = cfg.train_pi_iters  # no early stop: every step taken
    # Train policy with multiple steps of gradient descent (002), each on the whole batch
    for i in range(cfg.train_pi_iters):
        loss_pi, pi_info = compute_loss_pi(policy, data, cfg.clip_ratio)
        if cfg.target_kl is not None and pi_info["kl"] > cfg.kl_stop_factor * cfg.target_kl:
            stop_iter = i  # early stopping: pi is too far from pi_old; i steps were taken
            break
        step(pi_optimizer, loss_pi, policy, cfg.max_grad_norm)
    for i in range(cfg.train_v_iters):  # value function learning
        step(vf_optimizer, compute_loss_v(value_net, data), value_net, cfg.max_grad_norm)
    return pi_l_old, v_l_old, pi_info_old["ent"], stop_iter


def update_minibatch(policy, value_net, pi_optimizer, vf_optimizer, data, cfg):
    """--update minibatch: update_epochs passes of num_minibatches shuffled minibatches, a policy
    step and a value step on each: ppo_cartpole.py's (CleanRL's) loop with this script's losses,
    two optimizers and early stop (checked on the whole batch before each policy step; the value
    steps go on after it). The advantages were normalised over the whole batch (batch_of)."""
    pi_l_old, pi_info_old = compute_loss_pi(policy, data, cfg.clip_ratio)
    pi_l_old, v_l_old = pi_l_old.item(), compute_loss_v(value_net, data).item()
    steps, stopped = 0, False
    for epoch in range(cfg.update_epochs):
        order = torch.randperm(len(data["obs"]), device=data["obs"].device)
        for mb_inds in order.tensor_split(cfg.num_minibatches):
            mb = {key: x[mb_inds] for key, x in data.items()}
            if cfg.target_kl is not None and not stopped:
                with torch.no_grad():
                    kl = compute_loss_pi(policy, data, cfg.clip_ratio)[1]["kl"]
                stopped = kl > cfg.kl_stop_factor * cfg.target_kl
            if not stopped:
                step(pi_optimizer, compute_loss_pi(policy, mb, cfg.clip_ratio)[0], policy,
                     cfg.max_grad_norm)
                steps += 1
            step(vf_optimizer, compute_loss_v(value_net, mb), value_net, cfg.max_grad_norm)
    return pi_l_old, v_l_old, pi_info_old["ent"], steps


def batch_of(rollout, obs, policy, value_net, obs_norm, return_norm, cfg):
    """A rollout (T, N, ...) as one batch without the autoreset steps: obs normalized as pi_old
    saw them, log pi_old(a|s), advantages (GAE, normalized over the batch as 002's buf.get does)
    and value targets; and the raw obs the rollout met (for the next one's statistics)."""
    raw = rollout["obs"][rollout["valid"]]
    # The statistics have not moved since the rollout began: normalising now gives the inputs
    # pi_old acted on, so log pi_old and V are computed here (002's ac.step stores them)
    rollout["obs"] = obs_norm(rollout["obs"])
    if cfg.norm_reward:  # r / the running std of the discounted return, this rollout's in
        return_norm.update(rollout["discounted"][rollout["valid"]])
        rollout["rewards"] = rollout["rewards"] / torch.sqrt(return_norm.var + 1e-8).float()
    with torch.no_grad():
        logp_old = policy(rollout["obs"], rollout["actions"])[1]  # log pi_old(a|s), (T, N)
        values = value_net(rollout["obs"])  # (T, N)
        last_value = value_net(obs_norm(torch.as_tensor(obs, dtype=torch.float32,
                                                        device=values.device)))  # V(s_T)
        next_values = torch.cat([values[1:], last_value[None]])  # (T, N)
        # GAE, bootstrapping at a time limit only (Reacher's episodes all end at one: 50 steps)
        advantages = common.gae(rollout["rewards"], values, next_values, rollout["terminated"],
                                rollout["truncated"], cfg.gamma, cfg.lam)  # (T, N)
        returns = advantages + values  # value targets R_t = A_t + V(s_t), detached
    keep = rollout["valid"].reshape(-1)  # the autoreset steps train nothing
    data = {key: x.flatten(0, 1)[keep] for key, x in dict(
        obs=rollout["obs"], act=rollout["actions"], logp=logp_old, adv=advantages,
        ret=returns).items()}
    data["adv"] = (data["adv"] - data["adv"].mean()) / (data["adv"].std() + 1e-8)
    return data, raw


def after_update(policy, data, cfg, loss_pi, loss_v, entropy, pi_steps):
    """evaluations.csv's own columns (LOGGED) from the last update: its losses before it, how
    far pi moved on the whole batch after it (approx_kl, clipfrac, where r went), sigma, the
    policy steps taken."""
    with torch.no_grad():
        info = compute_loss_pi(policy, data, cfg.clip_ratio)[1]
    std = policy.log_std.detach().exp()
    ratio = common.ratio_stats(info["ratio"], data["adv"], cfg.clip_ratio)
    return dict(loss_pi=loss_pi, loss_v=loss_v, approx_kl=info["kl"], clipfrac=info["cf"],
                entropy=entropy, pi_steps=pi_steps, std_min=std.min().item(),
                std_max=std.max().item(), **{k: ratio[k] for k in common.RATIO_COLUMNS
                                             if k != "clipfrac_after"})  # = clipfrac here


def evaluate(run, actor, device, info, step, last):
    """Episodes of mu(s): evaluations.csv's row (with `last`: the update's), model.pt, best.pt."""
    cfg, seen = run.cfg, []  # seen: the evaluation's episodes, where the fingertip ended
    returns = common.evaluate(cfg.env_id, common.deterministic(actor, device),
                              cfg.eval_episodes, cfg.eval_seed, trajectories=seen)
    row = dict(last, distance=mujoco_env.reacher_distance(seen))
    best = run.evaluation(step, returns, **{key: row[key] for key in LOGGED})  # LOGGED's order
    report.after_evaluation(run, actor, best, device, info, pictures(cfg),
                            mujoco_env.gif_for(cfg.env_id))


LOGGED = dict(loss_pi=(None, "-L_CLIP before the update"), loss_v=(None, "L_VF before it"),
              approx_kl=(None, "approx_kl: E[log pi_old - log pi] after it"),
              clipfrac=(None, "clipfrac: |r - 1| > eps, after it"),
              entropy=(None, "entropy of pi (nats), all dimensions"),
              pi_steps=(None, "policy steps taken (the early stop: fewer)"),
              distance=(None, "fingertip to target, last step of each episode"),
              std_min=(None, "sigma, smallest dimension"), std_max=(None, "sigma, largest"),
              **{k: v for k, v in common.RATIO_COLUMNS.items() if k != "clipfrac_after"})


def pictures(cfg):
    """inside.png (docs/inside.md): exploration shrinking, the arm reaching, the early stop."""
    band = (1 - cfg.clip_ratio, 1 + cfg.clip_ratio)
    limits = () if cfg.target_kl is None else (cfg.target_kl, cfg.kl_stop_factor * cfg.target_kl)
    return dict(inside=[
        [plots.lines("std_min", "std_max", title="exploration: sigma of pi", ylabel="sigma"),
         plots.lines("distance", title="reaching (Reacher)", ylabel="fingertip to target, end"),
         plots.lines("pi_steps", title="policy steps on the last batch", ylabel="policy steps",
                     ylim=(0, 1.05 * max(cfg.train_pi_iters, 10)), legend="above")],
        [plots.spread("ratio", "r after the last update; dashed: 1 +- eps", band,
                      ylabel="r = pi / pi_old"),
         plots.lines("approx_kl", title="after the last update; dashed: target_kl, 1.5 x it",
                     hlines=limits, ylabel="approx_kl", legend="above"),
         plots.lines("clipfrac", title="after the last update", ylabel="clipfrac")]])


SMOKE = dict(total_timesteps=600, num_steps=100, eval_every=200, eval_episodes=1,
             train_pi_iters=5, train_v_iters=5, checkpoint_every=300)  # tests: seconds


# ==== Training ============================================================================
def train(cfg: Config):
    """Train PPO with `cfg`, or continue the run cfg.resume; returns report.finish_evaluations()."""
    if cfg.resume:
        cfg = checkpoints.config_to_resume(cfg, SCRIPT)  # the saved run's settings
    # --- seeding and setup ---
    torch.set_num_threads(cfg.threads)  # also for reproducibility: threads change float sums
    torch.manual_seed(cfg.seed)  # the networks' init and the sampled actions
    device = torch.device("cuda" if cfg.cuda and torch.cuda.is_available() else "cpu")
    envs, obs, _ = common.make_vec_env(cfg.env_id, cfg.num_envs, cfg.seed, continuous=True)
    obs_dim, act_dim = envs.single_observation_space.shape[0], envs.single_action_space.shape[0]
    low, high = envs.single_action_space.low, envs.single_action_space.high
    T, N = cfg.num_steps, cfg.num_envs
    buffer = RolloutBuffer(T, N, obs_dim, act_dim)
    policy = PolicyNetwork(obs_dim, act_dim, cfg.hidden, cfg.log_std_init).to(device)
    value_net = ValueNetwork(obs_dim, cfg.hidden).to(device)
    obs_norm = common.RunningNorm(obs_dim, cfg.norm_obs).to(device)
    return_norm = common.RunningNorm((), cfg.norm_reward).to(device)  # of the discounted return
    actor = MeanActor(obs_norm, policy, low, high).to(device)  # evaluations, model.pt, --eval
    untrained = copy.deepcopy(actor)  # before.gif
    pi_optimizer = torch.optim.Adam(policy.parameters(), lr=cfg.pi_lr)
    vf_optimizer = torch.optim.Adam(value_net.parameters(), lr=cfg.vf_lr)
    run = runlog.EvaluationLog(SCRIPT, cfg, device, LOGGED, 0, cfg.eval_every, step_size=T * N)
    actor_info = dict(obs_dim=obs_dim, act_dim=act_dim, low=low.tolist(), high=high.tolist())
    autoreset = np.zeros(N, dtype=bool)  # which envs are at a NEXT_STEP autoreset step
    discounted = np.zeros(N)  # each env's discounted return so far (--norm-reward)
    in_checkpoint = dict(policy=policy, value=value_net, obs_norm=obs_norm, log=run,
                         return_norm=return_norm, pi_optimizer=pi_optimizer,
                         vf_optimizer=vf_optimizer, env=mujoco_env.MujocoVecEnvState(envs),
                         rng=checkpoints.RandomState(envs, device),
                         loop=checkpoints.Arrays(autoreset=autoreset, discounted=discounted))
    global_step = 0
    if cfg.resume:  # where the run stopped: its step and the loop's obs
        global_step, obs = checkpoints.resume(run.dir, SCRIPT, cfg, in_checkpoint)
    num_updates, stats = cfg.total_timesteps // (T * N), None  # stats: the progress line's
    if global_step == 0:  # the untrained mean action: mu is near 0, the arm barely moves
        evaluate(run, actor, device, actor_info, 0, dict.fromkeys(LOGGED))

    with checkpoints.CtrlC() as ctrl_c:
        for k in range(global_step // (T * N) + 1, num_updates + 1):
            if cfg.anneal_lr:  # lr_k = lr * (1 - (k - 1) / K): from lr at the first update to 0
                for opt, lr in ((pi_optimizer, cfg.pi_lr), (vf_optimizer, cfg.vf_lr)):
                    opt.param_groups[0]["lr"] = lr * (1 - (k - 1) / num_updates)

            # --- collect: T steps of N envs with the current policy (pi_old) ---
            for t in range(T):
                # pi_old sees the obs normalized with statistics that stay fixed in a rollout
                obs_t = obs_norm(torch.as_tensor(obs, dtype=torch.float32, device=device))
                with torch.no_grad():
                    action = policy(obs_t)[0].sample().cpu().numpy()  # a ~ pi(.|s), (N, act_dim)
                # The env gets a inside its box; the buffer keeps a as drawn (compute_loss_pi)
                next_obs, reward, terminated, truncated, info = envs.step(
                    np.clip(action, low, high))
                global_step += N
                discounted[:] = discounted * cfg.gamma * ~autoreset + reward  # --norm-reward's
                # store step t; valid = ~autoreset: after an episode's end the vector env's
                # next step is a reset step (its action ignored, reward 0), which trains nothing
                buffer.store(t, obs, action, reward, terminated, truncated, valid=~autoreset,
                             discounted=discounted)
                obs, autoreset = next_obs, terminated | truncated
                if "episode" in info:  # the returns of the episodes that ended at this step
                    for ep_return in info["episode"]["r"][info["_episode"]]:
                        run.episode_ended(global_step, ep_return)
                run.progress(global_step, stats, (policy, value_net))  # nan/inf: stop

            # --- pi_old, V and the advantages of the whole rollout: one batch, then the update ---
            data, raw = batch_of(buffer.get_batch(device), obs, policy, value_net, obs_norm,
                                 return_norm, cfg)
            learn = update if cfg.update == "full_batch" else update_minibatch
            last = after_update(policy, data, cfg, *learn(policy, value_net, pi_optimizer,
                                                          vf_optimizer, data, cfg))
            stats = {key: last[key] for key in ("loss_pi", "loss_v", "approx_kl", "std_max")}
            if cfg.norm_obs:  # the next rollout's statistics: every obs so far, this one's in
                obs_norm.update(raw)

            # --- evaluate mu(s), no sampling, after the update that reaches each eval_every ---
            if global_step % cfg.eval_every < T * N or k == num_updates:
                evaluate(run, actor, device, actor_info, global_step, last)
            if (global_step % cfg.checkpoint_every < T * N or k == num_updates
                    or ctrl_c.pressed):  # between rollouts: the buffer holds nothing to keep
                checkpoints.save(run.dir / "checkpoint.pt", SCRIPT, cfg, global_step, obs,
                                 in_checkpoint, say=not ctrl_c.pressed)
                run.clock_from(global_step)
            if ctrl_c.pressed:  # stop where the update is whole (its checkpoint is written)
                break
    envs.close()
    return report.finish_evaluations(run, global_step, ctrl_c.pressed, untrained, actor, device,
                                     actor_info, mujoco_env.gif_for(cfg.env_id))


def main(argv=None):
    """python ppo_reacher.py [flags]: train (then --watch), --resume a run, or --eval an actor."""
    cfg = cli.parse_config(Config, argv, description=__doc__.split("\n\n")[0])
    with cli.clear_exit():  # bad input: one line, exit 2; Ctrl-C: one line, exit 130
        saved = cfg.eval or report.saved_model(train(cfg))  # after a Ctrl-C: exit 130
        if cfg.eval or cfg.watch:  # play the saved actor (in a window with --watch)
            actor, env_id = checkpoints.load_model(saved, SCRIPT, "actor", lambda c: MeanActor(
                common.RunningNorm(c["obs_dim"]), PolicyNetwork(c["obs_dim"], c["act_dim"],
                c["config"]["hidden"], 0.0), np.array(c["low"]), np.array(c["high"])))
            mean = [("eval_returns", "mean action", lambda _: common.deterministic(actor, "cpu"))]
            report.play(cfg, saved, env_id, mean, mujoco_env.gif_for(env_id),
                        mujoco_env.watch_camera)


if __name__ == "__main__":
    main()
