"""Advantage actor-critic (A2C) on CartPole-v1 (Mnih et al. 2016, "Asynchronous Methods for
Deep Reinforcement Learning"; A2C is its synchronous variant).

Read beside tutorial 004, which trains a Keras actor-critic one whole episode at a
time: the same model (a shared hidden layer feeding an actor head and a critic
head), the same running reward and before/after GIFs. What changes is how often it
learns: A2C takes one gradient step every num_steps steps of num_envs envs, with
n-step returns bootstrapped from the critic, instead of waiting for episodes to end.
It is ppo_cartpole.py's sibling: the same buffer, loop and logs; one step per batch
where PPO takes many behind its clip. The loop, top to bottom:

    collect  num_steps x num_envs transitions with the current policy
    returns  n-step returns R_t (common.discounted_returns), bootstrapped from V at the
             rollout's end and at time-limit truncations; advantages A_t = R_t - V(s_t)
    update   one gradient step on -log pi(a|s) * A + c_v * (R - V)^2 / 2 - c_e * entropy
    log      one progress.csv row per update; a progress line now and then

    python actor_critic_cartpole.py                  # train until solved (seconds to minutes)
    python actor_critic_cartpole.py --help           # every hyperparameter, with its meaning
    python actor_critic_cartpole.py --eval runs/<run> --watch   # replay a saved model in a window

中文导读：本脚本教 A2C（优势 actor-critic）：一个共享隐藏层接 actor 和 critic 两个头，
每采一批数据就用 n 步回报更新一次，不必等回合结束。配套教程：
《使用 actor-critic 方法来控制 CartPole-V0 游戏》（004）。循环四步：

    采样  当前策略在 num_envs 个环境里各走 num_steps 步
    回报  n 步回报 R_t（批末和时间截断处用 V 自举），优势 A_t = R_t - V(s_t)
    更新  一步梯度：策略损失 + vf_coef * 价值损失 - ent_coef * 熵
    记录  每次更新在 progress.csv 里记一行，隔几次打印一行进度（含 running reward）
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
    total_timesteps: int = 200_000
    """budget of env steps (all envs together); training usually stops long before, when solved"""
    stop_when_solved: bool = True
    """stop once the mean return of the last 20 finished episodes reaches the solved return
    and pi as it is then does too, over eval_episodes episodes with actions drawn from pi
    (env seed eval_seed + 1); checked at most once per update, training goes on until then"""
    solved_return: float | None = None
    """the return that counts as solved; none = the env's reward_threshold (CartPole-v1: 475)"""

    # --- collection ---
    num_envs: int = 8
    """parallel envs (A3C's parallel actors, here in lockstep; 1 .. 64)"""
    num_steps: int = 64
    """steps per env between updates, the n of the n-step return (A3C: 5 .. 20; here longer,
    so that CartPole's one signal, the pole falling, reaches back further per update)"""

    # --- A2C ---
    learning_rate: float = 0.01
    """Adam step size (tutorial 004: 0.01; A2C usually 7e-4 .. 1e-2)"""
    anneal_lr: bool = False
    """decay the learning rate linearly to 0 over total_timesteps"""
    gamma: float = 0.98
    """discount factor (tutorial 004: 0.99; 0.95 .. 0.99); 0.98 looks about 50 steps ahead"""
    reward_scale: float | None = None
    """rewards are multiplied by this for learning (logged returns are not); none = 1 - gamma
    (1 when gamma = 1), which keeps V's targets in [0, 1] (the tutorial normalizes returns)"""
    lam: float | None = None
    """none = the textbook n-step returns and A = R - V; a number in [0, 1] = GAE(lambda)
    advantages instead (Schulman et al. 2016; 0.9 .. 0.97 usual)"""
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
            self, total_timesteps="> 0", num_envs="> 0", num_steps="> 0", hidden="> 0",
            print_every="> 0", eval_episodes="> 0", threads="> 0", learning_rate="> 0",
            ent_coef=">= 0", vf_coef=">= 0", max_grad_norm=">= 0", gamma="(0, 1]",
            lam="[0, 1] or none", reward_scale="> 0 or none", running_reward_alpha="(0, 1]")
        batch = self.num_envs * self.num_steps
        common.check(self.total_timesteps >= batch,
                     f"--total-timesteps ({self.total_timesteps}) is less than one rollout "
                     f"(num_envs x num_steps = {batch}): nothing would be learned")
        common.check(not self.gif or self.eval,
                     "--gif writes a GIF of a saved policy: it needs --eval")


# =============================================================================
# Rollout buffer and loss
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


