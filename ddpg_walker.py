"""DDPG on MuJoCo Walker2d-v5 (Lillicrap et al. 2016, "Continuous control with deep
reinforcement learning").

Read beside tutorial 003: ReplayBuffer, Actor and Critic (the critic takes the
action at its second layer), target networks updated softly with rate tau,
Gaussian exploration noise, random actions for the first start_steps steps,
and an evaluation every 5000 steps over 10 episodes. The loop, top to bottom:

    act      random for start_steps steps, then mu(s) + Gaussian noise
    store    (s, a, r, s', terminated) in the replay buffer; a time-limit
             truncation is NOT terminal, so its target still bootstraps
    update   one critic and one actor step on a random minibatch, then the
             targets move a fraction tau toward the networks
    evaluate every eval_every steps: 10 episodes of mu(s) without noise; the run folder
             keeps model.pt, best.pt (the best evaluation so far), best.gif and curve.png

    python ddpg_walker.py                         # 1M steps: hours on a CPU, less on a GPU
    python ddpg_walker.py --eval runs/<run>/best.pt --watch   # replay a saved actor
"""

from __future__ import annotations

import copy
import dataclasses
import time
from dataclasses import asdict, dataclass

import gymnasium as gym
import numpy as np
import torch
import torch.nn as nn
import torch.nn.functional as F

import common
import plots


@dataclass
class Config:
    # --- experiment ---
    env_id: str = "Walker2d-v5"
    """gymnasium id of an env with Box observations and Box actions (Walker2d-v5, Hopper-v5, ...)"""
    seed: int = 0
    """seeds torch and the env: same seed, same machine => same evaluations.csv on the CPU"""
    total_timesteps: int = 1_000_000
    """env steps to train for (the tutorial and the TD3 paper: 1M)"""
    start_steps: int = 25_000
    """uniformly random actions for this many steps before the actor acts and learning
    starts (TD3 paper: 25k; at least batch_size)"""

    # --- DDPG ---
    expl_noise: float = 0.1
    """std of the Gaussian exploration noise, as a fraction of the action range's half-width
    (0.1 .. 0.3)"""
    batch_size: int = 256
    """transitions per update (64 .. 256)"""
    gamma: float = 0.99
    """discount factor (0.98 .. 0.995)"""
    tau: float = 0.005
    """target networks move this fraction toward the networks after every update (0.001 .. 0.01)"""
    actor_lr: float = 3e-4
    """Adam step size of the actor (tutorial: 1e-4; TD3's DDPG: 3e-4)"""
    critic_lr: float = 3e-4
    """Adam step size of the critic (tutorial: 1e-3 with weight decay; TD3's DDPG: 3e-4)"""
    hidden: int = 256
    """units in each of the two hidden layers (tutorial: 400 and 300; TD3, CleanRL: 256)"""
    buffer_size: int = 1_000_000
    """replay buffer capacity; the oldest transitions are overwritten"""

    # --- output ---
    run_dir: str = "runs"
    """parent folder of the run folder <script>__<env>__seed<k>__<time>/"""
    eval_every: int = 5000
    """evaluate (and save the model) every this many env steps"""
    eval_episodes: int = 10
    """episodes per evaluation, without exploration noise"""
    eval_seed: int = 10_000
    """seed of the evaluation env, kept apart from the training seed"""
    print_every: int = 1000
    """print a progress line every this many env steps"""
    gifs: bool = True
    """write before.gif (untrained actor), after.gif (trained actor) and best.gif (the best
    evaluation so far, refreshed as it improves) to the run folder"""
    tensorboard: bool = False
    """also write the logs as TensorBoard scalars into the run folder, with CleanRL's tag
    names (needs `pip install tensorboard`; then: tensorboard --logdir runs)"""
    curves: bool = True
    """write curve.png (evaluation returns against env steps) at every evaluation"""
    watch: bool = False
    """after training (or with --eval), play the actor in a window; needs a display"""
    eval: str | None = None
    """a saved model.pt or best.pt, or a run folder (its model.pt): skip training, play
    eval_episodes episodes without noise"""
    resume: str | None = None
    """a saved model.pt: continue that run's training from its saved step (see the README)"""
    cuda: bool = True
    """train on the GPU when there is one"""
    threads: int = 1
    """torch CPU threads (1-4). 1 never fights another busy program for a core; the README
    measures what more threads give on an idle machine"""

    def __post_init__(self):
        common.check(not self.tensorboard or plots.tensorboard_installed(), plots.NO_TENSORBOARD)
        for name in ("total_timesteps", "batch_size", "hidden", "buffer_size", "eval_every",
                     "eval_episodes", "print_every", "actor_lr", "critic_lr", "threads"):
            common.check(getattr(self, name) > 0,
                         f"--{name.replace('_', '-')} must be positive, got {getattr(self, name)}")
        # The first update samples batch_size transitions: the warm-up must have stored that many.
        common.check(self.start_steps >= self.batch_size,
                     f"--start-steps must be at least --batch-size ({self.batch_size}), "
                     f"got {self.start_steps}")
        common.check(self.expl_noise >= 0, f"--expl-noise must be >= 0, got {self.expl_noise}")
        common.check(0 < self.gamma <= 1, f"--gamma must be in (0, 1], got {self.gamma}")
        common.check(0 < self.tau <= 1, f"--tau must be in (0, 1], got {self.tau}")
        common.check(self.resume or self.total_timesteps > self.start_steps,
                     f"--total-timesteps ({self.total_timesteps}) must exceed --start-steps "
                     f"({self.start_steps}): learning starts after the warm-up")


