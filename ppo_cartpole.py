"""PPO-clip on CartPole-v1 (Schulman et al. 2017, "Proximal Policy Optimization Algorithms").

Read beside tutorials 000 (PolicyNetwork, ValueNetwork, RolloutBuffer,
ppo_update) and 002 (compute_loss_pi, compute_loss_v, approx_kl, clipfrac,
early stop at 1.5 x target_kl). The loop, top to bottom:

    collect  num_steps x num_envs transitions with the current policy
    GAE      advantages A_t and value targets R_t = A_t + V(s_t)   (common.gae)
    update   a few epochs of shuffled minibatches on the clipped surrogate
    log      one progress.csv row per update; a progress line now and then

    python ppo_cartpole.py                  # train until solved (seconds to minutes)
    python ppo_cartpole.py --help           # every hyperparameter, with its meaning
    python ppo_cartpole.py --eval runs/<run> --watch   # replay a saved model in a window

中文导读：本脚本教 PPO-clip（近端策略优化的裁剪版本，教程里叫 PPO2）：策略网络、价值网络、
缓冲区、裁剪代理目标和 GAE 怎样写对。配套教程：《PPO近段策略优化玩cartpole游戏》（000，
标题里的“近段”应为“近端”）、《强化学习PPO从理论到代码详解(2)---PPO1和PPO2》（001），
以及讲 compute_loss_pi 和 finish_path 的 002（原文没有标题）。循环四步：

    采样  当前策略在 num_envs 个环境里各走 num_steps 步
    优势  GAE 算出优势 A_t 和价值目标 R_t = A_t + V(s_t)（common.gae）
    更新  打乱成小批量，在裁剪代理目标上训练 update_epochs 遍
    记录  每次更新在 progress.csv 里记一行，隔几次打印一行进度
"""

from __future__ import annotations

import common  # first: it turns a Ctrl-C while torch loads into one line (see its top)

import copy
import dataclasses
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import torch
import torch.nn as nn
from torch.distributions import Categorical

import plots

SCRIPT = Path(__file__).stem  # names its run folders; saved in its models (it loads no other's)


# =============================================================================
# Networks
# =============================================================================


def layer_init(layer, gain=np.sqrt(2)):
    """Orthogonal weights, zero bias: the init of the PPO reference code (baselines)."""
    nn.init.orthogonal_(layer.weight, gain)
    nn.init.zeros_(layer.bias)
    return layer


class PolicyNetwork(nn.Module):
    """pi(a|s): observation -> logits of a categorical distribution over actions."""

    def __init__(self, obs_dim, n_actions, hidden):
        super().__init__()
        self.net = nn.Sequential(
            layer_init(nn.Linear(obs_dim, hidden)), nn.Tanh(),
            layer_init(nn.Linear(hidden, hidden)), nn.Tanh(),
            # A small last layer makes the first policy close to uniform.
            layer_init(nn.Linear(hidden, n_actions), gain=0.01),
        )

    def forward(self, obs):
        return self.net(obs)  # logits, (B, n_actions); pi(.|s) = softmax(logits)


class ValueNetwork(nn.Module):
    """V(s): observation -> expected discounted return from s."""

    def __init__(self, obs_dim, hidden):
        super().__init__()
        self.net = nn.Sequential(
            layer_init(nn.Linear(obs_dim, hidden)), nn.Tanh(),
            layer_init(nn.Linear(hidden, hidden)), nn.Tanh(),
            layer_init(nn.Linear(hidden, 1), gain=1.0),
        )

    def forward(self, obs):
        return self.net(obs).squeeze(-1)  # (B,): a stray (B, 1) would broadcast against targets


# =============================================================================
# Hyperparameters: every one once, here; --help prints the string under each
# =============================================================================


