"""Small helpers shared by every script: returns, GAE, GIFs, and the plumbing.

Nothing here is specific to one algorithm. The training loops live in the
scripts themselves (ppo_cartpole.py, ...), deliberately duplicated, so each
script reads top to bottom on its own. What is *not* algorithm lives here once:

    discounted_returns, gae       -- the two ways to turn rewards into targets
    record_gif, before_after_gifs -- off-screen rendering of one episode to a GIF
    evaluate                      -- play N episodes with a policy, return their returns
    parse_config, main            -- a @dataclass Config becomes --flag options; the CLI flow
    seed_everything, make_run_dir, append_csv, save_checkpoint, load_checkpoint
    UserError, exit_on_user_error -- bad input ends in one clear line, exit 2
"""

from __future__ import annotations

import argparse
import ast
import contextlib
import csv
import dataclasses
import inspect
import os
import random
import sys
import textwrap
import time
from pathlib import Path

# --- headless machines ---
# Rendering needs a display unless we say otherwise. This must run before
# pygame or mujoco are imported (gymnasium imports them only when an env that
# needs them is made), and it never overrides a choice the user made.
if sys.platform.startswith("linux") and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
    os.environ.setdefault("SDL_VIDEODRIVER", "dummy")  # pygame draws into memory
    os.environ.setdefault("MUJOCO_GL", "egl")  # MuJoCo renders through EGL, no X server
os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")

import gymnasium as gym  # noqa: E402  (after the environment variables above)
import numpy as np  # noqa: E402
import torch  # noqa: E402
from torch.optim.adam import adam as torch_adam  # noqa: E402  (the function behind torch.optim.Adam)


# =============================================================================
# Returns and advantages
# =============================================================================
# Both helpers work on rollouts shaped (T, N): T time steps of N parallel envs.
# The bootstrap rule, as in Spinning Up's `finish_path(last_val)`:
#
#   * terminated[t]  -- the episode really ended (the pole fell): the future is 0.
#   * truncated[t]   -- a time limit cut the episode short: the future is not 0,
#                       so we bootstrap with the value of the real final
#                       observation, next_values[t].
#   * t == T - 1     -- the rollout ran out mid-episode: bootstrap likewise.
#
# `next_values[t]` is V(s_{t+1}), the value of the observation that step t led
# to (for a truncated step, the final observation of the episode, not the first
# observation of the next one). If both flags are set, termination wins.


def discounted_returns(rewards, next_values, terminated, truncated, gamma):
    """Reward-to-go G_t = r_t + gamma * G_{t+1}, cut at episode ends.

    At a termination the future is 0; at a truncation, or at the last step of
    the rollout, the future is next_values[t] (bootstrap). With gamma=0.5:

    >>> r = torch.tensor([[1.], [1.], [1.]])            # T=3, N=1
    >>> v = torch.tensor([[9.], [9.], [4.]])            # V(s_{t+1})
    >>> no = torch.zeros(3, 1, dtype=torch.bool)
    >>> discounted_returns(r, v, no, no, 0.5).flatten().tolist()
    [2.25, 2.5, 3.0]
    >>> term = torch.tensor([[False], [True], [False]])
    >>> discounted_returns(r, v, term, no, 0.5).flatten().tolist()
    [1.5, 1.0, 3.0]
    >>> discounted_returns(r, v, no, term, 0.5).flatten().tolist()  # truncated at t=1
    [3.75, 5.5, 3.0]

    Returns a tensor shaped like `rewards`. For an episodic Monte-Carlo return,
    pass whole episodes with next_values = 0.
    """
    T = rewards.shape[0]
    returns = torch.zeros_like(rewards)
    future = next_values[T - 1]  # bootstrap past the end of the rollout
    for t in reversed(range(T)):
        # At a truncation, the future is the value of the final observation.
        future = torch.where(truncated[t], next_values[t], future)
        # At a termination, there is no future at all.
        future = torch.where(terminated[t], torch.zeros_like(future), future)
        returns[t] = rewards[t] + gamma * future
        future = returns[t]
    return returns