# =============================================================================
# Networks
# =============================================================================


class Actor(nn.Module):
    """mu(s): observation -> action, squashed by tanh into the action box."""

    def __init__(self, obs_dim, act_dim, hidden, low, high):
        super().__init__()
        self.l1 = nn.Linear(obs_dim, hidden)
        self.l2 = nn.Linear(hidden, hidden)
        self.l3 = nn.Linear(hidden, act_dim)
        # tanh gives [-1, 1]; scale and shift it onto [low, high] (Walker2d: [-1, 1] already).
        self.register_buffer("scale", torch.as_tensor((high - low) / 2, dtype=torch.float32))
        self.register_buffer("bias", torch.as_tensor((high + low) / 2, dtype=torch.float32))

    def forward(self, obs):
        a = F.relu(self.l1(obs))
        a = F.relu(self.l2(a))
        return self.bias + self.scale * torch.tanh(self.l3(a))


class Critic(nn.Module):
    """Q(s, a). As in the DDPG paper and tutorial 003, the action joins at the second layer."""

    def __init__(self, obs_dim, act_dim, hidden):
        super().__init__()
        self.l1 = nn.Linear(obs_dim, hidden)
        self.l2 = nn.Linear(hidden + act_dim, hidden)
        self.l3 = nn.Linear(hidden, 1)

    def forward(self, obs, action):
        q = F.relu(self.l1(obs))
        q = F.relu(self.l2(torch.cat([q, action], dim=-1)))
        return self.l3(q).squeeze(-1)  # (B,): squeeze so Q never broadcasts against (B,) targets


# =============================================================================
# Replay buffer and update
# =============================================================================


