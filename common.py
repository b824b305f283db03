"""What the scripts share and a reader reads beside them: discounted returns and GAE (with
worked examples), running statistics to normalise with, running a policy (evaluation), what
the pictures of inside.png measure, making the envs, and at the end the small tools everything
else builds on (one-line errors, SIGTERM as Ctrl-C, whole-file writes). It imports no other
module of this project.

The training loops live in the scripts, each read top to bottom on its own. What a reader
may skip is in cli.py (flags), runlog.py (run folders, logs), checkpoints.py (saving, exact
resume) and report.py (pictures, evaluations, GIFs, --eval).
"""

import contextlib
import math
import os
import signal
import sys
import tempfile
from pathlib import Path

import gymnasium as gym
import numpy as np
import torch


# =============================================================================
# Returns and advantages
# =============================================================================
# Rollouts are shaped (T, N): T time steps of N parallel envs. next_values[t] is V(s_{t+1}),
# the value of the obs that step t led to.
#
# The bootstrap rule (Spinning Up's finish_path(last_val)):
# - at terminated[t] the episode really ended, and the future is 0;
# - at truncated[t] (a time limit) and at t = T-1 (the rollout ran out) it did not:
#   bootstrap with next_values[t].
# Termination wins over truncation.


def discounted_returns(rewards, next_values, terminated, truncated, gamma):
    """Reward-to-go G_t = r_t + gamma * G_{t+1}, cut at episode ends (bootstrap rule above).

    Over a rollout of T steps this is A3C's n-step return: the rewards to the rollout's end,
    then gamma^k * V there. A worked example, gamma = 0.5, T = 3, one env, V(s_3) = 4:
    G_2 = 1 + 0.5 * 4 = 3, G_1 = 1 + 0.5 * G_2 = 2.5, G_0 = 1 + 0.5 * G_1 = 2.25.

    >>> r = torch.tensor([[1.], [1.], [1.]])
    >>> v = torch.tensor([[9.], [9.], [4.]])  # V(s_{t+1})
    >>> no = torch.zeros(3, 1, dtype=torch.bool)
    >>> at1 = torch.tensor([[False], [True], [False]])
    >>> discounted_returns(r, v, no, no, 0.5).flatten().tolist()
    [2.25, 2.5, 3.0]
    >>> discounted_returns(r, v, at1, no, 0.5).flatten().tolist()  # terminated at t=1: no future
    [1.5, 1.0, 3.0]
    >>> discounted_returns(r, v, no, at1, 0.5).flatten().tolist()  # truncated at t=1: + 0.5 * 9
    [3.75, 5.5, 3.0]
    """
    returns = torch.zeros_like(rewards)
    future = next_values[-1]  # bootstrap past the rollout's end
    for t in reversed(range(len(rewards))):
        future = torch.where(truncated[t], next_values[t], future)  # time limit: V(final obs)
        future = torch.where(terminated[t], torch.zeros_like(future), future)  # no future
        returns[t] = future = rewards[t] + gamma * future
    return returns


def gae(rewards, values, next_values, terminated, truncated, gamma, lam):
    """Generalized advantage estimation (Schulman et al. 2016, eq. 16), shaped like `rewards`:

        delta_t = r_t + gamma * V(s_{t+1}) * (1 - terminated_t) - V(s_t)
        A_t     = delta_t + gamma * lam * (1 - done_t) * A_{t+1},  done = terminated or truncated

    A truncated step keeps gamma * V(final obs) in its delta (bootstrap), but stops the sum
    over later deltas, which belong to the next episode. lam = 1 gives G_t - V(s_t), lam = 0
    the one-step TD error; the value targets are A + V.

    A worked example, gamma = 0.5, lam = 1: delta_1 = 1 + 0.5 * 4 - 2 = 1 and
    delta_0 = 1 + 0.5 * 2 - 1 = 1, so A_1 = 1 and A_0 = delta_0 + 0.5 * A_1 = 1.5:

    >>> r, v = torch.tensor([[1.], [1.]]), torch.tensor([[1.], [2.]])
    >>> nv, no = torch.tensor([[2.], [4.]]), torch.zeros(2, 1, dtype=torch.bool)
    >>> gae(r, v, nv, no, no, 0.5, 1.0).flatten().tolist()
    [1.5, 1.0]
    """
    advantages = torch.zeros_like(rewards)
    last = torch.zeros_like(rewards[0])
    not_terminated = (~terminated).to(rewards.dtype)
    not_done = (~(terminated | truncated)).to(rewards.dtype)
    for t in reversed(range(len(rewards))):
        delta = rewards[t] + gamma * next_values[t] * not_terminated[t] - values[t]
        last = advantages[t] = delta + gamma * lam * not_done[t] * last
    return advantages