@dataclass
class Config:
    # --- experiment ---
    env_id: str = "CartPole-v1"
    """gymnasium id of an env with a Box observation and Discrete actions"""
    seed: int = 0
    """seeds torch and the envs: same seed, same machine => same progress.csv"""
    total_timesteps: int = 100_000
    """budget of env steps (all envs together); training usually stops long before, when solved"""
    stop_when_solved: bool = True
    """stop once the mean return of the last 20 finished episodes reaches the solved return
    and pi as it is then does too, over eval_episodes episodes with actions drawn from pi
    (env seed eval_seed + 1); checked at most once per update, training goes on until then"""
    solved_return: float | None = None
    """the return that counts as solved; none = the env's reward_threshold (CartPole-v1: 475)"""

    # --- collection ---
    num_envs: int = 8
    """parallel envs; more = more diverse batches, fewer updates per env step (1 .. 64)"""
    num_steps: int = 32
    """steps per env per rollout; the batch is num_envs * num_steps transitions (32 .. 2048)"""

    # --- PPO ---
    learning_rate: float = 4e-3
    """Adam step size for both networks (PPO usually 3e-4 .. 3e-3; CartPole takes more)"""
    anneal_lr: bool = True
    """decay the learning rate linearly to 0 over total_timesteps"""
    gamma: float = 0.99
    """discount factor (0.98 .. 0.999); 0.99 looks about 100 steps ahead"""
    reward_scale: float = 0.05
    """rewards are multiplied by this for learning (logged returns are not): V's targets,
    discounted returns up to ~100, become at most ~5, which the critic fits within a few
    steps (1 = off; 0.01 .. 1)"""
    lam: float = 0.95
    """GAE lambda (usually 0.9 .. 0.97): 0 = one-step TD errors r + gamma V(s') - V(s) (low
    variance, biased by V); 1 = the discounted rewards to the episode's end minus V(s), still
    bootstrapped from V where the rollout or a time limit cuts the episode (less bias)"""
    update_epochs: int = 10
    """passes over each batch (tutorial 000: 10; 3 .. 30)"""
    num_minibatches: int = 4
    """minibatches per epoch; minibatch size = batch / num_minibatches (1 .. 32)"""
    norm_adv: bool = True
    """normalize advantages to mean 0, std 1 within each minibatch"""
    clip_coef: float = 0.2
    """epsilon of the clipped surrogate: the ratio is kept in [1 - eps, 1 + eps] (0.1 .. 0.3)"""
    ent_coef: float = 0.0
    """entropy bonus weight c2 (eq. 9; 0 .. 0.01). CartPole explores enough without it"""
    vf_coef: float = 0.5
    """value loss weight c1 (eq. 9; 0.5 .. 1)"""
    max_grad_norm: float = 0.5
    """clip the global gradient norm of both networks to this (0.5 .. 10; 0 = no clipping)"""
    target_kl: float | None = None
    """tutorial 002's early stop: no more policy steps on a batch once approx_kl exceeds
    kl_stop_factor * target_kl (0.01 .. 0.05); none = never"""
    kl_stop_factor: float = 1.5
    """the 1.5 of tutorial 002's early stop"""
    hidden: int = 64
    """units in each of the two hidden layers of both networks (32 .. 256)"""

    # --- output ---
    run_dir: str = "runs"
    """parent folder of the run folder <script>__<env>__seed<k>__<time>/"""
    print_every: int = 10
    """print a progress line every this many updates"""
    gifs: bool = True
    """write before.gif (untrained policy) and after.gif (trained policy) to the run folder:
    one episode each, actions drawn from pi as in training (and in tutorial 004's GIFs)"""
    tensorboard: bool = False
    """also write the logs as TensorBoard scalars into the run folder, with CleanRL's tag
    names (needs `pip install tensorboard`; then: tensorboard --logdir runs)"""
    curves: bool = True
    """draw curve.png (returns and the update's diagnostics against env steps) after training"""
    eval_episodes: int = 10
    """episodes played after training (and by --eval) twice: actions drawn from pi, then
    pi's most probable action (greedy); both mean returns are printed"""
    eval_seed: int = 10_000
    """seed of the evaluation env and its action draws, kept apart from the training seeds
    (the stop check uses eval_seed + 1)"""
    watch: bool = False
    """after training (or with --eval), play the policy (actions drawn from pi) in a window;
    needs a display"""
    eval: str | None = None
    """a saved model.pt or its run folder: skip training, play eval_episodes episodes (as
    after training: actions drawn from pi, then greedy)"""
    gif: str | None = None
    """with --eval: write one episode of the saved policy (actions drawn from pi, as
    after.gif) to this GIF file instead (no display needed)"""
    threads: int = 1
    """torch CPU threads (1 .. cores); the same seed gives the same logs only with the same
    count (threads change float sums). Networks this small have little work to share out"""
    cuda: bool = False
    """train on the GPU if there is one (CartPole's tiny networks are faster on the CPU)"""

    def __post_init__(self):
        common.check(not self.tensorboard or plots.tensorboard_installed(), plots.NO_TENSORBOARD)
        common.check_ranges(
            self, total_timesteps="> 0", num_envs="> 0", num_steps="> 0", update_epochs="> 0",
            num_minibatches="> 0", hidden="> 0", print_every="> 0", eval_episodes="> 0",
            threads="> 0", learning_rate="> 0", reward_scale="> 0", ent_coef=">= 0", vf_coef=">= 0",
            max_grad_norm=">= 0", gamma="(0, 1]", lam="[0, 1]",
            clip_coef="> 0", kl_stop_factor="> 0", target_kl="> 0 or none")
        batch = self.num_envs * self.num_steps
        common.check(self.num_minibatches <= batch,
                     f"--num-minibatches ({self.num_minibatches}) exceeds the batch size ({batch})")
        common.check(self.total_timesteps >= batch,
                     f"--total-timesteps ({self.total_timesteps}) is less than one rollout "
                     f"(num_envs x num_steps = {batch}): nothing would be learned")
        common.check(not self.gif or self.eval,
                     "--gif writes a GIF of a saved policy: it needs --eval")