def a2c_targets(model, rollout, next_obs, cfg):
    """Critic targets R_t and advantages A_t of one rollout, each (T, N)."""
    with torch.no_grad():  # targets are constants: no gradient flows into the bootstrap
        _, values = model(rollout["obs"])  # (T, N)
        # V(s_{t+1}) is the value of the next stored obs. After a done step that obs is the
        # episode's real final observation (the reset step reports it), so a truncated step
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
    # we minimize its negative. A_t is a constant here: no gradient flows into it.
    loss_pi = -(dist.log_prob(act) * adv).mean()
    # Critic: (R_t - V(s_t))^2 (Algorithm S3), halved as is usual: plain MSE.
    loss_v = 0.5 * ((values - ret) ** 2).mean()
    # Entropy bonus H(pi(.|s)) = -sum_a pi log pi (Mnih et al. 2016, section 4): keeps exploring.
    entropy = dist.entropy().mean()
    loss = loss_pi + cfg.vf_coef * loss_v - cfg.ent_coef * entropy
    return loss, dict(loss_pi=loss_pi.item(), loss_v=loss_v.item(), entropy=entropy.item())


# =============================================================================
# Training
# =============================================================================


def act_fn(model, device, seed, greedy=False):
    """obs -> action, for evaluation and GIFs: drawn from pi(.|s) as in training (and as
    tutorial 004 draws its GIFs), or with greedy=True pi's most probable action. The draws
    come from their own generator, seeded with `seed`: an evaluation replays exactly."""
    rng = np.random.default_rng(seed)

    def act(obs):
        with torch.no_grad():
            logits, _ = model(torch.as_tensor(obs, dtype=torch.float32, device=device))
        if greedy:
            return int(logits.argmax())
        probs = torch.softmax(logits.double(), -1).cpu().numpy()  # float64: sums to 1 for numpy
        return int(rng.choice(len(probs), p=probs))  # a ~ pi(.|s), tutorial 004's np.random.choice
    return act


def holds(model, device, cfg, threshold, step):
    """Does pi, as it is now, also reach `threshold`: the mean return of cfg.eval_episodes
    episodes, actions drawn from pi, env and draws seeded with eval_seed + 1 (apart from
    training and from the evaluation after it)? Says what it found in one line."""
    returns = common.evaluate(cfg.env_id, act_fn(model, device, cfg.eval_seed + 1),
                              cfg.eval_episodes, cfg.eval_seed + 1)
    held = np.mean(returns) >= threshold
    print(f"check at step {step}: pi as it is now averages {np.mean(returns):.1f} over "
          f"{len(returns)} episodes: " + ("it holds, training stops" if held else
                                         f"below {threshold:g}, training goes on"), flush=True)
    return held


