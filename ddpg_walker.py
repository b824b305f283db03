"""DDPG on MuJoCo Walker2d-v5 (Lillicrap et al. 2016, "Continuous control with deep
reinforcement learning").

Read beside tutorial 003: ReplayBuffer, Actor and Critic (the critic takes the
action at its second layer), target networks updated softly with rate tau,
Gaussian exploration noise, random actions for the first start_steps steps,
and an evaluation every 5000 steps over 10 episodes. The loop, top to bottom:

    act      random for start_steps steps, then mu(s) + Gaussian noise
    store    (s, a, r, s', terminated) in the replay buffer; a time-limit
             truncation is NOT terminal, so its target still bootstraps
    learn    one critic and one actor step on a random minibatch, then the
             targets move a fraction tau toward the networks
    evaluate every eval_every steps (once only during the warm-up): 10 episodes of mu(s)
             without noise

Around it, plumbing a first reading can skip: the run folder keeps evaluations.csv,
episodes.csv, model.pt, best.pt and best.gif (the best evaluation so far) and curve.png, and
every checkpoint_every steps a checkpoint.pt from which --resume continues the very same run.

    python ddpg_walker.py                         # 1M steps: hours on a CPU, less on a GPU
    python ddpg_walker.py --resume runs/<run>     # continue a stopped or killed run exactly
    python ddpg_walker.py --eval runs/<run>/best.pt --watch   # replay a saved actor

中文导读：本脚本教 DDPG，连续动作的 actor-critic：经验回放、目标网络和软更新、高斯探索噪声。
配套教程：《【PyTorch深度强化学习】DDPG算法的讲解及实战(超详细 附源码)》（003）。循环四步：

    行动  先随机动作预热 start_steps 步，之后用 mu(s) 加高斯噪声
    存储  (s, a, r, s', terminated) 存进经验回放；时间截断不算终止，目标照样自举
    学习  随机小批量上 critic、actor 各更新一步，目标网络向网络靠近 tau
    评估  每 eval_every 步不加噪声跑 10 个回合，记进 evaluations.csv
"""

from __future__ import annotations

import common  # first: it turns a Ctrl-C while torch loads into one line (see its top)

import copy
import dataclasses
import signal
import threading
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import gymnasium as gym
import numpy as np
import torch
import torch.nn as nn
import torch.nn.functional as F

import plots

SCRIPT = Path(__file__).stem  # names its run folders; saved in its models (it loads no other's)


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
# Hyperparameters: every one once, here; --help prints the string under each
# =============================================================================


