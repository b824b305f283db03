"""Plumbing the scripts call; nothing in it changes what is learned, so a reader may skip it.

What lives here: the flags every script shares and their checks, one-line errors and
Ctrl-C, run folders, CSV logs and progress lines, the solved check, saving and loading
models, DDPG's exact checkpoint and resume, the divergence check, --eval / --watch / --gif
playback and the end of a run (curve, TensorBoard, evaluation, GIFs).

It is a tool, like CleanRL's SummaryWriter: a script calls it and hands it its networks;
it never calls back into a script, draws no random numbers from the training streams, and
ends a run only through the one `with run.until_interrupted():` block around the loop.
"""

import argparse
import ast
import contextlib
import copy
import csv
import dataclasses
import inspect
import os
import shutil
import signal
import sys
import textwrap
import threading
import time
from dataclasses import asdict, dataclass
from pathlib import Path


# --- Ctrl-C while torch and gymnasium load (a second or more): one line and exit 130, when a
# script beside this file is the program (never in a notebook); clear_exit() takes over after.
def _ctrl_c_while_starting(signum, frame):
    print("\ninterrupted (Ctrl-C)", file=sys.stderr, flush=True)
    os._exit(130)  # nothing to save yet; an exception would pass through C import code


_program = getattr(sys.modules.get("__main__"), "__file__", None)
_beside_us = _program and Path(_program).resolve().parent == Path(__file__).resolve().parent
if _beside_us and signal.getsignal(signal.SIGINT) is signal.default_int_handler:
    signal.signal(signal.SIGINT, _ctrl_c_while_starting)

# --- headless machines: set before pygame or mujoco are imported; never overrides the user ---
_DISPLAYS = ("DISPLAY", "WAYLAND_DISPLAY")
HEADLESS = sys.platform == "linux" and not any(os.environ.get(name) for name in _DISPLAYS)
if HEADLESS:
    os.environ.setdefault("SDL_VIDEODRIVER", "dummy")  # pygame draws into memory
    os.environ.setdefault("MUJOCO_GL", "egl")  # MuJoCo renders through EGL, no X server
os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")

import gymnasium as gym  # noqa: E402  (after the environment variables above)
import numpy as np  # noqa: E402
import torch  # noqa: E402

import common  # noqa: E402  (common imports this module too: each uses the other in functions)
import plots  # noqa: E402


# =============================================================================
# One-line errors and Ctrl-C
# =============================================================================


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
    except (KeyboardInterrupt, ImportError, RuntimeError, MemoryError, gym.error.Error) as e:
        if from_ctrl_c(e):
            print("\ninterrupted (Ctrl-C)", file=sys.stderr, flush=True)
            sys.exit(130)
        if isinstance(e, MemoryError) or "allocate" in str(e):  # e.g. --buffer-size too large
            print(f"error: not enough memory for these settings (too many envs or steps, or too "
                  f"large a buffer?): {str(e).splitlines()[0] if str(e) else 'MemoryError'}",
                  file=sys.stderr, flush=True)
            sys.exit(2)
        raise


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
        if before is not None:
            signal.signal(signal.SIGINT, before)
        if pressed:
            signal.raise_signal(signal.SIGINT)  # the held Ctrl-C, now


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
        if "egl" not in str(e).lower():
            raise
        raise UserError(f"{env_id}: MuJoCo cannot render without the EGL library (install "
                        "libegl1, or set MUJOCO_GL=osmesa with OSMesa installed)") from None
    except MemoryError:
        raise UserError(f"not enough memory for {env_id} (too many envs or steps?)") from None


# =============================================================================
# Flags: the ones every script shares, declared once; parse_config reads a Config
# =============================================================================


@dataclass
class OutputFlags:
    """What a run writes and shows, and playback. A script's Config adds its algorithm."""

    run_dir: str = "runs"
    """parent folder of the run folder <script>__<env>__seed<k>__<time>/"""
    print_every: int = 10
    """print a progress line every this many updates"""
    gifs: bool = True
    """write before.gif (untrained) and after.gif (trained) to the run folder, one episode each
    (CartPole scripts: actions drawn from pi, as in training and in tutorial 004's GIFs)"""
    curves: bool = True
    """draw curve.png (the learning curve) and inside.png (what the updates do inside the
    algorithm; docs/inside.md) in the run folder"""
    tensorboard: bool = False
    """also write the logs as TensorBoard scalars into the run folder, with CleanRL's tag
    names (needs `pip install tensorboard`; then: tensorboard --logdir runs)"""
    eval_episodes: int = 10
    """episodes of each evaluation (DDPG: each one; CartPole: the checks and the last; --eval)"""
    eval_seed: int = 10_000
    """seed of the evaluation env (and its action draws), kept apart from the training seed"""
    watch: bool = False
    """after training (or with --eval), play the policy in a window; needs a display"""
    eval: str | None = None
    """a saved model (model.pt, best.pt) or its run folder: skip training and play it"""
    gif: str | None = None
    """with --eval: write one episode of the saved policy to this GIF file instead (no
    display needed)"""
    threads: int = 1
    """torch CPU threads (1 .. cores); the same seed gives the same logs only with the same
    count (threads change float sums)"""
    cuda: bool = False
    """train on the GPU if there is one (its gain is unmeasured; other numbers per seed)"""

    def __post_init__(self):
        check(not self.tensorboard or plots.tensorboard_installed(), plots.NO_TENSORBOARD)
        check_ranges(self, print_every="> 0", eval_episodes="> 0", threads="> 0")
        check(not self.gif or self.eval, "--gif writes a GIF of a saved policy: it needs --eval")
        check(not self.gif or self.gif.lower().endswith(".gif"),
              f"--gif writes a GIF: give a file name that ends in .gif, got {self.gif}")


@dataclass
class SolvedCheckFlags(OutputFlags):
    """The CartPole scripts' flags: OutputFlags and the solved check."""

    stop_when_solved: bool = True
    """stop once the mean return of the last 20 finished episodes reaches the solved return
    and pi as it is then does too, over eval_episodes episodes with actions drawn from pi
    (env seed eval_seed + 1); checked at most once per update, training goes on until then"""
    solved_return: float | None = None
    """the return that counts as solved; none = the env's reward_threshold (CartPole-v1: 475)"""

    def __post_init__(self):
        super().__post_init__()
        batch = self.num_envs * self.num_steps  # the scripts' rollout: num_steps of num_envs
        positive = min(self.num_envs, self.num_steps, self.total_timesteps) > 0  # else the
        check(not positive or self.total_timesteps >= batch,  # script's own checks say so
              f"--total-timesteps ({self.total_timesteps}) is less than one rollout "
              f"(num_envs x num_steps = {batch}): nothing would be learned")


