"""Saving and loading: model.pt and best.pt (weights and what rebuilds them), checkpoint.pt
(each object's state_dict(), so --resume goes on exactly), and the Ctrl-C that stops a
training loop at a whole step. Every file is written whole or not at all.
"""

import dataclasses
import os
import re
import signal
import threading
import time
from dataclasses import asdict
from pathlib import Path

import torch

from common import UserError, check_writable, written_whole

def save_checkpoint(obj, path):
    """torch.save, flushed to disk, written whole."""
    with written_whole(path) as tmp, open(tmp, "wb") as f:
        torch.save(obj, f)
        f.flush()
        os.fsync(f.fileno())


def load_checkpoint(path, required=(), script=None):
    """torch.load(weights_only=True), or one clear UserError; a run folder means its model.pt.
    With `script` (a script's name), a checkpoint that names another script is refused."""
    path = Path(path) / "model.pt" if Path(path).is_dir() else Path(path)
    if not path.is_file():
        here = Path(__file__).resolve().parent / path  # e.g. a model in docs/, from elsewhere
        where = "" if path.is_absolute() else f" (relative to {Path.cwd()}, where you are" + (
            f"; did you mean {here}?)" if here.exists() else ")")
        raise UserError(f"no checkpoint at {path}{where}")
    try:  # weights_only: tensors and plain values, never arbitrary Python objects
        ckpt = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as e:  # cut short, damaged, not a torch file, or Python objects inside
        refused = re.search(r"Unsupported global: GLOBAL (\S+)", str(e))
        if refused:  # whole, but it holds an object that torch will not load safely
            raise UserError(f"cannot read {path}: it holds a {refused[1]} object, which is not "
                            "loaded (only tensors and plain values are, for safety); if a script "
                            "here wrote it, it saved another object by mistake (a numpy number: "
                            "save float(x))") from None
        raise UserError(f"cannot read {path}: truncated, corrupt or not a checkpoint of these "
                        "scripts") from None
    if script and isinstance(ckpt, dict) and ckpt.get("script") != script:
        raise UserError(f"{path} is not a model of {script}.py: it is " + (
            f"a model of {ckpt['script']}.py" if "script" in ckpt else
            "from an older version that did not record its script: train it again"))
    if isinstance(ckpt, dict) and "obs" in ckpt and "obs" not in required:  # save() writes obs
        raise UserError(f"{path} is the run's checkpoint, for --resume {path.parent}; --eval "
                        "plays model.pt or best.pt (or the run folder)")
    if not isinstance(ckpt, dict) or not set(required) <= set(ckpt):
        raise UserError(f"{path} is not a checkpoint of this script (it lacks {set(required)})")
    return ckpt


def load_state(obj, state, path):
    """obj.load_state_dict(state), with a UserError naming `path` if it does not fit."""
    try:
        obj.load_state_dict(state)
    except (RuntimeError, ValueError, KeyError) as e:  # shapes, keys or optimizer groups differ
        raise UserError(f"{path} does not fit this script's {type(obj).__name__}: "
                        f"{str(e).splitlines()[0]}") from None


def save_model(path, script, cfg, step, nets, **info):
    """model.pt (or best.pt): the networks' weights, the settings, and what rebuilds them
    (`info`, e.g. obs_dim and n_actions)."""
    save_checkpoint(dict(script=script, **{name: net.state_dict() for name, net in nets.items()},
                         config=asdict(cfg), **info, global_step=step), path)


def load_model(path, script, key, build):
    """--eval: the network saved under `key` at `path` (model.pt, best.pt or a run folder),
    made by `build(checkpoint)` (the script's constructor call) with its weights. Returns the
    network and the saved run's env id (None for a task that is not an env)."""
    ckpt = load_checkpoint(path, script=script, required=(key, "config"))
    net = build(ckpt)
    load_state(net, ckpt[key], path)
    return net, ckpt["config"].get("env_id")