@dataclass
class Config:
    # --- experiment ---
    env_id: str = "Walker2d-v5"
    """gymnasium id of a MuJoCo env with Box actions (Walker2d-v5, Hopper-v5, HalfCheetah-v5,
    ...)"""
    seed: int = 0
    """seeds torch and the env: same seed, same machine => same evaluations.csv on the CPU"""
    total_timesteps: int = 1_000_000
    """env steps to train for (the tutorial and the TD3 paper: 1M)"""
    start_steps: int = 25_000
    """uniformly random actions for this many steps before the actor acts and learning
    starts (the TD3 authors' code: 25k; their paper: 1k on Walker2d; at least batch_size)"""

    # --- DDPG ---
    expl_noise: float = 0.1
    """std of the Gaussian exploration noise, as a fraction of the action range's half-width
    (0.1 .. 0.3)"""
    batch_size: int = 256
    """transitions per update (64 .. 256; DDPG paper: 64; the TD3 authors' OurDDPG.py: 256)"""
    gamma: float = 0.99
    """discount factor (0.98 .. 0.995)"""
    tau: float = 0.005
    """target networks move this fraction toward the networks after every update (0.001 .. 0.01)"""
    actor_lr: float = 3e-4
    """Adam step size of the actor (DDPG paper and tutorial: 1e-4; OurDDPG.py: 3e-4)"""
    critic_lr: float = 3e-4
    """Adam step size of the critic (DDPG paper and tutorial: 1e-3 with weight decay;
    OurDDPG.py: 3e-4)"""
    hidden: int = 256
    """units in each of the two hidden layers (DDPG paper and tutorial: 400 and 300;
    OurDDPG.py and CleanRL: 256)"""
    buffer_size: int = 1_000_000
    """replay buffer capacity; the oldest transitions are overwritten"""

    # --- output ---
    run_dir: str = "runs"
    """parent folder of the run folder <script>__<env>__seed<k>__<time>/"""
    eval_every: int = 5000
    """evaluate (and save model.pt) every this many env steps; during the random warm-up only
    once, as the untrained baseline"""
    eval_episodes: int = 10
    """episodes per evaluation, without exploration noise"""
    eval_seed: int = 10_000
    """seed of the evaluation env, kept apart from the training seed"""
    checkpoint_every: int = 25_000
    """write checkpoint.pt (networks, optimizers, replay buffer, random generators, logs) every
    this many env steps and on Ctrl-C; --resume continues from it"""
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
    gif: str | None = None
    """with --eval: write one episode of the saved actor to this GIF file instead (no display
    needed)"""
    resume: str | None = None
    """a run folder: continue that run exactly where its checkpoint.pt left it, in the same
    folder and with its saved settings (--total-timesteps may extend it)"""
    cuda: bool = True
    """train on the GPU when there is one"""
    threads: int = 1
    """torch CPU threads (1-4). 1 never fights another busy program for a core
    (benchmarks/bench_ddpg.py --threads-table measures 1 against 2)"""

    def __post_init__(self):
        common.check(not self.tensorboard or plots.tensorboard_installed(), plots.NO_TENSORBOARD)
        common.check_ranges(
            self, total_timesteps="> 0", batch_size="> 0", hidden="> 0", buffer_size="> 0",
            eval_every="> 0", eval_episodes="> 0", checkpoint_every="> 0", print_every="> 0",
            actor_lr="> 0", critic_lr="> 0", threads="> 0", expl_noise=">= 0", gamma="(0, 1]",
            tau="(0, 1]")
        # The first update samples batch_size transitions: the warm-up must have stored that many.
        common.check(self.start_steps >= self.batch_size,
                     f"--start-steps must be at least --batch-size ({self.batch_size}), "
                     f"got {self.start_steps}")
        common.check(self.resume or self.total_timesteps > self.start_steps,
                     f"--total-timesteps ({self.total_timesteps}) must exceed --start-steps "
                     f"({self.start_steps}): learning starts after the warm-up")
        common.check(not (self.eval and self.resume),
                     "--eval plays a saved actor and --resume continues training: pass one")
        common.check(not self.gif or self.eval,
                     "--gif writes a GIF of a saved actor: it needs --eval")


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
# Helpers of the loop: acting without noise, making the env and the networks
# =============================================================================


def deterministic(actor, device):
    """obs -> mu(obs) as a numpy action, without noise; for evaluation and GIFs."""
    def act(obs):
        with torch.no_grad():
            return actor(torch.as_tensor(obs, dtype=torch.float32, device=device)).cpu().numpy()
    return act


# GIFs look through the model's "track" camera, which follows the walker (gymnasium's
# default free camera stays put, and a walking agent leaves the picture). Models without
# such a camera (InvertedPendulum) keep the default view. 1000 steps -> every 4th frame,
# 250 frames, at half size: a GIF of a few MB.
CAMERA = dict(camera_name="track")
GIF = dict(max_frames=250, every=4, scale=2)


def make_continuous_env(env_id):
    """The env, or a UserError if it is not a MuJoCo env with Box actions."""
    with common.env_errors(env_id):
        # RecordEpisodeStatistics: info["episode"]["r"] is the return when an episode ends
        env = gym.wrappers.RecordEpisodeStatistics(gym.make(env_id))
    if not isinstance(env.action_space, gym.spaces.Box):
        env.close()
        raise common.UserError(f"{env_id} has a {type(env.action_space).__name__} action space; "
                               "DDPG needs continuous (Box) actions")
    if not hasattr(env.unwrapped, "data"):  # checkpoints save MuJoCo's simulator state
        env.close()
        raise common.UserError(f"{env_id} is not a MuJoCo env; this script trains MuJoCo tasks "
                               "(Walker2d-v5, Hopper-v5, HalfCheetah-v5, InvertedPendulum-v5, ...)")
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


# =============================================================================
# Plumbing of the loop: evaluation, logs, saved models, checkpoints, Ctrl-C. A first
# reading can skip to train() below; each function says in its first line what it does.
# =============================================================================