# =============================================================================
# Rollout buffer, losses, update
# =============================================================================


class RolloutBuffer:
    """num_steps x num_envs transitions, stored as (T, N, ...) numpy arrays.

    The envs speak numpy, so the loop stores their outputs as they come and
    get_batch turns the whole rollout into tensors once, not at every step.
    """

    def __init__(self, T, N, obs_dim):
        self.obs = np.zeros((T, N, obs_dim), dtype=np.float32)
        self.actions = np.zeros((T, N), dtype=np.int64)
        self.rewards = np.zeros((T, N), dtype=np.float32)
        self.terminated = np.zeros((T, N), dtype=bool)
        self.truncated = np.zeros((T, N), dtype=bool)
        self.valid = np.ones((T, N), dtype=bool)  # False at a vector-env autoreset step

    def store(self, t, obs, action, reward, terminated, truncated, valid):
        self.obs[t], self.actions[t], self.rewards[t] = obs, action, reward
        self.terminated[t], self.truncated[t], self.valid[t] = terminated, truncated, valid

    def get_batch(self, device):
        """Every field as a tensor on `device`, still shaped (T, N, ...)."""
        return {name: torch.as_tensor(array, device=device) for name, array in vars(self).items()}


def compute_loss_pi(policy, data, clip_coef):
    """Clipped surrogate loss on a batch `data`: (loss_pi, entropy, info: approx_kl, clipfrac)."""
    obs, act, adv, logp_old = data["obs"], data["act"], data["adv"], data["logp"]
    dist = Categorical(logits=policy(obs))  # pi(.|s)
    logp = dist.log_prob(act)  # log pi(a|s) of the taken actions, (B,)
    ratio = torch.exp(logp - logp_old)  # r_t = pi(a|s) / pi_old(a|s)
    # L_CLIP = E[min(r*A, clip(r, 1-eps, 1+eps)*A)]  (Schulman et al. 2017, eq. 7); minimize -L_CLIP
    clip_adv = torch.clamp(ratio, 1 - clip_coef, 1 + clip_coef) * adv
    loss_pi = -torch.min(ratio * adv, clip_adv).mean()
    # How far pi has moved from pi_old (tutorial 002's "useful extra info"): approx_kl
    # estimates KL(pi_old || pi) as E[(r - 1) - log r], never negative and of lower variance
    # than E[logp_old - logp]; clipfrac is the share of ratios outside the clip range.
    with torch.no_grad():
        log_ratio = logp - logp_old
        info = dict(approx_kl=((ratio - 1) - log_ratio).mean(),
                    clipfrac=((ratio - 1).abs() > clip_coef).float().mean())
    return loss_pi, dist.entropy().mean(), info