# =============================================================================
# Normalisation: running statistics
# =============================================================================


class RunningNorm(torch.nn.Module):
    """Observation (or return) normalisation, as a PPO for MuJoCo usually has it: the running
    mean and variance of everything update() has seen (Chan et al.'s formula for merging two
    batches' moments, as gymnasium's RunningMeanStd), and forward: (x - mean) / sqrt(var +
    1e-8), clipped to +-10. Its numbers are buffers: saved with the networks' weights in
    state_dict(). Off (active False): forward returns x as it is.

    A worked example: after [0, 2] and then [4], the mean is 2 and the variance 8/3, as of
    [0, 2, 4] at once (the count starts at 1e-4, as gymnasium's, so they differ by ~1e-4).

    >>> norm = RunningNorm(())
    >>> norm.update(torch.tensor([0., 2.])); norm.update(torch.tensor([4.]))
    >>> round(norm.mean.item(), 3), round(norm.var.item(), 3)
    (2.0, 2.667)
    """

    def __init__(self, shape, active=True):
        super().__init__()
        self.register_buffer("mean", torch.zeros(shape, dtype=torch.float64))
        self.register_buffer("var", torch.ones(shape, dtype=torch.float64))
        self.register_buffer("count", torch.tensor(1e-4, dtype=torch.float64))
        self.register_buffer("active", torch.tensor(active))

    def update(self, x):
        x = torch.as_tensor(x, dtype=torch.float64)  # (B, *shape)
        delta, n = x.mean(0) - self.mean, x.shape[0]
        total = self.count + n
        self.mean += delta * n / total
        self.var = (self.var * self.count + x.var(0, unbiased=False) * n
                    + delta ** 2 * self.count * n / total) / total
        self.count = total

    def forward(self, x):
        if not self.active:
            return x
        return ((x - self.mean) / torch.sqrt(self.var + 1e-8)).clamp(-10, 10).to(x.dtype)


# =============================================================================
# Running a policy: obs -> action functions, evaluation, GIFs
# =============================================================================


def pi_actions(logits_of, device, seed, greedy=False):
    """obs -> action of a categorical policy, for evaluation and GIFs: drawn from pi(.|s) as in
    training (and as tutorial 004 draws its GIFs), or with greedy=True pi's most probable action.
    `logits_of` maps observations to the logits of pi. The draws come from their own
    generator, seeded with `seed`: an evaluation replays exactly."""
    rng = np.random.default_rng(seed)

    def act(obs):
        with torch.no_grad():
            logits = logits_of(torch.as_tensor(obs, dtype=torch.float32, device=device))
        if greedy:
            return int(logits.argmax())
        probs = torch.softmax(logits.double(), -1).cpu().numpy()  # float64: sums to 1 for numpy
        return int(rng.choice(len(probs), p=probs))  # a ~ pi(.|s), tutorial 004's np.random.choice

    return act


def deterministic(actor, device):
    """obs -> mu(obs) as a numpy action, without exploration noise: DDPG's evaluation."""
    def act(obs):
        with torch.no_grad():
            return actor(torch.as_tensor(obs, dtype=torch.float32, device=device)).cpu().numpy()

    return act


