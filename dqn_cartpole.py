"""DQN on CartPole-v1 (Mnih et al. 2015, "Human-level control through deep reinforcement
learning"), and Double DQN as the named variant --double (van Hasselt et al. 2016).

Value-based control: no policy network, only Q(s, a); the policy is epsilon-greedy in Q
while training and greedy, argmax_a Q(s, a), after it. The replay buffer and the target
network are DDPG's (ddpg_walker.py) for discrete actions: the target copies the network
every target_update_interval gradient steps instead of following it softly. The loop in
train(), top to bottom:

    act      random for start_steps steps, then epsilon-greedy, epsilon falling linearly
    store    (s, a, r, s', terminated) in the replay buffer; a time-limit truncation is NOT
             terminal, so its target still bootstraps
    learn    every train_freq env steps, gradient_steps minibatch steps on the Huber loss
             against y = r + gamma * max_a Q'(s', a); the target network copies the network
             every target_update_interval of them
    log      one progress.csv row per learning phase; now and then the greedy policy plays, so
             that Q(s, argmax Q) can be set against the return it really obtains (inside.png)
Solved as the other CartPole scripts: the last 20 training episodes average 475, then the
greedy policy as it is then must too (seeds 0-4: at 35k to 56k steps,
benchmarks/results/dqn_cartpole_seeds.csv).

    python dqn_cartpole.py                  # train until solved (about a minute on a CPU)
    python dqn_cartpole.py --double       # Double DQN: compare inside.png's Q with the return
    python dqn_cartpole.py --eval runs/latest --watch   # the greedy policy, in a window

中文导读：DQN（深度 Q 网络），基于价值的方法：没有策略网络，只学 Q(s, a)；训练时按 ε-贪心
选动作，训练后贪心地选 argmax_a Q(s, a)。回放缓冲区和目标网络的写法和 ddpg_walker.py 一样，
只是目标网络每隔 target_update_interval 个梯度步整个复制一次（硬更新），而不是软更新。
max 在同一组带噪声的估计上既挑动作又给它估值，所以系统性地偏高（E[max Q] >= max E[Q]）；
--double 是 Double DQN：由当前网络选下一个动作、目标网络给它估值，治的就是这种高估；
inside.png 把 Q(s, argmax Q) 和贪心策略从同一个状态出发实际得到的折扣回报画在一起，
加不加 --double 各跑一次，比较两张图。在这里的默认设置下，CartPole 上 DQN 的 max 目标和
Double DQN 的目标相差很小，两张图看起来差不多。TD3 的裁剪双 Q 学习就是从这里来的。
"""

import copy
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch
import torch.nn as nn
import torch.nn.functional as F

import cartpole_env
import checkpoints
import cli
import common
import plots
import report
import runlog

SCRIPT = Path(__file__).stem  # names its run folders; saved in its models (it loads no other's)


# ==== Networks ============================================================================
class QNetwork(nn.Module):
    """Q(s, .): observation -> one value per action (rl-zoo's CartPole net: 256, 256)."""

    def __init__(self, obs_dim, n_actions, hidden):
        super().__init__()
        self.l1 = nn.Linear(obs_dim, hidden)
        self.l2 = nn.Linear(hidden, hidden)
        self.l3 = nn.Linear(hidden, n_actions)

    def forward(self, obs):
        q = F.relu(self.l1(obs))
        q = F.relu(self.l2(q))
        return self.l3(q)  # (B, n_actions): Q(s, a) for every a at once


