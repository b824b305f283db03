"""Advantage actor-critic (A2C) on CartPole-v1 (Mnih et al. 2016, "Asynchronous Methods for
Deep Reinforcement Learning"; A2C is its synchronous variant).

Read beside tutorial 004, which trains a Keras actor-critic one whole episode at a
time: the same model (a shared hidden layer feeding an actor head and a critic
head), the same running reward and before/after GIFs. What changes is how often it
learns: A2C takes one gradient step every num_steps steps of num_envs envs, with
n-step returns bootstrapped from the critic, instead of waiting for episodes to end.
It is ppo_cartpole.py's sibling: the same buffer, loop and logs; one step per batch
where PPO takes many behind its clip. The loop in train(), top to bottom:

    collect  num_steps x num_envs transitions with the current policy
    returns  n-step returns R_t (common.discounted_returns), bootstrapped from V at the
             rollout's end and at time-limit truncations; advantages A_t = R_t - V(s_t)
    update   one gradient step on -log pi(a|s) * A + c_v * (R - V)^2 / 2 - c_e * entropy
    log      one progress.csv row per update; a progress line now and then
After training: curve.png, inside.png, the evaluation, the GIFs (report.finish_updates).

    python actor_critic_cartpole.py                  # train until solved (under a minute on a CPU)
    python actor_critic_cartpole.py --eval runs/latest --watch   # replay a saved model in a window

中文导读：A2C（优势演员-评论员）：一个共享隐藏层接演员和评论员两个头，每采集一批数据就用
n 步回报更新一次，不必等回合结束。配套教程：004，对照阅读见 README.zh-CN.md 的路线四。
train() 里的循环：采集数据、算 n 步回报和优势、更新、记录（含平滑回报）。
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


class ActorCritic(nn.Module):
    """Tutorial 004's model: one shared hidden layer, `common`, feeding two heads.

        obs -> common (Linear + ReLU) -> actor:  logits of pi(a|s)  (tutorial: `action`, softmax)
                                      -> critic: V(s)
    """

    def __init__(self, obs_dim, n_actions, hidden):
        super().__init__()
        self.common = layer_init(nn.Linear(obs_dim, hidden))
        # A small actor head makes the first policy close to uniform.
        self.actor = layer_init(nn.Linear(hidden, n_actions), gain=0.01)
        self.critic = layer_init(nn.Linear(hidden, 1), gain=1.0)

    def forward(self, obs):
        h = torch.relu(self.common(obs))
        # (B, n_actions), (B,): a stray (B, 1) value would broadcast against targets
        return self.actor(h), self.critic(h).squeeze(-1)


# ==== Hyperparameters: each once, here; --help shows the string under each =============
@dataclass
class Config(cli.SolvedFlags):
    """The algorithm's settings; the shared flags (--run-dir, --eval, ...): cli.SolvedFlags."""
    # --- experiment ---
    env_id: str = "CartPole-v1"
    """gymnasium id of an env with a Box observation and Discrete actions"""
    seed: int = 0
    """seeds torch and the envs: same seed, same machine => same progress.csv"""
    total_timesteps: int = 200_000
    """budget of env steps (all envs together); training usually stops long before, when solved"""
    # --- collection ---
    num_envs: int = 8
    """parallel envs (A3C's parallel actors, here in lockstep; 1 .. 64)"""
    num_steps: int = 64
    """steps per env between updates: the longest n of the n-step returns (a rollout's first
    step looks num_steps ahead, its last one step; A3C: 5 .. 20; longer here for CartPole)"""
    # --- A2C ---
    learning_rate: float = 0.01
    """Adam step size (tutorial 004: 0.01; A2C usually 7e-4 .. 1e-2)"""
    anneal_lr: bool = False
    """decay the learning rate linearly to 0 over total_timesteps"""
    gamma: float = 0.98
    """discount factor (tutorial 004: 0.99; 0.95 .. 0.99); 0.98 looks about 50 steps ahead"""
    reward_scale: float | None = None
    """rewards are multiplied by this for learning (logged returns are not); none = 1 - gamma
    (1 when gamma = 1): true values in [0, 1], targets near it (the tutorial normalizes returns)"""
    lam: float | None = None
    """none: n-step returns, A = R - V; in [0, 1]: GAE(lam) (Schulman et al. 2016; 0.9 .. 0.97)"""
    norm_adv: bool = True
    """normalize advantages to mean 0, std 1 over each rollout"""
    ent_coef: float = 0.01
    """entropy bonus weight (A3C: 0.01; 0 .. 0.05); keeps the policy from collapsing early"""
    vf_coef: float = 1.0
    """critic loss weight: the layer is shared, so this balances the two heads (0.25 .. 2)"""
    max_grad_norm: float = 0.5
    """clip the global gradient norm to this (0.5 .. 10; 0 = no clipping)"""
    hidden: int = 128
    """units in the shared hidden layer (tutorial 004: 128)"""
    running_reward_alpha: float = 0.05
    """tutorial 004's running reward: r <- alpha * episode_return + (1 - alpha) * r"""

    def __post_init__(self):
        super().__post_init__()  # the shared flags' checks
        cli.check_ranges(self, total_timesteps="> 0", num_envs="> 0", num_steps="> 0",
                         hidden="> 0", learning_rate="> 0", ent_coef=">= 0", vf_coef=">= 0",
                         max_grad_norm=">= 0", gamma="(0, 1]", lam="[0, 1] or none",
                         reward_scale="> 0 or none", running_reward_alpha="(0, 1]")
        batch = self.num_envs * self.num_steps
        cli.check(self.total_timesteps >= batch, f"--total-timesteps ({self.total_timesteps})"
                  f" is less than one rollout (num_envs x num_steps = {batch})")