def gae(rewards, values, next_values, terminated, truncated, gamma, lam):
    """Generalized advantage estimation (Schulman et al. 2016, eq. 16).

        delta_t = r_t + gamma * V(s_{t+1}) * (1 - terminated_t) - V(s_t)
        A_t     = delta_t + gamma * lam * (1 - done_t) * A_{t+1},  done = terminated or truncated

    A truncated step keeps gamma * V(final observation) inside its delta
    (bootstrap) but, like a terminated one, stops the sum over later deltas,
    which belong to the next episode. lam=1 gives G_t - V(s_t) (Monte Carlo
    minus baseline); lam=0 gives the one-step TD error. With gamma=0.5, lam=1:

    >>> r = torch.tensor([[1.], [1.]]); v = torch.tensor([[1.], [2.]])
    >>> nv = torch.tensor([[2.], [4.]]); no = torch.zeros(2, 1, dtype=torch.bool)
    >>> gae(r, v, nv, no, no, 0.5, 1.0).flatten().tolist()
    [1.5, 1.0]

    (delta_1 = 1 + 0.5*4 - 2 = 1; delta_0 = 1 + 0.5*2 - 1 = 1; A_0 = 1 + 0.5*1.)
    Returns advantages shaped like `rewards`; the value targets are A + V.
    """
    T = rewards.shape[0]
    advantages = torch.zeros_like(rewards)
    not_terminated = (~terminated).to(rewards.dtype)
    not_done = (~(terminated | truncated)).to(rewards.dtype)
    last = torch.zeros_like(rewards[0])
    for t in reversed(range(T)):
        delta = rewards[t] + gamma * next_values[t] * not_terminated[t] - values[t]
        last = delta + gamma * lam * not_done[t] * last
        advantages[t] = last
    return advantages


# =============================================================================
# Optimizer
# =============================================================================


class Adam:
    """torch.optim.Adam without its one-second first use: the same function, called directly.

    The first use of any torch.optim optimizer object imports torch._dynamo, the
    compiler, which takes about 1.1 s on a 2-core CPU. Our CartPole scripts solve
    in about 3 s in all, so that import alone would be a third of the wait. This
    class keeps Adam's state itself and calls torch.optim.adam.adam, the function
    behind torch.optim.Adam (fused kernel), so the arithmetic is torch's own:

        m_t = beta1 * m_{t-1} + (1 - beta1) * g_t          (Kingma & Ba 2015, Algorithm 1)
        v_t = beta2 * v_{t-1} + (1 - beta2) * g_t^2
        theta_t = theta_{t-1} - lr * (m_t / (1 - beta1^t)) / (sqrt(v_t / (1 - beta2^t)) + eps)

    It has the interface our loops use: zero_grad(), step() and
    param_groups[0]["lr"]; tests/test_common.py checks it against torch.optim.Adam.
    """

    def __init__(self, params, lr, betas=(0.9, 0.999), eps=1e-8):
        self.params = [p for p in params if p.requires_grad]
        self.param_groups = [dict(lr=lr, betas=betas, eps=eps)]
        self.exp_avgs = [torch.zeros_like(p) for p in self.params]  # m
        self.exp_avg_sqs = [torch.zeros_like(p) for p in self.params]  # v
        self.state_steps = [torch.zeros((), device=p.device) for p in self.params]  # t

    def zero_grad(self):
        for p in self.params:
            p.grad = None

    @torch.no_grad()
    def step(self):
        group = self.param_groups[0]
        torch_adam(self.params, [p.grad for p in self.params], self.exp_avgs, self.exp_avg_sqs, [],
                   self.state_steps, fused=True, amsgrad=False, beta1=group["betas"][0],
                   beta2=group["betas"][1], lr=group["lr"], weight_decay=0.0, eps=group["eps"],
                   maximize=False)


# =============================================================================
# Running a policy: greedy evaluation and GIFs
# =============================================================================
# A "policy" here is any function obs (numpy array) -> action for one env.