def evaluate(env_id, policy, episodes, seed, render_mode=None, log=False, trajectories=None,
             **make_kw):
    """Returns of `episodes` episodes of `policy` (obs -> action), the env seeded once with
    `seed`. render_mode="human" shows a window (make_kw go to gym.make); log=True prints each
    return as its episode ends; a list `trajectories` receives each episode's observations,
    rewards and whether it terminated (rather than hit the time limit)."""
    with env_errors(env_id):
        env = gym.make(env_id, render_mode=render_mode, **make_kw)
    returns = []
    try:
        obs, _ = env.reset(seed=seed)
        viewer = getattr(getattr(env.unwrapped, "mujoco_renderer", None), "viewer", None)
        if viewer is not None and render_mode == "human":
            viewer._hide_menu = True  # MuJoCo's window: its menu would cover half the walker
        for episode in range(1, episodes + 1):
            done, total, seen, rewards = False, 0.0, [], []
            while not done:
                if trajectories is not None:  # the states it acts in, and what each brought
                    seen.append(obs)
                obs, reward, terminated, truncated, _ = env.step(policy(obs))
                total += float(reward)
                done = terminated or truncated
                if trajectories is not None:
                    rewards.append(float(reward))
            returns.append(total)
            if trajectories is not None:
                trajectories.append(dict(obs=np.array(seen), rewards=np.array(rewards),
                                         terminated=bool(terminated)))
            if log:
                print(f"episode {episode}/{episodes}: return {total:.1f}  (Ctrl-C stops)",
                      flush=True)
            obs, _ = env.reset()
    finally:
        env.close()
    return returns


def record_gif(env_id, policy, path, seed, max_frames=300, fps=30, every=1, scale=1, **make_kw):
    """Play one episode off-screen and return its return. One frame in `every` (fps lowered to
    match), at most `max_frames`, `scale` times smaller, go to `path` as a looping GIF, written
    whole or not at all."""
    import imageio.v2 as imageio
    import PIL.Image  # comes with imageio

    def frame():  # Image.reduce: each pixel the mean of a scale x scale block (thin lines stay)
        return np.asarray(PIL.Image.fromarray(env.render()).reduce(scale))

    with env_errors(env_id):
        env = gym.make(env_id, render_mode="rgb_array", **make_kw)
    frames, total, t, done = [], 0.0, 0, False
    try:
        obs, _ = env.reset(seed=seed)
        frames.append(frame())
        while not done:
            obs, reward, terminated, truncated, _ = env.step(policy(obs))
            total, t = total + float(reward), t + 1
            done = terminated or truncated
            if (t % every == 0 or done) and len(frames) < max_frames:
                frames.append(frame())
    finally:
        env.close()
    with written_whole(path) as tmp:  # a Ctrl-C waits until the GIF is whole
        imageio.mimsave(tmp, frames, format="GIF", duration=1000 * every / fps, loop=0)
    return total



# =============================================================================
# Inside the algorithms: what an update did to PPO's ratio, and DDPG's overestimation
# =============================================================================

QUANTILES = {"ratio_q05": 0.05, "ratio_q25": 0.25, "ratio_median": 0.5, "ratio_q75": 0.75,
             "ratio_q95": 0.95}


# ratio_stats' numbers as progress.csv columns: (progress-line format: none, what each is)
RATIO_COLUMNS = {**{key: (None, f"r's {key[6:]} after the update")
                    for key in ("ratio_min", *QUANTILES, "ratio_max")},
                 "zero_grad_frac": (None, "no policy gradient after it (clip binds on A's side)"),
                 "clipfrac_after": (None, "clipfrac after the update")}


