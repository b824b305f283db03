"""PPO-penalty on CartPole-v1: the adaptive KL penalty of Schulman et al. 2017, section 4.

Tutorial 001 calls it PPO1: instead of clipping the ratio (PPO2, ppo_cartpole.py),
it subtracts beta * KL(pi_old || pi) from the surrogate and adapts beta after
every update so that the KL stays near a target d_targ. This script is
ppo_cartpole.py with that loss and that rule, and nothing else changed:
`diff ppo_cartpole.py ppo_kl_cartpole.py` shows the config, the policy loss
and the beta update. The loop, top to bottom:

    collect  num_steps x num_envs transitions with the current policy
    GAE      advantages A_t and value targets R_t = A_t + V(s_t)   (common.gae)
    update   a few epochs of shuffled minibatches on the KL-penalized surrogate
    beta     halve or double beta, from the mean KL of the update
    log      one progress.csv row per update; a progress line now and then

    python ppo_kl_cartpole.py                  # train until solved, ~3 s on a laptop CPU
    python ppo_kl_cartpole.py --help           # every hyperparameter, with its meaning
    python ppo_kl_cartpole.py --eval runs/<run>/model.pt --watch   # replay in a window
"""

from __future__ import annotations

import copy
import time
from collections import deque
from dataclasses import asdict, dataclass

import numpy as np
import torch
import torch.nn as nn

import common


@dataclass
class Config:
    # --- experiment ---
    env_id: str = "CartPole-v1"
    """gymnasium id of an env with a Box observation and Discrete actions"""
    seed: int = 0
    """seeds python, numpy, torch and the envs: same seed, same machine => same progress.csv"""
    total_timesteps: int = 100_000
    """budget of env steps (all envs together); training usually stops long before, once solved"""
    stop_when_solved: bool = True
    """stop as soon as the mean return of the last 20 finished episodes reaches the solved return"""
    solved_return: float | None = None
    """the return that counts as solved; none = the env's reward_threshold (475 for CartPole-v1)"""

    # --- collection ---
    num_envs: int = 8
    """parallel envs in the vector env; more envs = more diverse batches, fewer updates per env step"""
    num_steps: int = 32
    """steps per env per rollout; the batch is num_envs * num_steps transitions (here 256)"""

    # --- PPO ---
    learning_rate: float = 4e-3
    """Adam step size for both networks (PPO: 3e-4 .. 3e-3 is usual; CartPole takes more)"""
    anneal_lr: bool = True
    """decay the learning rate linearly to 0 over total_timesteps"""
    gamma: float = 0.99
    """discount factor; 0.98 .. 0.999. 0.99 looks ~100 steps ahead"""
    reward_scale: float = 0.05
    """rewards are multiplied by this for learning (returns are logged unscaled): discounted returns near
    100 become near 5, targets V reaches within a few Adam steps, so the advantages are useful sooner
    (1.0 = off; PPO-clip then took 40% more steps to solve, median of seeds 0-29)"""
    lam: float = 0.95
    """GAE lambda: 0 = one-step TD advantages (low variance), 1 = Monte Carlo (no bias); usually 0.8 .. 0.97"""
    update_epochs: int = 10
    """passes over each batch (tutorial 000 uses 10)"""
    num_minibatches: int = 4
    """minibatches per epoch; minibatch size = batch / num_minibatches"""
    norm_adv: bool = True
    """normalize advantages to mean 0, std 1 within each minibatch"""
    d_targ: float = 0.01
    """target KL(pi_old || pi) per update; the paper tries 0.003, 0.01 and 0.03"""
    beta_init: float = 1.0
    """initial KL penalty coefficient beta; the rule adapts it within a few updates (paper: "not important")"""
    kl_tolerance: float = 1.5
    """beta changes only when the KL leaves [d_targ / 1.5, d_targ * 1.5] (the paper's 1.5)"""
    beta_factor: float = 2.0
    """beta is halved or doubled (the paper's 2)"""
    ent_coef: float = 0.0
    """entropy bonus weight c2 (eq. 9); 0 .. 0.01. CartPole explores enough without it"""
    vf_coef: float = 0.5
    """value loss weight c1 (eq. 9)"""
    max_grad_norm: float = 0.5
    """clip the global gradient norm of both networks to this"""
    hidden: int = 64
    """units in each of the two hidden layers of both networks"""

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
    """train on the GPU if there is one (CartPole's tiny networks are faster on the CPU)"""

    def __post_init__(self):
        for name in ("total_timesteps", "num_envs", "num_steps", "update_epochs", "num_minibatches", "hidden",
                     "print_every", "eval_episodes", "threads", "learning_rate", "reward_scale", "d_targ", "beta_init"):
            common.check(getattr(self, name) > 0, f"--{name.replace('_', '-')} must be positive, got {getattr(self, name)}")
        for name in ("ent_coef", "vf_coef", "max_grad_norm"):
            common.check(getattr(self, name) >= 0, f"--{name.replace('_', '-')} must be >= 0, got {getattr(self, name)}")
        common.check(0 < self.gamma <= 1, f"--gamma must be in (0, 1], got {self.gamma}")
        common.check(0 <= self.lam <= 1, f"--lam must be in [0, 1], got {self.lam}")
        common.check(self.kl_tolerance > 1, f"--kl-tolerance must be > 1, got {self.kl_tolerance}")
        common.check(self.beta_factor > 1, f"--beta-factor must be > 1, got {self.beta_factor}")
        common.check(self.num_envs * self.num_steps >= self.num_minibatches,
                     f"--num-minibatches ({self.num_minibatches}) exceeds the batch size ({self.num_envs * self.num_steps})")


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
        return self.net(obs).squeeze(-1)  # (B, 1) -> (B,): a stray (B, 1) would broadcast against (B,) targets


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
        # False where the step was a vector-env autoreset step (see the loop).
        self.valid = np.ones((T, N), dtype=bool)

    def store(self, t, obs, action, reward, terminated, truncated, valid):
        self.obs[t], self.actions[t], self.rewards[t] = obs, action, reward
        self.terminated[t], self.truncated[t], self.valid[t] = terminated, truncated, valid

    def get_batch(self, device):
        """Every field as a tensor on `device`, still shaped (T, N, ...)."""
        return {name: torch.as_tensor(array, device=device) for name, array in vars(self).items()}


