"""The command line: the flags every script shares (the output flags, the solved rule's
settings, the checkpoints of a script that resumes), a script's Config read from flags, and
one-line errors with their exit codes (2: bad input, 130: Ctrl-C, 143: SIGTERM).

A Config is a @dataclass; each field is a flag (`num_envs: int = 8` -> `--num-envs 8`), its
help the string under it, bool -> `--x/--no-x`, `float | None` also takes `none`.
"""

import argparse
import contextlib
import dataclasses
import difflib
import inspect
import sys
from dataclasses import dataclass
from pathlib import Path

import gymnasium as gym
import numpy as np
import torch

import help_zh
import plots
from common import (UserError, check_writable, from_ctrl_c, headless, sigterm_as_ctrl_c,
                    stopped_by)


@dataclass
class OutputFlags:
    """What a run writes and shows, and playback: the flags every script shares."""

    run_dir: str = "runs"
    """parent folder of the run folder <script>__<env or task>__seed<k>__<time>/ (runs/latest:
    this script's newest one, for --eval, and for --resume where the script has it)"""
    print_every: int = 10
    """print a progress line every this many updates (rows of progress.csv)"""
    gifs: bool = True
    """write before.gif (untrained) and after.gif (trained) to the run folder, one episode each,
    acting as the script's first evaluation does (PPO and A2C: actions drawn from pi, as in
    training and in tutorial 004's GIFs; DQN: the greedy action)"""
    curves: bool = True
    """draw curve.png (the learning curve) and inside.png (what the updates do inside the
    algorithm; docs/inside.md) in the run folder"""
    tensorboard: bool = False
    """also write the logs as TensorBoard scalars into the run folder, with CleanRL's tag
    names (needs `pip install tensorboard`; then: tensorboard --logdir runs)"""
    eval_episodes: int = 10
    """episodes of each evaluation (--eval too)"""
    eval_seed: int = 10_000
    """seed of the evaluation env (and of its action draws, for a policy that samples), kept
    apart from the training seed"""
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
    """train on the GPU if there is one; the networks are too small for it to help much (one
    H100 against one CPU thread: DDPG 1.16x, TD3 1.29x, PPO on CartPole 0.25x); other numbers
    per seed"""

    def __post_init__(self):
        check(not self.tensorboard or plots.tensorboard_installed(), plots.NO_TENSORBOARD)
        check_ranges(self, print_every="> 0", eval_episodes="> 0", eval_seed=">= 0", threads="> 0")
        check(not self.gif or self.eval, "--gif writes a GIF of a saved policy: it needs --eval")
        check(not self.gif or self.gif.lower().endswith(".gif"),
              f"--gif writes a GIF: give a file name that ends in .gif, got {self.gif}")
        if self.gif:  # a folder that is missing or read-only: now, not after the episode
            check_writable(Path(self.gif).parent, f"--gif {self.gif}")


@dataclass
class SolvedFlags(OutputFlags):
    """The flags of a script with a solved rule: the shared ones and the rule's."""

    stop_when_solved: bool = True
    """stop once the mean return of the last solved_window finished episodes reaches the
    solved return and the policy as it is then does too, over eval_episodes episodes acting as
    its first evaluation does (env seed eval_seed + 1); checked at most once per update"""
    solved_return: float | None = None
    """the return that counts as solved; none = the env's reward_threshold (CartPole's: 475)"""
    solved_window: int = 20
    """how many of the last finished episodes the solved rule averages (and the progress
    line's return shows)"""

    def __post_init__(self):
        super().__post_init__()
        check_ranges(self, solved_window="> 0")