def train(cfg: Config):
    """Train A2C with `cfg`. Returns a dict: run_dir, solved, global_step,
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

    model = ActorCritic(obs_dim, n_actions, cfg.hidden).to(device)
    untrained = copy.deepcopy(model)  # before.gif is drawn from these weights after training
    optimizer = torch.optim.Adam(model.parameters(), lr=cfg.learning_rate, eps=1e-5)
    num_updates = cfg.total_timesteps // (T * N)
    default_scale = 1 - cfg.gamma if cfg.gamma < 1 else 1.0
    reward_scale = cfg.reward_scale if cfg.reward_scale is not None else default_scale

    # In NEXT_STEP autoreset mode, the step after an episode ends is a reset
    # step: its action is ignored, its reward is 0 and the obs it returns is
    # the first of the new episode. `autoreset` marks envs whose next step is one.
    autoreset = np.zeros(N, dtype=bool)

    # --- episode bookkeeping, the stop and the log: plumbing, out of the loop's way ---
    episodes = []  # (env step, return) of every finished training episode, in order
    running_reward, alpha = 0.0, cfg.running_reward_alpha  # tutorial 004's smoothed return
    global_step, solved_step, update, interrupted, stats = 0, None, 0, False, {}
    checked, stopped = 0, False  # the last update at which pi was checked; whether it held

    def mean20():  # the mean return of the last 20 finished episodes
        return float(np.mean([r for _, r in episodes[-20:]])) if episodes else float("nan")

    def log(stats, line=False):  # one progress.csv row: the state of training now
        common.append_csv(run_dir / "progress.csv", dict(
            global_step=global_step, episodes=len(episodes), return_mean20=mean20(),
            running_reward=running_reward, lr=optimizer.param_groups[0]["lr"], **stats))
        if line:  # and the progress line
            elapsed = time.time() - start_time
            print(f"step {global_step:>7}  {global_step / elapsed:6.0f} steps/s  "
                  f"return(20) {mean20():6.1f}  running reward {running_reward:6.1f}  "
                  f"loss_pi {stats['loss_pi']:+.3f}  loss_v {stats['loss_v']:.2e}  "
                  f"entropy {stats['entropy']:.3f}  {elapsed:.1f}s", flush=True)

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
        if not holds(model, device, cfg, threshold, global_step):
            return False
        log(dict.fromkeys(stats, float("nan")))  # the last row: where training ended
        return True

    try:
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
                ended, solved = common.finished_episodes(info, global_step, episodes, threshold)
                episodes += ended
                for _, ep_return in ended:  # tutorial 004's running reward
                    running_reward = alpha * ep_return + (1 - alpha) * running_reward
                stopped = solved and stop_now(update)
                if stopped:
                    break
            if stopped:  # solved, and pi held: the partial rollout trains nothing
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
            common.stop_if_diverged(global_step, stats, (model,), run_dir, obs=next_obs)
            log(stats, line=update % cfg.print_every == 0 or update == 1)  # CSV, progress line
    except KeyboardInterrupt:
        interrupted = True
    except (ValueError, RuntimeError):  # e.g. Categorical refusing nan logits: diverged?
        # If so, one line: stop_if_diverged finds the nan in the weights or in their output.
        common.stop_if_diverged(global_step, {}, (model,), run_dir, obs=next_obs)
        raise
    finally:
        envs.close()
        if run_dir.exists():  # common.stop_if_diverged removes a diverged run's folder
            for step, ep_return in episodes:
                common.append_csv(run_dir / "episodes.csv",
                                  {"global_step": step, "return": ep_return})
            common.save_checkpoint(dict(script=SCRIPT, model=model.state_dict(),
                                        config=asdict(cfg), obs_dim=obs_dim, n_actions=n_actions,
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
    returns = common.evaluate(cfg.env_id, act_fn(model, device, cfg.eval_seed), n, cfg.eval_seed)
    print(f"evaluation over {n} episodes, actions drawn from pi: mean {np.mean(returns):.1f}, "
          f"min {min(returns):.0f}", flush=True)
    greedy_returns = common.evaluate(cfg.env_id, act_fn(model, device, cfg.eval_seed, greedy=True),
                                     n, cfg.eval_seed)
    print(f"greedy evaluation over {n} episodes (pi's most probable action): mean "
          f"{np.mean(greedy_returns):.1f}, min {min(greedy_returns):.0f}", flush=True)
    result["eval_returns"], result["greedy_returns"] = returns, greedy_returns
    if cfg.gifs:  # one episode each, actions drawn from pi: after.gif shows the evaluation's
        # first episode. Every 2nd frame at half size: small files.
        for name, net in (("before.gif", untrained), ("after.gif", model)):
            ret = common.record_gif(cfg.env_id, act_fn(net, device, cfg.eval_seed), run_dir / name,
                                    cfg.eval_seed, every=2, scale=2)
            print(f"{name}: return {ret:.0f} -> {run_dir / name}", flush=True)
    return result


def play(cfg: Config):
    """--eval PATH: load a saved model, play cfg.eval_episodes episodes with actions drawn from
    pi (shown with --watch), then as many greedy ones. Returns the first ones' returns.
    With --gif: write one episode, drawn as after.gif is, to that file instead."""
    ckpt = common.load_checkpoint(cfg.eval, script=SCRIPT,
                                  required=("model", "obs_dim", "n_actions", "config"))
    model = ActorCritic(ckpt["obs_dim"], ckpt["n_actions"], ckpt["config"]["hidden"])
    common.load_weights(model, ckpt["model"], cfg.eval)
    env_id = ckpt["config"]["env_id"]
    if cfg.gif:  # one episode to a GIF file, as after.gif is drawn
        ret = common.record_gif(env_id, act_fn(model, "cpu", cfg.eval_seed), cfg.gif,
                                cfg.eval_seed, every=2, scale=2)
        print(f"{cfg.gif}: one episode, return {ret:.0f}", flush=True)
        return [ret]
    print(f"playing {cfg.eval_episodes} episodes of {env_id} with {cfg.eval}"
          + ("; Ctrl-C stops" if cfg.watch else ""), flush=True)
    returns = common.evaluate(env_id, act_fn(model, "cpu", cfg.eval_seed), cfg.eval_episodes,
                              cfg.eval_seed, render_mode="human" if cfg.watch else None,
                              log=cfg.watch)
    print(f"{env_id}, {cfg.eval}: returns {[round(r) for r in returns]}, "
          f"mean {np.mean(returns):.1f} (actions drawn from pi)", flush=True)
    greedy_returns = common.evaluate(env_id, act_fn(model, "cpu", cfg.eval_seed, greedy=True),
                                     cfg.eval_episodes, cfg.eval_seed)
    print(f"greedy (pi's most probable action): returns {[round(r) for r in greedy_returns]}, "
          f"mean {np.mean(greedy_returns):.1f}", flush=True)
    return returns


def main(argv=None):
    """python actor_critic_cartpole.py [flags]: train (then --watch), or --eval a saved model."""
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
