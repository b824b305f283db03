"""Small helpers shared by every script: returns and GAE, evaluation and GIFs, plumbing.
The training loops live in the scripts, each read top to bottom on its own."""

import argparse, ast, contextlib, csv, dataclasses, inspect, os, shutil, signal, sys, textwrap, time
from pathlib import Path

# --- Ctrl-C while torch and gymnasium load (a second or more): one line and exit 130, when a
# script beside this file is the program (never in a notebook); clear_exit() takes over after.
def _ctrl_c_while_starting(signum, frame):
    print("\ninterrupted (Ctrl-C)", file=sys.stderr, flush=True)
    os._exit(130)  # nothing to save yet; an exception would pass through C import code

_program = getattr(sys.modules.get("__main__"), "__file__", None)
if (_program and Path(_program).resolve().parent == Path(__file__).resolve().parent
        and signal.getsignal(signal.SIGINT) is signal.default_int_handler):
    signal.signal(signal.SIGINT, _ctrl_c_while_starting)

# --- headless machines: set before pygame or mujoco are imported; never overrides the user ---
HEADLESS = sys.platform == "linux" and not any(map(os.environ.get, ("DISPLAY", "WAYLAND_DISPLAY")))
if HEADLESS:
    os.environ.setdefault("SDL_VIDEODRIVER", "dummy")  # pygame draws into memory
    os.environ.setdefault("MUJOCO_GL", "egl")  # MuJoCo renders through EGL, no X server
os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")

import gymnasium as gym  # noqa: E402  (after the environment variables above)
import numpy as np  # noqa: E402
import torch  # noqa: E402

# ====================== Returns and advantages ======================================
# Rollouts are shaped (T, N): T time steps of N parallel envs; next_values[t] is V(s_{t+1}), the
# value of the obs that step t led to. The bootstrap rule (Spinning Up's finish_path(last_val)):
# at terminated[t] the episode really ended and the future is 0; at truncated[t] (a time limit)
# and at t = T-1 (the rollout ran out) it is not: bootstrap with next_values[t]. Termination wins.
def discounted_returns(rewards, next_values, terminated, truncated, gamma):
    """Reward-to-go G_t = r_t + gamma * G_{t+1}, cut at episode ends (bootstrap rule above); over
    a rollout of T steps, A3C's n-step return (rewards to its end, then gamma^k * V there).
    >>> r, v = torch.tensor([[1.], [1.], [1.]]), torch.tensor([[9.], [9.], [4.]])  # v: V(s_{t+1})
    >>> no, at1 = torch.zeros(3, 1, dtype=torch.bool), torch.tensor([[False], [True], [False]])
    >>> discounted_returns(r, v, no, no, 0.5).flatten().tolist()  # gamma=0.5, T=3, N=1
    [2.25, 2.5, 3.0]
    >>> discounted_returns(r, v, at1, no, 0.5).flatten().tolist()  # terminated at t=1: no future
    [1.5, 1.0, 3.0]
    >>> discounted_returns(r, v, no, at1, 0.5).flatten().tolist()  # truncated at t=1: + 0.5 * 9
    [3.75, 5.5, 3.0]
    """
    returns, future = torch.zeros_like(rewards), next_values[-1]  # bootstrap past the rollout
    for t in reversed(range(len(rewards))):
        future = torch.where(truncated[t], next_values[t], future)  # time limit: V(final obs)
        future = torch.where(terminated[t], torch.zeros_like(future), future)  # no future at all
        returns[t] = future = rewards[t] + gamma * future
    return returns

def gae(rewards, values, next_values, terminated, truncated, gamma, lam):
    """Generalized advantage estimation (Schulman et al. 2016, eq. 16), shaped like `rewards`:

        delta_t = r_t + gamma * V(s_{t+1}) * (1 - terminated_t) - V(s_t)
        A_t     = delta_t + gamma * lam * (1 - done_t) * A_{t+1},  done = terminated or truncated

    A truncated step keeps gamma * V(final obs) in its delta (bootstrap) but stops the sum over
    later deltas, of the next episode. lam=1 gives G_t - V(s_t), lam=0 the one-step TD error; the
    value targets are A + V. With gamma=0.5, lam=1: delta_1 = 1 + 0.5*4 - 2 = 1, delta_0 = 1:
    >>> r, v = torch.tensor([[1.], [1.]]), torch.tensor([[1.], [2.]])
    >>> nv, no = torch.tensor([[2.], [4.]]), torch.zeros(2, 1, dtype=torch.bool)
    >>> gae(r, v, nv, no, no, 0.5, 1.0).flatten().tolist()  # A_0 = 1 + 0.5 * A_1
    [1.5, 1.0]
    """
    advantages, last = torch.zeros_like(rewards), torch.zeros_like(rewards[0])
    not_terminated = (~terminated).to(rewards.dtype)
    not_done = (~(terminated | truncated)).to(rewards.dtype)
    for t in reversed(range(len(rewards))):
        delta = rewards[t] + gamma * next_values[t] * not_terminated[t] - values[t]
        last = advantages[t] = delta + gamma * lam * not_done[t] * last
    return advantages