# ==== Hyperparameters: each once, here; --help shows the string under each =============
@dataclass
class Config(cli.SolvedFlags):
    """The algorithm's settings (rl-zoo's CartPole-v1 DQN unless said); shared: cli.SolvedFlags."""
    # --- experiment ---
    env_id: str = "CartPole-v1"
    """gymnasium id of an env with a Box observation and Discrete actions"""
    seed: int = 0
    """seeds torch, numpy's draws and the env: same seed, same machine => same progress.csv"""
    total_timesteps: int = 100_000
    """budget of env steps (rl-zoo, SB3's tuned settings: 50000); training stops when solved"""
    start_steps: int = 1000
    """steps of random actions that fill the buffer before learning (>= batch_size; rl-zoo: 1000)"""
    # --- DQN ---
    buffer_size: int = 100_000
    """replay buffer capacity; the oldest transitions are overwritten"""
    batch_size: int = 64
    """transitions per gradient step (32 .. 256; Mnih et al.: 32)"""
    learning_rate: float = 5e-4
    """Adam step size (1e-4 .. 3e-3; rl-zoo's 2.3e-3 made Q diverge with a copy every 32 steps)"""
    gamma: float = 0.99
    """discount factor (0.98 .. 0.999); 0.99: about 100 steps ahead (0.98: 3 of 5 seeds failed)"""
    train_freq: int = 256
    """env steps between learning phases (Mnih et al.: 4)"""
    gradient_steps: int = 128
    """minibatch steps in each learning phase (Mnih et al.: 1)"""
    target_update_interval: int = 64
    """gradient steps between copies of the network into the target (Mnih et al.: 10000); each
    copy lets the targets look one step further (docs/experiments.md: every 32, Q diverged)"""
    eps_start: float = 1.0
    """epsilon of epsilon-greedy at step 0"""
    eps_end: float = 0.01
    """final epsilon (0.01 .. 0.1; rl-zoo's 0.04 left the training returns far below greedy's)"""
    exploration_steps: int = 8000
    """env steps of epsilon's linear fall from eps_start to eps_end (rl-zoo: 0.16 x 50000)"""
    max_grad_norm: float = 10.0
    """clip the gradient norm to this (SB3's DQN: 10; 0 = no clipping)"""
    hidden: int = 256
    """units in each of the two hidden layers (64 .. 256)"""
    double: bool = False
    """Double DQN (van Hasselt et al. 2016): the network picks a', the target network values it"""
    q_check_every: int = 10
    """learning phases between checks of Q against the return: 2 greedy episodes of <= 1000 steps"""

    def __post_init__(self):
        super().__post_init__()  # the shared flags' checks
        cli.check_ranges(
            self, total_timesteps="> 0", buffer_size="> 0", batch_size="> 0", hidden="> 0",
            learning_rate="> 0", gamma="(0, 1]", train_freq="> 0", gradient_steps="> 0",
            target_update_interval="> 0", eps_start="[0, 1]", eps_end="[0, 1]",
            exploration_steps="> 0", max_grad_norm=">= 0", q_check_every="> 0")
        cli.check(self.batch_size <= self.start_steps <= self.buffer_size, f"--start-steps "
                  f"({self.start_steps}) must lie between --batch-size ({self.batch_size}) and "
                  f"--buffer-size ({self.buffer_size}): a whole first batch, all in the buffer")
        cli.check(self.total_timesteps > self.start_steps,
                  f"--total-timesteps ({self.total_timesteps}) must exceed --start-steps "
                  f"({self.start_steps}): learning starts after the warm-up")


# ==== Replay buffer, target, loss, update =================================================
class ReplayBuffer:
    """A ring of the last `max_size` transitions, a tensor per field, on the training device
    (as ddpg_walker.py's; the action is an index here)."""

    def __init__(self, obs_dim, max_size, device):
        self.obs = torch.zeros(max_size, obs_dim, device=device)       # s   (max_size, obs_dim)
        self.action = torch.zeros(max_size, dtype=torch.int64, device=device)  # a  (max_size,)
        self.reward = torch.zeros(max_size, device=device)             # r   (max_size,)
        self.next_obs = torch.zeros(max_size, obs_dim, device=device)  # s'  (max_size, obs_dim)
        self.not_done = torch.zeros(max_size, device=device)           # 1 - terminated  (max_size,)
        self.max_size, self.ptr, self.size = max_size, 0, 0

    def add(self, obs, action, reward, next_obs, terminated):
        i = self.ptr
        self.obs[i] = torch.as_tensor(obs)
        self.action[i] = int(action)
        self.reward[i] = float(reward)
        self.next_obs[i] = torch.as_tensor(next_obs)
        # not_done = 0 only when the episode really ended. A time-limit truncation keeps
        # not_done = 1: the state was not terminal, so its target bootstraps from max Q'(s', .).
        self.not_done[i] = 0.0 if terminated else 1.0
        self.ptr = (self.ptr + 1) % self.max_size  # wrap around: overwrite the oldest
        self.size = min(self.size + 1, self.max_size)

    def sample(self, batch_size):
        """A uniformly random minibatch of stored transitions:
        obs (B, obs_dim), action (B,), reward (B,), next_obs (B, obs_dim), not_done (B,)."""
        idx = torch.randint(0, self.size, (batch_size,), device=self.obs.device)
        return (self.obs[idx], self.action[idx], self.reward[idx], self.next_obs[idx],
                self.not_done[idx])