def approx_kl(policy, data, cfg):
    """compute_loss_pi's approx_kl, KL(pi_old || pi), on all of `data`, as a number."""
    with torch.no_grad():
        return compute_loss_pi(policy, data, cfg.clip_coef)[2]["approx_kl"].item()


def compute_loss_v(value_net, data):
    """L_VF = E[(V(s_t) - R_t)^2]  (Schulman et al. 2017, eq. 9), halved as is usual."""
    obs, ret = data["obs"], data["ret"]
    return 0.5 * ((value_net(obs) - ret) ** 2).mean()  # unclipped: a simplification


def ppo_update(policy, value_net, optimizer, data, cfg):
    """update_epochs passes of shuffled minibatches over one batch, `data`: tutorial 002's
    dict of obs, act, logp (log pi_old(a|s)), adv and ret, each with one row per transition.
    Returns the update's stats for the log, averaged over its minibatch steps."""
    params = [*policy.parameters(), *value_net.parameters()]
    stats = []
    policy_stopped = False  # tutorial 002's early stop: once set, for the rest of this update
    for epoch in range(cfg.update_epochs):
        # num_minibatches random minibatches that together hold every transition once.
        order = torch.randperm(len(data["obs"]), device=data["obs"].device)
        for mb_inds in order.tensor_split(cfg.num_minibatches):
            mb = {key: x[mb_inds] for key, x in data.items()}
            if cfg.norm_adv:
                mb["adv"] = (mb["adv"] - mb["adv"].mean()) / (mb["adv"].std(unbiased=False) + 1e-8)
            loss_pi, entropy, info = compute_loss_pi(policy, mb, cfg.clip_coef)
            loss_v = compute_loss_v(value_net, mb)
            # Tutorial 002's early stop, on the whole batch before each policy step: once pi is
            # too far from pi_old, no more policy steps on this batch, even if the KL dips again.
            if cfg.target_kl is not None and not policy_stopped:
                policy_stopped = approx_kl(policy, data, cfg) > cfg.kl_stop_factor * cfg.target_kl
            # L = L_CLIP - c1 * L_VF + c2 * S[pi], maximized  (Schulman et al. 2017, eq. 9).
            # The networks are separate, so c1 only matters through the shared gradient clip.
            loss = cfg.vf_coef * loss_v
            if not policy_stopped:  # a stopped policy gets no gradient: Adam leaves it as it is
                loss = loss + loss_pi - cfg.ent_coef * entropy

            optimizer.zero_grad()
            loss.backward()
            if cfg.max_grad_norm > 0:
                nn.utils.clip_grad_norm_(params, cfg.max_grad_norm)
            optimizer.step()
            stats.append(torch.stack([loss_pi.detach(), loss_v.detach(), entropy.detach(),
                                      info["clipfrac"]]))
    means = torch.stack(stats).mean(0).tolist()
    return dict(zip(("loss_pi", "loss_v", "entropy"), means),
                approx_kl=approx_kl(policy, data, cfg),  # how far the whole update moved pi
                clipfrac=means[3], policy_stopped=int(policy_stopped))


