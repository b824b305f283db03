"""DDPG on MuJoCo Walker2d-v5 (Lillicrap et al. 2016, "Continuous control with deep
reinforcement learning").

Read beside tutorial 003: ReplayBuffer, Actor and Critic (the critic takes the
action at its second layer), target networks updated softly with rate tau,
Gaussian exploration noise, random actions for the first start_steps steps,
and an evaluation every 5000 steps over 10 episodes. The loop in train(), top to bottom:

    act      random for start_steps steps, then mu(s) + Gaussian noise
    store    (s, a, r, s', terminated) in the buffer; a time-limit truncation still bootstraps
    learn    one critic and one actor step on a random minibatch, then the
             targets move a fraction tau toward the networks
    evaluate every eval_every steps (once in the warm-up): 10 episodes of mu(s), no noise

    python ddpg_walker.py                         # 1M steps: several hours on a CPU
    python ddpg_walker.py --resume runs/latest     # continue a stopped or killed run exactly
    python ddpg_walker.py --eval runs/latest/best.pt --watch   # replay a saved actor

中文导读：DDPG，连续动作的演员-评论员方法：确定性策略 μ(s)、经验回放、目标网络和软更新、
高斯探索噪声。配套教程：003《【PyTorch深度强化学习】DDPG算法的讲解及实战(超详细 附源码)》，
对照阅读见 README.zh-CN.md 的路线三。train() 里的循环：行动、存储、学习、定期评估。
"""

import copy
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
    """env steps to train for (the tutorial and the TD3 paper: 1M)"""
    start_steps: int = 25_000
    """random actions for this many steps, then the actor acts and learns (>= batch_size)"""
    # --- DDPG ---
    expl_noise: float = 0.1
    """std of the Gaussian exploration noise, a share of the action box's half-width (0.1 .. 0.3)"""
    batch_size: int = 256
    """transitions per update (64 .. 256; DDPG paper: 64; the TD3 authors' OurDDPG.py: 256)"""
    gamma: float = 0.99
    """discount factor (0.98 .. 0.995)"""
    tau: float = 0.005
    """the targets move this fraction toward the networks at each target update (0.001 .. 0.01)"""
    actor_lr: float = 3e-4
    """Adam step size of the actor (DDPG paper and tutorial: 1e-4; OurDDPG.py: 3e-4)"""
    critic_lr: float = 3e-4
    """Adam step size of the critic (DDPG paper, tutorial: 1e-3 and weight decay; OurDDPG: 3e-4)"""
    hidden: int = 256
    """units in each of the two hidden layers (DDPG paper, tutorial: 400, 300; OurDDPG.py: 256)"""
    buffer_size: int = 1_000_000
    """replay buffer capacity; the oldest transitions are overwritten"""
    eval_every: int = 5000
    """env steps between evaluations of mu(s), no noise, which save model.pt (tutorial 003: 5000)"""

    def __post_init__(self):
        super().__post_init__()  # the shared flags' checks
        mujoco_env.check_mujoco(self.env_id)
        cli.check_ranges(
            self, total_timesteps="> 0", batch_size="> 0", hidden="> 0", buffer_size="> 0",
            eval_every="> 0", actor_lr="> 0", critic_lr="> 0", expl_noise=">= 0",
            gamma="(0, 1]", tau="(0, 1]")
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


def td_target(reward, not_done, next_q, gamma):
    """The critic's target y = r + gamma * Q'(s', mu'(s')), with no future after a termination
    (not_done = 0)  (Lillicrap et al. 2016, Algorithm 1)."""
    return reward + gamma * not_done * next_q


def compute_loss_actor(actor, critic, obs):
    """Deterministic policy gradient: grad J = mean grad_a Q(s, a)|a=mu(s) * grad mu(s)
    (Silver et al. 2014, Theorem 1; Lillicrap et al. 2016, Algorithm 1). The actor ascends Q,
    so its loss is -Q: autograd through Q's action input gives the product. The states come
    from the buffer (off-policy DPG), the action is mu(s): where the critic may never have
    been trained, and may overestimate (docs/why.md)."""
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
    actor_loss.backward(inputs=list(actor.parameters()))  # gradients for the actor only
    actor_opt.step()

    soft_update(critic_target, critic, cfg.tau)
    soft_update(actor_target, actor, cfg.tau)
    return critic_loss.detach(), actor_loss.detach()


def build(obs_dim, act_dim, low, high, cfg, device):
    """Actor, critic, their targets and optimizers, by name."""
    actor = Actor(obs_dim, act_dim, cfg.hidden, low, high).to(device)
    critic = Critic(obs_dim, act_dim, cfg.hidden).to(device)
    # The targets start equal to the networks, then lag behind them.
    actor_target, critic_target = copy.deepcopy(actor), copy.deepcopy(critic)
    # fused=True: torch's one-kernel Adam step for all parameters (a standard option).
    actor_opt = torch.optim.Adam(actor.parameters(), lr=cfg.actor_lr, fused=True)
    critic_opt = torch.optim.Adam(critic.parameters(), lr=cfg.critic_lr, fused=True)
    return dict(actor=actor, critic=critic, actor_target=actor_target,
                critic_target=critic_target, actor_opt=actor_opt, critic_opt=critic_opt)