@dataclass
class CheckpointFlags(OutputFlags):
    """DDPG's flags: OutputFlags, its evaluation every eval_every steps and its checkpoints."""

    print_every: int = 1000
    """print a progress line every this many env steps"""
    gifs: bool = True
    """write before.gif (untrained actor), after.gif (trained actor) and best.gif (the best
    evaluation so far, refreshed as it improves) to the run folder"""
    curves: bool = True
    """write curve.png (evaluation returns against env steps) and inside.png (the critic's
    Q against the return it estimates) at every evaluation"""
    checkpoint_every: int = 25_000
    """write checkpoint.pt (networks, optimizers, replay buffer, random generators, logs) every
    this many env steps and on Ctrl-C; --resume continues from it"""
    resume: str | None = None
    """a run folder: continue that run exactly where its checkpoint.pt left it, in the same
    folder and with its saved settings (--total-timesteps may extend it)"""

    def __post_init__(self):
        super().__post_init__()
        check_ranges(self, checkpoint_every="> 0")
        check(not (self.eval and self.resume),
              "--eval plays a saved actor and --resume continues training: pass one")


def parse_config(cls, argv=None, description=None):
    """A @dataclass `cls` from flags: `num_envs: int = 8` -> `--num-envs 8` (help: the string
    under it), bool -> `--x/--no-x`, `float | None` also takes `none`. The script's own fields
    come first in --help, the shared ones after. Bad input: one line, exit 2."""
    parser = argparse.ArgumentParser(description=description, allow_abbrev=False,
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.error = lambda message: parser.exit(2, f"{parser.prog}: error: {message}\n")  # no usage
    docs = {}
    for klass in reversed(cls.__mro__[:-1]):  # the string under each field; subclasses win
        docs.update(_field_docs(klass))
    own = vars(cls).get("__annotations__", {})  # the script's own fields: first in --help
    fields = sorted(dataclasses.fields(cls), key=lambda f: f.name not in own)
    for f in fields:
        name = f.type if isinstance(f.type, str) else getattr(f.type, "__name__", str(f.type))
        kind = name.replace(" | None", "")  # "float | None" -> "float"
        convert = {"int": int, "float": float, "str": str, "bool": bool}[kind]
        how = dict(type=_or_none(convert) if "None" in name else convert, metavar=kind.upper())
        if kind == "bool":
            how = dict(action=argparse.BooleanOptionalAction)
        text = docs.get(f.name, "") + ("; none on the command line: --" + f.name.replace("_", "-")
                                       + " none" if "None" in name else "")
        parser.add_argument("--" + f.name.replace("_", "-"), default=f.default, **how,
                            help=text.replace("%", "%%"))  # % starts a format
    args = parser.parse_args(argv)
    for name, value in vars(args).items():  # nan fails every test, inf never ends: refuse both
        if isinstance(value, float) and not np.isfinite(value):
            parser.error(f"--{name.replace('_', '-')} must be a finite number, got {value}")
    if getattr(args, "watch", False) and HEADLESS:  # fail now, not after hours of training
        parser.error("--watch opens a window, but this machine has no display (see the GIFs, "
                     "or write one of a saved model: --eval RUN --gif OUT.gif)")
    script = Path(inspect.getfile(cls)).stem  # the script whose Config this is
    for name in ("eval", "resume"):  # runs/latest: this script's newest run folder there
        if getattr(args, name, None):
            try:
                setattr(args, name, latest_run(getattr(args, name), script))
            except UserError as e:
                parser.error(str(e))
    try:
        cfg = cls(**vars(args))
    except ValueError as e:
        parser.error(str(e))
    asked = getattr(cfg, "cuda", False) and not cls.cuda  # --cuda, where the default is not
    if asked and not torch.cuda.is_available():
        print("warning: --cuda, but torch sees no GPU here (a CPU-only torch, or no driver): "
              "running on the CPU", file=sys.stderr, flush=True)  # as the scripts then do
    return cfg


def latest_run(path, script):
    """`path` with a part named `latest` (runs/latest, runs/latest/best.pt) read as the newest
    run folder of `script` in that folder, by the time in its name; a path that exists as it
    is stays as it is.

    >>> latest_run("runs/ppo_cartpole__CartPole-v1__seed0__20260101-120000", "ppo_cartpole")
    'runs/ppo_cartpole__CartPole-v1__seed0__20260101-120000'
    """
    parts = Path(path).parts
    if "latest" not in parts or Path(path).exists():
        return path
    at = parts.index("latest")
    parent = Path(*parts[:at]) if at else Path(".")
    runs = sorted(parent.glob(f"{script}__*"), key=lambda run: run.name.split("__")[-1])
    if not runs:
        raise UserError(f"{path}: no run of {script}.py in {parent} yet")
    return str(Path(runs[-1], *parts[at + 1:]))


def _field_docs(klass):
    """{field: the string under it} of one dataclass, read from its source."""
    if "__dataclass_fields__" not in vars(klass):
        return {}
    body = ast.parse(textwrap.dedent(inspect.getsource(klass))).body[0].body
    return {node.target.id: " ".join(str(nxt.value.value).split())
            for node, nxt in zip(body, body[1:]) if isinstance(node, ast.AnnAssign)
            and isinstance(nxt, ast.Expr) and isinstance(nxt.value, ast.Constant)}


def _or_none(convert):
    """A flag's type that also takes "none"; argparse names it in errors."""
    def parse(text):
        return None if text.lower() == "none" else convert(text)
    parse.__name__ = convert.__name__
    return parse


def check(condition, message):
    """For Config.__post_init__: raise ValueError(message) unless `condition`."""
    if not condition:
        raise ValueError(message)


RANGES = {"> 0": (lambda v: v > 0, "positive"), ">= 0": (lambda v: v >= 0, ">= 0"),
          "> 1": (lambda v: v > 1, "> 1"), "(0, 1]": (lambda v: 0 < v <= 1, "in (0, 1]"),
          "[0, 1]": (lambda v: 0 <= v <= 1, "in [0, 1]")}


def check_mujoco(env_id):
    """For DDPG's Config, before the other checks: a gymnasium env that is not a MuJoCo one is
    refused at once (found from its registration; no env is made). Other ids: train() sees."""
    try:
        entry = gym.spec(env_id).entry_point
    except gym.error.Error:
        return  # unknown: train() says so, with gymnasium's suggestion
    if isinstance(entry, str) and entry.startswith("gymnasium.envs."):
        check(entry.startswith("gymnasium.envs.mujoco"),
              f"{env_id} is not a MuJoCo env; this script trains MuJoCo tasks (Walker2d-v5, "
              "Hopper-v5, HalfCheetah-v5, InvertedPendulum-v5, ...)")


def check_ranges(config, **ranges):
    """For Config.__post_init__: each named field lies in its range (a key of RANGES; "... or
    none" also lets None through), else ValueError. Checks relating two fields stay explicit."""
    for name, allowed in ranges.items():
        value, optional = getattr(config, name), allowed.endswith(" or none")
        inside, words = RANGES[allowed.removesuffix(" or none")]
        if not (value is None and optional or value is not None and inside(value)):
            raise ValueError(f"--{name.replace('_', '-')} must be {words}"
                             f"{' or none' if optional else ''}, got {value}")


# =============================================================================
# Files: run folders, CSV rows, whole writes, models and checkpoints
# =============================================================================


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
        if new:
            writer.writeheader()
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
    if not path.is_file():
        here = Path(__file__).resolve().parent / path  # e.g. docs/ddpg_walker2d.pt, from elsewhere
        where = "" if path.is_absolute() else f" (relative to {Path.cwd()}, where you are" + (
            f"; did you mean {here}?)" if here.exists() else ")")
        raise UserError(f"no checkpoint at {path}{where}")
    try:  # weights_only: tensors and plain values, never arbitrary Python objects
        ckpt = torch.load(path, map_location="cpu", weights_only=True)
    except Exception:  # cut short, damaged, not a torch file, or Python objects inside
        raise UserError(f"cannot read {path}: truncated, corrupt or not a checkpoint of these "
                        "scripts") from None
    if script and isinstance(ckpt, dict) and ckpt.get("script") != script:
        raise UserError(f"{path} is not a model of {script}.py: it is " + (
            f"a model of {ckpt['script']}.py" if "script" in ckpt else
            "from an older version that did not record its script: train it again"))
    if isinstance(ckpt, dict) and "buffer" in ckpt and not set(required) <= set(ckpt):
        raise UserError(f"{path} is the run's checkpoint, for --resume {path.parent}; --eval "
                        "plays model.pt or best.pt (or the run folder)")
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


def save_model(path, script, cfg, step, nets, **info):
    """model.pt (or best.pt): the networks' weights, the settings, and what --eval needs to
    rebuild them (`info`, e.g. obs_dim and n_actions)."""
    save_checkpoint(dict(script=script, **{name: net.state_dict() for name, net in nets.items()},
                         config=asdict(cfg), **info, global_step=step), path)


def stop_if_diverged(step, losses, nets, run_dir=None, obs=None):
    """nan or inf in `losses` (name -> number), or in the weights of `nets` or their output for
    `obs`: remove `run_dir`, raise one UserError naming the step and the likely cause."""
    bad = [name for name, value in losses.items()
           if np.ndim(value) == 0 and not np.isfinite(float(value))]  # arrays: kept for pictures
    for net in nets:
        tensors = list(net.parameters())
        if obs is not None:
            with torch.no_grad():
                out = net(torch.as_tensor(obs, dtype=torch.float32, device=tensors[0].device))
            tensors += list(out) if type(out) is tuple else [out]
        if not all(bool(t.isfinite().all()) for t in tensors):
            bad.append(f"{type(net).__name__}'s weights or output")
    if bad:
        if run_dir is not None:
            shutil.rmtree(run_dir, ignore_errors=True)
        raise UserError(f"training diverged at step {step}: nan or inf in {', '.join(bad)}; "
                        "likely cause: too high a learning rate (try a smaller one)"
                        + (f"; {run_dir} was removed" if run_dir is not None else ""))


def hours_minutes(seconds):
    """5000 -> 'about 1 h 23 min', 90 -> 'about 2 min', 20 -> 'under a minute'."""
    minutes = round(seconds / 60)
    if minutes < 1:
        return "under a minute"
    return (f"about {minutes // 60} h {minutes % 60:02d} min" if minutes >= 60
            else f"about {minutes} min")


def aside(draw, *args):
    """Call draw(*args) (a picture: numpy and matplotlib only) in a forked child process, so
    that it overlaps what this process does next; where there is no fork (or off Linux) call
    it now. Returns a function that waits for it and says where the picture is."""
    if sys.platform != "linux":
        path = draw(*args)
        return lambda: print(f"inside: {path}", flush=True)
    pid = os.fork()
    if pid == 0:  # the child: draw, then leave without the parent's exit handlers
        signal.signal(signal.SIGINT, signal.SIG_IGN)  # a Ctrl-C is the parent's to handle
        code = 1
        try:
            print(f"inside: {draw(*args)}", flush=True)
            code = 0
        finally:
            os._exit(code)

    def wait():
        with ctrl_c_deferred():
            _, status = os.waitpid(pid, 0)
        if status != 0:
            print("warning: inside.png could not be drawn", file=sys.stderr, flush=True)
    return wait


def clock(seconds):
    """1234.5 -> '20:34', 5000 -> '1:23:20'."""
    return time.strftime("%H:%M:%S", time.gmtime(seconds)).lstrip("0").lstrip(":") or "0"


# =============================================================================
# The CartPole scripts' run: progress.csv and progress lines, the solved check, the end
# =============================================================================


def pi_holds(policy, device, cfg, threshold, step):
    """Does pi, as it is now, also reach `threshold`: the mean return of cfg.eval_episodes
    episodes, actions drawn from pi, env and draws seeded with eval_seed + 1 (apart from
    training and from the evaluation after it)? Says what it found in one line."""
    returns = common.evaluate(cfg.env_id, common.pi_actions(policy, device, cfg.eval_seed + 1),
                              cfg.eval_episodes, cfg.eval_seed + 1)
    held = np.mean(returns) >= threshold
    print(f"check at step {step}: pi as it is now averages {np.mean(returns):.1f} over "
          f"{len(returns)} episodes: " + ("it holds, training stops" if held else
                                         f"below {threshold:g}, training goes on"), flush=True)
    return held


def cartpole_maps(policy, value, device, n=41):
    """V(s) and pi(push right | s) on a grid of pole angle (+-0.21 rad, where an episode ends)
    and angular velocity (+-2 rad/s), the cart at rest in the middle. `policy` outputs logits
    (or (logits, V)), `value` V (or (logits, V))."""
    angle, velocity = np.linspace(-0.21, 0.21, n), np.linspace(-2.0, 2.0, n)
    a, v = np.meshgrid(angle, velocity)  # rows: velocity, columns: angle
    obs = np.stack([np.zeros_like(a), np.zeros_like(a), a, v], axis=-1).reshape(-1, 4)
    with torch.no_grad():
        x = torch.as_tensor(obs, dtype=torch.float32, device=device)
        logits, values = policy(x), value(x)
        logits = logits[0] if isinstance(logits, tuple) else logits
        values = values[1] if isinstance(values, tuple) else values
        right = torch.softmax(logits, -1)[:, 1]
    return dict(angle=angle, velocity=velocity, value=values.reshape(n, n).cpu().numpy(),
                right=right.reshape(n, n).cpu().numpy())


def cartpole_true_values(policy, device, gamma, reward_scale, seed, n=11, rollouts=10):
    """The truth beside the learned V(s): V^pi(s), the expected discounted return of pi from
    s, by Monte-Carlo. From each state of an n x n grid (the maps' pole angle and angular
    velocity, the cart at rest in the middle), `rollouts` episodes with actions drawn from pi,
    all at once in gymnasium's vectorized CartPole, without a time limit: each is followed
    until it terminates or gamma^t < 0.001 (the rest is then under 0.1% of the largest
    return). Rewards are scaled as the script scales them for learning. Returns
    {"angle", "velocity", "value": (n, n)}."""
    from gymnasium.envs.classic_control.cartpole import CartPoleVectorEnv

    angle, velocity = np.linspace(-0.21, 0.21, n), np.linspace(-2.0, 2.0, n)
    a, v = np.meshgrid(angle, velocity)  # rows: velocity, columns: angle
    start = np.stack([np.zeros(a.size), np.zeros(a.size), a.ravel(), v.ravel()])  # (4, n*n)
    envs = CartPoleVectorEnv(num_envs=n * n * rollouts, max_episode_steps=10**9)
    envs.reset(seed=seed)
    envs.state = np.repeat(start, rollouts, axis=1)  # each state `rollouts` times, in a row
    rng, obs = np.random.default_rng(seed), envs.state.T.astype(np.float32)
    alive, total, discount = np.ones(envs.num_envs, dtype=bool), np.zeros(envs.num_envs), 1.0
    while alive.any() and discount >= 1e-3:
        with torch.no_grad():
            out = policy(torch.as_tensor(obs, device=device))
        logits = out[0] if isinstance(out, tuple) else out
        probs = torch.softmax(logits.double(), -1).cpu().numpy()
        action = (rng.random((len(probs), 1)) > probs.cumsum(1)).sum(1)  # a ~ pi(.|s)
        obs, reward, terminated, _, _ = envs.step(np.minimum(action, probs.shape[1] - 1))
        total += alive * discount * reward_scale * reward  # the step that ends still counts
        alive &= ~terminated
        discount *= gamma
    envs.close()
    return dict(angle=angle, velocity=velocity,
                value=total.reshape(n * n, rollouts).mean(1).reshape(n, n))


# How the progress line shows each logged number, in this order (the ones a script logs).
SHOWN = {"running_reward": "6.1f", "loss_pi": "+.3f", "loss_v": ".2e", "approx_kl": ".4f",
         "kl": ".4f", "beta": ".3g", "entropy": ".3f", "clipfrac": ".3f"}


class Run:
    """The run folder of a CartPole script and what goes into it: a progress.csv row per
    update (and a progress line now and then), episodes.csv, model.pt, and after training
    curve.png, the evaluation and the GIFs. It keeps the finished episodes for the solved
    check. `nets` (name -> module) are saved in model.pt; `policy` (its output: the logits
    of pi, or (logits, V)) is what is checked, evaluated and drawn; `value` (V, or (logits,
    V)) is mapped in inside.png; `untrained` is drawn in before.gif."""

    def __init__(self, script, cfg, threshold, optimizer, nets, policy, value, untrained, device,
                 reward_scale=1.0, **info):
        self.script, self.cfg, self.threshold, self.optimizer = script, cfg, threshold, optimizer
        self.nets, self.policy, self.untrained, self.device = nets, policy, untrained, device
        self.value = value  # for the maps in inside.png; untrained, before any update:
        self.untrained_value = untrained if value is policy else copy.deepcopy(value)
        self.kept = []  # (env step, {name: array}) of each update, for inside.png
        self.visited = []  # the obs of the last few updates' batches: the maps' marks
        self.reward_scale = reward_scale  # as the script scales rewards: V's scale
        self.info = info  # what --eval needs to rebuild the networks, e.g. obs_dim
        self.start_time = time.time()
        self.dir = make_run_dir(cfg.run_dir, script, cfg.env_id, cfg.seed)
        print(f"run folder: {self.dir}", flush=True)
        self.episodes = []  # (env step, return) of every finished training episode, in order
        self.global_step, self.updates, self.checked = 0, 0, 0  # checked: the update last checked
        self.solved_step, self.stats, self.interrupted = None, {}, False
        self.stopped = False  # solved, and pi held: training stops

    def mean20(self):
        """The mean return of the last 20 finished training episodes."""
        return float(np.mean([r for _, r in self.episodes[-20:]])) if self.episodes else np.nan

    def episodes_ended(self, info, step):
        """Record the episodes that ended at env step `step` (from the vector env's `info`);
        return their returns."""
        self.global_step = step
        if "episode" not in info:
            return []
        ended = [float(r) for r in info["episode"]["r"][info["_episode"]]]  # _episode: which envs
        self.episodes += [(step, r) for r in ended]
        return ended

    def solved_and_pi_holds(self, **columns):
        """Solved (the mean return of the last 20 finished episodes reaches the threshold)? Say
        so the first time. Then, at most once per update, play pi as it is now (pi_holds): the
        last 20 episodes were played by the policies of several updates, and the latest one can
        have undone what they show. True, with a last progress.csv row (`columns` as in log()),
        when training should stop."""
        last = [r for _, r in self.episodes[-20:]]
        if len(last) < 20 or np.mean(last) < self.threshold:
            return False
        if self.solved_step is None:
            self.solved_step = self.global_step
            print(f"solved: mean return of the last 20 episodes {self.mean20():.1f} >= "
                  f"{self.threshold:g} at step {self.global_step} (episode {len(self.episodes)}) "
                  f"after {time.time() - self.start_time:.1f}s", flush=True)
        update = self.updates + 1  # the update whose rollout is being collected
        if not self.cfg.stop_when_solved or self.checked == update:
            return False
        self.checked = update
        if not pi_holds(self.policy, self.device, self.cfg, self.threshold, self.global_step):
            return False
        self._row(columns, dict.fromkeys(self.stats, float("nan")))  # where training ended
        self.stopped = True
        return True

    def log(self, stats, visited=None, **columns):
        """After an update: its progress.csv row (the step, episodes, mean of the last 20
        returns, `columns`, the learning rate, then the numbers of `stats`; its arrays, such as
        the batch's ratios, are kept for inside.png), and every print_every updates (and after
        the first) a progress line. `visited`: the batch's observations; the last 10 batches'
        are marked on inside.png's maps, as the states the policy really visits."""
        self.updates += 1
        if visited is not None:
            self.visited = [*self.visited[-9:], visited.detach().cpu().numpy()]
        arrays = {k: v.detach().cpu().numpy() for k, v in stats.items() if torch.is_tensor(v)}
        stats = {k: v for k, v in stats.items() if k not in arrays}  # numbers: to progress.csv
        self.kept.append((self.global_step, arrays))
        self.stats = stats
        self._row(columns, stats)
        if self.updates % self.cfg.print_every == 0 or self.updates == 1:
            elapsed = time.time() - self.start_time
            shown = {**columns, **stats}
            numbers = "  ".join(f"{key.replace('_', ' ') if key == 'running_reward' else key} "
                                f"{shown[key]:{form}}" for key, form in SHOWN.items()
                                if key in shown)
            print(f"step {self.global_step:>7}  {self.global_step / elapsed:6.0f} steps/s  "
                  f"return(20) {self.mean20():6.1f}  {numbers}  {elapsed:.1f}s", flush=True)

    def _row(self, columns, stats):
        append_csv(self.dir / "progress.csv", dict(
            global_step=self.global_step, episodes=len(self.episodes),
            return_mean20=self.mean20(), **columns, lr=self.optimizer.param_groups[0]["lr"],
            **stats))

    @contextlib.contextmanager
    def until_interrupted(self):
        """Around the training loop. Ctrl-C ends it (the run is then `interrupted`); a nan
        that stopped a distribution ends it with one line (stop_if_diverged). Either way,
        episodes.csv and model.pt are written as training left them."""
        try:
            yield self
        except KeyboardInterrupt:
            self.interrupted = True
        except (ValueError, RuntimeError):  # e.g. Categorical refusing nan logits: diverged?
            stop_if_diverged(self.global_step, {}, self.nets.values(), self.dir)  # if so
            raise
        finally:
            if self.dir.exists():  # stop_if_diverged removes a diverged run's folder
                for step, ep_return in self.episodes:
                    append_csv(self.dir / "episodes.csv", episode_row(step, ep_return))
                save_model(self.dir / "model.pt", self.script, self.cfg, self.global_step,
                           self.nets, **self.info)

    def draw_inside(self):
        """Start drawing inside.png (plots.draw_inside): what the updates did (the kept arrays,
        progress.csv) and, on CartPole, V(s) and pi(right|s) as maps, untrained and trained,
        also kept in maps.npz (`python plots.py --maps` puts several runs' side by side).
        Returns a function that waits until the picture is written and says where it is."""
        maps = None
        if self.cfg.env_id.startswith("CartPole"):
            maps = {when: cartpole_maps(policy, value, self.device) for when, policy, value in (
                ("untrained", self.untrained, self.untrained_value),
                ("trained", self.policy, self.value))}
            true = cartpole_true_values(self.policy, self.device, self.cfg.gamma,
                                        self.reward_scale, self.cfg.eval_seed)
            visited = (np.concatenate(self.visited)[:, 2:4] if self.visited
                       else np.zeros((0, 2)))  # (pole angle, angular velocity) of each obs
            maps.update(true=true, visited=visited)
            with written_whole(self.dir / "maps.npz") as tmp, open(tmp, "wb") as f:
                np.savez(f, **{f"{when}_{key}": maps[when][key] for when in ("untrained", "trained")
                               for key in ("value", "right")},
                         angle=maps["trained"]["angle"], velocity=maps["trained"]["velocity"],
                         true_value=true["value"], true_angle=true["angle"],
                         true_velocity=true["velocity"], visited=visited)
        return aside(plots.draw_inside, self.dir, self.script, asdict(self.cfg), self.kept, maps)

    def finish(self):
        """After training: curve.png, TensorBoard, two evaluations (actions drawn from pi, and
        pi's most probable action) and the GIFs. Returns train()'s result: run_dir, solved,
        solved_step, global_step, episode_returns, eval_returns, greedy_returns, interrupted."""
        cfg, run_dir, step = self.cfg, self.dir, self.global_step
        result = dict(run_dir=run_dir, solved=self.solved_step is not None,
                      solved_step=self.solved_step, global_step=step,
                      episode_returns=[r for _, r in self.episodes], eval_returns=[],
                      greedy_returns=[], interrupted=self.interrupted)
        if self.interrupted:  # the curve so far and where everything is; main() exits with 130
            if cfg.curves and (run_dir / "progress.csv").exists():
                with ctrl_c_deferred():  # a second Ctrl-C waits for the picture
                    plots.draw_run(run_dir, self.threshold, self.solved_step)
            print(f"\ninterrupted at step {step}: {run_dir} holds "
                  f"{', '.join(sorted(f.name for f in run_dir.iterdir()))} "
                  f"(replay: python {self.script}.py --eval {run_dir})", flush=True)
            return result
        elapsed = time.time() - self.start_time
        print(f"trained {step} steps, {len(self.episodes)} episodes in {elapsed:.1f}s; "
              f"model: {run_dir / 'model.pt'}", flush=True)
        inside_drawn = lambda: None  # noqa: E731
        if cfg.curves:
            with ctrl_c_deferred():  # Ctrl-C waits until curve.png is whole
                print(f"curve: {plots.draw_run(run_dir, self.threshold, self.solved_step)}",
                      flush=True)
            inside_drawn = self.draw_inside()  # drawn aside while the evaluation runs
        try:
            self._evaluate_and_draw(result, elapsed)
        finally:
            inside_drawn()  # a Ctrl-C too waits for inside.png (a second or less)
        return result

    def _evaluate_and_draw(self, result, elapsed):
        """finish(), after curve.png: TensorBoard (steps/s over the `elapsed` seconds of
        training), the two evaluations into `result`, the GIFs."""
        cfg, run_dir, step = self.cfg, self.dir, self.global_step
        if cfg.tensorboard:
            plots.to_tensorboard(run_dir, sps=step / elapsed)
        # Two evaluations of the same episode seeds: actions drawn from pi, as in training (the
        # policy that "solved" judged), and pi's most probable action (greedy). They can differ
        # either way: a policy trained to be sampled need not be good when it is not.
        n, seed = cfg.eval_episodes, cfg.eval_seed
        for key, greedy, what in (("eval_returns", False, "actions drawn from pi"),
                                  ("greedy_returns", True, "pi's most probable action")):
            act = common.pi_actions(self.policy, self.device, seed, greedy=greedy)
            result[key] = returns = common.evaluate(cfg.env_id, act, n, seed)
            print(f"{'greedy ' if greedy else ''}evaluation over {n} episodes, {what}: mean "
                  f"{np.mean(returns):.1f}, min {min(returns):.0f}", flush=True)
        if cfg.gifs:  # one episode each, actions drawn from pi: after.gif shows the evaluation's
            # first episode. Every 2nd frame at half size: small files.
            for name, net in (("before.gif", self.untrained), ("after.gif", self.policy)):
                ret = common.record_gif(cfg.env_id, common.pi_actions(net, self.device, seed),
                                        run_dir / name, seed, every=2, scale=2)
                print(f"{name}: return {ret:.0f} -> {run_dir / name}", flush=True)


def saved_model(result):
    """train()'s result -> its run folder (its model.pt, for --watch); after a Ctrl-C, which
    train() has already reported with what it saved, exit 130 instead."""
    if result["interrupted"]:
        raise SystemExit(130)
    return str(result["run_dir"])


def play(cfg, path, script, network, key):
    """--eval (and --watch after training): rebuild the network saved at `path` (a model.pt
    or best.pt, or a run folder), a `network` with the weights saved under `key`, and play
    it. A DDPG actor (its model.pt names act_dim) plays without noise (play_actor); a
    categorical policy draws its actions from pi (play_policy). Returns the returns."""
    ckpt = load_checkpoint(path, script=script, required=(key, "obs_dim", "config"))
    if "act_dim" in ckpt:
        net = network(ckpt["obs_dim"], ckpt["act_dim"], ckpt["config"]["hidden"],
                      np.array(ckpt["low"]), np.array(ckpt["high"]))
    else:
        net = network(ckpt["obs_dim"], ckpt["n_actions"], ckpt["config"]["hidden"])
    load_weights(net, ckpt[key], path)
    env_id = ckpt["config"]["env_id"]
    return (play_actor if "act_dim" in ckpt else play_policy)(cfg, path, env_id, net)


def play_policy(cfg, path, env_id, policy):
    """--eval: play cfg.eval_episodes episodes of a saved CartPole policy, actions drawn from
    pi (in a window with --watch), then as many greedy ones; returns the first ones' returns.
    With --gif: one episode, drawn as after.gif is, to that file instead."""
    if cfg.gif:
        ret = common.record_gif(env_id, common.pi_actions(policy, "cpu", cfg.eval_seed), cfg.gif,
                                cfg.eval_seed, every=2, scale=2)
        print(f"{cfg.gif}: one episode, return {ret:.0f}", flush=True)
        return [ret]
    print(f"playing {cfg.eval_episodes} episodes of {env_id} with {path}"
          + ("; Ctrl-C stops" if cfg.watch else ""), flush=True)
    returns = common.evaluate(env_id, common.pi_actions(policy, "cpu", cfg.eval_seed),
                              cfg.eval_episodes, cfg.eval_seed,
                              render_mode="human" if cfg.watch else None, log=cfg.watch)
    print(f"{env_id}, {path}: returns {[round(r) for r in returns]}, "
          f"mean {np.mean(returns):.1f} (actions drawn from pi)", flush=True)
    greedy = common.evaluate(env_id, common.pi_actions(policy, "cpu", cfg.eval_seed, greedy=True),
                             cfg.eval_episodes, cfg.eval_seed)
    print(f"greedy (pi's most probable action): returns {[round(r) for r in greedy]}, "
          f"mean {np.mean(greedy):.1f}", flush=True)
    return returns


# =============================================================================
# DDPG's run: evaluations, best model, progress lines, exact checkpoints and --resume
# =============================================================================

# GIFs look through the model's "track" camera, which follows the walker (gymnasium's
# default free camera stays put, and a walking agent leaves the picture). Models without
# such a camera (InvertedPendulum) keep the default view. 1000 steps -> every 4th frame,
# 250 frames, at half size: a GIF of a few MB.
CAMERA = dict(camera_name="track")
GIF = dict(max_frames=250, every=4, scale=2)
BUFFER = ("obs", "action", "reward", "next_obs", "not_done")  # the replay buffer's fields
ENV_COUNTERS = ("_elapsed_steps", "episode_returns", "episode_lengths")
# Settings --resume may change: how long to go on, and what is shown or written. The rest
# decide the run's numbers and come from its checkpoint.
MAY_CHANGE_ON_RESUME = ("total_timesteps", "print_every", "gifs", "tensorboard", "curves",
                        "watch", "resume", "run_dir")


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


def config_to_resume(cfg, script):
    """The Config of the run cfg.resume, as saved, with the flags of MAY_CHANGE_ON_RESUME that
    this command set. A learning setting set to something else than the saved run's is refused."""
    path = Path(cfg.resume) / "checkpoint.pt"
    saved = load_checkpoint(path, required=("config", "global_step"), script=script)
    defaults = {f.name: f.default for f in dataclasses.fields(cfg)}
    kept = {**defaults, **{k: v for k, v in saved["config"].items() if k in defaults}}
    for name, value in asdict(cfg).items():
        if name in MAY_CHANGE_ON_RESUME or value in (defaults[name], kept[name]):
            continue
        raise UserError(f"--resume continues the run with its saved settings: --"
                        f"{name.replace('_', '-')} {value} differs from the saved {kept[name]}")
    changed = {name: getattr(cfg, name) for name in MAY_CHANGE_ON_RESUME
               if getattr(cfg, name) != defaults[name]}
    cfg = type(cfg)(**{**kept, **changed})
    if cfg.total_timesteps <= saved["global_step"]:
        raise UserError(f"{cfg.resume} already ran {saved['global_step']} steps; pass a "
                        f"larger --total-timesteps to go on")
    return cfg


class CheckpointedRun:
    """DDPG's run folder and what goes into it: episodes.csv as episodes end; at each
    evaluation a row of evaluations.csv, model.pt, best.pt and best.gif (the best so far) and
    curve.png; progress lines with steps/s and the time left; and every checkpoint_every steps
    checkpoint.pt, from which --resume continues the very same run. `nets` (name -> network
    or optimizer, nets["actor"] the one played), `buffer` and `env` are the script's own: a
    checkpoint saves them and --resume puts them back."""

    def __init__(self, script, cfg, nets, buffer, env, device, **info):
        self.script, self.cfg, self.nets, self.buffer, self.env = script, cfg, nets, buffer, env
        self.device, self.info = device, info  # info: what --eval needs to rebuild the actor
        self.dir = Path(cfg.resume) if cfg.resume else None
        self.episodes, self.evaluations = [], []  # (step, return); (step, mean, std)
        self.inside = []  # per evaluation: (mean Q(s, mu(s)), mean discounted return, states)
        now = time.time()
        self.timer = dict(start=now, step=0, time=now, rate=float("nan"))
        self.ctrl_c = CtrlC()

    def start(self, obs):
        """A new run folder; or with --resume, everything as its checkpoint saved it. Returns
        the loop's (global_step, obs)."""
        if not self.cfg.resume:
            self.dir = make_run_dir(self.cfg.run_dir, self.script, self.cfg.env_id, self.cfg.seed)
            print(f"run folder: {self.dir}  (device: {self.device})", flush=True)
            first = max(self.cfg.eval_every * (self.cfg.start_steps // self.cfg.eval_every + 1),
                        self.cfg.eval_every)
            warm_up = (f"once in the warm-up (step {self.cfg.eval_every}), then "
                       if self.cfg.eval_every <= self.cfg.start_steps else "")
            print(f"curve.png there is redrawn at every evaluation: {warm_up}from step {first} "
                  f"on, every {self.cfg.eval_every} steps", flush=True)
            shipped = Path(__file__).resolve().parent / "docs" / f"{self.script}2d.pt"
            if self.cfg.env_id == "Walker2d-v5" and shipped.exists():
                print(f"meanwhile, a trained walker (a 1M-step run's best actor): python "
                      f"{self.script}.py --eval {shipped} --gif walker.gif (or --watch)", flush=True)
            return 0, obs
        step, obs = self._load_checkpoint()
        self._rewind_logs()
        self.timer.update(step=step)  # the run's clock goes on from where it was saved:
        self.timer["start"] -= self.saved_elapsed  # not from 0 at each --resume
        print(f"resumed {self.dir} at step {step} of {self.cfg.total_timesteps}", flush=True)
        return step, obs

    @property
    def ctrl_c_pressed(self):
        """Was Ctrl-C pressed? The loop then stops after the step, with a checkpoint."""
        return self.ctrl_c.pressed

    @contextlib.contextmanager
    def until_interrupted(self):
        """Around the training loop: a first Ctrl-C only sets ctrl_c_pressed; a second one
        ends the loop at once (the last checkpoint is kept)."""
        with self.ctrl_c:
            try:
                yield self
            except KeyboardInterrupt:
                self.ctrl_c.pressed = True

    def episode_ended(self, step, episode_return):
        self.episodes.append((step, float(episode_return)))
        append_csv(self.dir / "episodes.csv", episode_row(*self.episodes[-1]))

    def print_progress(self, step, losses):
        """Every print_every steps a progress line, after a check that the losses and the
        networks are finite (nan or inf: one line, and a run without a checkpoint is removed)."""
        if step > self.cfg.start_steps:  # steps/s of learning: from this process's first update
            self.timer.setdefault("learning_since", (step, time.time()))
        if step % self.cfg.print_every:
            return
        if losses is not None:
            nets = (self.nets["actor"], self.nets["critic"])
            checkpointed = (self.dir / "checkpoint.pt").exists()
            stop_if_diverged(step, dict(critic_loss=losses[0], actor_loss=losses[1]), nets,
                             None if checkpointed else self.dir)
        print(self._progress_line(step, losses), flush=True)

    def _progress_line(self, step, losses):
        """'step 30000  151 steps/s  rest of the budget 1:47:02  return(10) ...'."""
        now, cfg, timer = time.time(), self.cfg, self.timer
        # steps/s of learning since the last line (or since learning began, if it was later)
        since_step, since = max((timer["step"], timer["time"]),
                                timer.get("learning_since", (step, 0)))
        if step > cfg.start_steps and step > since_step:
            timer["rate"] = (step - since_step) / (now - since)
            left = (cfg.total_timesteps - step) / timer["rate"]
            speed = f"{timer['rate']:5.0f} steps/s  {hours_minutes(left)} to go"
        else:
            speed = "learning starts" if step > cfg.start_steps else "warm-up (random actions)"
        timer.update(step=step, time=now)
        recent = (f"{np.mean([r for _, r in self.episodes[-10:]]):8.1f}" if self.episodes
                  else "     n/a")
        loss_text = (f"  critic_loss {losses[0].item():8.3f}  actor_loss {losses[1].item():8.2f}"
                     if losses is not None else "")
        return (f"step {step:>8}  {speed}  return(10) {recent}{loss_text}  "
                f"{clock(now - timer['start'])}")

    def log_evaluation(self, step, returns, trajectories=()):
        """An evaluation's row in evaluations.csv, with the critic's Q(s, mu(s)) against the
        discounted return from the evaluation's states (common.q_against_return); model.pt,
        and best.pt and best.gif if it is the best so far; curve.png and inside.png redrawn."""
        cfg, actor = self.cfg, self.nets["actor"]
        mean, std = float(np.mean(returns)), float(np.std(returns))
        best = max((m for _, m, _ in self.evaluations), default=-float("inf"))
        self.evaluations.append((step, mean, std))
        self.inside.append(common.q_against_return(trajectories, actor, self.nets["critic"],
                                                   cfg.gamma, self.device))
        append_csv(self.dir / "evaluations.csv", evaluation_row(self.evaluations[-1],
                                                                self.episodes, self.inside[-1]))
        print(f"evaluation at step {step}: {mean:.1f} +- {std:.1f} over {len(returns)} "
              f"episodes", flush=True)
        self._save_actor(self.dir / "model.pt", step)
        if mean > best:
            self._save_actor(self.dir / "best.pt", step)
            if cfg.gifs:
                common.record_gif(cfg.env_id, common.deterministic(actor, self.device),
                                  self.dir / "best.gif", cfg.eval_seed, **GIF, **CAMERA)
        if cfg.curves:
            plots.draw_run(self.dir)  # rewritten at every evaluation: open it any time
            plots.draw_inside(self.dir, self.script, asdict(cfg))
        if cfg.tensorboard:
            plots.to_tensorboard(self.dir, sps=self.timer["rate"])
        # The next progress line's steps/s counts learning from here: not this evaluation
        # (nor best.gif, nor the pictures), which the loop does between two lines.
        self.timer.update(step=step, time=time.time())

    def _save_actor(self, path, step):
        save_model(path, self.script, self.cfg, step, {"actor": self.nets["actor"]}, **self.info)

    def checkpoint_when_due(self, step, obs):
        """checkpoint.pt every checkpoint_every steps, at the last step (a later --resume with
        a larger --total-timesteps extends the run) and when Ctrl-C was pressed."""
        cfg = self.cfg
        if step % cfg.checkpoint_every == 0 or step == cfg.total_timesteps or self.ctrl_c.pressed:
            self._save_checkpoint(step, obs)

    def _save_checkpoint(self, step, obs):
        """Everything that decides what the run does next, so that --resume goes on exactly as
        if the run had never stopped."""
        buffer, filled = self.buffer, slice(0, self.buffer.size)  # only the filled part
        started, path = time.time(), self.dir / "checkpoint.pt"
        save_checkpoint(dict(
            script=self.script, config=asdict(self.cfg), global_step=step,
            obs=torch.as_tensor(obs), **{key: net.state_dict() for key, net in self.nets.items()},
            buffer={key: getattr(buffer, key)[filled].cpu().clone() for key in BUFFER},
            buffer_ptr=buffer.ptr, buffer_count=buffer.size,
            torch_rng=torch.get_rng_state(),  # the exploration noise and the minibatch draws
            cuda_rng=torch.cuda.get_rng_state() if buffer.obs.is_cuda else None,
            action_space_rng=self.env.action_space.np_random.bit_generator.state,  # warm-up
            env=env_state(self.env), episodes=self.episodes, evaluations=self.evaluations,
            inside=self.inside, elapsed=started - self.timer["start"]), path)
        print(f"checkpoint at step {step}: {path} ({path.stat().st_size / 2**20:.0f} MB, "
              f"written in {time.time() - started:.1f} s)", flush=True)
        self.timer.update(step=step, time=time.time())  # steps/s: learning, not the write

    def _load_checkpoint(self):
        """Put back what _save_checkpoint saved; return the loop's (global_step, obs)."""
        path = self.dir / "checkpoint.pt"
        ckpt = load_checkpoint(path, required=(*self.nets, "buffer", "env", "torch_rng", "obs"),
                               script=self.script)
        for key, obj in self.nets.items():
            load_weights(obj, ckpt[key], path)
        buffer, n = self.buffer, ckpt["buffer_count"]
        for key in BUFFER:
            getattr(buffer, key)[:n] = ckpt["buffer"][key].to(buffer.obs.device)
        # A run extended by --total-timesteps may get a larger buffer: it fills on after row n.
        buffer.ptr, buffer.size = (ckpt["buffer_ptr"] if n == buffer.max_size else n), n
        torch.set_rng_state(ckpt["torch_rng"])
        if ckpt["cuda_rng"] is not None and buffer.obs.is_cuda:
            torch.cuda.set_rng_state(ckpt["cuda_rng"])
        self.env.action_space.np_random.bit_generator.state = ckpt["action_space_rng"]
        set_env_state(self.env, ckpt["env"])
        self.episodes[:], self.evaluations[:] = ckpt["episodes"], ckpt["evaluations"]
        nan = (float("nan"), float("nan"), 0)  # a checkpoint from before Q was logged
        self.inside[:] = ckpt.get("inside", [nan] * len(self.evaluations))
        self.saved_elapsed = ckpt.get("elapsed", 0.0)  # seconds the run had run, if recorded
        return ckpt["global_step"], ckpt["obs"].numpy()

    def _rewind_logs(self):
        """On resume: rewrite the CSV logs as they were at the checkpoint. Rows a killed run
        wrote after its last checkpoint go; the resumed run writes them again, identically."""
        for stale in self.dir.glob("*.tmp*"):  # a write that a kill cut short
            stale.unlink()
        for name, rows in (("episodes.csv", [episode_row(*e) for e in self.episodes]),
                           ("evaluations.csv", [evaluation_row(e, self.episodes, q)
                                                for e, q in zip(self.evaluations, self.inside)])):
            (self.dir / name).unlink(missing_ok=True)
            for row in rows:
                append_csv(self.dir / name, row)

    def finish(self, global_step, untrained):
        """After the loop: where a stopped run is and how to go on, or the learning phase's
        steps/s and the before/after GIFs. Returns train()'s result: run_dir, global_step,
        evaluations, episodes, steps_per_second (learning phase) and interrupted."""
        learned_from, since = self.timer.get("learning_since", (global_step, time.time()))
        learned = global_step - learned_from
        rate = learned / (time.time() - since) if learned > 0 else float("nan")
        interrupted = self.ctrl_c.pressed
        result = dict(run_dir=self.dir, global_step=global_step, evaluations=self.evaluations,
                      episodes=self.episodes, steps_per_second=rate, interrupted=interrupted)
        if interrupted:
            saved = (torch.load(self.dir / "checkpoint.pt", weights_only=True,
                                mmap=True)["global_step"]
                     if (self.dir / "checkpoint.pt").exists() else None)
            where = (f"its checkpoint is at step {saved}: continue with `python {self.script}.py "
                     f"--resume {self.dir}`" if saved else "no checkpoint was written yet")
            print(f"interrupted at step {global_step}; {where} (before.gif and after.gif come "
                  f"when a run finishes; best.gif shows its best evaluation so far)", flush=True)
            return result
        print(f"learning phase: {learned} steps at {rate:.1f} steps/s (updates and evaluations "
              f"included); run folder: {self.dir}", flush=True)
        if self.cfg.gifs:
            for name, net in (("before.gif", untrained), ("after.gif", self.nets["actor"])):
                ret = common.record_gif(self.cfg.env_id, common.deterministic(net, self.device),
                                        self.dir / name, self.cfg.eval_seed, **GIF, **CAMERA)
                print(f"{name}: return {ret:.0f} -> {self.dir / name}", flush=True)
        return result


def episode_row(step, ep_return):
    """An episodes.csv row, as the CartPole scripts write it."""
    return {"global_step": step, "return": ep_return}


def evaluation_row(evaluation, episodes, inside):
    """An evaluations.csv row: the evaluation, the training return before it, and the critic's
    estimate against the return (`inside`: common.q_against_return's three numbers)."""
    step, mean, std = evaluation
    done = [ret for s, ret in episodes if s <= step]
    q, g, n = inside
    return dict(global_step=step, eval_mean=mean, eval_std=std, episodes=len(done),
                train_return_mean10=float(np.mean(done[-10:])) if done else float("nan"),
                q_estimate=q, discounted_return=g, q_states=n)


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


def set_env_state(env, saved):
    import mujoco

    sim = env.unwrapped
    mujoco.mj_setState(sim.model, sim.data, saved["mujoco"].numpy(),
                       mujoco.mjtState.mjSTATE_INTEGRATION)
    sim.np_random.bit_generator.state = saved["rng"]
    for name in ENV_COUNTERS:
        env.set_wrapper_attr(name, saved[name])


def play_actor(cfg, path, env_id, actor):
    """--eval: play cfg.eval_episodes episodes of a saved DDPG actor without noise (in a window
    with --watch, its camera following the agent), or with --gif one episode to that file."""
    policy = common.deterministic(actor, torch.device("cpu"))
    if cfg.gif:
        print(f"recording one episode of {env_id} with {path} (up to a minute)", flush=True)
        ret = common.record_gif(env_id, policy, cfg.gif, cfg.eval_seed, **GIF, **CAMERA)
        print(f"{cfg.gif}: one episode, return {ret:.1f}", flush=True)
        return [ret]
    print(f"playing {cfg.eval_episodes} episodes of {env_id} with {path}"
          + ("; Ctrl-C stops" if cfg.watch else ""), flush=True)
    returns = common.evaluate(env_id, policy, cfg.eval_episodes, cfg.eval_seed,
                              render_mode="human" if cfg.watch else None, log=cfg.watch,
                              **(watch_camera(env_id) if cfg.watch else {}))
    print(f"{env_id}, {path}: returns {[round(r, 1) for r in returns]}, "
          f"mean {np.mean(returns):.1f}", flush=True)
    return returns


def watch_camera(env_id):
    """gym.make arguments for --watch: the window's camera follows the agent. (The window
    ignores camera_name; it takes the env's own view settings, here with a tracking type.)"""
    import mujoco

    with env_errors(env_id):
        env = gym.make(env_id)
    view = dict(env.unwrapped.mujoco_renderer.default_cam_config or {})
    env.close()
    return dict(default_camera_config={**view, "type": mujoco.mjtCamera.mjCAMERA_TRACKING})