def ratio_stats(ratio, adv, clip_coef, normalize=True):
    """The ratio r = pi(a|s) / pi_old(a|s) over a batch after a PPO update: its min, quantiles
    and max, and zero_grad_frac, the share of samples whose term of L_CLIP has no gradient.

    The clip does not keep r inside [1 - eps, 1 + eps]. min(r A, clip(r) A) only goes flat
    on the side the advantage favours: for A > 0 once r > 1 + eps, for A < 0 once r < 1 - eps.
    Such a sample stops pulling pi further; the other samples, and the shared network, still
    move it. clipfrac_after is clipfrac (|r - 1| > eps, either side) on these same ratios: never
    below zero_grad_frac, except for samples with A = 0. The sign of `adv` is taken against the
    batch's mean when the update normalizes (per minibatch: approximate).

    >>> r, a = torch.tensor([1.5, 1.5, 0.5, 0.5, 1.0]), torch.tensor([1., -1., 1., -1., 1.])
    >>> ratio_stats(r, a, 0.2, normalize=False)["zero_grad_frac"]  # samples 0 and 3
    0.4
    """
    if normalize:
        adv = adv - adv.mean()  # the sign after normalization (the std does not change it)
    flat = ((adv > 0) & (ratio > 1 + clip_coef)) | ((adv < 0) & (ratio < 1 - clip_coef))
    stats = {key: torch.quantile(ratio, q).item() for key, q in QUANTILES.items()}
    outside = (ratio - 1).abs() > clip_coef  # clipfrac's count, on these same ratios
    return dict(ratio_min=ratio.min().item(), **stats, ratio_max=ratio.max().item(),
                zero_grad_frac=(flat | (adv == 0)).double().mean().item(), ratio=ratio, adv=adv,
                clipfrac_after=outside.double().mean().item())


def tail_horizon(gamma, tail=0.66, at_least=500):
    """How many steps before a time-limit end a state needs, for q_against_return, so that the
    return it cannot see past that end, at most gamma^H * r_max / (1 - gamma), stays under
    `tail` * r_max: 500 up to gamma = 0.99 (0.99^500 / 0.01 = 0.66), more above (gamma =
    0.995: 1140, so a 1000-step episode cut by the limit gives no state). gamma = 1: no
    horizon is enough (inf): only terminated episodes count.

    >>> tail_horizon(0.99), tail_horizon(0.995), tail_horizon(1.0)
    (500, 1140, inf)
    """
    if gamma >= 1:
        return math.inf
    return max(at_least, math.ceil(math.log(tail * (1 - gamma)) / math.log(gamma)))


def q_against_return(trajectories, actor, critic, gamma, device, horizon=None):
    """DDPG's overestimation, after the TD3 paper's Figure 1 (Fujimoto et al. 2018): the
    critic's estimate Q(s, mu(s)) against the discounted return mu really obtained from s,
    both averaged over the states of evaluation episodes. Returns (mean Q, mean return,
    number of states). A variant of the paper's measure: its rollouts start from states of
    the replay buffer; ours are the evaluation episodes' own states, so Q is checked where
    mu itself goes.

    Where an episode hit the time limit, its return past the limit is unseen. So only states
    at least `horizon` (default: tail_horizon(gamma)) steps before that end count: the unseen
    tail then adds at most 0.66 times a step's largest reward to their return (Walker2d's
    rewards per step are a few units). After a termination the future really is 0 and every
    state counts."""
    horizon = tail_horizon(gamma) if horizon is None else horizon
    states, targets = [], []
    for episode in trajectories:
        rewards, g = episode["rewards"], 0.0
        returns = np.zeros(len(rewards))
        for t in reversed(range(len(rewards))):  # G_t = r_t + gamma * G_{t+1}
            g = returns[t] = rewards[t] + gamma * g
        # gamma = 1: horizon inf, no bound on the unseen tail: no state of a cut episode counts
        keep = len(rewards) if episode["terminated"] else max(len(rewards) - horizon, 0)
        states.append(episode["obs"][:keep])
        targets.append(returns[:keep])
    states = np.concatenate(states) if states else np.zeros((0, 1))
    if len(states) == 0:
        return float("nan"), float("nan"), 0
    with torch.no_grad():
        obs = torch.as_tensor(states, dtype=torch.float32, device=device)
        q = critic(obs, actor(obs))
    return float(q.mean()), float(np.concatenate(targets).mean()), len(states)


# =============================================================================
# Making the envs
# =============================================================================