def evaluate(env_id, policy, episodes, seed, render_mode=None):
    """Play `episodes` full episodes with `policy`; return their returns.

    The env is seeded once with `seed`, so the same policy gives the same
    returns every time. Pass render_mode="human" to watch in a window.

    >>> evaluate("CartPole-v1", lambda obs: 0, episodes=2, seed=0)  # always push left
    [11.0, 9.0]
    """
    env = make_env(env_id, render_mode=render_mode)
    returns = []
    try:
        obs, _ = env.reset(seed=seed)
        for _ in range(episodes):
            done, total = False, 0.0
            while not done:
                obs, reward, terminated, truncated, _ = env.step(policy(obs))
                total += float(reward)
                done = terminated or truncated
            returns.append(total)
            obs, _ = env.reset()
    finally:
        env.close()
    return returns


def record_gif(env_id, policy, path, seed, max_frames=300, fps=30, every=1, scale=1):
    """Play one episode off-screen and write it to `path` as a looping GIF.

    Works on a machine with no display (see the top of this file). `every`
    keeps one frame in `every` (with fps lowered to match, so the clip plays at
    real speed), `scale` shrinks frames by an integer factor, and `max_frames`
    caps the length, all to keep the file small. Returns the episode's return.

    >>> record_gif("CartPole-v1", lambda obs: 0, "left.gif", seed=0)  # doctest: +SKIP
    10.0
    """
    import imageio.v2 as imageio

    env = make_env(env_id, render_mode="rgb_array")
    frames, total, t = [], 0.0, 0
    try:
        obs, _ = env.reset(seed=seed)
        frames.append(env.render()[::scale, ::scale])
        done = False
        while not done and len(frames) < max_frames:
            obs, reward, terminated, truncated, _ = env.step(policy(obs))
            total += float(reward)
            done = terminated or truncated
            t += 1
            if t % every == 0 or done:
                frames.append(env.render()[::scale, ::scale])
    finally:
        env.close()
    try:
        imageio.mimsave(path, frames, duration=1000 * every / fps, loop=0)
    except OSError as e:
        raise UserError(f"cannot write {path}: {e}") from None
    return total


def before_after_gifs(env_id, run_dir, untrained, trained, seed, **gif_kwargs):
    """Write run_dir/before.gif and run_dir/after.gif: one episode of each policy (see record_gif)."""
    for name, policy in (("before.gif", untrained), ("after.gif", trained)):
        path = Path(run_dir) / name
        ret = record_gif(env_id, policy, path, seed, **gif_kwargs)
        print(f"{name}: return {ret:.0f} -> {path}", flush=True)


# =============================================================================
# Environments
# =============================================================================


@contextlib.contextmanager
def env_errors(env_id):
    """Turn gymnasium's errors for an unknown id or a missing extra into one clear UserError."""
    try:
        yield
    except (ImportError, gym.error.DependencyNotInstalled) as e:  # e.g. MuJoCo missing; before its base class
        raise UserError(f"{env_id} needs a package that is not installed: {e}") from None
    except gym.error.Error as e:  # NameNotFound, VersionNotFound, ...
        raise UserError(f"unknown environment {env_id!r}: {e}") from None


def make_env(env_id, **kwargs):
    """gym.make, with a clear UserError for an unknown id or a missing extra."""
    with env_errors(env_id):
        return gym.make(env_id, **kwargs)


def make_vec_env(env_id, num_envs, seed):
    """gym.make_vec (its own vectorized version when the env has one), reset with `seed`.

    Autoreset mode is NEXT_STEP (gymnasium 1.x default): the step after an
    episode ends returns the first observation of the next episode, with reward
    0, and ignores the action. Scripts must drop that step from their batches.
    """
    with env_errors(env_id):
        envs = gym.make_vec(env_id, num_envs=num_envs)
    mode = envs.metadata.get("autoreset_mode", gym.vector.AutoresetMode.NEXT_STEP)
    if mode != gym.vector.AutoresetMode.NEXT_STEP:
        raise UserError(f"{env_id}: expected NEXT_STEP autoreset, got {mode}")
    envs.action_space.seed(seed)
    obs, _ = envs.reset(seed=seed)
    return envs, obs


