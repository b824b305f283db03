"""PPO-clip on CartPole-v1 (Schulman et al. 2017, "Proximal Policy Optimization Algorithms").

Read beside tutorials 000 (PolicyNetwork, ValueNetwork, RolloutBuffer,
ppo_update) and 002 (compute_loss_pi, compute_loss_v, approx_kl, clipfrac,
early stop at 1.5 x target_kl). The loop in train(), top to bottom:

    collect  num_steps x num_envs transitions with the current policy
    GAE      advantages A_t and value targets R_t = A_t + V(s_t)   (common.gae)
    update   a few epochs of shuffled minibatches on the clipped surrogate
    log      one progress.csv row per update; a progress line now and then
After training: curve.png, inside.png, the evaluation, the GIFs (report.finish_updates).

    python ppo_cartpole.py                  # train until solved (tens of seconds on a CPU)
    python ppo_cartpole.py --eval runs/latest --watch   # replay a saved model in a window

中文导读：PPO-clip（近端策略优化的裁剪版本，教程里叫 PPO2），同策略算法。配套教程：
000《PPO近段策略优化玩cartpole游戏》（“近段”应为“近端”）、
001《强化学习PPO从理论到代码详解(2)---PPO1和PPO2》和 002（原文无标题）。对照阅读见
README.zh-CN.md 的路线一、路线二。train() 里的循环四步：采集数据、算优势（GAE）、更新、记录。
"""

import copy
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch
import torch.nn as nn
from torch.distributions import Categorical

import cartpole_env
import checkpoints
import cli
import common
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


# ==== Hyperparameters: each once, here; --help shows the string under each =============
@dataclass
class Config(cli.SolvedFlags):
    """The algorithm's settings; the flags every script shares (--run-dir, --gifs, --eval,
    --watch, --threads, ...) and the solved rule's come from cli.SolvedFlags."""
    # --- experiment ---
    env_id: str = "CartPole-v1"
    """gymnasium id of an env with a Box observation and Discrete actions"""
    seed: int = 0
    """seeds torch and the envs: same seed, same machine => same progress.csv"""
    total_timesteps: int = 100_000
    """budget of env steps (all envs together); training usually stops long before, when solved"""
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
    discounted returns up to ~100, become at most ~5, quick to fit (1 = off; 0.01 .. 1)"""
    lam: float = 0.95
    """GAE lambda (0.9 .. 0.97): 0 = one-step TD errors (low variance, biased by V); 1 = the
    discounted rewards to the episode's end minus V(s), bootstrapped where it is cut (less bias)"""
    update_epochs: int = 10
    """passes over each batch (tutorial 000: 10; 3 .. 30)"""
    num_minibatches: int = 4
    """minibatches per epoch; minibatch size = batch / num_minibatches (1 .. 32)"""
    norm_adv: bool = True
    """normalize advantages to mean 0, std 1 within each minibatch"""
    clip_coef: float = 0.2
    """epsilon of the clipped surrogate (0.1 .. 0.3): a sample whose ratio pi/pi_old has left
    [1 - eps, 1 + eps] on the side its advantage favours stops pulling pi further. The ratio
    itself is not bounded: it can end an update far outside the band"""
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

    def __post_init__(self):
        super().__post_init__()  # the shared flags' checks
        cli.check_ranges(
            self, total_timesteps="> 0", num_envs="> 0", num_steps="> 0", update_epochs="> 0",
            num_minibatches="> 0", hidden="> 0", learning_rate="> 0", reward_scale="> 0",
            ent_coef=">= 0", vf_coef=">= 0", max_grad_norm=">= 0", gamma="(0, 1]", lam="[0, 1]",
            clip_coef="> 0", kl_stop_factor="> 0", target_kl="> 0 or none")
        batch = self.num_envs * self.num_steps
        cli.check(self.num_minibatches <= batch, f"--num-minibatches "
                  f"({self.num_minibatches}) exceeds the batch size ({batch})")
        cli.check(self.total_timesteps >= batch, f"--total-timesteps ({self.total_timesteps})"
                  f" is less than one rollout (num_envs x num_steps = {batch})")