# =============================================================================
# Training
# =============================================================================


def act_fn(policy, device, seed, greedy=False):
    """obs -> action, for evaluation and GIFs: drawn from pi(.|s) as in training (and as
    tutorial 004 draws its GIFs), or with greedy=True pi's most probable action. The draws
    come from their own generator, seeded with `seed`: an evaluation replays exactly."""
    rng = np.random.default_rng(seed)

    def act(obs):
        with torch.no_grad():
            logits = policy(torch.as_tensor(obs, dtype=torch.float32, device=device))
        if greedy:
            return int(logits.argmax())
        probs = torch.softmax(logits.double(), -1).cpu().numpy()  # float64: sums to 1 for numpy
        return int(rng.choice(len(probs), p=probs))  # a ~ pi(.|s), tutorial 004's np.random.choice
    return act


def holds(policy, device, cfg, threshold, step):
    """Does pi, as it is now, also reach `threshold`: the mean return of cfg.eval_episodes
    episodes, actions drawn from pi, env and draws seeded with eval_seed + 1 (apart from
    training and from the evaluation after it)? Says what it found in one line."""
    returns = common.evaluate(cfg.env_id, act_fn(policy, device, cfg.eval_seed + 1),
                              cfg.eval_episodes, cfg.eval_seed + 1)
    held = np.mean(returns) >= threshold
    print(f"check at step {step}: pi as it is now averages {np.mean(returns):.1f} over "
          f"{len(returns)} episodes: " + ("it holds, training stops" if held else
                                         f"below {threshold:g}, training goes on"), flush=True)
    return held