class CtrlC:
    """While training, a first Ctrl-C only sets `pressed`: the loop finishes its step, where
    nothing is half done, and stops there with a checkpoint. A second Ctrl-C stops at once
    (the last checkpoint is kept)."""

    def __init__(self):
        self.pressed = False
        self.active = (threading.current_thread() is threading.main_thread()
                       and signal.getsignal(signal.SIGINT) is signal.default_int_handler)

    def __enter__(self):
        if self.active:
            signal.signal(signal.SIGINT, self.handler)
        return self

    def handler(self, signum, frame):
        if self.pressed:
            raise KeyboardInterrupt
        self.pressed = True

    def __exit__(self, *exc):
        if self.active:
            signal.signal(signal.SIGINT, signal.default_int_handler)


@dataclass
class Run:
    """What the plumbing works on besides the loop's own variables."""
    cfg: Config
    dir: Path  # the run folder
    nets: tuple  # actor, critic, actor_target, critic_target, actor_opt, critic_opt
    buffer: ReplayBuffer
    env: gym.Env
    device: torch.device
    episodes: list  # (step, return) of every finished training episode
    evaluations: list  # (step, mean, std) of every evaluation
    timer: dict  # for steps/s: when this process started, and the last progress line
    ctrl_c: CtrlC


def after_step(run, step, obs, losses):
    """The rest of one env step: every eval_every steps (once only during the warm-up) an
    evaluation of mu(s) without noise, with its row in evaluations.csv, model.pt, best.pt and
    best.gif when it is the best so far, curve.png; a finished episode's row in episodes.csv;
    a progress line every print_every steps; a checkpoint every checkpoint_every steps, at the
    end, and when Ctrl-C was pressed, which then stops the run here, where the step is whole."""
    cfg, actor = run.cfg, run.nets[0]
    if step > cfg.start_steps:  # the learning phase's steps/s: from this process's first update
        run.timer.setdefault("learning_since", (step, time.time()))
    if run.episodes and run.episodes[-1][0] == step:
        common.append_csv(run.dir / "episodes.csv", episode_row(*run.episodes[-1]))
    if step % cfg.print_every == 0:
        if losses is not None:  # nan or inf: stop with one line (a run with no checkpoint yet goes)
            common.stop_if_diverged(step, dict(critic_loss=losses[0], actor_loss=losses[1]),
                                    run.nets[:2], None if (run.dir / "checkpoint.pt").exists()
                                    else run.dir)
        print(progress_line(step, cfg, run.episodes, losses, run.timer), flush=True)
    if step % cfg.eval_every == 0 and (step > cfg.start_steps or not run.evaluations):
        evaluate_and_save(run, step)
    if step % cfg.checkpoint_every == 0 or step == cfg.total_timesteps or run.ctrl_c.pressed:
        save_checkpoint(run, step, obs)  # the last one is kept: --total-timesteps may extend it
    if run.ctrl_c.pressed:
        raise KeyboardInterrupt


def evaluate_and_save(run, step):
    """Evaluate the actor without noise; log it, save model.pt, and best.pt and best.gif if
    it is the best evaluation so far; redraw curve.png."""
    cfg, actor = run.cfg, run.nets[0]
    returns = common.evaluate(cfg.env_id, deterministic(actor, run.device), cfg.eval_episodes,
                              cfg.eval_seed)
    mean, std = float(np.mean(returns)), float(np.std(returns))
    best = max((m for _, m, _ in run.evaluations), default=-float("inf"))
    run.evaluations.append((step, mean, std))
    common.append_csv(run.dir / "evaluations.csv",
                      evaluation_row(run.evaluations[-1], run.episodes))
    print(f"evaluation at step {step}: {mean:.1f} +- {std:.1f} over {cfg.eval_episodes} "
          f"episodes", flush=True)
    save_model(run.dir / "model.pt", actor, cfg, step)
    if mean > best:
        save_model(run.dir / "best.pt", actor, cfg, step)
        if cfg.gifs:
            common.record_gif(cfg.env_id, deterministic(actor, run.device), run.dir / "best.gif",
                              cfg.eval_seed, **GIF, **CAMERA)
    if cfg.curves:
        plots.draw_run(run.dir)  # rewritten at every evaluation: open it any time
    if cfg.tensorboard:
        plots.to_tensorboard(run.dir, sps=run.timer["rate"])