class ReplayBuffer:
    """A ring of the last `size` transitions, one named tensor per field, on the training device.

    Kept as tensors where training runs, a minibatch is one index into each
    field: no numpy -> torch conversion per batch, no copy to the GPU.
    """

    def __init__(self, obs_dim, act_dim, size, device):
        self.obs = torch.zeros(size, obs_dim, device=device)       # s   (size, obs_dim)
        self.action = torch.zeros(size, act_dim, device=device)    # a   (size, act_dim)
        self.reward = torch.zeros(size, device=device)             # r   (size,)
        self.next_obs = torch.zeros(size, obs_dim, device=device)  # s'  (size, obs_dim)
        self.not_done = torch.zeros(size, device=device)           # 1 - terminated  (size,)
        self.size, self.ptr, self.count = size, 0, 0

    def add(self, obs, action, reward, next_obs, terminated):
        i = self.ptr
        self.obs[i] = torch.as_tensor(obs)
        self.action[i] = torch.as_tensor(action)
        self.reward[i] = float(reward)
        self.next_obs[i] = torch.as_tensor(next_obs)
        # not_done = 0 only when the episode really ended. A time-limit truncation keeps
        # not_done = 1: the state was not terminal, so its target bootstraps from Q(s', mu(s')).
        self.not_done[i] = 0.0 if terminated else 1.0
        self.ptr = (self.ptr + 1) % self.size  # wrap around: overwrite the oldest
        self.count = min(self.count + 1, self.size)

    def sample(self, batch_size):
        """A uniformly random minibatch of stored transitions:
        obs (B, obs_dim), action (B, act_dim), reward (B,), next_obs (B, obs_dim), not_done (B,)."""
        idx = torch.randint(0, self.count, (batch_size,), device=self.obs.device)
        return (self.obs[idx], self.action[idx], self.reward[idx], self.next_obs[idx],
                self.not_done[idx])


@torch.no_grad()
def soft_update(target, source, tau):
    """theta' <- tau * theta + (1 - tau) * theta'  (Lillicrap et al. 2016, Algorithm 1)."""
    for p_target, p in zip(target.parameters(), source.parameters()):
        p_target.mul_(1 - tau).add_(tau * p)


def td_target(reward, not_done, next_q, gamma):
    """The critic's target y = r + gamma * Q'(s', mu'(s')), with no future after a termination
    (not_done = 0)  (Lillicrap et al. 2016, Algorithm 1)."""
    return reward + gamma * not_done * next_q


def compute_loss_actor(actor, critic, obs):
    """Deterministic policy gradient: grad J = mean grad_a Q(s, a)|a=mu(s) * grad mu(s)
    (Lillicrap et al. 2016, Algorithm 1). The actor ascends Q, so its loss is -Q."""
    return -critic(obs, actor(obs)).mean()


def ddpg_update(actor, critic, actor_target, critic_target, actor_opt, critic_opt, batch, cfg):
    """One critic step and one actor step on a minibatch, then the soft target update."""
    obs, action, reward, next_obs, not_done = batch
    with torch.no_grad():  # targets are constants: no gradient flows into them
        y = td_target(reward, not_done, critic_target(next_obs, actor_target(next_obs)), cfg.gamma)
    # L = mean (y - Q(s, a))^2  (Lillicrap et al. 2016, Algorithm 1)
    critic_loss = F.mse_loss(critic(obs, action), y)
    critic_opt.zero_grad()
    critic_loss.backward()
    critic_opt.step()

    actor_loss = compute_loss_actor(actor, critic, obs)
    actor_opt.zero_grad()
    # inputs=: gradients for the actor only; the critic's would be thrown away.
    actor_loss.backward(inputs=list(actor.parameters()))
    actor_opt.step()

    soft_update(critic_target, critic, cfg.tau)
    soft_update(actor_target, actor, cfg.tau)
    return critic_loss.detach(), actor_loss.detach()


# =============================================================================
# Training
# =============================================================================


def deterministic(actor, device):
    """obs -> mu(obs) as a numpy action, without noise; for evaluation and GIFs."""
    def act(obs):
        with torch.no_grad():
            return actor(torch.as_tensor(obs, dtype=torch.float32, device=device)).cpu().numpy()
    return act


# GIFs and --watch look through the model's "track" camera, which follows the walker
# (gymnasium's default free camera stays put, and a walking agent leaves the picture).
# Models without such a camera (InvertedPendulum) keep the default view.
CAMERA = dict(camera_name="track")