@torch.no_grad()
def hard_update(target, source):
    """theta^- <- theta, every C steps  (Mnih et al. 2015, Algorithm 1)."""
    for p_target, p in zip(target.parameters(), source.parameters()):
        p_target.copy_(p)


def epsilon_at(step, cfg):
    """eps = eps_start + (eps_end - eps_start) * min(1, step / exploration_steps): linear, then
    flat (Mnih et al. 2015 anneal 1 -> 0.1 over their first million frames)."""
    return cfg.eps_start + (cfg.eps_end - cfg.eps_start) * min(1.0, step / cfg.exploration_steps)


def next_q(q_net, q_target, next_obs, double):
    """The value of s' in the target: (max_a Q'(s', a), Q'(s', argmax_a Q(s', a))), (B,) each,
    and the first or, with `double`, the second as the one to use."""
    q_next = q_target(next_obs)  # Q'(s', .), (B, n_actions)
    greedy_max = q_next.max(-1).values  # the target network picks and values: DQN
    a_star = q_net(next_obs).argmax(-1, keepdim=True)  # the network picks ...
    double_q = q_next.gather(-1, a_star).squeeze(-1)  # ... the target network values: Double
    return (double_q if double else greedy_max), greedy_max, double_q


def td_target(reward, not_done, next_value, gamma):
    """y = r + gamma * next_value, with no future after a termination (not_done = 0).
    DQN:        next_value = max_a Q'(s', a)                    (van Hasselt et al. 2016, eq. 3)
    Double DQN: next_value = Q'(s', argmax_a Q(s', a))   (van Hasselt et al. 2016: eq. 4, its
                second weights theta' being the target network's, section "Double DQN")
    The max both picks and values the action with the same noisy estimates, so it is biased
    upward: E[max_a Q] >= max_a E[Q]. Two actions worth the same, each estimated with
    independent noise of std 1: the max is 1/sqrt(pi) = 0.56 too high on average, and each
    bootstrapped target passes that on to the next. Double DQN picks with one network and
    values with the other, whose noise is not the one the pick was made on."""
    return reward + gamma * not_done * next_value


def compute_loss_q(q_net, obs, action, y):
    """Huber loss of the TD error y - Q(s, a) (Huber 1964; delta = 1): quadratic within +-1,
    linear outside, so a large error's gradient is clipped to +-1 as in Mnih et al. 2015,
    Methods ("clip the error term ... between -1 and 1"). Returns (loss, Q(s, a))."""
    q = q_net(obs).gather(-1, action[:, None]).squeeze(-1)  # Q(s, a) of the taken a, (B,)
    # L = mean of 0.5 x^2 if |x| <= 1 else |x| - 0.5, x = Q(s, a) - y
    return F.smooth_l1_loss(q, y), q


def dqn_update(q_net, q_target, optimizer, batch, cfg):
    """One gradient step on a minibatch. Returns its loss, mean Q(s, a), and the two next-state
    values of next_q (both measured, whichever the target used)."""
    obs, action, reward, next_obs, not_done = batch
    with torch.no_grad():  # the target is a constant: no gradient flows into it
        value, greedy_max, double_q = next_q(q_net, q_target, next_obs, cfg.double)
        y = td_target(reward, not_done, value, cfg.gamma)
    loss, q = compute_loss_q(q_net, obs, action, y)
    optimizer.zero_grad()
    loss.backward()
    if cfg.max_grad_norm > 0:
        nn.utils.clip_grad_norm_(q_net.parameters(), cfg.max_grad_norm)
    optimizer.step()
    return torch.stack([loss.detach(), q.detach().mean(), greedy_max.mean(), double_q.mean()])