# ==== Rollout buffer, losses, update ======================================================
class RolloutBuffer:
    """num_steps x num_envs transitions as (T, N, ...) numpy arrays, as the envs give them;
    get_batch turns the whole rollout into tensors once, not at every step."""

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


def store_and_advance(buffer, t, obs, action, reward, next_obs, terminated, truncated,
                      autoreset):
    """Store step t of the N envs and return what step t + 1 starts from: (the obs its
    actions are chosen in, which of its envs are at an autoreset step), each (N, ...).

    NEXT_STEP autoreset (gymnasium 1.x's vector envs): the step after an episode ends is a
    reset step: its action is ignored, its reward is 0, its obs the new episode's first.
    E.g. env 0 hits the time limit at step t: row t stores terminated False, truncated True;
    row t + 1 stores that episode's real final obs (next_obs at t) with valid False. GAE reads
    it as V(s_{t+1}) and bootstraps from it, and the update drops row t + 1."""
    # The trap of every hand-written loop: the action (and its value) belong to obs;
    # next_obs is only where they led. terminated and truncated are kept apart: GAE
    # bootstraps at a time-limit truncation only (common.gae). valid = ~autoreset: the
    # previous step ended an episode, so this one is a reset step and trains nothing.
    buffer.store(t, obs, action, reward, terminated, truncated, valid=~autoreset)
    return next_obs, terminated | truncated  # obs = next_obs; where one ended, a reset step next


def compute_loss_pi(policy, data, clip_coef):
    """Clipped surrogate loss on a batch `data`: (loss_pi, entropy, info: approx_kl, clipfrac).
    Why: the ratio reweights pi_old's samples so that several epochs can reuse them (L_CPI,
    eq. 6, whose gradient at pi_old is the policy gradient); the min() with the clipped term
    is a pessimistic bound that stops rewarding a sample once its ratio is past the band on
    its advantage's side (docs/why.md)."""
    obs, act, adv, logp_old = data["obs"], data["act"], data["adv"], data["logp"]
    dist = Categorical(logits=policy(obs))  # pi(.|s)
    logp = dist.log_prob(act)  # log pi(a|s) of the taken actions, (B,)
    ratio = torch.exp(logp - logp_old)  # r_t = pi(a|s) / pi_old(a|s)
    # L_CLIP = E[min(r*A, clip(r, 1-eps, 1+eps)*A)]  (Schulman et al. 2017, eq. 7); minimize -L_CLIP
    clip_adv = torch.clamp(ratio, 1 - clip_coef, 1 + clip_coef) * adv
    loss_pi = -torch.min(ratio * adv, clip_adv).mean()
    # How far pi moved from pi_old (tutorial 002's "useful extra info"): approx_kl estimates
    # KL(pi_old || pi) as E[(r - 1) - log r] (>= 0, less variance than E[logp_old - logp]);
    # clipfrac is the share of ratios outside [1 - eps, 1 + eps], on either side.
    with torch.no_grad():
        log_ratio = logp - logp_old
        info = dict(approx_kl=((ratio - 1) - log_ratio).mean(),
                    clipfrac=((ratio - 1).abs() > clip_coef).float().mean(), ratio=ratio.detach())
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
            # Tutorial 002's early stop (off by default), on the whole batch before each policy
            # step: once pi is too far from pi_old, no more policy steps on this batch.
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
    with torch.no_grad():  # the whole batch after the update: how far pi moved, where r went
        info = compute_loss_pi(policy, data, cfg.clip_coef)[2]
    return dict(zip(("loss_pi", "loss_v", "entropy"), means), approx_kl=info["approx_kl"].item(),
                clipfrac=means[3], policy_stopped=int(policy_stopped),
                **common.ratio_stats(info["ratio"], data["adv"], cfg.clip_coef, cfg.norm_adv))