def make_continuous_env(env_id):
    """The env, or a UserError if its actions are not a Box."""
    with common.env_errors(env_id):
        env = gym.make(env_id)
    if not isinstance(env.action_space, gym.spaces.Box):
        env.close()
        raise common.UserError(f"{env_id} has a {type(env.action_space).__name__} action space; "
                               "DDPG needs continuous (Box) actions")
    return env


def build(obs_dim, act_dim, low, high, cfg, device):
    """Actor, critic, their targets and optimizers."""
    actor = Actor(obs_dim, act_dim, cfg.hidden, low, high).to(device)
    critic = Critic(obs_dim, act_dim, cfg.hidden).to(device)
    # The targets start equal to the networks, then lag behind them.
    actor_target, critic_target = copy.deepcopy(actor), copy.deepcopy(critic)
    # fused=True: torch's one-kernel Adam step for all parameters (a standard option).
    actor_opt = torch.optim.Adam(actor.parameters(), lr=cfg.actor_lr, fused=True)
    critic_opt = torch.optim.Adam(critic.parameters(), lr=cfg.critic_lr, fused=True)
    return actor, critic, actor_target, critic_target, actor_opt, critic_opt


def clock(seconds):
    """1234.5 -> '0:20:34'."""
    return time.strftime("%H:%M:%S", time.gmtime(seconds)).lstrip("0").lstrip(":") or "0"