def episode_row(step, ep_return):
    """An episodes.csv row, as the CartPole scripts write it."""
    return {"global_step": step, "return": ep_return}


def evaluation_row(evaluation, episodes):
    """An evaluations.csv row: the evaluation and the training return before it."""
    step, mean, std = evaluation
    done = [ret for s, ret in episodes if s <= step]
    return dict(global_step=step, eval_mean=mean, eval_std=std, episodes=len(done),
                train_return_mean10=float(np.mean(done[-10:])) if done else float("nan"))


def clock(seconds):
    """1234.5 -> '0:20:34'."""
    return time.strftime("%H:%M:%S", time.gmtime(seconds)).lstrip("0").lstrip(":") or "0"


def progress_line(step, cfg, episodes, losses, timer):
    """'step 30000  151 steps/s  rest of the budget 1:47:02  return(10) ...' (plumbing)."""
    now = time.time()
    # steps/s of learning since the last line (or since learning began, if it was later)
    since_step, since = max((timer["step"], timer["time"]), timer.get("learning_since", (step, 0)))
    if step > cfg.start_steps and step > since_step:
        timer["rate"] = (step - since_step) / (now - since)
        left = (cfg.total_timesteps - step) / timer["rate"]
        speed = f"{timer['rate']:5.0f} steps/s  rest of the budget {clock(left)}"
    else:
        speed = "learning starts" if step > cfg.start_steps else "warm-up (random actions)"
    timer.update(step=step, time=now)
    recent = f"{np.mean([r for _, r in episodes[-10:]]):8.1f}" if episodes else "     n/a"
    loss_text = (f"  critic_loss {losses[0].item():8.3f}  actor_loss {losses[1].item():8.2f}"
                 if losses is not None else "")
    return (f"step {step:>8}  {speed}  return(10) {recent}{loss_text}  "
            f"{clock(now - timer['start'])}")


def save_model(path, actor, cfg, step):
    """The actor and what --eval needs to rebuild it (small; checkpoint.pt has the rest)."""
    common.save_checkpoint(dict(
        script=SCRIPT, actor=actor.state_dict(), config=asdict(cfg), global_step=step,
        obs_dim=actor.l1.in_features, act_dim=actor.l3.out_features,
        low=(actor.bias - actor.scale).tolist(), high=(actor.bias + actor.scale).tolist()), path)


NETS = ("actor", "critic", "actor_target", "critic_target", "actor_opt", "critic_opt")
BUFFER = ("obs", "action", "reward", "next_obs", "not_done")


def save_checkpoint(run, step, obs):
    """checkpoint.pt: everything that decides what the run does next, so that --resume goes
    on exactly as if the run had never stopped."""
    buffer, filled = run.buffer, slice(0, run.buffer.count)  # only the filled part: compact
    started, path = time.time(), run.dir / "checkpoint.pt"
    common.save_checkpoint(dict(
        script=SCRIPT, config=asdict(run.cfg), global_step=step, obs=torch.as_tensor(obs),
        **{key: net.state_dict() for key, net in zip(NETS, run.nets)},
        buffer={key: getattr(buffer, key)[filled].cpu().clone() for key in BUFFER},
        buffer_ptr=buffer.ptr, buffer_count=buffer.count,
        torch_rng=torch.get_rng_state(),  # the exploration noise and the minibatch draws
        cuda_rng=torch.cuda.get_rng_state() if buffer.obs.is_cuda else None,
        action_space_rng=run.env.action_space.np_random.bit_generator.state,  # warm-up actions
        env=env_state(run.env), episodes=run.episodes, evaluations=run.evaluations), path)
    print(f"checkpoint at step {step}: {path} ({path.stat().st_size / 2**20:.0f} MB, written in "
          f"{time.time() - started:.1f} s)", flush=True)


