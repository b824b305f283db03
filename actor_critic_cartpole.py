"""Advantage actor-critic (A2C) on CartPole-v1 (Mnih et al. 2016, "Asynchronous Methods for Deep RL").

Read beside tutorial 004, which trains a Keras actor-critic one whole episode at
a time. Same model (a shared hidden layer feeding an actor head and a critic
head), same Huber critic loss, same running reward and before/after GIFs; what
changes is how often it learns. A2C updates every num_steps steps of
num_envs envs, with n-step returns bootstrapped from the critic, instead of
waiting for an episode to end. The loop, top to bottom:

    collect  num_steps x num_envs transitions with the current policy
    returns  advantages A_t by GAE(lambda) (common.gae), bootstrapped from V at the
             rollout's end and at time-limit truncations; with lam = 1 this is A3C's
             n-step advantage R_t - V(s_t). Critic targets R_t = A_t + V(s_t)
    update   one pass over the rollout in num_minibatches random minibatches, one gradient step
             on -log pi(a|s) * A + c_v * Huber(V, R) - c_e * entropy for each: every transition
             is used once (PPO reuses each one for many epochs, behind its clip)
    log      one progress.csv row per update; a progress line now and then

    python actor_critic_cartpole.py                  # train until solved
    python actor_critic_cartpole.py --help           # every hyperparameter, with its meaning
    python actor_critic_cartpole.py --eval runs/<run>/model.pt --watch   # replay in a window
"""

from __future__ import annotations

import copy
import time
from collections import deque
from dataclasses import asdict, dataclass

import numpy as np
import torch
import torch.nn as nn
import torch.nn.functional as F
from torch.distributions import Categorical

import common

# torch.distributions checks its arguments on every call; in this loop the
# checks cost more than the network itself, and our inputs are always valid.
torch.distributions.Distribution.set_default_validate_args(False)