def require_discrete(env_id, space):
    """Raise UserError unless `space` is a Discrete action space."""
    if not isinstance(space, gym.spaces.Discrete):
        raise UserError(f"{env_id} has a {type(space).__name__} action space; this script needs Discrete actions")


def solve_threshold(env_id, override=None):
    """The return that counts as solved: `override`, else the env's reward_threshold."""
    if override is not None:
        return override
    with env_errors(env_id):
        threshold = gym.spec(env_id).reward_threshold
    if threshold is None:
        raise UserError(f"{env_id} has no reward_threshold; pass --solved-return")
    return threshold


# =============================================================================
# Config -> command line
# =============================================================================


def field_docs(cls):
    """Map each dataclass field to the string literal written under it.

        @dataclass
        class Config:
            lr: float = 3e-4
            \"\"\"Adam learning rate\"\"\"      ->  {"lr": "Adam learning rate"}
    """
    tree = ast.parse(textwrap.dedent(inspect.getsource(cls)))
    body = tree.body[0].body
    docs = {}
    for node, nxt in zip(body, body[1:]):
        if isinstance(node, ast.AnnAssign) and isinstance(nxt, ast.Expr) and isinstance(nxt.value, ast.Constant):
            docs[node.target.id] = " ".join(str(nxt.value.value).split())
    return docs


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line and exit 2, instead of a usage dump
        self.exit(2, f"{self.prog}: error: {message}\n")