def load_checkpoint(run):
    """Put back what save_checkpoint saved; return the loop's (global_step, obs)."""
    path = run.dir / "checkpoint.pt"
    ckpt = common.load_checkpoint(path, required=NETS + ("buffer", "env", "torch_rng", "obs"),
                                  script=SCRIPT)
    for key, obj in zip(NETS, run.nets):
        common.load_weights(obj, ckpt[key], path)
    buffer, n = run.buffer, ckpt["buffer_count"]
    for key in BUFFER:
        getattr(buffer, key)[:n] = ckpt["buffer"][key].to(buffer.obs.device)
    # A run extended by --total-timesteps may get a larger buffer: it fills on after row n.
    buffer.ptr, buffer.count = (ckpt["buffer_ptr"] if n == buffer.size else n), n
    torch.set_rng_state(ckpt["torch_rng"])
    if ckpt["cuda_rng"] is not None and buffer.obs.is_cuda:
        torch.cuda.set_rng_state(ckpt["cuda_rng"])
    run.env.action_space.np_random.bit_generator.state = ckpt["action_space_rng"]
    set_env_state(run.env, ckpt["env"])
    run.episodes[:], run.evaluations[:] = ckpt["episodes"], ckpt["evaluations"]
    return ckpt["global_step"], ckpt["obs"].numpy()


def env_state(env):
    """The env mid-episode: MuJoCo's whole simulator state (positions, velocities, the
    solver's warm start), the time limit's step count, the episode's return and length so
    far, and the generator used at reset."""
    import mujoco

    sim, what = env.unwrapped, mujoco.mjtState.mjSTATE_INTEGRATION
    state = np.empty(mujoco.mj_stateSize(sim.model, what))
    mujoco.mj_getState(sim.model, sim.data, state, what)
    return dict(mujoco=torch.from_numpy(state), rng=sim.np_random.bit_generator.state,
                **{name: float(env.get_wrapper_attr(name)) if name == "episode_returns"
                   else int(env.get_wrapper_attr(name)) for name in ENV_COUNTERS})


ENV_COUNTERS = ("_elapsed_steps", "episode_returns", "episode_lengths")


def set_env_state(env, saved):
    import mujoco

    sim = env.unwrapped
    mujoco.mj_setState(sim.model, sim.data, saved["mujoco"].numpy(),
                       mujoco.mjtState.mjSTATE_INTEGRATION)
    sim.np_random.bit_generator.state = saved["rng"]
    for name in ENV_COUNTERS:
        env.set_wrapper_attr(name, saved[name])


# Settings --resume may change: how long to go on, and what is shown or written. The rest
# decide the run's numbers and come from its checkpoint.
MAY_CHANGE_ON_RESUME = ("total_timesteps", "print_every", "gifs", "tensorboard", "curves",
                        "watch", "resume", "run_dir")


def config_to_resume(cfg):
    """The saved run's Config, with the flags of MAY_CHANGE_ON_RESUME that this command set.
    A learning setting set to something else than the saved run's is refused."""
    path = Path(cfg.resume) / "checkpoint.pt"
    saved = common.load_checkpoint(path, required=("config", "global_step"), script=SCRIPT)
    defaults = {f.name: f.default for f in dataclasses.fields(Config)}
    kept = {**defaults, **{k: v for k, v in saved["config"].items() if k in defaults}}
    for name, value in asdict(cfg).items():
        if name in MAY_CHANGE_ON_RESUME or value in (defaults[name], kept[name]):
            continue
        raise common.UserError(f"--resume continues the run with its saved settings: --"
                               f"{name.replace('_', '-')} {value} differs from the saved "
                               f"{kept[name]}")
    changed = {name: getattr(cfg, name) for name in MAY_CHANGE_ON_RESUME
               if getattr(cfg, name) != defaults[name]}
    cfg = Config(**{**kept, **changed})
    if cfg.total_timesteps <= saved["global_step"]:
        raise common.UserError(f"{cfg.resume} already ran {saved['global_step']} steps; pass a "
                               f"larger --total-timesteps to go on")
    return cfg


# =============================================================================
# Training
# =============================================================================