def exact_kl(log_probs_old, log_probs):
    """KL(pi_old || pi) per state, exactly: sum_a pi_old(a|s) * (log pi_old(a|s) - log pi(a|s)).

    Both arguments are log-probabilities of every action, shaped (B, n_actions);
    with few discrete actions the sum is cheap, so no sample estimate is needed.
    """
    return (log_probs_old.exp() * (log_probs_old - log_probs)).sum(-1)  # (B,)


def compute_loss_pi(policy, obs, act, adv, logp_old, log_probs_old, beta):
    """KL-penalized surrogate loss. Returns (loss_pi, log pi(.|s))."""
    log_probs = torch.log_softmax(policy(obs), dim=-1)  # log pi(.|s), (B, n_actions)
    logp = log_probs.gather(1, act.unsqueeze(1)).squeeze(1)  # log pi(a|s) of the taken actions, (B,)
    ratio = torch.exp(logp - logp_old)  # r_t = pi(a|s) / pi_old(a|s)
    # L_KLPEN = E[r*A - beta * KL(pi_old(.|s), pi(.|s))]  (Schulman et al. 2017, eq. 8); we minimize -L_KLPEN.
    loss_pi = -(ratio * adv).mean() + beta * exact_kl(log_probs_old, log_probs).mean()
    return loss_pi, log_probs