# progress.csv's columns, once: (progress-line format or None, picture label, CleanRL's tag)
LOGGED = dict(lr=(None, "learning rate", "charts/learning_rate"),
              loss_pi=("+.3f", "-L_CLIP", "losses/policy_loss"),
              loss_v=(".2e", "L_VF", "losses/value_loss"),
              approx_kl=(".4f", "approx_kl: KL(pi_old || pi) after it", "losses/approx_kl"),
              entropy=(".3f", "entropy of pi (nats)", "losses/entropy"),
              clipfrac=(".3f", "clipfrac: |r - 1| > eps, during it", "losses/clipfrac"),
              policy_stopped=(None, "1: the early stop ended pi's steps"),
              **common.RATIO_COLUMNS)  # where r went (common.ratio_stats)
SMOKE = dict(total_timesteps=2048, stop_when_solved=False, eval_episodes=2)  # tests: seconds


def pictures(cfg):
    """curve.png: pi's entropy and approx_kl below the returns; inside.png (docs/inside.md): r
    against [1 - eps, 1 + eps], the share of the batch without gradient, r at three updates."""
    band = (1 - cfg.clip_coef, 1 + cfg.clip_coef)
    entropy_kl = plots.lines("entropy", right=("approx_kl",), right_ylabel="approx_kl")
    return dict(curve=[[entropy_kl]], inside=[
        [plots.spread("ratio", "r = pi/pi_old after each update; dashed: 1 +- eps", band,
                      ylabel="r = pi / pi_old"),
         plots.lines("clipfrac", "clipfrac_after", "zero_grad_frac", title="share of the batch",
                     ylabel="share of the batch's samples")],
        [plots.histograms("ratio", "adv", band)]])