# evaluations.csv's own columns, once: (progress-line format, picture label)
LOGGED = dict(q_estimate=(None, "critic: Q(s, mu(s))"), q_states=(None, "states averaged"),
              discounted_return=(None, "what mu obtained: sum of gamma^k r from s"))
PICTURES = dict(inside=[[plots.lines(  # docs/inside.md, "DDPG: overestimation"
    "q_estimate", "discounted_return", ylabel="discounted return from s, mean over the states",
    title="each evaluation: the critic's Q against the discounted return mu obtained")]])
SHIPPED = Path(__file__).resolve().parent / "docs" / f"{SCRIPT}2d.pt"  # a 1M-step run's best
SMOKE = dict(env_id="InvertedPendulum-v5", total_timesteps=300, start_steps=200,  # the tests':
             eval_every=150, eval_episodes=1, batch_size=64, hidden=64)  # seconds, every file

# ==== Training ============================================================================
def train(cfg: Config):
    """Train DDPG with `cfg`, or resume the run cfg.resume; returns report.finish_evaluations()."""
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
    actor, critic, actor_target, critic_target, actor_opt, critic_opt = nets.values()  # by name
    untrained = copy.deepcopy(actor)  # before.gif is drawn from these weights after training
    torch.manual_seed(cfg.seed)  # the noise and the minibatches: not shifted by the init
    env.action_space.seed(cfg.seed)  # the random warm-up actions
    buffer = ReplayBuffer(obs_dim, act_dim, min(cfg.buffer_size, cfg.total_timesteps), device)
    noise_std = torch.as_tensor(cfg.expl_noise * (high - low) / 2, dtype=torch.float32).to(device)
    low_t = torch.as_tensor(low, dtype=torch.float32, device=device)
    high_t = torch.as_tensor(high, dtype=torch.float32, device=device)
    obs, _ = env.reset(seed=cfg.seed)
    run = runlog.EvaluationLog(SCRIPT, cfg, device, LOGGED, cfg.start_steps, cfg.eval_every,
                               shipped=SHIPPED if cfg.env_id == "Walker2d-v5" else None)
    actor_info = dict(obs_dim=obs_dim, act_dim=act_dim, low=low.tolist(), high=high.tolist())
    in_checkpoint = dict(nets, buffer=buffer, env=mujoco_env.MujocoEnvState(env),
                         rng=checkpoints.RandomState(env, device), log=run)
    first_step = 0
    if cfg.resume:  # where the run stopped: its step and the loop's obs
        first_step, obs = checkpoints.resume(run.dir, SCRIPT, cfg, in_checkpoint)
    global_step, losses = first_step, None

    with checkpoints.CtrlC() as ctrl_c:
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

            # --- store (s, a, r, s', terminated), then move on to s' (or a new episode's s) ---
            obs = store_and_advance(env, buffer, obs, action, reward, next_obs, terminated,
                                    truncated)
            if terminated or truncated:
                run.episode_ended(global_step, info["episode"]["r"])  # its return, episodes.csv

            # --- learn: one critic and one actor update per env step ---
            if learning:
                batch = buffer.sample(cfg.batch_size)
                critic_loss, actor_loss = ddpg_update(actor, critic, actor_target, critic_target,
                                                      actor_opt, critic_opt, batch, cfg)
                losses = dict(critic_loss=critic_loss, actor_loss=actor_loss)  # progress line's
            run.progress(global_step, losses, nets.values())  # nan/inf: stop

            # --- evaluate mu(s), no noise, every eval_every steps; in the warm-up once ---
            if global_step % cfg.eval_every == 0 and (learning or not run.evaluations):
                seen = []  # the evaluation's states and rewards: Q(s, mu(s)) against the return
                returns = common.evaluate(cfg.env_id, common.deterministic(actor, device),
                                          cfg.eval_episodes, cfg.eval_seed, trajectories=seen)
                q, g, n = common.q_against_return(seen, actor, nets["critic"], cfg.gamma, device)
                best = run.evaluation(global_step, returns, q_estimate=q, discounted_return=g,
                                      q_states=n)  # a row of evaluations.csv
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
    """python ddpg_walker.py [flags]: train (then --watch), --resume a run, or --eval an actor."""
    cfg = cli.parse_config(Config, argv, description=__doc__.split("\n\n")[0])
    with cli.clear_exit():  # bad input: one line, exit 2; Ctrl-C: one line, exit 130
        saved = cfg.eval or report.saved_model(train(cfg))  # after a Ctrl-C: exit 130
        if cfg.eval or cfg.watch:  # play the saved actor (in a window with --watch)
            actor, env_id = checkpoints.load_model(saved, SCRIPT, "actor", lambda ckpt: Actor(
                ckpt["obs_dim"], ckpt["act_dim"], ckpt["config"]["hidden"],
                np.array(ckpt["low"]), np.array(ckpt["high"])))
            mu = [("eval_returns", "mu(s), no noise", lambda _: common.deterministic(actor, "cpu"))]
            report.play(cfg, saved, env_id, mu, mujoco_env.GIF, mujoco_env.watch_camera)


if __name__ == "__main__":
    main()