def train(cfg: Config):
    """Train DDPG with `cfg` (or continue the run cfg.resume). Returns a dict: run_dir,
    global_step, evaluations (list of (step, mean, std)), episodes (list of (step, return)),
    steps_per_second (learning phase) and interrupted."""
    start_time = time.time()
    if cfg.resume:
        cfg = config_to_resume(cfg)  # the saved run's settings
    # --- seeding and setup ---
    torch.set_num_threads(cfg.threads)  # also for reproducibility: threads change float sums
    torch.manual_seed(cfg.seed)  # the networks' init
    device = torch.device("cuda" if cfg.cuda and torch.cuda.is_available() else "cpu")
    env = make_continuous_env(cfg.env_id)  # one env, as in the paper and tutorial 003
    obs_dim, act_dim = int(env.observation_space.shape[0]), int(env.action_space.shape[0])
    low, high = env.action_space.low.astype(np.float64), env.action_space.high.astype(np.float64)
    nets = build(obs_dim, act_dim, low, high, cfg, device)
    actor, critic, actor_target, critic_target, actor_opt, critic_opt = nets
    untrained = copy.deepcopy(actor)  # before.gif is drawn from these weights after training
    torch.manual_seed(cfg.seed)  # the noise and the minibatches
    env.action_space.seed(cfg.seed)  # the random warm-up actions
    try:
        buffer = ReplayBuffer(obs_dim, act_dim, min(cfg.buffer_size, cfg.total_timesteps), device)
    except (MemoryError, RuntimeError) as e:  # e.g. --buffer-size far beyond this machine's memory
        raise common.UserError(f"cannot allocate a replay buffer of {cfg.buffer_size} transitions: "
                               f"{str(e).splitlines()[0]}") from None
    noise_std = torch.as_tensor(cfg.expl_noise * (high - low) / 2, dtype=torch.float32,
                                device=device)
    low_t = torch.as_tensor(low, dtype=torch.float32, device=device)
    high_t = torch.as_tensor(high, dtype=torch.float32, device=device)
    obs, _ = env.reset(seed=cfg.seed)
    global_step, losses = 0, None
    run_dir = Path(cfg.resume) if cfg.resume else None
    run = Run(cfg, run_dir, nets, buffer, env, device, episodes=[], evaluations=[],
              timer=dict(start=start_time, step=0, time=time.time(), rate=float("nan")),
              ctrl_c=CtrlC())
    if cfg.resume:  # the same run goes on: weights, buffer, generators, env, logs as saved
        global_step, obs = load_checkpoint(run)
        rewind_logs(run)
        run.timer.update(step=global_step)
        print(f"resumed {run.dir} at step {global_step} of {cfg.total_timesteps}", flush=True)
    else:
        run.dir = common.make_run_dir(cfg.run_dir, SCRIPT, cfg.env_id, cfg.seed)
        print(f"run folder: {run.dir}  (device: {device})", flush=True)
    first_step = global_step

    with run.ctrl_c:
        try:
            for global_step in range(first_step + 1, cfg.total_timesteps + 1):
                learning = global_step > cfg.start_steps  # after the random warm-up
                # --- act ---
                if not learning:
                    action = env.action_space.sample()  # a random warm-up fills the buffer widely
                else:
                    with torch.no_grad():
                        a = actor(torch.as_tensor(obs, dtype=torch.float32, device=device))
                        a = a + noise_std * torch.randn(act_dim, device=device)  # Gaussian noise
                        action = torch.clamp(a, low_t, high_t).cpu().numpy()
                next_obs, reward, terminated, truncated, info = env.step(action)

                # --- store: with terminated, not truncated (see ReplayBuffer.add) ---
                buffer.add(obs, action, reward, next_obs, terminated)
                obs = next_obs  # the transition is stored; the next action starts from here
                if terminated or truncated:
                    run.episodes.append((global_step, float(info["episode"]["r"])))  # return
                    obs, _ = env.reset()

                # --- learn: one critic and one actor update per env step ---
                if learning:
                    losses = ddpg_update(actor, critic, actor_target, critic_target, actor_opt,
                                         critic_opt, buffer.sample(cfg.batch_size), cfg)

                # --- evaluate every eval_every steps; logs, checkpoints (plumbing) ---
                after_step(run, global_step, obs, losses)
            interrupted = False
        except KeyboardInterrupt:
            interrupted = True
        finally:
            env.close()

    learned_from, since = run.timer.get("learning_since", (global_step, time.time()))
    learned = global_step - learned_from
    rate = learned / (time.time() - since) if learned > 0 else float("nan")
    result = dict(run_dir=run.dir, global_step=global_step, evaluations=run.evaluations,
                  episodes=run.episodes, steps_per_second=rate, interrupted=interrupted)
    if interrupted:
        saved = (torch.load(run.dir / "checkpoint.pt", weights_only=True, mmap=True)["global_step"]
                 if (run.dir / "checkpoint.pt").exists() else None)
        where = (f"its checkpoint is at step {saved}: continue with `python ddpg_walker.py "
                 f"--resume {run.dir}`" if saved else "no checkpoint was written yet")
        print(f"\ninterrupted at step {global_step}; {where}", flush=True)
        return result
    print(f"learning phase: {learned} steps at {rate:.1f} steps/s (one critic and one actor "
          f"update per step, evaluations included); run folder: {run.dir}", flush=True)
    if cfg.gifs:
        for name, net in (("before.gif", untrained), ("after.gif", actor)):
            ret = common.record_gif(cfg.env_id, deterministic(net, device), run.dir / name,
                                    cfg.eval_seed, **GIF, **CAMERA)
            print(f"{name}: return {ret:.0f} -> {run.dir / name}", flush=True)
    return result