@dataclass
class CheckpointFlags(OutputFlags):
    """The flags of a script that evaluates every so many steps and resumes from its
    checkpoints: the shared ones, its progress lines and its checkpoints."""

    # Settings --resume may change: how long to go on, and what is shown or written. The
    # rest decide the run's numbers and come from its checkpoint.
    MAY_CHANGE_ON_RESUME = ("total_timesteps", "print_every", "gifs", "tensorboard", "curves",
                            "watch", "resume", "run_dir")

    print_every: int = 1000
    """print a progress line every this many env steps"""
    gifs: bool = True
    """write before.gif (untrained actor), after.gif (trained actor) and best.gif (the best
    evaluation so far, refreshed as it improves) to the run folder"""
    curves: bool = True
    """write curve.png (evaluation returns against env steps) and inside.png (what the updates
    do inside the algorithm, e.g. a critic's Q against the discounted return really obtained
    from the same states: docs/inside.md) at every evaluation"""
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
    """The @dataclass `cls` from flags. The script's own fields come first in --help, the
    shared ones after. Bad input: one line, exit 2 (abbreviations are refused). --help-zh (or
    --help in a Chinese locale) adds a Chinese line under each flag, from locale/flags.zh-CN.md;
    --lang zh (or a Chinese locale; --lang en: English) prints the output in Chinese."""
    argv, zh, chinese = help_zh.wanted(sys.argv[1:] if argv is None else argv)
    if chinese:  # --lang zh, or a Chinese locale: each line printed from here on in Chinese
        help_zh.print_in_chinese()
    module = sys.modules[cls.__module__]  # the script (its FLAGS_ZH, if it has them)
    zh_docs = help_zh.flags(Path(inspect.getfile(cls)).stem, module) if zh else {}
    parser = argparse.ArgumentParser(description=help_zh.overview(cls, description) if zh else
                                     description, allow_abbrev=False, epilog=help_zh.EPILOG,
                                     formatter_class=help_zh.HelpFormatterZh if zh
                                     else help_zh.HelpFormatter)
    parser.error = lambda message: parser.exit(2, f"{parser.prog}: error: {message}\n")  # no usage
    docs = help_zh.english(cls)  # the string under each field, its bases' too
    # UNUSED_FLAGS: {shared field: why this script has no use for it}: out of --help, refused
    own, unused = vars(cls).get("__annotations__", {}), getattr(cls, "UNUSED_FLAGS", {})
    for f in sorted(dataclasses.fields(cls), key=lambda f: f.name not in own):
        name = f.type if isinstance(f.type, str) else getattr(f.type, "__name__", str(f.type))
        kind = name.replace(" | None", "")  # "float | None" -> "float"
        convert = {"int": int, "float": float, "str": str, "bool": bool}[kind]
        how = dict(type=_or_none(convert) if "None" in name else convert, metavar=kind.upper())
        if kind == "bool":
            how = dict(action=argparse.BooleanOptionalAction)
        flag = "--" + f.name.replace("_", "-")
        text = docs.get(f.name, "") + (f"; none on the command line: {flag} none"
                                       if "None" in name else "")
        chinese = zh_docs.get(f.name, "（还没有中文说明）") + (
            "" if "None" not in name else f"；默认不设（命令行上写 {flag} none 也表示不设）"
            if f.default is None else f"；命令行上写 {flag} none 表示不设")
        text = (text + (f"\n{chinese}" if zh else "")).replace("%", "%%")
        hidden = f.name in unused  # out of --help, and absent unless given (then refused)
        parser.add_argument(flag, default=argparse.SUPPRESS if hidden else f.default, **how,
                            help=argparse.SUPPRESS if hidden else text)
    parser.add_argument("--lang", choices=("zh", "en"), default=argparse.SUPPRESS,  # read by
                        help="\n".join(help_zh.LANG_HELP[:2 if zh else 1]))  # help_zh.wanted
    args, unknown = parser.parse_known_args(argv)
    if unknown:  # a mistyped flag: the nearest known one, if any is near (cutoff 0.7: a flag
        # of another script, --resume, is not offered --curves)
        flags = [o for a in parser._actions for o in a.option_strings if o.startswith("--")]
        near = difflib.get_close_matches(next((u.split("=")[0] for u in unknown
                                               if u.startswith("--")), ""), flags, n=1, cutoff=0.7)
        parser.error(f"unrecognized arguments: {' '.join(unknown)}"
                     + (f" (did you mean {near[0]}?)" if near else ""))
    given = [name for name in unused if name in vars(args)]  # unused, given anyway: refused
    if given:
        parser.error(f"--{given[0].replace('_', '-')}: {unused[given[0]]}")
    for name, value in vars(args).items():  # nan fails every test, inf never ends: refuse both
        if isinstance(value, float) and not np.isfinite(value):
            parser.error(f"--{name.replace('_', '-')} must be a finite number, got {value}")
    if getattr(args, "watch", False) and headless() and "watch" not in unused:  # fail now
        parser.error("--watch opens a window, but this machine has no display (see the GIFs, "
                     "or write one of a saved model: --eval RUN --gif OUT.gif)")
    script = Path(inspect.getfile(cls)).stem  # the script whose Config this is
    try:
        for name in ("eval", "resume"):  # runs/latest: this script's newest run folder there
            if getattr(args, name, None):
                setattr(args, name, latest_run(getattr(args, name), script,
                                               "checkpoint.pt" if name == "resume" else "model.pt"))
        cfg = cls(**vars(args))
    except (ValueError, UserError) as e:
        parser.error(str(e))
    if getattr(cfg, "cuda", False) and not cls.cuda and not torch.cuda.is_available():
        print("warning: --cuda, but torch sees no GPU here (a CPU-only torch, or no driver): "
              "running on the CPU", file=sys.stderr, flush=True)  # as the scripts then do
    return cfg