# ==== Rollout buffer and loss =============================================================
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


def a2c_targets(model, rollout, next_obs, cfg):
    """Critic targets R_t and advantages A_t of one rollout, each (T, N)."""
    with torch.no_grad():  # targets are constants: no gradient flows into the bootstrap
        _, values = model(rollout["obs"])  # (T, N)
        # V(s_{t+1}) is the value of the next stored obs. After a done step that obs is the
        # episode's real final observation (the done step returned it), so a truncated step
        # bootstraps from it and a terminated one ignores it.
        _, last_value = model(torch.as_tensor(next_obs, dtype=torch.float32, device=values.device))
        next_values = torch.cat([values[1:], last_value[None]])  # (T, N)
        if cfg.lam is None:
            # R_t = r_t + gamma r_{t+1} + ... + gamma^k V(s_{t+k}): the n-step return up to
            # the rollout's end (Mnih et al. 2016, Algorithm S3), computed from t = T-1 down as
            # R_t = r_t + gamma * (1 - terminated_t) * (V(s_{t+1}) if truncated_t or t = T-1
            # else R_{t+1}); A_t = R_t - V(s_t), which is GAE below with lam = 1.
            returns = common.discounted_returns(rollout["rewards"], next_values,
                                                rollout["terminated"], rollout["truncated"],
                                                cfg.gamma)
            return returns, returns - values
        # TD error  delta_t = r_t + gamma * V(s_{t+1}) * (1 - terminated_t) - V(s_t)
        # GAE       A_t = delta_t + gamma * lam * (1 - done_t) * A_{t+1}, from t = T-1 down
        #           (Schulman et al. 2016, eq. 16; done = terminated or truncated); R_t = A_t + V
        advantages = common.gae(rollout["rewards"], values, next_values, rollout["terminated"],
                                rollout["truncated"], cfg.gamma, cfg.lam)
        return advantages + values, advantages


def a2c_loss(model, data, cfg):
    """The A2C loss on one batch `data` (obs, act, adv, ret). Returns (loss, stats for the log)."""
    obs, act, adv, ret = data["obs"], data["act"], data["adv"], data["ret"]
    logits, values = model(obs)
    dist = Categorical(logits=logits)  # pi(.|s)
    # Policy gradient: grad log pi(a_t|s_t) * A_t, ascended (Mnih et al. 2016, Algorithm S3);
    # we minimize its negative. A_t is a constant here: no gradient flows into it. Any V(s)
    # as the baseline leaves the expected gradient as it is: a weak critic makes it noisier,
    # not wrong (docs/why.md).
    loss_pi = -(dist.log_prob(act) * adv).mean()
    # Critic: (R_t - V(s_t))^2 (Algorithm S3), halved as is usual: plain MSE.
    loss_v = 0.5 * ((values - ret) ** 2).mean()
    # Entropy bonus H(pi(.|s)) = -sum_a pi log pi (Mnih et al. 2016, section 4): keeps exploring.
    entropy = dist.entropy().mean()
    # One loss, one backward: the shared layer learns from both heads, vf_coef weighing them.
    loss = loss_pi + cfg.vf_coef * loss_v - cfg.ent_coef * entropy
    # How well V fits its targets: 1 - Var(R - V) / Var(R) (1: exactly; 0: no better than their
    # mean); V and R themselves are kept for inside.png.
    explained = 1 - (ret - values).var() / ret.var().clamp_min(1e-8)
    return loss, dict(loss_pi=loss_pi.item(), loss_v=loss_v.item(), entropy=entropy.item(),
                      explained_var=explained.item(), values=values.detach(), ret=ret)