# ====================== Running a policy (a function obs -> action): evaluation, GIFs ==
def evaluate(env_id, policy, episodes, seed, render_mode=None, log=False, **make_kw):
    """Returns of `episodes` episodes of `policy`, the env seeded once with `seed`. render_mode=
    "human" shows a window (make_kw go to gym.make); log=True prints each return as it ends."""
    with env_errors(env_id):
        env = gym.make(env_id, render_mode=render_mode, **make_kw)
    returns = []
    try:
        obs, _ = env.reset(seed=seed)
        for episode in range(1, episodes + 1):
            done, total = False, 0.0
            while not done:
                obs, reward, terminated, truncated, _ = env.step(policy(obs))
                total, done = total + float(reward), terminated or truncated
            returns.append(total)
            if log:
                print(f"episode {episode}/{episodes}: return {total:.1f}  (Ctrl-C stops)",
                      flush=True)
            obs, _ = env.reset()
    finally:
        env.close()
    return returns

def record_gif(env_id, policy, path, seed, max_frames=300, fps=30, every=1, scale=1, **make_kw):
    """Play one episode off-screen; return its return. One frame in `every` (fps lowered to match),
    at most `max_frames`, `scale` times smaller, go to `path` as a looping GIF (whole or none)."""
    import imageio.v2 as imageio, PIL.Image  # PIL comes with imageio
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
            total, t, done = total + float(reward), t + 1, terminated or truncated
            if (t % every == 0 or done) and len(frames) < max_frames:
                frames.append(frame())
    finally:
        env.close()
    with written_whole(path) as tmp:  # a Ctrl-C waits until the GIF is whole (a second at most)
        imageio.mimsave(tmp, frames, format="GIF", duration=1000 * every / fps, loop=0)
    return total

# ====================== Plumbing: envs, flags, run folders, logs, checkpoints, errors ==
class UserError(Exception):
    """Bad input the user can fix: printed as one line, exit code 2 (see clear_exit)."""

@contextlib.contextmanager
def clear_exit():
    """Bad input: one `error:` line, exit 2. Ctrl-C, even turned into another error: exit 130."""
    if signal.getsignal(signal.SIGINT) is _ctrl_c_while_starting:  # the imports are done
        signal.signal(signal.SIGINT, signal.default_int_handler)  # Ctrl-C: KeyboardInterrupt
    try:
        yield
    except UserError as e:
        print(f"error: {e}", file=sys.stderr, flush=True)
        sys.exit(2)
    except (KeyboardInterrupt, ImportError, RuntimeError, gym.error.Error) as e:
        if not from_ctrl_c(e): raise
        print("\ninterrupted (Ctrl-C)", file=sys.stderr, flush=True)
        sys.exit(130)

def from_ctrl_c(error):
    """Is `error` a KeyboardInterrupt, or raised because of one (MuJoCo's import, a torch write)?"""
    while error is not None and not isinstance(error, KeyboardInterrupt):
        error = error.__cause__ or error.__context__  # Python keeps this chain free of loops
    return error is not None

@contextlib.contextmanager
def ctrl_c_deferred():
    """Hold a Ctrl-C back while the block runs (a file write), then deliver it."""
    before, pressed = signal.getsignal(signal.SIGINT), []
    try:
        signal.signal(signal.SIGINT, lambda signum, frame: pressed.append(signum))
    except (ValueError, TypeError):  # not the main thread, or a handler set outside Python
        before = None
    try:
        yield
    finally:
        if before is not None: signal.signal(signal.SIGINT, before)
        if pressed: signal.raise_signal(signal.SIGINT)  # the held Ctrl-C, now

@contextlib.contextmanager
def env_errors(env_id):
    """An unknown id, a missing extra or too little memory: one clear UserError."""
    try:
        yield
    except (ImportError, gym.error.DependencyNotInstalled) as e:  # e.g. no MuJoCo
        if from_ctrl_c(e):  # Ctrl-C while MuJoCo was imported: no package is missing
            raise KeyboardInterrupt from None
        raise UserError(f"{env_id} needs a package that is not installed: {e}") from None
    except gym.error.Error as e:  # NameNotFound, VersionNotFound, ...
        raise UserError(f"unknown environment {env_id!r}: {e}") from None
    except AttributeError as e:  # MuJoCo's import with MUJOCO_GL=egl finds no libEGL
        if "egl" not in str(e).lower(): raise
        raise UserError(f"{env_id}: MuJoCo cannot render without the EGL library (install libegl1, "
                        "or set MUJOCO_GL=osmesa with OSMesa installed)") from None
    except MemoryError:
        raise UserError(f"not enough memory for {env_id} (too many envs or steps?)") from None