@dataclass
class Config:
    # --- experiment ---
    env_id: str = "CartPole-v1"
    """gymnasium id of an env with a Box observation and Discrete actions"""
    seed: int = 0
    """seeds python, numpy, torch and the envs: same seed, same machine => same progress.csv"""
    total_timesteps: int = 200_000
    """budget of env steps (all envs together); training usually stops long before, once solved"""
    stop_when_solved: bool = True
    """stop as soon as the mean return of the last 20 finished episodes reaches the solved return"""
    solved_return: float | None = None
    """the return that counts as solved; none = the env's reward_threshold (475 for CartPole-v1)"""

    # --- collection ---
    num_envs: int = 2
    """parallel envs (A3C's parallel actors, here in lockstep)"""
    num_steps: int = 256
    """steps per env between updates, the n of the n-step return (A3C: 5 .. 20; long rollouts carry
    CartPole's sparse signal, failure, back further with each update)"""
    num_minibatches: int = 8
    """the rollout is split into this many random minibatches, one gradient step each, every transition
    used once (1 = the classic A2C single step per rollout; A3C's actors each applied their own gradient)"""

    # --- A2C ---
    learning_rate: float = 0.0035
    """Adam step size (tutorial 004: 0.01, one step per episode; A2C usually 7e-4 .. 1e-2)"""
    anneal_lr: bool = False
    """decay the learning rate linearly to 0 over total_timesteps"""
    gamma: float = 0.99
    """discount factor (tutorial 004: 0.99)"""
    lam: float = 1.0
    """GAE lambda: 1 = A3C's n-step return minus V (no bias from V inside the rollout), lower = less variance"""
    norm_adv: bool = True
    """normalize advantages to mean 0, std 1 in each batch (tutorial 004 normalizes its returns, to the same end)"""
    ent_coef: float = 0.01
    """entropy bonus weight (A3C: 0.01); keeps the policy from collapsing early"""
    vf_coef: float = 1.0
    """critic loss weight: the trunk is shared, so this balances the two heads' gradients"""
    reward_scale: float | None = None
    """rewards are multiplied by this for learning (returns are logged unscaled); none = 1 - gamma, which
    keeps V in [0, 1], so the critic's errors cannot swamp the shared layer (the tutorial normalizes returns)"""
    huber_delta: float = 1.0
    """the critic's Huber loss is quadratic within delta of the target, linear beyond (Keras default: 1)"""
    max_grad_norm: float = 0.5
    """clip the global gradient norm to this"""
    hidden: int = 128
    """units in the shared hidden layer (tutorial 004: 128)"""
    running_reward_alpha: float = 0.05
    """tutorial 004's running reward: r <- alpha * episode_return + (1 - alpha) * r"""

    # --- output ---
    run_dir: str = "runs"
    """parent folder of the run folder <script>__<env>__seed<k>__<time>/"""
    print_every: int = 10
    """print a progress line every this many updates"""
    gifs: bool = True
    """write before.gif (untrained policy) and after.gif (trained policy) to the run folder"""
    eval_episodes: int = 10
    """greedy episodes played after training (and by --eval)"""
    eval_seed: int = 10_000
    """seed of the evaluation env, kept apart from the training seeds"""
    watch: bool = False
    """after training (or with --eval), play the policy in a pygame window"""
    eval: str | None = None
    """path of a saved model.pt: skip training, play eval_episodes greedy episodes and print their returns"""
    threads: int = 1
    """torch CPU threads. 1 is fastest here: for networks this small, waking a second thread for every op
    costs more than it saves (5x slower with 2 threads while another program is busy)"""
    cuda: bool = False
    """train on the GPU if there is one (CartPole's tiny network is faster on the CPU)"""

    def __post_init__(self):
        for name in ("total_timesteps", "num_envs", "num_steps", "num_minibatches", "hidden", "print_every",
                     "eval_episodes", "threads", "learning_rate", "huber_delta"):
            common.check(getattr(self, name) > 0, f"--{name.replace('_', '-')} must be positive, got {getattr(self, name)}")
        for name in ("ent_coef", "vf_coef", "max_grad_norm"):
            common.check(getattr(self, name) >= 0, f"--{name.replace('_', '-')} must be >= 0, got {getattr(self, name)}")
        common.check(0 < self.gamma <= 1, f"--gamma must be in (0, 1], got {self.gamma}")
        common.check(0 <= self.lam <= 1, f"--lam must be in [0, 1], got {self.lam}")
        common.check(self.reward_scale is None or self.reward_scale > 0,
                     f"--reward-scale must be positive or none, got {self.reward_scale}")
        common.check(0 < self.running_reward_alpha <= 1,
                     f"--running-reward-alpha must be in (0, 1], got {self.running_reward_alpha}")
        common.check(self.num_envs * self.num_steps >= self.num_minibatches,
                     f"--num-minibatches ({self.num_minibatches}) exceeds the batch size ({self.num_envs * self.num_steps})")


# =============================================================================
# Network
# =============================================================================


def layer_init(layer, gain=np.sqrt(2)):
    """Orthogonal weights, zero bias: the init of the A2C/PPO reference code (baselines)."""
    nn.init.orthogonal_(layer.weight, gain)
    nn.init.zeros_(layer.bias)
    return layer


class ActorCritic(nn.Module):
    """Tutorial 004's model: one shared hidden layer, `common`, feeding two heads.

        obs -> common (Linear + ReLU) -> actor:  logits of pi(a|s)   (tutorial: `action`, with softmax)
                                      -> critic: V(s)
    """

    def __init__(self, obs_dim, n_actions, hidden):
        super().__init__()
        self.common = layer_init(nn.Linear(obs_dim, hidden))
        self.actor = layer_init(nn.Linear(hidden, n_actions), gain=0.01)  # small: the first policy is near uniform
        self.critic = layer_init(nn.Linear(hidden, 1), gain=1.0)

    def forward(self, obs):
        h = F.relu(self.common(obs))
        return self.actor(h), self.critic(h).squeeze(-1)  # (B, n_actions), (B,): squeeze so V never broadcasts against (B,) targets


# =============================================================================
# Rollout buffer and loss
# =============================================================================