def train(cfg: Config):
    """Train DDPG with `cfg`. Returns a dict: run_dir, global_step, evaluations (list of
    (step, mean, std)), episode_returns, steps_per_second (learning phase) and interrupted."""
    start_time = time.time()
    # --- seeding and setup ---
    torch.set_num_threads(cfg.threads)  # also for reproducibility: threads change float sums
    torch.manual_seed(cfg.seed)  # the networks' init
    device = torch.device("cuda" if cfg.cuda and torch.cuda.is_available() else "cpu")
    env = make_continuous_env(cfg.env_id)
    obs_dim, act_dim = int(env.observation_space.shape[0]), int(env.action_space.shape[0])
    low, high = env.action_space.low.astype(np.float64), env.action_space.high.astype(np.float64)
    nets = build(obs_dim, act_dim, low, high, cfg, device)
    actor, critic, actor_target, critic_target, actor_opt, critic_opt = nets
    untrained = copy.deepcopy(actor)  # before.gif is drawn from these weights after training
    first_step = 0
    if cfg.resume:
        first_step = load(cfg.resume, nets)["global_step"]
        for opt, lr in ((actor_opt, cfg.actor_lr), (critic_opt, cfg.critic_lr)):
            opt.param_groups[0]["lr"] = lr  # this run's flags win over the saved learning rates
        print(f"resumed {cfg.resume} at step {first_step}; the replay buffer starts empty and is "
              f"refilled by the loaded actor for start_steps steps", flush=True)
    # A resumed run continues with fresh randomness (noise, minibatches, env) instead of
    # replaying the first run's: it seeds everything with seed + the step it resumes at.
    run_seed = cfg.seed + first_step
    torch.manual_seed(run_seed)
    env.action_space.seed(run_seed)
    try:
        buffer = ReplayBuffer(obs_dim, act_dim, min(cfg.buffer_size, cfg.total_timesteps), device)
    except (MemoryError, RuntimeError) as e:  # e.g. --buffer-size far beyond this machine's memory
        raise common.UserError(f"cannot allocate a replay buffer of {cfg.buffer_size} transitions: "
                               f"{str(e).splitlines()[0]}") from None
    run_dir = common.make_run_dir(cfg.run_dir, __file__, cfg.env_id, cfg.seed)
    print(f"run folder: {run_dir}  (device: {device})", flush=True)
    noise_std = torch.as_tensor(cfg.expl_noise * (high - low) / 2, dtype=torch.float32,
                                device=device)
    low_t = torch.as_tensor(low, dtype=torch.float32, device=device)
    high_t = torch.as_tensor(high, dtype=torch.float32, device=device)

    def save(name):
        common.save_checkpoint(dict(
            actor=actor.state_dict(), critic=critic.state_dict(),
            actor_target=actor_target.state_dict(), critic_target=critic_target.state_dict(),
            actor_opt=actor_opt.state_dict(), critic_opt=critic_opt.state_dict(),
            config=asdict(cfg), obs_dim=obs_dim, act_dim=act_dim, low=low.tolist(),
            high=high.tolist(), global_step=global_step), run_dir / name)

    # --- bookkeeping ---
    episode_returns, evaluations = [], []
    ep_return, losses, best = 0.0, None, -float("inf")
    learn_start_time, learn_start_step = None, None
    global_step, interrupted = first_step, False
    warmup_until = first_step + cfg.start_steps
    obs, _ = env.reset(seed=run_seed)

    try:
        for global_step in range(first_step + 1, cfg.total_timesteps + 1):
            # --- act ---
            if global_step <= warmup_until and not cfg.resume:
                action = env.action_space.sample()  # a random warm-up fills the buffer widely
            else:
                with torch.no_grad():
                    a = actor(torch.as_tensor(obs, dtype=torch.float32, device=device))
                    a = a + noise_std * torch.randn(act_dim, device=device)  # Gaussian noise
                    action = torch.clamp(a, low_t, high_t).cpu().numpy()
            next_obs, reward, terminated, truncated, _ = env.step(action)
            # Stored with terminated, not truncated: see ReplayBuffer.add.
            buffer.add(obs, action, reward, next_obs, terminated)
            # obs = next_obs: the transition above is stored, the next action starts from here.
            obs = next_obs
            ep_return += float(reward)
            if terminated or truncated:
                episode_returns.append(ep_return)
                ep_return = 0.0
                obs, _ = env.reset()

            # --- learn: one critic and one actor update per env step after the warm-up ---
            if global_step > warmup_until:
                if learn_start_time is None:
                    learn_start_time, learn_start_step = time.time(), global_step
                losses = ddpg_update(actor, critic, actor_target, critic_target, actor_opt,
                                     critic_opt, buffer.sample(cfg.batch_size), cfg)

            # --- logging ---
            if global_step % cfg.print_every == 0:
                elapsed = time.time() - start_time
                if learn_start_time is not None and global_step > learn_start_step:
                    rate = (global_step - learn_start_step) / (time.time() - learn_start_time)
                    left = (cfg.total_timesteps - global_step) / rate
                    speed = f"{rate:5.0f} steps/s  rest of the budget {clock(left)}"
                else:
                    speed = "warm-up (random actions)"
                recent = f"{np.mean(episode_returns[-10:]):8.1f}" if episode_returns else "     n/a"
                loss_text = (f"  critic_loss {losses[0].item():8.3f}  "
                             f"actor_loss {losses[1].item():8.2f}" if losses is not None else "")
                print(f"step {global_step:>8}  {speed}  return(10) {recent}{loss_text}  "
                      f"{clock(elapsed)}", flush=True)
            # --- evaluation, checkpoints, curve; the best model so far and its GIF ---
            if global_step % cfg.eval_every == 0:
                returns = common.evaluate(cfg.env_id, deterministic(actor, device),
                                          cfg.eval_episodes, cfg.eval_seed)
                evaluations.append((global_step, float(np.mean(returns)), float(np.std(returns))))
                recent = float(np.mean(episode_returns[-10:])) if episode_returns else float("nan")
                common.append_csv(run_dir / "evaluations.csv", dict(
                    global_step=global_step, eval_mean=evaluations[-1][1],
                    eval_std=evaluations[-1][2], episodes=len(episode_returns),
                    train_return_mean10=recent))
                print(f"evaluation at step {global_step}: {evaluations[-1][1]:.1f} +- "
                      f"{evaluations[-1][2]:.1f} over {cfg.eval_episodes} episodes", flush=True)
                save("model.pt")  # atomic: a crash never leaves half a model.pt
                if evaluations[-1][1] > best:
                    best = evaluations[-1][1]
                    save("best.pt")
                    if cfg.gifs:
                        common.record_gif(cfg.env_id, deterministic(actor, device),
                                          run_dir / "best.gif", cfg.eval_seed, **GIF, **CAMERA)
                if cfg.curves:
                    plots.draw_run(run_dir)  # rewritten at every evaluation: open it any time
                if cfg.tensorboard:
                    plots.to_tensorboard(run_dir, sps=(global_step - first_step)
                                         / (time.time() - start_time))
    except KeyboardInterrupt:
        interrupted = True
        print("\ninterrupted: saving the model and the logs", flush=True)
    finally:
        env.close()
        save("model.pt")

    learned = global_step - (learn_start_step or global_step)
    rate = learned / (time.time() - learn_start_time) if learned > 0 else float("nan")
    result = dict(run_dir=run_dir, global_step=global_step, evaluations=evaluations,
                  episode_returns=episode_returns, steps_per_second=rate, interrupted=interrupted)
    print(f"learning phase: {learned} steps at {rate:.1f} steps/s (one critic and one actor "
          f"update per step, evaluations included); model: {run_dir / 'model.pt'}", flush=True)
    if interrupted:
        return result
    if cfg.gifs:
        for name, net in (("before.gif", untrained), ("after.gif", actor)):
            ret = common.record_gif(cfg.env_id, deterministic(net, device), run_dir / name,
                                    cfg.eval_seed, **GIF, **CAMERA)
            print(f"{name}: return {ret:.0f} -> {run_dir / name}", flush=True)
    return result