def make_vec_env(env_id, num_envs, seed, solved_return=None, continuous=False):
    """gym.make_vec of a Discrete-action env (continuous=True: a Box-action one), reset with
    `seed`. Returns the envs, the first obs and the return that counts as solved (solved_return,
    or the env's reward_threshold; a Discrete-action env must have one, for the solved rule).

    Autoreset is NEXT_STEP (gymnasium 1.x's default): the step after an episode ends is a reset
    step. RecordEpisodeStatistics puts each ended episode's return in info["episode"]."""
    kind = gym.spaces.Box if continuous else gym.spaces.Discrete
    with env_errors(env_id):
        envs = gym.make_vec(env_id, num_envs)
        envs = gym.wrappers.vector.RecordEpisodeStatistics(envs)
        assert envs.metadata["autoreset_mode"] == gym.vector.AutoresetMode.NEXT_STEP
        if not isinstance(envs.single_action_space, kind):
            envs.close()
            raise UserError(f"{env_id} has {type(envs.single_action_space).__name__} "
                            f"actions; this script needs {kind.__name__} actions")
        solved = envs.spec.reward_threshold if solved_return is None else solved_return
        if solved is None and not continuous:
            raise UserError(f"{env_id} has no reward_threshold; pass --solved-return")
        envs.action_space.seed(seed)
        obs, _ = envs.reset(seed=seed)
    return envs, obs, solved


def make_continuous_env(env_id):
    """One MuJoCo env with Box actions, as DDPG needs (tutorial 003: one env). Its
    RecordEpisodeStatistics wrapper puts an ended episode's return in info["episode"]["r"]."""
    with env_errors(env_id):
        env = gym.wrappers.RecordEpisodeStatistics(gym.make(env_id))
    if not isinstance(env.action_space, gym.spaces.Box):
        env.close()
        raise UserError(f"{env_id} has a {type(env.action_space).__name__} action "
                        "space; this script needs continuous (Box) actions")
    if not hasattr(env.unwrapped, "data"):  # checkpoints save MuJoCo's simulator state
        env.close()
        raise UserError(f"{env_id} is not a MuJoCo env; this script trains MuJoCo tasks "
                        "(its checkpoints save MuJoCo's simulator state)")
    return env


# =============================================================================
# Tools the other modules build on: one-line errors, headless rendering, SIGTERM as Ctrl-C,
# whole-file writes and the check that a folder takes them
# =============================================================================


class UserError(Exception):
    """Bad input the user can fix: printed as one line, exit code 2 (cli.clear_exit)."""


def from_ctrl_c(error):
    """Is `error` a KeyboardInterrupt (Ctrl-C, or a SIGTERM under sigterm_as_ctrl_c), or raised
    because of one (MuJoCo's import, a torch write)?"""
    while error is not None and not isinstance(error, KeyboardInterrupt):
        error = error.__cause__ or error.__context__  # Python keeps this chain free of loops
    return error is not None


def headless():
    """Is this a Linux machine without a display (no window can open)?"""
    return sys.platform == "linux" and not any(map(os.environ.get, ("DISPLAY", "WAYLAND_DISPLAY")))


def headless_defaults():
    """Without a display, pygame draws into memory and MuJoCo renders through EGL. Called
    where an env is made, before pygame or MuJoCo load; never overrides the user's settings."""
    if headless():
        os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
        os.environ.setdefault("MUJOCO_GL", "egl")
    os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")


@contextlib.contextmanager
def env_errors(env_id):
    """Makes an env (headless_defaults first): an unknown id, a missing extra or too little
    memory becomes one clear UserError."""
    headless_defaults()
    try:
        yield
    except (ImportError, gym.error.DependencyNotInstalled) as e:  # e.g. no MuJoCo
        if from_ctrl_c(e):  # Ctrl-C while MuJoCo was imported: no package is missing
            raise KeyboardInterrupt from None
        raise UserError(f"{env_id} needs a package that is not installed: {e}") from None
    except gym.error.Error as e:  # NameNotFound, VersionNotFound, ...
        raise UserError(f"unknown environment {env_id!r}: {e}") from None
    except AttributeError as e:  # MuJoCo's import with MUJOCO_GL=egl finds no libEGL
        if "egl" not in str(e).lower():
            raise
        raise UserError(f"{env_id}: MuJoCo cannot render without the EGL library (install "
                        "libegl1, or set MUJOCO_GL=osmesa with OSMesa installed)") from None
    except MemoryError:
        raise UserError(f"not enough memory for {env_id} (too many envs or steps?)") from None