class RolloutBuffer:
    """num_steps x num_envs transitions, stored as (T, N, ...) tensors."""

    def __init__(self, T, N, obs_dim, device):
        self.obs = torch.zeros(T, N, obs_dim, device=device)
        self.actions = torch.zeros(T, N, dtype=torch.long, device=device)
        self.rewards = torch.zeros(T, N, device=device)
        self.terminated = torch.zeros(T, N, dtype=torch.bool, device=device)
        self.truncated = torch.zeros(T, N, dtype=torch.bool, device=device)
        # False where the step was a vector-env autoreset step (see the loop).
        self.valid = torch.ones(T, N, dtype=torch.bool, device=device)

    def store(self, t, obs, action, reward, terminated, truncated, valid):
        self.obs[t], self.actions[t] = obs, action
        self.rewards[t] = torch.as_tensor(reward)
        self.terminated[t] = torch.as_tensor(terminated)
        self.truncated[t] = torch.as_tensor(truncated)
        self.valid[t] = torch.as_tensor(valid)


def a2c_targets(model, buffer, next_obs, cfg):
    """Advantages and critic targets for one rollout, flattened to its real transitions.

    Returns (obs, actions, advantages, returns), each with one row per valid step."""
    T, N = buffer.actions.shape
    with torch.no_grad():  # targets are constants: no gradient flows into the bootstrap
        # One forward pass over the rollout plus the observation after it: V(s_0 .. s_T).
        _, values = model(torch.cat([buffer.obs, next_obs[None]]))  # (T+1, N)
        # V(s_{t+1}) is the value of the next stored obs. After a done step that obs is the
        # episode's real final observation (the reset step reports it), so a truncated step
        # bootstraps from it and a terminated one ignores it (common.gae).
        next_values = values[1:]  # (T, N)
        # With lam = 1: A_t = R_t - V(s_t), R_t = r_t + gamma r_{t+1} + ... + gamma^k V(s_{t+k}), the n-step
        # return up to the rollout's end (Mnih et al. 2016, Algorithm S3). lam < 1 is GAE (Schulman et al. 2016, eq. 16).
        advantages = common.gae(buffer.rewards, values[:T], next_values, buffer.terminated, buffer.truncated,
                                cfg.gamma, cfg.lam)  # (T, N)
        returns = advantages + values[:T]  # critic targets (T, N)
    keep = buffer.valid  # drop the autoreset steps: their transition is not real
    adv = advantages[keep]
    if cfg.norm_adv:  # over the whole rollout, before it is split into minibatches
        adv = (adv - adv.mean()) / (adv.std(unbiased=False) + 1e-8)
    return buffer.obs[keep], buffer.actions[keep], adv, returns[keep]


def a2c_loss(model, obs, actions, advantages, returns, cfg):
    """The A2C loss on a batch of transitions. Returns (loss, stats)."""
    logits, values = model(obs)
    log_probs = torch.log_softmax(logits, dim=-1)  # log pi(.|s), (B, A)
    logp = log_probs.gather(-1, actions.unsqueeze(-1)).squeeze(-1)  # log pi(a|s), (B,)
    # Policy gradient: grad log pi(a_t|s_t) * A_t  (Mnih et al. 2016, section 4); we minimize its negative.
    loss_pi = -(logp * advantages).mean()
    # Critic: Huber loss between V(s_t) and R_t, as in tutorial 004 (less sensitive to outlier returns than MSE).
    loss_v = F.huber_loss(values, returns, delta=cfg.huber_delta)
    # Entropy bonus H(pi(.|s)) = -sum_a pi log pi  (Mnih et al. 2016, section 4), keeps exploring.
    entropy = -(log_probs.exp() * log_probs).sum(-1).mean()
    loss = loss_pi + cfg.vf_coef * loss_v - cfg.ent_coef * entropy
    return loss, dict(loss_pi=loss_pi.detach(), loss_v=loss_v.detach(), entropy=entropy.detach())


# =============================================================================
# Training
# =============================================================================


def greedy(model, device):
    """obs -> the most probable action; for evaluation and GIFs."""
    def act(obs):
        with torch.no_grad():
            return int(model(torch.as_tensor(obs, dtype=torch.float32, device=device))[0].argmax())
    return act