# progress.csv's columns, once: (progress-line format or None, picture label, CleanRL's tag)
LOGGED = dict(running_reward=("6.1f", "tutorial 004's running reward"),
              lr=(None, "learning rate", "charts/learning_rate"), loss_pi=("+.3f", "policy loss"),
              loss_v=(".2e", "value loss"), entropy=(".3f", "entropy of pi (nats)"),
              explained_var=(None, "1 - Var(R - V) / Var(R)", "losses/explained_variance"))
SMOKE = dict(total_timesteps=2048, stop_when_solved=False, eval_episodes=2)  # tests: seconds


def pictures(cfg):
    """curve.png: pi's entropy; inside.png (docs/inside.md): explained variance, V(s_t) vs R_t."""
    return dict(curve=[[plots.lines("entropy")]], inside=[[
        plots.lines("explained_var", ylim=(-1, 1.05), ylabel="explained variance of R by V",
                    title="explained variance: 1 - Var(R - V) / Var(R)"),
        plots.scatters("ret", "values", "target R_t", "V(s_t)")]])


# ==== Training ============================================================================
def train(cfg: Config):
    """Train A2C with `cfg`. Returns a dict: run_dir, solved, solved_step, global_step,
    episode_returns, eval_returns, greedy_returns, interrupted (report.finish_updates)."""
    # --- seeding and setup ---
    torch.manual_seed(cfg.seed)  # the networks' init and the sampled actions
    torch.set_num_threads(cfg.threads)  # also for reproducibility: threads change float sums
    device = torch.device("cuda" if cfg.cuda and torch.cuda.is_available() else "cpu")
    envs, next_obs, threshold = common.make_vec_env(cfg.env_id, cfg.num_envs, cfg.seed,
                                                    cfg.solved_return)
    obs_dim = int(envs.single_observation_space.shape[0])
    n_actions = int(envs.single_action_space.n)
    T, N = cfg.num_steps, cfg.num_envs
    buffer = RolloutBuffer(T, N, obs_dim)

    model = ActorCritic(obs_dim, n_actions, cfg.hidden).to(device)
    untrained = copy.deepcopy(model)  # before.gif and the maps: from these weights, at the end
    optimizer = torch.optim.Adam(model.parameters(), lr=cfg.learning_rate, eps=1e-5)
    num_updates = cfg.total_timesteps // (T * N)
    default_scale = 1 - cfg.gamma if cfg.gamma < 1 else 1.0
    reward_scale = cfg.reward_scale if cfg.reward_scale is not None else default_scale
    run = runlog.UpdateLog(SCRIPT, cfg, LOGGED)  # the run folder, progress.csv, progress lines
    play = report.sampled_and_greedy(lambda x: model(x)[0], device)  # checks, evaluations, GIF

    # In NEXT_STEP autoreset mode, the step after an episode ends is a reset step: its action
    # is ignored, its reward is 0, its obs the new episode's first. `autoreset` marks them.
    autoreset = np.zeros(N, dtype=bool)
    global_step, checked, stopped = 0, 0, False
    running_reward, alpha = 0.0, cfg.running_reward_alpha  # tutorial 004's smoothed return

    # Ctrl-C ends the loop; either way, model.pt and episodes.csv are saved as training left them
    with run.saving_model(dict(model=model), obs_dim=obs_dim, n_actions=n_actions):
        for update in range(1, num_updates + 1):
            if cfg.anneal_lr:  # lr_k = lr * (1 - (k - 1) / K): from lr at the first update toward 0
                frac = 1 - (update - 1) / num_updates
                optimizer.param_groups[0]["lr"] = cfg.learning_rate * frac

            # --- collect: T steps of N envs with the current policy ---
            for t in range(T):
                # obs = next_obs: the trap of every hand-written loop. The action (and its
                # value) belong to obs; next_obs is only where they led.
                obs = next_obs  # as the env gives it: no normalization (a simplification)
                with torch.no_grad():
                    logits, _ = model(torch.as_tensor(obs, dtype=torch.float32, device=device))
                action = Categorical(logits=logits).sample().cpu().numpy()  # a ~ pi(.|s), (N,)
                next_obs, reward, terminated, truncated, info = envs.step(action)
                global_step += N
                buffer.store(t, obs, action, reward_scale * reward, terminated, truncated,
                             valid=~autoreset)
                autoreset = terminated | truncated
                for ep_return in run.episodes_ended(info, global_step):  # tutorial 004's
                    running_reward = alpha * ep_return + (1 - alpha) * running_reward  # smoothing
                # Solved when the mean return of the last solved_window episodes reaches the
                # threshold; then pi as it is now must too (at most one check per update)
                if run.solved(threshold) and cfg.stop_when_solved and checked < update:
                    checked = update  # pi plays eval_episodes episodes: does it hold?
                    if stopped := report.pi_holds(play, cfg, threshold, global_step):
                        break
            if stopped:  # the partial rollout trains nothing; a last row says where it ended
                run.stopped_row(running_reward=running_reward, lr=optimizer.param_groups[0]["lr"])
                break

            # --- V of the whole rollout in one batch, then returns and advantages ---
            rollout = buffer.get_batch(device)  # (T, N, ...) tensors
            returns, advantages = a2c_targets(model, rollout, next_obs, cfg)  # (T, N) each

            # --- update: flatten (T, N) to one batch `data`, dropping the autoreset steps ---
            keep = rollout["valid"].reshape(-1)
            data = {key: x.flatten(0, 1)[keep] for key, x in dict(
                obs=rollout["obs"], act=rollout["actions"], adv=advantages, ret=returns).items()}
            if cfg.norm_adv:  # A to mean 0, std 1 over the batch
                adv = data["adv"]
                data["adv"] = (adv - adv.mean()) / (adv.std(unbiased=False) + 1e-8)
            # One gradient step on the whole batch: A2C uses each transition once.
            loss, stats = a2c_loss(model, data, cfg)
            optimizer.zero_grad()
            loss.backward()
            if cfg.max_grad_norm > 0:
                nn.utils.clip_grad_norm_(model.parameters(), cfg.max_grad_norm)
            optimizer.step()
            with torch.no_grad():  # nan or inf anywhere: stop, in one line
                outputs = model(torch.as_tensor(next_obs, dtype=torch.float32, device=device))
            runlog.stop_if_diverged(global_step, stats, (model,), run.dir, outputs)
            run.update(stats, visited=data["obs"], running_reward=running_reward,
                       lr=optimizer.param_groups[0]["lr"])
    envs.close()
    nets = {when: (lambda x, net=net: net(x)[0], lambda x, net=net: net(x)[1])  # for the maps:
            for when, net in (("untrained", untrained), ("trained", model))}  # obs -> pi, V
    before = report.sampled_and_greedy(nets["untrained"][0], device)  # before.gif
    return report.finish_updates(run, threshold, play, before, pictures(cfg),
                                 cartpole_env.maps(cfg, nets, device, run.visited, reward_scale))


def main(argv=None):
    """python actor_critic_cartpole.py [flags]: train (then --watch), or --eval a saved model."""
    cfg = cli.parse_config(Config, argv, description=__doc__.split("\n\n")[0])
    with cli.clear_exit():  # bad input: one line, exit 2; Ctrl-C: one line, exit 130
        saved = cfg.eval or report.saved_model(train(cfg))  # after a Ctrl-C: exit 130
        if cfg.eval or cfg.watch:  # play the saved policy (in a window with --watch)
            model, env_id = checkpoints.load_model(saved, SCRIPT, "model", lambda ckpt: (
                ActorCritic(ckpt["obs_dim"], ckpt["n_actions"], ckpt["config"]["hidden"])))
            report.play(cfg, saved, env_id, report.sampled_and_greedy(lambda x: model(x)[0], "cpu"))


if __name__ == "__main__":
    main()