def train(cfg: Config):
    """Train PPO-clip with `cfg`. Returns a dict: run_dir, solved, global_step,
    solved_step (or None), episode_returns (all finished training episodes),
    eval_returns (episodes after training, actions drawn from pi), greedy_returns (the same
    episode seeds, pi's most probable action) and interrupted."""
    start_time = time.time()
    # --- seeding and setup ---
    torch.manual_seed(cfg.seed)  # the networks' init and the sampled actions
    torch.set_num_threads(cfg.threads)  # also for reproducibility: threads change float sums
    device = torch.device("cuda" if cfg.cuda and torch.cuda.is_available() else "cpu")
    envs, next_obs, threshold = common.make_vec_env(cfg.env_id, cfg.num_envs, cfg.seed,
                                                    cfg.solved_return)
    obs_dim = int(envs.single_observation_space.shape[0])
    n_actions = int(envs.single_action_space.n)
    T, N = cfg.num_steps, cfg.num_envs
    with common.env_errors(cfg.env_id):  # too little memory for the buffer: one clear line
        buffer = RolloutBuffer(T, N, obs_dim)
    run_dir = common.make_run_dir(cfg.run_dir, SCRIPT, cfg.env_id, cfg.seed)
    print(f"run folder: {run_dir}", flush=True)

    policy = PolicyNetwork(obs_dim, n_actions, cfg.hidden).to(device)
    value_net = ValueNetwork(obs_dim, cfg.hidden).to(device)
    untrained = copy.deepcopy(policy)  # before.gif is drawn from these weights after training
    optimizer = torch.optim.Adam([*policy.parameters(), *value_net.parameters()],
                                 lr=cfg.learning_rate, eps=1e-5)
    num_updates = cfg.total_timesteps // (T * N)

    # In NEXT_STEP autoreset mode, the step after an episode ends is a reset
    # step: its action is ignored, its reward is 0 and the obs it returns is
    # the first of the new episode. `autoreset` marks envs whose next step is one.
    autoreset = np.zeros(N, dtype=bool)

    # --- episode bookkeeping, the stop and the log: plumbing, out of the loop's way ---
    episodes = []  # (env step, return) of every finished training episode, in order
    global_step, solved_step, update, interrupted, stats = 0, None, 0, False, {}
    checked, stopped = 0, False  # the last update at which pi was checked; whether it held

    def mean20():  # the mean return of the last 20 finished episodes
        return float(np.mean([r for _, r in episodes[-20:]])) if episodes else float("nan")

    def log(stats, line=False):  # one progress.csv row: the state of training now
        common.append_csv(run_dir / "progress.csv", dict(
            global_step=global_step, episodes=len(episodes), return_mean20=mean20(),
            lr=optimizer.param_groups[0]["lr"], **stats))
        if line:  # and the progress line
            elapsed = time.time() - start_time
            print(f"step {global_step:>7}  {global_step / elapsed:6.0f} steps/s  "
                  f"return(20) {mean20():6.1f}  "
                  f"loss_pi {stats['loss_pi']:+.3f}  loss_v {stats['loss_v']:.2e}  "
                  f"approx_kl {stats['approx_kl']:.4f}  entropy {stats['entropy']:.3f}  "
                  f"clipfrac {stats['clipfrac']:.3f}  {elapsed:.1f}s", flush=True)

    def stop_now(update):
        """Solved: say so the first time. Stop if pi as it is now holds too: the last 20
        episodes were played by the policies of several updates, and the latest update can
        have undone what they show. Checked at most once per update."""
        nonlocal solved_step, checked
        if solved_step is None:
            solved_step = global_step
            print(f"solved: mean return of the last 20 episodes {mean20():.1f} >= {threshold:g} "
                  f"at step {global_step} (episode {len(episodes)}) after "
                  f"{time.time() - start_time:.1f}s", flush=True)
        if not cfg.stop_when_solved or checked == update:
            return False
        checked = update
        if not holds(policy, device, cfg, threshold, global_step):
            return False
        log(dict.fromkeys(stats, float("nan")))  # the last row: where training ended
        return True

    try:
        for update in range(1, num_updates + 1):
            if cfg.anneal_lr:  # lr_k = lr * (1 - (k - 1) / K): from lr at the first update toward 0
                frac = 1 - (update - 1) / num_updates
                optimizer.param_groups[0]["lr"] = cfg.learning_rate * frac

            # --- collect: T steps of N envs with the current policy (pi_old) ---
            for t in range(T):
                # obs = next_obs: the trap of every hand-written loop. The action (and its
                # value) belong to obs; next_obs is only where they led.
                obs = next_obs  # as the env gives it: no normalization (a simplification)
                with torch.no_grad():
                    logits = policy(torch.as_tensor(obs, dtype=torch.float32, device=device))
                action = Categorical(logits=logits).sample().cpu().numpy()  # a ~ pi(.|s), (N,)
                next_obs, reward, terminated, truncated, info = envs.step(action)
                global_step += N
                buffer.store(t, obs, action, cfg.reward_scale * reward, terminated, truncated,
                             valid=~autoreset)
                autoreset = terminated | truncated
                ended, solved = common.finished_episodes(info, global_step, episodes, threshold)
                episodes += ended
                stopped = solved and stop_now(update)
                if stopped:
                    break
            if stopped:  # solved, and pi held: the partial rollout trains nothing
                break

            # --- pi_old and V of the whole rollout in one batch, then advantages ---
            rollout = buffer.get_batch(device)  # (T, N, ...) tensors
            with torch.no_grad():
                # pi_old: the policy has not changed since it chose these actions.
                dist_old = Categorical(logits=policy(rollout["obs"]))
                logp_old = dist_old.log_prob(rollout["actions"])  # log pi_old(a|s), (T, N)
                values = value_net(rollout["obs"])  # (T, N)
                # V(s_{t+1}) is the value of the next stored obs. After a done step that obs is
                # the episode's real final observation (the reset step reports it), so a
                # truncated step bootstraps from it and a terminated one ignores it (common.gae).
                last_obs = torch.as_tensor(next_obs, dtype=torch.float32, device=device)
                last_value = value_net(last_obs)  # (N,)
                next_values = torch.cat([values[1:], last_value[None]])  # (T, N)
                # TD error  delta_t = r_t + gamma * V(s_{t+1}) * (1 - terminated_t) - V(s_t)
                # GAE       A_t = delta_t + gamma * lam * (1 - done_t) * A_{t+1}, from t = T-1 down
                #           (Schulman et al. 2016, eq. 16; done = terminated or truncated)
                advantages = common.gae(rollout["rewards"], values, next_values,
                                        rollout["terminated"], rollout["truncated"],
                                        cfg.gamma, cfg.lam)  # (T, N)
                returns = advantages + values  # value targets R_t = A_t + V(s_t), detached

            # --- update: flatten (T, N) to one batch `data`, dropping the autoreset steps ---
            keep = rollout["valid"].reshape(-1)
            data = {key: x.flatten(0, 1)[keep] for key, x in dict(
                obs=rollout["obs"], act=rollout["actions"], logp=logp_old, adv=advantages,
                ret=returns).items()}
            stats = ppo_update(policy, value_net, optimizer, data, cfg)
            common.stop_if_diverged(global_step, stats, (policy, value_net), run_dir, obs=next_obs)
            log(stats, line=update % cfg.print_every == 0 or update == 1)  # CSV, progress line
    except KeyboardInterrupt:
        interrupted = True
    except (ValueError, RuntimeError):  # e.g. Categorical refusing nan logits: diverged?
        # If so, one line: stop_if_diverged finds the nan in the weights or in their output.
        common.stop_if_diverged(global_step, {}, (policy, value_net), run_dir, obs=next_obs)
        raise
    finally:
        envs.close()
        if run_dir.exists():  # common.stop_if_diverged removes a diverged run's folder
            for step, ep_return in episodes:
                common.append_csv(run_dir / "episodes.csv",
                                  {"global_step": step, "return": ep_return})
            common.save_checkpoint(dict(script=SCRIPT, policy=policy.state_dict(),
                                        value=value_net.state_dict(), config=asdict(cfg),
                                        obs_dim=obs_dim, n_actions=n_actions,
                                        global_step=global_step), run_dir / "model.pt")

    result = dict(run_dir=run_dir, solved=solved_step is not None, solved_step=solved_step,
                  global_step=global_step, episode_returns=[r for _, r in episodes],
                  eval_returns=[], greedy_returns=[], interrupted=interrupted)
    if interrupted:  # the curve so far and where everything is; main() exits with 130
        if cfg.curves and (run_dir / "progress.csv").exists():
            with common.ctrl_c_deferred():  # a second Ctrl-C waits for the picture
                plots.draw_run(run_dir, threshold, solved_step)
        print(f"\ninterrupted at step {global_step}: {run_dir} holds "
              f"{', '.join(sorted(f.name for f in run_dir.iterdir()))} "
              f"(replay: python {SCRIPT}.py --eval {run_dir})", flush=True)
        return result
    elapsed = time.time() - start_time
    print(f"trained {global_step} steps, {len(episodes)} episodes in {elapsed:.1f}s; "
          f"model: {run_dir / 'model.pt'}", flush=True)

    # --- after training: the learning curve, evaluation and GIFs ---
    if cfg.curves:
        with common.ctrl_c_deferred():  # Ctrl-C waits until curve.png is whole
            print(f"curve: {plots.draw_run(run_dir, threshold, solved_step)}", flush=True)
    if cfg.tensorboard:
        plots.to_tensorboard(run_dir, sps=global_step / elapsed)
    # Two evaluations of the same episode seeds: actions drawn from pi, as in training (the
    # policy that "solved" judged), and pi's most probable action (greedy). They can differ
    # either way: a policy trained to be sampled need not be good when it is not.
    n = cfg.eval_episodes
    returns = common.evaluate(cfg.env_id, act_fn(policy, device, cfg.eval_seed), n, cfg.eval_seed)
    print(f"evaluation over {n} episodes, actions drawn from pi: mean {np.mean(returns):.1f}, "
          f"min {min(returns):.0f}", flush=True)
    greedy_returns = common.evaluate(cfg.env_id, act_fn(policy, device, cfg.eval_seed, greedy=True),
                                     n, cfg.eval_seed)
    print(f"greedy evaluation over {n} episodes (pi's most probable action): mean "
          f"{np.mean(greedy_returns):.1f}, min {min(greedy_returns):.0f}", flush=True)
    result["eval_returns"], result["greedy_returns"] = returns, greedy_returns
    if cfg.gifs:  # one episode each, actions drawn from pi: after.gif shows the evaluation's
        # first episode. Every 2nd frame at half size: small files.
        for name, net in (("before.gif", untrained), ("after.gif", policy)):
            ret = common.record_gif(cfg.env_id, act_fn(net, device, cfg.eval_seed), run_dir / name,
                                    cfg.eval_seed, every=2, scale=2)
            print(f"{name}: return {ret:.0f} -> {run_dir / name}", flush=True)
    return result