def train(cfg: Config):
    """Train A2C with `cfg`. Returns a dict: run_dir, solved, global_step,
    solved_step (or None), episode_returns (all finished training episodes) and
    eval_returns (greedy episodes after training)."""
    start_time = time.time()
    # --- seeding and setup ---
    common.seed_everything(cfg.seed)
    torch.set_num_threads(cfg.threads)  # also part of reproducibility: the thread count changes float sums
    device = common.pick_device(cfg.cuda)
    envs, next_obs = common.make_vec_env(cfg.env_id, cfg.num_envs, cfg.seed)
    common.require_discrete(cfg.env_id, envs.single_action_space)
    threshold = common.solve_threshold(cfg.env_id, cfg.solved_return)
    obs_dim, n_actions = int(envs.single_observation_space.shape[0]), int(envs.single_action_space.n)
    run_dir = common.make_run_dir(cfg.run_dir, __file__, cfg.env_id, cfg.seed)
    print(f"run folder: {run_dir}", flush=True)

    model = ActorCritic(obs_dim, n_actions, cfg.hidden).to(device)
    untrained = copy.deepcopy(model)  # before.gif is drawn from these weights after training
    # common.Adam is torch.optim.Adam's update without its 1-second first-use import (see its docstring).
    optimizer = common.Adam(model.parameters(), lr=cfg.learning_rate, eps=1e-5)
    T, N = cfg.num_steps, cfg.num_envs
    buffer = RolloutBuffer(T, N, obs_dim, device)
    reward_scale = cfg.reward_scale if cfg.reward_scale is not None else 1 - cfg.gamma
    num_updates = cfg.total_timesteps // (T * N)

    # --- episode bookkeeping ---
    ep_return = np.zeros(N)
    episode_returns = []  # every finished training episode, in order
    last20 = deque(maxlen=20)
    running_reward = 0.0  # tutorial 004's smoothed episode return
    # In NEXT_STEP autoreset mode, the step after an episode ends is a reset
    # step: its action is ignored, its reward is 0 and the obs it returns is
    # the first of the new episode. `autoreset` marks envs whose next step is one.
    autoreset = np.zeros(N, dtype=bool)
    global_step, solved_step, update, interrupted = 0, None, 0, False
    next_obs = torch.as_tensor(next_obs, dtype=torch.float32, device=device)

    try:
        for update in range(1, num_updates + 1):
            if cfg.anneal_lr:
                optimizer.param_groups[0]["lr"] = cfg.learning_rate * (1 - (update - 1) / num_updates)

            # --- collect: T steps of N envs with the current policy ---
            for t in range(T):
                # obs = next_obs: the trap of every hand-written loop. The action (and its
                # value) belong to obs; next_obs is only where they led.
                obs = next_obs
                with torch.no_grad():
                    action = Categorical(logits=model(obs)[0]).sample()
                next_obs, reward, terminated, truncated, _ = envs.step(action.cpu().numpy())
                global_step += N
                buffer.store(t, obs, action, reward_scale * reward, terminated, truncated, valid=~autoreset)
                next_obs = torch.as_tensor(next_obs, dtype=torch.float32, device=device)

                ep_return += reward
                done = terminated | truncated
                for i in np.flatnonzero(done):
                    episode_returns.append(ep_return[i])
                    last20.append(ep_return[i])
                    running_reward = cfg.running_reward_alpha * ep_return[i] + (1 - cfg.running_reward_alpha) * running_reward
                ep_return[done | autoreset] = 0.0  # the reset step's reward (0) starts no episode
                autoreset = done
                if solved_step is None and len(last20) == last20.maxlen and np.mean(last20) >= threshold:
                    solved_step = global_step
                    print(f"solved: mean return of the last 20 episodes {np.mean(last20):.1f} >= {threshold:g} "
                          f"at step {global_step} (episode {len(episode_returns)}) after {time.time() - start_time:.1f}s",
                          flush=True)
                    if cfg.stop_when_solved:
                        break
            if solved_step is not None and cfg.stop_when_solved:
                break  # done: the partial rollout is not used for an update
            # --- update: one pass over the rollout, one gradient step per minibatch ---
            # Each transition is used once. After the first step the policy has moved a little
            # from the one that acted, as A3C's parameters moved between an actor's rollout and
            # its gradient landing; no correction is made for it (PPO's ratio and clip do that).
            obs_b, actions_b, adv_b, returns_b = a2c_targets(model, buffer, next_obs, cfg)
            for mb in torch.randperm(len(adv_b), device=device).chunk(cfg.num_minibatches):
                loss, stats = a2c_loss(model, obs_b[mb], actions_b[mb], adv_b[mb], returns_b[mb], cfg)
                optimizer.zero_grad()
                loss.backward()
                nn.utils.clip_grad_norm_(model.parameters(), cfg.max_grad_norm, foreach=True)
                optimizer.step()
            stats = {k: v.item() for k, v in stats.items()}  # of the last minibatch

            # --- logging ---
            mean20 = float(np.mean(last20)) if last20 else float("nan")
            common.append_csv(run_dir / "progress.csv", dict(
                global_step=global_step, episodes=len(episode_returns), return_mean20=mean20,
                running_reward=running_reward,
                lr=optimizer.param_groups[0]["lr"], **stats))
            if update % cfg.print_every == 0 or update == 1:
                elapsed = time.time() - start_time
                eta = elapsed / global_step * (cfg.total_timesteps - global_step)
                print(f"step {global_step:>7}  {global_step / elapsed:6.0f} steps/s  running reward {running_reward:6.1f}  "
                      f"return(20) {mean20:6.1f}  episodes {len(episode_returns):5d}  loss_pi {stats['loss_pi']:+.3f}  "
                      f"loss_v {stats['loss_v']:.2e}  entropy {stats['entropy']:.3f}  "
                      f"{common.format_time(elapsed)} (eta {common.format_time(eta)})",
                      flush=True)
    except KeyboardInterrupt:
        interrupted = True
        print("\ninterrupted: saving the model and the logs", flush=True)
    finally:
        envs.close()
        common.save_checkpoint(dict(model=model.state_dict(), config=asdict(cfg),
                                    obs_dim=obs_dim, n_actions=n_actions, global_step=global_step),
                               run_dir / "model.pt")

    result = dict(run_dir=run_dir, solved=solved_step is not None, solved_step=solved_step,
                  global_step=global_step, episode_returns=episode_returns, eval_returns=[],
                  interrupted=interrupted)
    if interrupted:
        return result
    print(f"trained {global_step} steps, {len(episode_returns)} episodes in {time.time() - start_time:.1f}s; "
          f"model: {run_dir / 'model.pt'}", flush=True)

    # --- after training: greedy evaluation and GIFs ---
    result["eval_returns"] = common.evaluate(cfg.env_id, greedy(model, device), cfg.eval_episodes, cfg.eval_seed)
    print(f"greedy evaluation over {cfg.eval_episodes} episodes: mean {np.mean(result['eval_returns']):.1f}, "
          f"min {min(result['eval_returns']):.0f}", flush=True)
    if cfg.gifs:
        common.before_after_gifs(cfg.env_id, run_dir, greedy(untrained, device), greedy(model, device), cfg.eval_seed,
                                 every=2, scale=2)  # every 2nd frame at half size: small files
    return result


def play(cfg: Config):
    """--eval PATH: load a saved model and play cfg.eval_episodes greedy episodes."""
    ckpt = common.load_checkpoint(cfg.eval, required=("model", "obs_dim", "n_actions", "config"))
    model = ActorCritic(ckpt["obs_dim"], ckpt["n_actions"], ckpt["config"]["hidden"])
    common.load_weights(model, ckpt["model"], cfg.eval)
    env_id = ckpt["config"]["env_id"]
    returns = common.evaluate(env_id, greedy(model, "cpu"), cfg.eval_episodes, cfg.eval_seed,
                              render_mode="human" if cfg.watch else None)
    print(f"{env_id}, {cfg.eval}: returns {[round(r) for r in returns]}, mean {np.mean(returns):.1f}", flush=True)
    return returns


def main(argv=None):
    """Parse the flags into a Config, then --eval, or train (and --watch); see common.main."""
    common.main(Config, train, play, argv, description=__doc__.split("\n")[0])


if __name__ == "__main__":
    main()