_terminated = []  # the SIGTERMs that sigterm_as_ctrl_c turned into a Ctrl-C


@contextlib.contextmanager
def sigterm_as_ctrl_c():
    """Within the block, SIGTERM (`kill PID`, a Slurm job at its time limit, `docker stop`) does
    what Ctrl-C does at that moment: a KeyboardInterrupt, or held back by ctrl_c_deferred, or a
    training loop's stop at a whole step (checkpoints.CtrlC). Ctrl-C works too where this process
    started with it ignored (a shell script's `cmd &`). stopped_by() then says which came."""
    before = signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)
    try:
        if before[0] == signal.SIG_IGN:
            signal.signal(signal.SIGINT, signal.default_int_handler)
        signal.signal(signal.SIGTERM, _as_ctrl_c)
    except ValueError:  # not the main thread, which alone receives signals
        before = None
    _terminated.clear()
    try:
        yield
    finally:
        for signum, handler in zip((signal.SIGINT, signal.SIGTERM), before or ()):
            if handler is not None:  # None: a handler set outside Python, left as it is
                signal.signal(signum, handler)


def _as_ctrl_c(signum, frame):
    """SIGTERM's handler: remembered, then handled by whatever handles Ctrl-C right now."""
    _terminated.append(signum)
    ctrl_c = signal.getsignal(signal.SIGINT)
    if not callable(ctrl_c):
        raise KeyboardInterrupt
    ctrl_c(signal.SIGINT, frame)


def stopped_by():
    """What stopped this process, and its exit code (128 + the signal's number, as a shell
    reports a process the signal killed): ("Ctrl-C", 130), or ("SIGTERM", 143) once
    sigterm_as_ctrl_c has turned a SIGTERM into a Ctrl-C."""
    if _terminated:
        return "SIGTERM", 128 + signal.SIGTERM
    return "Ctrl-C", 128 + signal.SIGINT


@contextlib.contextmanager
def ctrl_c_deferred():
    """Hold a Ctrl-C (or a SIGTERM, under sigterm_as_ctrl_c) back while the block runs (a file
    write), then deliver it."""
    before, pressed = signal.getsignal(signal.SIGINT), []
    try:
        signal.signal(signal.SIGINT, lambda signum, frame: pressed.append(signum))
    except (ValueError, TypeError):  # not the main thread, or a handler set outside Python
        before = None
    try:
        yield
    finally:
        if before is not None:
            signal.signal(signal.SIGINT, before)
        if pressed:
            signal.raise_signal(signal.SIGINT)  # the held Ctrl-C, now


@contextlib.contextmanager
def written_whole(path):
    """Yield a path to write, then rename it to `path`: no half file nor .tmp, Ctrl-C or not."""
    tmp = Path(f"{path}.tmp")
    with ctrl_c_deferred():
        try:
            yield tmp
            os.replace(tmp, path)
        except OSError as e:
            raise UserError(f"cannot write {path}: {e.strerror or e}") from None
        finally:
            with contextlib.suppress(OSError):  # a read-only folder: no .tmp, and the line says so
                tmp.unlink(missing_ok=True)


def check_writable(folder, what, then=""):
    """One UserError, before any long work, unless files can be written into `folder`: it exists
    and is not read-only. A write is tried (an unnamed temporary file: nothing is left there).
    `what` starts the line (the flag), `then` ends it (what to do instead)."""
    folder = Path(folder)
    if not folder.is_dir():
        raise UserError(f"{what}: no folder {folder} (create it first)")
    try:
        with tempfile.TemporaryFile(dir=folder):
            pass
    except OSError as e:
        raise UserError(f"{what}: cannot write into {folder}: {e.strerror or e}"
                        + (f"; {then}" if then else "")) from None