def play(cfg: Config):
    """--eval PATH: load a saved model, play cfg.eval_episodes episodes with actions drawn from
    pi (shown with --watch), then as many greedy ones. Returns the first ones' returns.
    With --gif: write one episode, drawn as after.gif is, to that file instead."""
    ckpt = common.load_checkpoint(cfg.eval, script=SCRIPT,
                                  required=("policy", "obs_dim", "n_actions", "config"))
    policy = PolicyNetwork(ckpt["obs_dim"], ckpt["n_actions"], ckpt["config"]["hidden"])
    common.load_weights(policy, ckpt["policy"], cfg.eval)
    env_id = ckpt["config"]["env_id"]
    if cfg.gif:  # one episode to a GIF file, as after.gif is drawn
        ret = common.record_gif(env_id, act_fn(policy, "cpu", cfg.eval_seed), cfg.gif,
                                cfg.eval_seed, every=2, scale=2)
        print(f"{cfg.gif}: one episode, return {ret:.0f}", flush=True)
        return [ret]
    print(f"playing {cfg.eval_episodes} episodes of {env_id} with {cfg.eval}"
          + ("; Ctrl-C stops" if cfg.watch else ""), flush=True)
    returns = common.evaluate(env_id, act_fn(policy, "cpu", cfg.eval_seed), cfg.eval_episodes,
                              cfg.eval_seed, render_mode="human" if cfg.watch else None,
                              log=cfg.watch)
    print(f"{env_id}, {cfg.eval}: returns {[round(r) for r in returns]}, "
          f"mean {np.mean(returns):.1f} (actions drawn from pi)", flush=True)
    greedy_returns = common.evaluate(env_id, act_fn(policy, "cpu", cfg.eval_seed, greedy=True),
                                     cfg.eval_episodes, cfg.eval_seed)
    print(f"greedy (pi's most probable action): returns {[round(r) for r in greedy_returns]}, "
          f"mean {np.mean(greedy_returns):.1f}", flush=True)
    return returns


def main(argv=None):
    """python ppo_cartpole.py [flags]: train (then --watch), or --eval a saved model."""
    cfg = common.parse_config(Config, argv, description=" ".join(__doc__.split("\n\n")[0].split()))
    with common.clear_exit():  # bad input: one line, exit 2; Ctrl-C: one line, exit 130
        if cfg.eval:
            play(cfg)
            return
        result = train(cfg)  # on Ctrl-C it saves the model and logs, says so, and returns
        if result["interrupted"]:
            raise SystemExit(130)
        if cfg.watch:
            play(dataclasses.replace(cfg, eval=str(result["run_dir"])))


if __name__ == "__main__":
    main()