def parse_config(cls, argv=None, description=None):
    """Build a `cls` (a @dataclass) from command-line flags.

    Each field `num_envs: int = 8` becomes `--num-envs 8`, its docstring the
    help text; a bool field becomes `--name/--no-name`; an `x: float | None`
    field accepts a number or `none`. Values are validated by the dataclass's
    own __post_init__: a ValueError there becomes one `error:` line and exit 2.
    """
    parser = _Parser(description=description, formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    docs = field_docs(cls)
    for f in dataclasses.fields(cls):
        flag = "--" + f.name.replace("_", "-")
        kind = f.type if isinstance(f.type, str) else getattr(f.type, "__name__", str(f.type))  # "float | None"
        help_text = docs.get(f.name, "")
        if kind == "bool":
            parser.add_argument(flag, action=argparse.BooleanOptionalAction, default=f.default, help=help_text)
            continue
        base = kind.replace(" | None", "").replace("Optional[", "").rstrip("]")
        convert = {"int": int, "float": float, "str": str}[base]
        if "None" in kind:
            convert = _or_none(convert)
        parser.add_argument(flag, type=convert, default=f.default, metavar=base.upper(), help=help_text)
    args = parser.parse_args(argv)
    try:
        return cls(**vars(args))
    except ValueError as e:
        parser.error(str(e))


def _or_none(convert):
    def parse(text):
        return None if text.lower() == "none" else convert(text)

    parse.__name__ = convert.__name__
    return parse


def check(condition, message):
    """For Config.__post_init__: raise ValueError(message) unless condition holds."""
    if not condition:
        raise ValueError(message)


# =============================================================================
# Seeding, run folders, logs, checkpoints
# =============================================================================


def seed_everything(seed):
    """Seed python, numpy and torch. Envs are seeded at their first reset."""
    random.seed(seed)
    np.random.seed(seed)
    torch.manual_seed(seed)


def make_run_dir(root, script, env_id, seed):
    """Create and return runs/<script>__<env>__seed<k>__<timestamp>/ under `root`."""
    stamp = time.strftime("%Y%m%d-%H%M%S")
    name = f"{Path(script).stem}__{env_id.replace('/', '-')}__seed{seed}__{stamp}"
    for suffix in [""] + [f"-{i}" for i in range(1, 100)]:
        path = Path(root) / (name + suffix)
        try:
            path.mkdir(parents=True, exist_ok=False)
            return path
        except FileExistsError:
            continue
        except OSError as e:
            raise UserError(f"cannot create run folder {path}: {e.strerror}") from None
    raise UserError(f"cannot create run folder {Path(root) / name}: too many runs this second")


def append_csv(path, row):
    """Append one dict as a CSV row (header first if the file is new).

    Opening the file for each row keeps the log complete at any moment, even
    if training is interrupted.
    """
    new = not Path(path).exists()
    with open(path, "a", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(row))
        if new:
            writer.writeheader()
        writer.writerow({k: _fmt(v) for k, v in row.items()})


def _fmt(value):
    return f"{value:.6g}" if isinstance(value, float) else value


def save_checkpoint(obj, path):
    """torch.save to a temporary file, then rename: a crash never leaves half a file."""
    path = Path(path)
    tmp = path.with_suffix(path.suffix + ".tmp")
    torch.save(obj, tmp)
    os.replace(tmp, path)


def load_checkpoint(path, required=()):
    """torch.load(weights_only=True) with one clear UserError for a bad file."""
    path = Path(path)
    if not path.is_file():
        raise UserError(f"no checkpoint at {path}")
    try:
        ckpt = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as e:  # corrupt, truncated, not a torch file, unsafe pickle ...
        raise UserError(f"cannot read checkpoint {path}: {type(e).__name__}: {str(e).splitlines()[0] if str(e) else ''}") from None
    missing = [k for k in required if not isinstance(ckpt, dict) or k not in ckpt]
    if missing:
        raise UserError(f"{path} is not a checkpoint of this script (missing {', '.join(missing)})")
    return ckpt


def require_display():
    """Raise UserError when a window cannot be opened (for --watch)."""
    if os.environ.get("SDL_VIDEODRIVER") == "dummy":
        raise UserError("--watch opens a window, but this machine has no display; "
                        "drop --watch (GIFs are written to the run folder) or run where DISPLAY is set")


def load_weights(module, state_dict, path):
    """module.load_state_dict(state_dict), with a UserError naming `path` if it does not fit."""
    try:
        module.load_state_dict(state_dict)
    except (RuntimeError, ValueError, KeyError) as e:  # shapes, keys or optimizer groups differ
        raise UserError(f"{path} does not fit this script's {type(module).__name__}: {str(e).splitlines()[0]}") from None


def pick_device(cuda):
    """torch.device("cuda") if asked for and present, else the CPU."""
    if cuda and not torch.cuda.is_available():
        print("no GPU found: training on the CPU", flush=True)
    return torch.device("cuda" if cuda and torch.cuda.is_available() else "cpu")


def format_time(seconds):
    """1234.5 -> '20m34s'; for progress lines."""
    seconds = int(seconds)
    if seconds < 60:
        return f"{seconds}s"
    if seconds < 3600:
        return f"{seconds // 60}m{seconds % 60:02d}s"
    return f"{seconds // 3600}h{seconds % 3600 // 60:02d}m"


# =============================================================================
# The command line of every script
# =============================================================================


def main(config_cls, train, play, argv=None, description=None):
    """What `python <script>.py [flags]` does, the same for every script:

        --eval PATH        play(cfg): replay a saved model, no training
        (otherwise)        train(cfg), which returns a dict with run_dir and interrupted
        --watch            then replay the trained model in a window (needs a display)

    Bad input ends in one `error:` line and exit code 2; Ctrl-C during training
    (after train has saved the model and logs) in exit code 130.
    """
    cfg = parse_config(config_cls, argv, description=description)
    with exit_on_user_error():
        if cfg.watch:
            require_display()  # fail now, not after an hour of training
        if cfg.eval:
            play(cfg)
            return
        result = train(cfg)
        if result["interrupted"]:
            raise SystemExit(130)
        if cfg.watch:
            play(dataclasses.replace(cfg, eval=str(Path(result["run_dir"]) / "model.pt")))


# =============================================================================
# Clear failures
# =============================================================================


class UserError(Exception):
    """Bad input the user can fix: printed as one line, exit code 2."""


@contextlib.contextmanager
def exit_on_user_error():
    """Turn a UserError into `error: ...` on stderr and exit code 2."""
    try:
        yield
    except UserError as e:
        print(f"error: {e}", file=sys.stderr, flush=True)
        sys.exit(2)