def make_vec_env(env_id, num_envs, seed, solved_return=None):
    """gym.make_vec of a Discrete-action env reset with `seed` (autoreset NEXT_STEP, gymnasium
    1.x's default; ended episodes in info["episode"]) -> envs, obs, solved_return or the env's
    reward_threshold."""
    with env_errors(env_id):
        envs = gym.wrappers.vector.RecordEpisodeStatistics(gym.make_vec(env_id, num_envs))
        assert envs.metadata["autoreset_mode"] == gym.vector.AutoresetMode.NEXT_STEP
        if not isinstance(envs.single_action_space, gym.spaces.Discrete):
            raise UserError(f"{env_id} has {type(envs.single_action_space).__name__} actions; "
                            "this script needs Discrete actions")
        solved = envs.spec.reward_threshold if solved_return is None else solved_return
        if solved is None:
            raise UserError(f"{env_id} has no reward_threshold; pass --solved-return")
        envs.action_space.seed(seed)
        obs, _ = envs.reset(seed=seed)
    return envs, obs, solved

def finished_episodes(info, step, episodes, threshold, window=20):
    """`episodes`: (step, return) of each finished episode. Returns the pairs that ended at this
    `step` of make_vec_env's envs, and whether the last `window` returns average `threshold`+."""
    ended = ([(step, float(r)) for r in info["episode"]["r"][info["_episode"]]]
             if "episode" in info else [])  # _episode: the envs whose episode ended
    last = [r for _, r in (episodes[-window:] + ended)[-window:]]
    return ended, len(last) == window and bool(np.mean(last) >= threshold)