# 1000 steps -> every 4th frame, 250 frames, at half size: a GIF of a few MB.
GIF = dict(max_frames=250, every=4, scale=2)


def load(path, nets):
    """Load a checkpoint into the six (actor, critic, their targets, their optimizers)."""
    keys = ("actor", "critic", "actor_target", "critic_target", "actor_opt", "critic_opt")
    ckpt = common.load_checkpoint(path, required=keys + ("global_step",))
    for key, obj in zip(keys, nets):
        common.load_weights(obj, ckpt[key], path)
    return ckpt


def play(cfg: Config):
    """--eval PATH (model.pt, best.pt or a run folder): play cfg.eval_episodes episodes
    of the saved actor without noise."""
    ckpt = common.load_checkpoint(cfg.eval, required=("actor", "obs_dim", "act_dim", "low",
                                                      "high", "config"))
    actor = Actor(ckpt["obs_dim"], ckpt["act_dim"], ckpt["config"]["hidden"],
                  np.array(ckpt["low"]), np.array(ckpt["high"]))
    common.load_weights(actor, ckpt["actor"], cfg.eval)
    env_id = ckpt["config"]["env_id"]
    print(f"playing {cfg.eval_episodes} episodes of {env_id} with {cfg.eval}"
          + ("; Ctrl-C stops" if cfg.watch else ""), flush=True)
    returns = common.evaluate(env_id, deterministic(actor, torch.device("cpu")), cfg.eval_episodes,
                              cfg.eval_seed, render_mode="human" if cfg.watch else None,
                              log=cfg.watch, **(CAMERA if cfg.watch else {}))
    print(f"{env_id}, {cfg.eval}: returns {[round(r, 1) for r in returns]}, "
          f"mean {np.mean(returns):.1f}", flush=True)
    return returns


def main(argv=None):
    """python ddpg_walker.py [flags]: train (then --watch), or --eval a saved model."""
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