# progress.csv's columns, once: (progress-line format or None, picture label, CleanRL's tag)
LOGGED = dict(epsilon=(".3f", "epsilon", "charts/epsilon"),
              loss=(".3f", "Huber loss", "losses/td_loss"),
              q=(".1f", "Q(s, a) on the minibatches", "losses/q_values"),
              next_max=(None, "max_a Q'(s', a): DQN's pick"),
              next_double=(None, "Q'(s', argmax_a Q(s', a)): Double DQN's pick"),
              q_greedy=(".1f", "Q(s, argmax Q): the network's estimate"),
              mc_return=(".1f", "what greedy obtained: sum of gamma^k r from s"))
SMOKE = dict(total_timesteps=1200, start_steps=200, train_freq=100, gradient_steps=4,
             q_check_every=2, stop_when_solved=False, eval_episodes=2)  # tests: seconds


def pictures(cfg):
    """curve.png: epsilon and the loss; inside.png: Q against the return, and the two targets."""
    what = "Double DQN" if cfg.double else "DQN"
    return dict(curve=[[plots.lines("epsilon", right=("loss",))]], inside=[[
        plots.lines("q_greedy", "mc_return", title=f"{what}: the greedy policy's states",
                    ylabel="discounted return from s, mean over the states"),
        plots.lines("next_max", "next_double", dashed=("next_double",),
                    ylabel="value of s', mean over the minibatches",
                    title="the value of s' in the target; dashed over solid: equal where the "
                          "picks agree")]])