def parse_config(cls, argv=None, description=None):
    """A @dataclass `cls` from flags: `num_envs: int = 8` -> `--num-envs 8` (help: the string under
    it), bool -> `--x/--no-x`, `float | None` also takes `none`; ValueError -> one line, exit 2."""
    parser = argparse.ArgumentParser(description=description,
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.error = lambda message: parser.exit(2, f"{parser.prog}: error: {message}\n")  # no usage
    body = ast.parse(textwrap.dedent(inspect.getsource(cls))).body[0].body
    docs = {node.target.id: " ".join(str(nxt.value.value).split())  # the string under each field
            for node, nxt in zip(body, body[1:]) if isinstance(node, ast.AnnAssign)
            and isinstance(nxt, ast.Expr) and isinstance(nxt.value, ast.Constant)}
    for f in dataclasses.fields(cls):
        name = f.type if isinstance(f.type, str) else getattr(f.type, "__name__", str(f.type))
        kind = name.replace(" | None", "")  # "float | None" -> "float"
        convert = {"int": int, "float": float, "str": str, "bool": bool}[kind]
        how = dict(type=_or_none(convert) if "None" in name else convert, metavar=kind.upper())
        if kind == "bool": how = dict(action=argparse.BooleanOptionalAction)
        parser.add_argument("--" + f.name.replace("_", "-"), default=f.default, **how,
                            help=docs.get(f.name, "").replace("%", "%%"))  # % starts a format
    args = parser.parse_args(argv)
    for name, value in vars(args).items():  # nan fails every test, inf never ends: refuse both
        if isinstance(value, float) and not np.isfinite(value):
            parser.error(f"--{name.replace('_', '-')} must be a finite number, got {value}")
    if getattr(args, "watch", False) and HEADLESS:  # fail now, not after hours of training
        parser.error("--watch opens a window, but this machine has no display (see the GIFs)")
    try:
        cfg = cls(**vars(args))
    except ValueError as e:
        parser.error(str(e))
    if getattr(cfg, "cuda", False) and not cls.cuda and not torch.cuda.is_available():  # asked
        print("warning: --cuda, but torch sees no GPU here (a CPU-only torch, or no driver): "
              "running on the CPU", file=sys.stderr, flush=True)  # as the scripts then do
    return cfg

def _or_none(convert):  # a flag's type that also takes "none"; argparse names it in errors
    parse = lambda text: None if text.lower() == "none" else convert(text)  # noqa: E731
    parse.__name__ = convert.__name__
    return parse

def check(condition, message):
    """For Config.__post_init__: raise ValueError(message) unless `condition`."""
    if not condition: raise ValueError(message)

RANGES = {"> 0": (lambda v: v > 0, "positive"), ">= 0": (lambda v: v >= 0, ">= 0"),
          "> 1": (lambda v: v > 1, "> 1"), "(0, 1]": (lambda v: 0 < v <= 1, "in (0, 1]"),
          "[0, 1]": (lambda v: 0 <= v <= 1, "in [0, 1]")}

def check_ranges(config, **ranges):
    """For Config.__post_init__: each named field lies in its range (a key of RANGES; "... or
    none" also lets None through), else ValueError. Checks relating two fields stay explicit."""
    for name, allowed in ranges.items():
        value, optional = getattr(config, name), allowed.endswith(" or none")
        inside, words = RANGES[allowed.removesuffix(" or none")]
        if not (value is None and optional or value is not None and inside(value)):
            raise ValueError(f"--{name.replace('_', '-')} must be {words}"
                             f"{' or none' if optional else ''}, got {value}")

def make_run_dir(root, script, env_id, seed):
    """Create and return <root>/<script>__<env>__seed<k>__<timestamp>[-i]/."""
    name = f"{script}__{env_id.replace('/', '-')}__seed{seed}__"
    base = Path(root) / (name + time.strftime("%Y%m%d-%H%M%S"))
    for path in [base, *(Path(f"{base}-{i}") for i in range(1, 1000))]:
        try:
            path.mkdir(parents=True)
            return path
        except FileExistsError:  # another run started this second: the next name
            continue
        except OSError as e:
            raise UserError(f"cannot create run folder {path}: {e.strerror}") from None

def append_csv(path, row):
    """Append a dict as a CSV row (header first); one open per row: complete after Ctrl-C."""
    new = not Path(path).exists()
    with open(path, "a", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(row))
        if new: writer.writeheader()
        writer.writerow({k: f"{v:.6g}" if isinstance(v, float) else v for k, v in row.items()})

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
            tmp.unlink(missing_ok=True)

def save_checkpoint(obj, path):
    """torch.save, flushed to disk, through written_whole."""
    with written_whole(path) as tmp, open(tmp, "wb") as f:
        torch.save(obj, f)
        f.flush()
        os.fsync(f.fileno())

def load_checkpoint(path, required=(), script=None):
    """torch.load(weights_only=True), or one clear UserError; a run folder means its model.pt.
    With `script` (e.g. "ppo_cartpole"), a checkpoint that names another script is refused."""
    path = Path(path) / "model.pt" if Path(path).is_dir() else Path(path)
    if not path.is_file(): raise UserError(f"no checkpoint at {path}")
    try:  # weights_only: tensors and plain values, never arbitrary Python objects
        ckpt = torch.load(path, map_location="cpu", weights_only=True)
    except Exception:  # cut short, damaged, not a torch file, or Python objects inside
        raise UserError(f"cannot read {path}: truncated, corrupt or not a checkpoint of these "
                        "scripts") from None
    if script and isinstance(ckpt, dict) and ckpt.get("script") != script:
        raise UserError(f"{path} is not a model of {script}.py: it is " + (
            f"a model of {ckpt['script']}.py" if "script" in ckpt else
            "from an older version that did not record its script: train it again"))
    if not isinstance(ckpt, dict) or not set(required) <= set(ckpt):
        raise UserError(f"{path} is not a checkpoint of this script (it lacks {set(required)})")
    return ckpt

def load_weights(module, state_dict, path):
    """module.load_state_dict(state_dict), with a UserError naming `path` if it does not fit."""
    try:
        module.load_state_dict(state_dict)
    except (RuntimeError, ValueError, KeyError) as e:  # shapes, keys or optimizer groups differ
        raise UserError(f"{path} does not fit this script's {type(module).__name__}: "
                        f"{str(e).splitlines()[0]}") from None

def stop_if_diverged(step, losses, nets, run_dir=None, obs=None):
    """nan or inf in `losses` (name -> number), or in the weights of `nets` or their output for
    `obs`: remove `run_dir`, raise one UserError naming the step and the likely cause."""
    bad = [name for name, value in losses.items() if not np.isfinite(float(value))]
    for net in nets:
        tensors = list(net.parameters())
        if obs is not None:
            with torch.no_grad():
                out = net(torch.as_tensor(obs, dtype=torch.float32, device=tensors[0].device))
            tensors += list(out) if type(out) is tuple else [out]
        if not all(bool(t.isfinite().all()) for t in tensors):
            bad.append(f"{type(net).__name__}'s weights or output")
    if bad:
        if run_dir is not None: shutil.rmtree(run_dir, ignore_errors=True)
        raise UserError(f"training diverged at step {step}: nan or inf in {', '.join(bad)}; likely "
                        "cause: too high a learning rate (try a smaller one)"
                        + (f"; {run_dir} was removed" if run_dir is not None else ""))