# ==== Training ============================================================================
def train(cfg: Config):
    """Train PPO-clip with `cfg`. Returns a dict: run_dir, solved, solved_step, global_step,
    episode_returns, eval_returns, greedy_returns, interrupted (report.finish_updates)."""
    # --- seeding and setup ---
    torch.manual_seed(cfg.seed)  # the networks' init and the sampled actions
    torch.set_num_threads(cfg.threads)  # also for reproducibility: threads change float sums
    device = torch.device("cuda" if cfg.cuda and torch.cuda.is_available() else "cpu")
    envs, obs, threshold = common.make_vec_env(cfg.env_id, cfg.num_envs, cfg.seed,
                                               cfg.solved_return)
    obs_dim = int(envs.single_observation_space.shape[0])
    n_actions = int(envs.single_action_space.n)
    T, N = cfg.num_steps, cfg.num_envs
    buffer = RolloutBuffer(T, N, obs_dim)

    policy = PolicyNetwork(obs_dim, n_actions, cfg.hidden).to(device)
    value_net = ValueNetwork(obs_dim, cfg.hidden).to(device)
    untrained, untrained_v = copy.deepcopy(policy), copy.deepcopy(value_net)  # before.gif, maps
    optimizer = torch.optim.Adam([*policy.parameters(), *value_net.parameters()],
                                 lr=cfg.learning_rate, eps=1e-5)
    num_updates = cfg.total_timesteps // (T * N)
    # The run folder: progress.csv, a progress line with these numbers every print_every updates
    run = runlog.UpdateLog(SCRIPT, cfg, LOGGED)
    play = report.sampled_and_greedy(policy, device)  # the checks, the evaluations, after.gif

    # In NEXT_STEP autoreset mode, the step after an episode ends is a reset step: its action
    # is ignored, its reward is 0, its obs the new episode's first. `autoreset` marks them.
    autoreset = np.zeros(N, dtype=bool)
    global_step, checked, stopped = 0, 0, False

    # Ctrl-C ends the loop; either way, model.pt and episodes.csv are saved as training left them
    with run.saving_model(dict(policy=policy, value=value_net), obs_dim=obs_dim,
                          n_actions=n_actions):
        for update in range(1, num_updates + 1):
            if cfg.anneal_lr:  # lr_k = lr * (1 - (k - 1) / K): from lr at the first update toward 0
                frac = 1 - (update - 1) / num_updates
                optimizer.param_groups[0]["lr"] = cfg.learning_rate * frac

            # --- collect: T steps of N envs with the current policy (pi_old) ---
            for t in range(T):
                # obs as the env gives it: no normalization (a simplification)
                with torch.no_grad():
                    logits = policy(torch.as_tensor(obs, dtype=torch.float32, device=device))
                action = Categorical(logits=logits).sample().cpu().numpy()  # a ~ pi(.|s), (N,)
                next_obs, reward, terminated, truncated, info = envs.step(action)
                global_step += N
                # store step t (a reset step masked), then move on: obs = next_obs
                obs, autoreset = store_and_advance(buffer, t, obs, action,
                                                   cfg.reward_scale * reward, next_obs,
                                                   terminated, truncated, autoreset)
                run.episodes_ended(info, global_step)
                # Solved when the mean return of the last solved_window episodes reaches the
                # threshold; then pi as it is now must too (at most one check per update)
                if run.solved(threshold) and cfg.stop_when_solved and checked < update:
                    checked = update  # pi plays eval_episodes episodes: does it hold?
                    if stopped := report.pi_holds(play, cfg, threshold, global_step):
                        break
            if stopped:  # the partial rollout trains nothing; a last row says where it ended
                run.stopped_row(lr=optimizer.param_groups[0]["lr"])
                break

            # --- pi_old and V of the whole rollout in one batch, then advantages ---
            rollout = buffer.get_batch(device)  # (T, N, ...) tensors
            with torch.no_grad():
                # pi_old: the policy has not changed since it chose these actions.
                dist_old = Categorical(logits=policy(rollout["obs"]))
                logp_old = dist_old.log_prob(rollout["actions"])  # log pi_old(a|s), (T, N)
                values = value_net(rollout["obs"])  # (T, N)
                # V(s_{t+1}) is the value of the next stored obs. After a done step that is the
                # reset step's obs: the finished episode's real final observation (the done step
                # returned it), so a truncated step bootstraps from it, a terminated one does not.
                last_value = value_net(torch.as_tensor(obs, dtype=torch.float32,
                                                       device=device))  # V(s_T), (N,)
                next_values = torch.cat([values[1:], last_value[None]])  # (T, N)
                # TD error  delta_t = r_t + gamma * V(s_{t+1}) * (1 - terminated_t) - V(s_t)
                # GAE       A_t = delta_t + gamma * lam * (1 - done_t) * A_{t+1}, from t = T-1 down
                #           (Schulman et al. 2016, eq. 16; done = terminated or truncated)
                # (Tutorial 000's delta has V(s_t) on both sides, its sum no gamma * lam.)
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
            runlog.stop_if_diverged(global_step, stats, (policy, value_net), run.dir)
            run.update(stats, visited=data["obs"], lr=optimizer.param_groups[0]["lr"])
    envs.close()
    nets = dict(untrained=(untrained, untrained_v), trained=(policy, value_net))  # the maps
    return report.finish_updates(run, threshold, play, report.sampled_and_greedy(untrained, device),
                                 pictures(cfg), cartpole_env.maps(cfg, nets, device, run.visited))


def main(argv=None):
    """python ppo_cartpole.py [flags]: train (then --watch), or --eval a saved model."""
    cfg = cli.parse_config(Config, argv, description=__doc__.split("\n\n")[0])
    with cli.clear_exit():  # bad input: one line, exit 2; Ctrl-C: one line, exit 130
        saved = cfg.eval or report.saved_model(train(cfg))  # after a Ctrl-C: exit 130
        if cfg.eval or cfg.watch:  # play the saved policy (in a window with --watch)
            policy, env_id = checkpoints.load_model(saved, SCRIPT, "policy", lambda ckpt: (
                PolicyNetwork(ckpt["obs_dim"], ckpt["n_actions"], ckpt["config"]["hidden"])))
            report.play(cfg, saved, env_id, report.sampled_and_greedy(policy, "cpu"))


if __name__ == "__main__":
    main()