def rewind_logs(run):
    """On resume: rewrite the CSV logs as they were at the checkpoint. Rows a killed run
    wrote after its last checkpoint go; the resumed run writes them again, identically."""
    for stale in run.dir.glob("*.tmp*"):  # a write that a kill cut short
        stale.unlink()
    for name, rows in (("episodes.csv", [episode_row(*e) for e in run.episodes]),
                       ("evaluations.csv", [evaluation_row(e, run.episodes)
                                            for e in run.evaluations])):
        (run.dir / name).unlink(missing_ok=True)
        for row in rows:
            common.append_csv(run.dir / name, row)


def play(cfg: Config):
    """--eval PATH (model.pt, best.pt or a run folder): play cfg.eval_episodes episodes
    of the saved actor without noise (in a window with --watch), or with --gif write one
    episode to a GIF file."""
    ckpt = common.load_checkpoint(cfg.eval, required=("actor", "obs_dim", "act_dim", "low",
                                                      "high", "config"), script=SCRIPT)
    actor = Actor(ckpt["obs_dim"], ckpt["act_dim"], ckpt["config"]["hidden"],
                  np.array(ckpt["low"]), np.array(ckpt["high"]))
    common.load_weights(actor, ckpt["actor"], cfg.eval)
    env_id, policy = ckpt["config"]["env_id"], deterministic(actor, torch.device("cpu"))
    if cfg.gif:
        print(f"recording one episode of {env_id} with {cfg.eval}", flush=True)
        ret = common.record_gif(env_id, policy, cfg.gif, cfg.eval_seed, **GIF, **CAMERA)
        print(f"{cfg.gif}: one episode, return {ret:.1f}", flush=True)
        return [ret]
    print(f"playing {cfg.eval_episodes} episodes of {env_id} with {cfg.eval}"
          + ("; Ctrl-C stops" if cfg.watch else ""), flush=True)
    returns = common.evaluate(env_id, policy, cfg.eval_episodes, cfg.eval_seed,
                              render_mode="human" if cfg.watch else None, log=cfg.watch,
                              **(watch_camera(env_id) if cfg.watch else {}))
    print(f"{env_id}, {cfg.eval}: returns {[round(r, 1) for r in returns]}, "
          f"mean {np.mean(returns):.1f}", flush=True)
    return returns


def watch_camera(env_id):
    """gym.make arguments for --watch: the window's camera follows the agent. (The window
    ignores camera_name; it takes the env's own view settings, here with a tracking type.)"""
    import mujoco

    with common.env_errors(env_id):
        env = gym.make(env_id)
    view = dict(env.unwrapped.mujoco_renderer.default_cam_config or {})
    env.close()
    return dict(default_camera_config={**view, "type": mujoco.mjtCamera.mjCAMERA_TRACKING})


def main(argv=None):
    """python ddpg_walker.py [flags]: train (then --watch), continue with --resume, or --eval
    a saved model."""
    cfg = common.parse_config(Config, argv, description=" ".join(__doc__.split("\n\n")[0].split()))
    with common.clear_exit():  # bad input: one line, exit 2; Ctrl-C: one line, exit 130
        if cfg.eval:
            play(cfg)
            return
        result = train(cfg)  # on Ctrl-C it saves a checkpoint and the logs, says so, and returns
        if result["interrupted"]:  # it said where everything is: exit 130 without another line
            raise SystemExit(130)
        if cfg.watch:
            play(dataclasses.replace(cfg, eval=str(result["run_dir"])))


if __name__ == "__main__":
    main()