def latest_run(path, script, needs="model.pt"):
    """`path` with a part named `latest` (runs/latest, runs/latest/best.pt) read as the newest
    run folder of `script` in that folder, by the time in its name, that holds the file asked
    for (the rest of `path`, or else `needs`); a newer one without it (killed before it wrote
    one, or still training) is passed over, with a line that says so. `latest` is read so
    where it is a link too (runlog.point_latest: the newest run of any script, maybe still
    training); a path without it, or with a real folder named `latest`, stays as it is.

    >>> latest_run("runs/my_script__some_env__seed0__20260101-120000", "my_script")
    'runs/my_script__some_env__seed0__20260101-120000'
    """
    parts = Path(path).parts
    if "latest" not in parts:
        return path
    at = parts.index("latest")
    named = Path(*parts[:at + 1])
    if named.is_dir() and not named.is_symlink():  # a folder of the reader's own named latest
        return path
    parent, inside = Path(*parts[:at]) if at else Path("."), Path(*parts[at + 1:] or [needs])
    runs = sorted(parent.glob(f"{script}__*"), key=lambda run: run.name.split("__")[-1])
    if not runs:
        raise UserError(f"{path}: no run of {script}.py in {parent} yet")
    ready = [run for run in runs if (run / inside).exists()]
    if not ready:
        raise UserError(f"{path}: no run of {script}.py in {parent} has {inside} yet (the "
                        f"newest: {runs[-1]})")
    if ready[-1] != runs[-1]:
        print(f"{path}: {runs[-1].name} has no {inside} (stopped before writing one, or still "
              f"training): {ready[-1].name} instead", file=sys.stderr, flush=True)
    return str(Path(ready[-1], *parts[at + 1:]))


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


def check_ranges(config, **ranges):
    """For Config.__post_init__: each named field lies in its range (a key of RANGES; "... or
    none" also lets None through), else ValueError. Checks relating two fields stay explicit."""
    for name, allowed in ranges.items():
        value, optional = getattr(config, name), allowed.endswith(" or none")
        inside, words = RANGES[allowed.removesuffix(" or none")]
        if not (value is None and optional or value is not None and inside(value)):
            raise ValueError(f"--{name.replace('_', '-')} must be {words}"
                             f"{' or none' if optional else ''}, got {value}")


@contextlib.contextmanager
def clear_exit():
    """Around main(): bad input, one `error:` line and exit 2; Ctrl-C, even turned into another
    error, one line and exit 130; SIGTERM does what Ctrl-C does (common.sigterm_as_ctrl_c),
    exit 143."""
    try:
        with sigterm_as_ctrl_c():
            yield
    except UserError as e:  # named as argparse names its errors: "<script>.py: error: ..."
        prog = Path(sys.argv[0]).name
        print(f"{prog + ': ' if prog.endswith('.py') else ''}error: {e}", file=sys.stderr,
              flush=True)
        sys.exit(2)
    except (KeyboardInterrupt, ImportError, RuntimeError, MemoryError, gym.error.Error) as e:
        if from_ctrl_c(e):
            name, code = stopped_by()
            print(f"\ninterrupted ({name})", file=sys.stderr, flush=True)
            sys.exit(code)
        if isinstance(e, MemoryError) or "allocate" in str(e):  # e.g. --buffer-size too large
            print(f"error: not enough memory for these settings (too many envs or steps, or too "
                  f"large a buffer?): {str(e).splitlines()[0] if str(e) else 'MemoryError'}",
                  file=sys.stderr, flush=True)
            sys.exit(2)
        raise