def adapt_beta(beta, d, cfg):
    """The paper's rule after each policy update (Schulman et al. 2017, section 4), d = mean KL:

        d < d_targ / 1.5  ->  beta / 2    (pi barely moved: penalize less)
        d > d_targ * 1.5  ->  beta * 2    (pi moved too far: penalize more)
    """
    if d < cfg.d_targ / cfg.kl_tolerance:
        return beta / cfg.beta_factor
    if d > cfg.d_targ * cfg.kl_tolerance:
        return beta * cfg.beta_factor
    return beta


def compute_loss_v(value_net, obs, ret):
    """L_VF = E[(V(s_t) - R_t)^2]  (Schulman et al. 2017, eq. 9), halved as is usual."""
    return 0.5 * ((value_net(obs) - ret) ** 2).mean()


@torch.no_grad()
def policy_shift(policy, obs, log_probs_old):
    """How far pi has moved from pi_old on the whole batch: the mean exact KL (the paper's d), and the entropy."""
    log_probs = torch.log_softmax(policy(obs), dim=-1)
    return dict(kl=exact_kl(log_probs_old, log_probs).mean().item(),
                entropy=-(log_probs.exp() * log_probs).sum(-1).mean().item())


def ppo_update(policy, value_net, optimizer, b_obs, b_act, b_logp, b_log_probs_old, b_adv, b_ret, beta, cfg):
    """update_epochs passes of shuffled minibatches over one batch. Returns stats for the log.

    b_log_probs_old is pi_old in full, (B, n_actions): every action's log-probability, for the exact KL.
    """
    params = list(policy.parameters()) + list(value_net.parameters())
    batch_size = b_obs.shape[0]
    mb_size = max(batch_size // cfg.num_minibatches, 1)
    losses_pi, losses_v = [], []
    for epoch in range(cfg.update_epochs):
        order = torch.randperm(batch_size, device=b_obs.device)
        for start in range(0, batch_size - mb_size + 1, mb_size):
            mb = order[start:start + mb_size]  # this minibatch's rows of the batch
            mb_obs, mb_adv = b_obs[mb], b_adv[mb]
            if cfg.norm_adv:
                mb_adv = (mb_adv - mb_adv.mean()) / (mb_adv.std(unbiased=False) + 1e-8)
            loss_pi, log_probs = compute_loss_pi(policy, mb_obs, b_act[mb], mb_adv, b_logp[mb],
                                                 b_log_probs_old[mb], beta)
            loss_v = compute_loss_v(value_net, mb_obs, b_ret[mb])
            # L = L_KLPEN - c1 * L_VF + c2 * S[pi], maximized  (Schulman et al. 2017, eq. 9 with L_KLPEN for L_CLIP).
            # The networks are separate, so c1 only matters through the shared gradient clip.
            loss = loss_pi + cfg.vf_coef * loss_v
            if cfg.ent_coef > 0:  # skipped at 0: "- 0 * entropy" would still cost a backward pass
                entropy = -(log_probs.exp() * log_probs).sum(-1).mean()  # S = -sum_a pi(a|s) log pi(a|s)
                loss = loss - cfg.ent_coef * entropy

            optimizer.zero_grad()
            loss.backward()
            nn.utils.clip_grad_norm_(params, cfg.max_grad_norm, foreach=True)
            optimizer.step()
            losses_pi.append(loss_pi.detach())
            losses_v.append(loss_v.detach())
    shift = policy_shift(policy, b_obs, b_log_probs_old)  # d, how far this update moved pi
    return dict(loss_pi=torch.stack(losses_pi).mean().item(), loss_v=torch.stack(losses_v).mean().item(),
                epochs=epoch + 1, **shift)


# =============================================================================
# Training
# =============================================================================


def greedy(policy, device):
    """obs -> the most probable action; for evaluation and GIFs."""
    def act(obs):
        with torch.no_grad():
            return int(policy(torch.as_tensor(obs, dtype=torch.float32, device=device)).argmax())
    return act


def train(cfg: Config):
    """Train PPO-penalty with `cfg`. Returns a dict: run_dir, solved, global_step,
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

    policy = PolicyNetwork(obs_dim, n_actions, cfg.hidden).to(device)
    value_net = ValueNetwork(obs_dim, cfg.hidden).to(device)
    untrained = copy.deepcopy(policy)  # before.gif is drawn from these weights after training
    # common.Adam is torch.optim.Adam's update without its 1-second first-use import (see its docstring).
    optimizer = common.Adam([*policy.parameters(), *value_net.parameters()], lr=cfg.learning_rate, eps=1e-5)
    T, N = cfg.num_steps, cfg.num_envs
    buffer = RolloutBuffer(T, N, obs_dim)
    num_updates = cfg.total_timesteps // (T * N)

    # --- episode bookkeeping ---
    ep_return = np.zeros(N)
    episode_returns = []  # every finished training episode, in order
    last20 = deque(maxlen=20)
    # In NEXT_STEP autoreset mode, the step after an episode ends is a reset
    # step: its action is ignored, its reward is 0 and the obs it returns is
    # the first of the new episode. `autoreset` marks envs whose next step is one.
    autoreset = np.zeros(N, dtype=bool)
    global_step, solved_step, update, interrupted = 0, None, 0, False
    beta = cfg.beta_init

    try:
        for update in range(1, num_updates + 1):
            if cfg.anneal_lr:
                optimizer.param_groups[0]["lr"] = cfg.learning_rate * (1 - (update - 1) / num_updates)

            # --- collect: T steps of N envs with the current policy (pi_old) ---
            for t in range(T):
                # obs = next_obs: the trap of every hand-written loop. The action (and its
                # value) belong to obs; next_obs is only where they led.
                obs = next_obs
                with torch.no_grad():
                    probs = torch.softmax(policy(torch.as_tensor(obs, dtype=torch.float32, device=device)), dim=-1)
                # a ~ pi(.|s): what Categorical(probs).sample() does, without building a distribution
                # object at every step (its log-probs are computed for the whole batch below).
                action = torch.multinomial(probs, 1).squeeze(1).cpu().numpy()  # (N,)
                next_obs, reward, terminated, truncated, _ = envs.step(action)
                global_step += N
                buffer.store(t, obs, action, cfg.reward_scale * reward, terminated, truncated, valid=~autoreset)

                ep_return += reward
                done = terminated | truncated
                for i in np.flatnonzero(done):
                    episode_returns.append(ep_return[i])
                    last20.append(ep_return[i])
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
            # --- pi_old and V of the whole rollout in one batch, then advantages ---
            rollout = buffer.get_batch(device)  # (T, N, ...) tensors
            with torch.no_grad():
                # log pi_old(a|s): the policy has not changed since it chose these actions.
                log_probs = torch.log_softmax(policy(rollout["obs"]), dim=-1)  # (T, N, n_actions)
                logp_old = log_probs.gather(-1, rollout["actions"].unsqueeze(-1)).squeeze(-1)  # (T, N)
                values = value_net(rollout["obs"])  # (T, N)
                # V(s_{t+1}) is the value of the next stored obs. After a done step that obs is
                # the episode's real final observation (the reset step reports it), so a
                # truncated step bootstraps from it and a terminated one ignores it (common.gae).
                last_value = value_net(torch.as_tensor(next_obs, dtype=torch.float32, device=device))  # (N,)
                next_values = torch.cat([values[1:], last_value[None]])  # (T, N)
                advantages = common.gae(rollout["rewards"], values, next_values, rollout["terminated"],
                                        rollout["truncated"], cfg.gamma, cfg.lam)  # (T, N)
                returns = advantages + values  # value targets R_t = A_t + V(s_t), detached

            # --- update: flatten (T, N) to a batch, dropping the autoreset steps ---
            keep = rollout["valid"].reshape(-1)
            b_obs = rollout["obs"].reshape(T * N, obs_dim)[keep]
            b_act, b_logp = rollout["actions"].reshape(-1)[keep], logp_old.reshape(-1)[keep]
            b_log_probs_old = log_probs.reshape(T * N, n_actions)[keep]  # pi_old in full, for the exact KL
            b_adv, b_ret = advantages.reshape(-1)[keep], returns.reshape(-1)[keep]
            stats = ppo_update(policy, value_net, optimizer, b_obs, b_act, b_logp, b_log_probs_old, b_adv, b_ret,
                               beta, cfg)
            stats["beta"] = beta  # the beta this update used
            beta = adapt_beta(beta, stats["kl"], cfg)  # and the one the next update will use

            # --- logging ---
            mean20 = float(np.mean(last20)) if last20 else float("nan")
            common.append_csv(run_dir / "progress.csv", dict(
                global_step=global_step, episodes=len(episode_returns), return_mean20=mean20,
                lr=optimizer.param_groups[0]["lr"], **stats))
            if update % cfg.print_every == 0 or update == 1:
                elapsed = time.time() - start_time
                eta = elapsed / global_step * (cfg.total_timesteps - global_step)
                print(f"step {global_step:>7}  {global_step / elapsed:6.0f} steps/s  return(20) {mean20:6.1f}  "
                      f"loss_pi {stats['loss_pi']:+.3f}  loss_v {stats['loss_v']:.2e}  "
                      f"kl {stats['kl']:.4f}  beta {stats['beta']:.3g}  entropy {stats['entropy']:.3f}  "
                      f"{common.format_time(elapsed)} (eta {common.format_time(eta)})",
                      flush=True)
    except KeyboardInterrupt:
        interrupted = True
        print("\ninterrupted: saving the model and the logs", flush=True)
    finally:
        envs.close()
        common.save_checkpoint(dict(policy=policy.state_dict(), value=value_net.state_dict(), config=asdict(cfg),
                                    obs_dim=obs_dim, n_actions=n_actions, global_step=global_step, beta=beta),
                               run_dir / "model.pt")

    result = dict(run_dir=run_dir, solved=solved_step is not None, solved_step=solved_step,
                  global_step=global_step, episode_returns=episode_returns, eval_returns=[],
                  interrupted=interrupted)
    if interrupted:
        return result
    print(f"trained {global_step} steps, {len(episode_returns)} episodes in {time.time() - start_time:.1f}s; "
          f"model: {run_dir / 'model.pt'}", flush=True)

    # --- after training: greedy evaluation and GIFs ---
    result["eval_returns"] = common.evaluate(cfg.env_id, greedy(policy, device), cfg.eval_episodes, cfg.eval_seed)
    print(f"greedy evaluation over {cfg.eval_episodes} episodes: mean {np.mean(result['eval_returns']):.1f}, "
          f"min {min(result['eval_returns']):.0f}", flush=True)
    if cfg.gifs:
        common.before_after_gifs(cfg.env_id, run_dir, greedy(untrained, device), greedy(policy, device), cfg.eval_seed,
                                 every=2, scale=2)  # every 2nd frame at half size: small files
    return result


def play(cfg: Config):
    """--eval PATH: load a saved model and play cfg.eval_episodes greedy episodes."""
    ckpt = common.load_checkpoint(cfg.eval, required=("policy", "obs_dim", "n_actions", "config"))
    policy = PolicyNetwork(ckpt["obs_dim"], ckpt["n_actions"], ckpt["config"]["hidden"])
    common.load_weights(policy, ckpt["policy"], cfg.eval)
    env_id = ckpt["config"]["env_id"]
    returns = common.evaluate(env_id, greedy(policy, "cpu"), cfg.eval_episodes, cfg.eval_seed,
                              render_mode="human" if cfg.watch else None)
    print(f"{env_id}, {cfg.eval}: returns {[round(r) for r in returns]}, mean {np.mean(returns):.1f}", flush=True)
    return returns


def main(argv=None):
    """Parse the flags into a Config, then --eval, or train (and --watch); see common.main."""
    common.main(Config, train, play, argv, description=__doc__.split("\n")[0])


if __name__ == "__main__":
    main()