def config_to_resume(cfg, script):
    """The Config of the run cfg.resume, as saved, with the flags of the Config's
    MAY_CHANGE_ON_RESUME (cli.CheckpointFlags) that this command set. A learning setting set
    to something else than the saved run's is refused."""
    path = Path(cfg.resume) / "checkpoint.pt"
    if not path.exists() and (Path(cfg.resume) / "model.pt").exists():  # whose run is it?
        load_checkpoint(Path(cfg.resume) / "model.pt", script=script)  # another's: says so
    if path.exists():  # a read-only folder fails now, in one line
        check_writable(path.parent, "--resume goes on in the run's folder", "resume a writable "
                       "copy of it (--eval only reads it)")
    saved = load_checkpoint(path, required=("config", "global_step", "obs"), script=script)
    may_change = type(cfg).MAY_CHANGE_ON_RESUME
    defaults = {f.name: f.default for f in dataclasses.fields(cfg)}
    kept = {**defaults, **{k: v for k, v in saved["config"].items() if k in defaults}}
    for name, value in asdict(cfg).items():
        if name in may_change or value in (defaults[name], kept[name]):
            continue
        raise UserError(f"--resume continues the run with its saved settings: --"
                        f"{name.replace('_', '-')} {value} differs from the saved {kept[name]}")
    changed = {name: getattr(cfg, name) for name in may_change
               if getattr(cfg, name) != defaults[name]}
    cfg = type(cfg)(**{**kept, **changed})
    if cfg.total_timesteps <= saved["global_step"]:
        raise UserError(f"{cfg.resume} already ran {saved['global_step']} steps; pass a "
                        f"larger --total-timesteps to go on")
    return cfg


def save(path, script, cfg, step, obs, holders, say=True):
    """checkpoint.pt: the settings, the step, the loop's obs and each holder's state_dict()
    (networks, optimizers, buffer, env, random generators, logs); a line says so if `say`
    (after a Ctrl-C the run's one last line says where its checkpoint is)."""
    started = time.time()
    save_checkpoint(dict(script=script, config=asdict(cfg), global_step=step,
                         obs=torch.as_tensor(obs),
                         **{key: obj.state_dict() for key, obj in holders.items()}), path)
    if say:
        print(f"checkpoint at step {step}: {path} ({path.stat().st_size / 2**20:.0f} MB, "
              f"written in {time.time() - started:.1f} s)", flush=True)


def resume(run_dir, script, cfg, holders):
    """Put back into each holder what save() saved in run_dir/checkpoint.pt; return the loop's
    (global_step, obs)."""
    path = Path(run_dir) / "checkpoint.pt"
    ckpt = load_checkpoint(path, required=(*holders, "obs"), script=script)
    for key, obj in holders.items():
        load_state(obj, ckpt[key], path)
    print(f"resumed {run_dir} at step {ckpt['global_step']} of {cfg.total_timesteps}", flush=True)
    return ckpt["global_step"], ckpt["obs"].numpy()


class RandomState:
    """The random generators a run draws from (torch's, the warm-up's action space), as a
    state_dict() for checkpoint.pt."""

    def __init__(self, env, device):
        self.env, self.cuda = env, torch.device(device).type == "cuda"

    def state_dict(self):
        return dict(torch=torch.get_rng_state(), action_space=self.action_space.state,
                    cuda=torch.cuda.get_rng_state() if self.cuda else None)

    def load_state_dict(self, state):
        torch.set_rng_state(state["torch"])
        if self.cuda and state["cuda"] is not None:
            torch.cuda.set_rng_state(state["cuda"])
        self.action_space.state = state["action_space"]

    @property
    def action_space(self):
        return self.env.action_space.np_random.bit_generator


class Arrays:
    """A training loop's own numpy arrays (e.g. which envs reset at their next step), by name,
    as a state_dict() for checkpoint.pt; load_state_dict() writes them back in place."""

    def __init__(self, **arrays):
        self.arrays = arrays

    def state_dict(self):
        return {name: torch.from_numpy(array.copy()) for name, array in self.arrays.items()}

    def load_state_dict(self, state):
        for name, array in self.arrays.items():
            array[...] = state[name].numpy()


class CtrlC:
    """Around a training loop: a first Ctrl-C (or SIGTERM: common.sigterm_as_ctrl_c) only sets
    `pressed`, so the loop can finish its step and stop where nothing is half done; a second
    one ends the block at once."""

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

    def __exit__(self, kind, error, traceback):
        if self.active:
            signal.signal(signal.SIGINT, signal.default_int_handler)
        if kind is KeyboardInterrupt:
            self.pressed = True
            return True  # the second Ctrl-C: the block ends, the run reports where it stopped