# ==== Training ============================================================================
def train(cfg: Config):
    """Train DQN (Double DQN with cfg.double). Returns report.finish_updates's dict: run_dir,
    solved, solved_step, global_step, episode_returns, greedy_returns, interrupted."""
    # --- seeding and setup ---
    torch.manual_seed(cfg.seed)  # the network's init and the minibatches
    torch.set_num_threads(cfg.threads)  # also for reproducibility: threads change float sums
    rng = np.random.default_rng(cfg.seed)  # epsilon-greedy's coin and its random actions
    device = torch.device("cuda" if cfg.cuda and torch.cuda.is_available() else "cpu")
    # One env, as in the paper; a vector env of one, so episodes are counted as the other
    # CartPole scripts count them (its autoreset step is handled below).
    envs, next_obs, threshold = common.make_vec_env(cfg.env_id, 1, cfg.seed, cfg.solved_return)
    obs_dim = int(envs.single_observation_space.shape[0])
    n_actions = int(envs.single_action_space.n)
    q_net = QNetwork(obs_dim, n_actions, cfg.hidden).to(device)
    q_target = copy.deepcopy(q_net)  # starts equal to the network, then lags behind it
    untrained = copy.deepcopy(q_net)  # before.gif and the maps
    optimizer = torch.optim.Adam(q_net.parameters(), lr=cfg.learning_rate)
    buffer = ReplayBuffer(obs_dim, min(cfg.buffer_size, cfg.total_timesteps), device)
    run = runlog.UpdateLog(SCRIPT, cfg, LOGGED)  # the run folder, progress.csv, progress lines
    greedy = [("greedy_returns", "greedy: argmax_a Q(s, a)",
               lambda seed: common.pi_actions(q_net, device, seed, greedy=True))]
    autoreset, gradient_steps, phases, checked = False, 0, 0, 0

    with run.saving_model(dict(q_net=q_net), obs_dim=obs_dim, n_actions=n_actions):
        for global_step in range(1, cfg.total_timesteps + 1):
            # --- act: random in the warm-up, then epsilon-greedy in Q ---
            obs = next_obs  # the action belongs to obs; next_obs is only where it led
            epsilon = epsilon_at(global_step, cfg)
            if global_step <= cfg.start_steps or rng.random() < epsilon:
                action = rng.integers(n_actions, size=1)
            else:
                with torch.no_grad():
                    q_values = q_net(torch.as_tensor(obs, dtype=torch.float32, device=device))
                action = q_values.argmax(-1).cpu().numpy()  # (1,)
            next_obs, reward, terminated, truncated, info = envs.step(action)

            # --- store: with terminated, not truncated (see ReplayBuffer.add) ---
            # In NEXT_STEP autoreset mode the step after an episode ends is a reset step (its
            # action ignored, its obs the new episode's first): no transition to store.
            if not autoreset:
                buffer.add(obs[0], action[0], reward[0], next_obs[0], terminated[0])
            autoreset = bool(terminated[0] or truncated[0])
            run.episodes_ended(info, global_step)
            # Solved when the mean return of the last solved_window episodes reaches the
            # threshold; then the greedy policy as it is now must too (once per phase)
            if run.solved(threshold) and cfg.stop_when_solved and checked <= phases:
                checked = phases + 1
                if report.pi_holds(greedy, cfg, threshold, global_step):
                    run.stopped_row(epsilon=epsilon)
                    break

            # --- learn: every train_freq steps, gradient_steps minibatch steps ---
            if global_step <= cfg.start_steps or global_step % cfg.train_freq:
                continue
            stats = []
            for _ in range(cfg.gradient_steps):
                batch = buffer.sample(cfg.batch_size)
                stats.append(dqn_update(q_net, q_target, optimizer, batch, cfg))
                gradient_steps += 1
                if gradient_steps % cfg.target_update_interval == 0:
                    hard_update(q_target, q_net)  # the target network: a copy, C steps old
            phases += 1
            loss, q, next_max, next_double = torch.stack(stats).mean(0).tolist()
            q_greedy = mc_return = None  # measured every q_check_every phases:
            if phases % cfg.q_check_every == 0:  # Q against the return (van Hasselt et al., fig. 3)
                seen = []  # the greedy policy's episodes: their states and rewards
                # 2 episodes of up to 1000 steps, longer than the limit's 500, so that a policy
                # that never falls still leaves 500 states far enough from its end
                common.evaluate(cfg.env_id, common.pi_actions(q_net, device, 0, greedy=True), 2,
                                cfg.eval_seed + 2, trajectories=seen, max_episode_steps=1000)
                # mean max_a Q(s, a) over their states, and the discounted return from each
                q_greedy, mc_return, _ = common.q_against_return(
                    seen, q_net, lambda obs, q_values: q_values.max(-1).values, cfg.gamma, device)
            runlog.stop_if_diverged(global_step, dict(loss=loss), (q_net,), run.dir)
            run.update(dict(loss=loss, q=q, next_max=next_max, next_double=next_double,
                            q_greedy=q_greedy, mc_return=mc_return), visited=batch[0],
                       epsilon=epsilon)
    envs.close()
    def greedy_and_value(net):  # for the maps: the greedy policy as logits (0 at argmax Q,
        # -inf elsewhere) and V(s) = max_a Q(s, a), the network's estimate of its value
        return (lambda obs: torch.log(F.one_hot(net(obs).argmax(-1), n_actions).float()),
                lambda obs: net(obs).max(-1).values)
    nets = dict(untrained=greedy_and_value(untrained), trained=greedy_and_value(q_net))
    before = [("", "", lambda seed: common.pi_actions(untrained, device, seed, greedy=True))]
    return report.finish_updates(run, threshold, greedy, before, pictures(cfg), cartpole_env.maps(
        cfg, nets, device, run.visited, 1.0, labels=("max_a Q(s, a)", "greedy: pushes right")))


def main(argv=None):
    """python dqn_cartpole.py [flags]: train (then --watch), or --eval a saved model."""
    cfg = cli.parse_config(Config, argv, description=__doc__.split("\n\n")[0])
    with cli.clear_exit():  # bad input: one line, exit 2; Ctrl-C: one line, exit 130
        saved = cfg.eval or report.saved_model(train(cfg))  # after a Ctrl-C: exit 130
        if cfg.eval or cfg.watch:  # play the saved greedy policy (in a window with --watch)
            q_net, env_id = checkpoints.load_model(saved, SCRIPT, "q_net", lambda ckpt: QNetwork(
                ckpt["obs_dim"], ckpt["n_actions"], ckpt["config"]["hidden"]))
            report.play(cfg, saved, env_id, [("greedy_returns", "greedy: argmax_a Q(s, a)",
                        lambda seed: common.pi_actions(q_net, "cpu", seed, greedy=True))])


if __name__ == "__main__":
    main()
