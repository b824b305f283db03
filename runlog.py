"""The run folder and its logs: CSV rows written as they come, progress lines, the finished
episodes and their recent mean (what the solved rule compares), and the check that stops a
diverged run. When to stop is decided in the scripts' loops, from what this keeps.
"""

import contextlib
import csv
import os
import shutil
import time
from pathlib import Path

import numpy as np
import torch

import checkpoints
import plots
from common import UserError, written_whole


def make_run_dir(root, script, env_id, seed):
    """Create and return <root>/<script>__<env>__seed<k>__<timestamp>[-i]/; <root>/latest
    links to it (point_latest)."""
    name = f"{script}__{env_id.replace('/', '-')}__seed{seed}__"
    base = Path(root) / (name + time.strftime("%Y%m%d-%H%M%S"))
    for path in [base, *(Path(f"{base}-{i}") for i in range(1, 1000))]:
        try:
            path.mkdir(parents=True)
        except FileExistsError:  # another run started this second: the next name
            continue
        except OSError as e:
            raise UserError(f"cannot create run folder {path}: {e.strerror}") from None
        point_latest(root, path)
        return path


LATEST = "latest"  # <root>/latest: a link to the newest run folder there, of any script


def point_latest(root, run=None):
    """Make <root>/latest a link to the run folder `run` (None: the newest left in `root`, by
    the time in its name; none left: no link). The link is made aside and renamed over the old
    one, so a reader never finds it half made. Where links cannot be made (Windows without the
    privilege, a filesystem without them), one line says so: --eval and --resume still read
    runs/latest as the script's newest run (cli.latest_run)."""
    link = Path(root) / LATEST
    if run is None:
        runs = sorted((p for p in Path(root).glob("*__*") if p.is_dir() and not p.is_symlink()),
                      key=lambda p: p.name.split("__")[-1])
        if not runs:
            if link.is_symlink():
                link.unlink()
            return
        run = runs[-1]
    tmp = Path(root) / f".{LATEST}.{os.getpid()}.tmp"
    try:
        tmp.unlink(missing_ok=True)
        tmp.symlink_to(Path(run).name, target_is_directory=True)  # relative: moves with root
        os.replace(tmp, link)
    except OSError as e:
        tmp.unlink(missing_ok=True)
        print(f"note: {link} cannot be made a link to this run ({e.strerror or e}); --eval and "
              f"--resume still take {link} as the script's newest run", flush=True)


def append_csv(path, row):
    """Append a dict as a CSV row (header first); one open per row: complete after Ctrl-C.
    None (not measured) is written as nan. A row whose columns are not the file's header is
    refused: a column cannot go missing from some rows."""
    new = not Path(path).exists()
    if not new:
        with open(path, newline="") as f:
            header = next(csv.reader(f), [])
        if header != list(row):
            raise UserError(f"{path}: a row with the columns {list(row)} under the header "
                            f"{header}")
    with open(path, "a", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(row))
        if new:
            writer.writeheader()
        writer.writerow({k: "nan" if v is None else f"{v:.6g}" if isinstance(v, float) else v
                         for k, v in row.items()})


def stop_if_diverged(step, losses, nets, run_dir=None, outputs=()):
    """nan or inf in `losses` (name -> number), in the weights of `nets` or in `outputs` (the
    networks' outputs on the next states): remove `run_dir` (unless it holds a checkpoint.pt,
    the last good state to --resume from), raise one UserError naming the step and the likely
    cause."""
    bad = [name for name, value in losses.items()  # None: not measured; arrays: for pictures
           if value is not None and np.ndim(value) == 0 and not np.isfinite(float(value))]
    bad += [f"{type(net).__name__}'s weights" for net in nets
            if not all(bool(p.isfinite().all()) for p in net.parameters())]
    bad += ["the networks' output"] * (not all(bool(out.isfinite().all()) for out in outputs))
    if bad:
        removed = run_dir is not None and not (Path(run_dir) / "checkpoint.pt").exists()
        if removed:
            shutil.rmtree(run_dir, ignore_errors=True)
            latest = Path(run_dir).parent / LATEST
            if latest.is_symlink() and not latest.exists():  # it named the removed folder
                point_latest(Path(run_dir).parent)
        raise UserError(f"training diverged at step {step}: nan or inf in {', '.join(bad)}; "
                        "likely cause: too high a learning rate (try a smaller one)"
                        + (f"; {run_dir} was removed" if removed else ""))


def hours_minutes(seconds):
    """5000 -> 'about 1 h 23 min', 90 -> 'about 2 min', 50 -> 'under a minute'."""
    if seconds < 60:  # not round(): 34 s would read "about 1 min" after "under a minute"
        return "under a minute"
    minutes = round(seconds / 60)
    return (f"about {minutes // 60} h {minutes % 60:02d} min" if minutes >= 60
            else f"about {minutes} min")


def clock(seconds):
    """1234.5 -> '20:34', 5000 -> '1:23:20'."""
    return time.strftime("%H:%M:%S", time.gmtime(seconds)).lstrip("0").lstrip(":") or "0"


# How many of the last finished episodes a progress line, evaluations.csv's
# train_return_mean10 and its label average (the solved rule has its own --solved-window).
RECENT = 10


def declared(logged, row, where):
    """Check that `row`'s columns are the ones the script declared in `logged` (a column
    written but not declared, or declared but not written, is the script's mistake)."""
    if set(row) != set(logged):
        raise ValueError(f"{where}: the script declares the columns {sorted(logged)} but "
                         f"logged {sorted(row)}: declare each column once, log each one")


def labels_and_tags(logged):
    """A script's declaration of what it logs -> ({column: the pictures' label},
    {column: its TensorBoard tag, where it declares one})."""
    return ({column: spec[1] for column, spec in logged.items()},
            {column: spec[2] for column, spec in logged.items() if len(spec) > 2})


class UpdateLog:
    """A run folder of a script that updates on batches: a progress.csv row per update, with
    a progress line every print_every updates; the finished episodes (episodes.csv at the end)
    and the mean return of the last solved_window of them; what inside.png draws (the updates'
    arrays, the states visited). `logged`: the script's declaration of what each update logs,
    {column: (format on the progress line or None: only in the CSV, what it is (the pictures'
    label)[, its TensorBoard tag])}; a value of
    None is "not measured at this update" (nan in the CSV, left out of the line). `unit`: what
    global_step counts, named on the progress line ("episode 40  120 episodes/s" where a
    tabular script logs once an episode)."""

    def __init__(self, script, cfg, logged, task=None, unit="step"):
        self.script, self.cfg, self.logged, self.unit = script, cfg, logged, unit
        self.labels, self.tags = labels_and_tags(logged)
        self.window = getattr(cfg, "solved_window", None)  # none: no episodes to average
        self.start_time = time.time()
        self.dir = make_run_dir(cfg.run_dir, script, task or cfg.env_id, cfg.seed)
        print(f"run folder: {self.dir}", flush=True)
        self.episodes = []  # (env step, return) of every finished training episode, in order
        self.kept, self.visited = [], []  # each update's arrays; the last batches' obs
        self.global_step, self.updates, self.stats = 0, 0, {}
        self.solved_step, self.interrupted = None, False

    def recent_return(self):
        """The mean return of the last solved_window finished training episodes."""
        recent = [r for _, r in self.episodes[-self.window:]]
        return float(np.mean(recent)) if recent else np.nan

    def episodes_ended(self, info, step):
        """Record the episodes that ended at env step `step` (from the vector env's `info`);
        return their returns."""
        self.global_step = step
        if "episode" not in info:
            return []
        ended = [float(r) for r in info["episode"]["r"][info["_episode"]]]  # _episode: which envs
        self.episodes += [(step, r) for r in ended]
        return ended

    def solved(self, threshold):
        """Has the mean return of the last solved_window episodes reached `threshold`? Says so
        the first time."""
        if len(self.episodes) < self.window or self.recent_return() < threshold:
            return False
        if self.solved_step is None:
            self.solved_step = self.global_step
            print(f"solved: mean return of the last {self.window} episodes "
                  f"{self.recent_return():.1f} >= {threshold:g} at step {self.global_step} "
                  f"(episode {len(self.episodes)}) after {time.time() - self.start_time:.1f}s",
                  flush=True)
        return True

    def update(self, stats, visited=None, show=False, **columns):
        """After an update: its progress.csv row (the step, episodes, recent return, `columns`,
        then the numbers of `stats`; its arrays are kept for inside.png), and every print_every
        updates (and after the first, and where `show`) a progress line of the declared
        formats, without the numbers not measured at this update (None). `visited`: the
        batch's observations, the last 10 batches' are marked on inside.png's maps."""
        self.updates += 1
        if visited is not None:
            self.visited = [*self.visited[-9:], visited.detach().cpu().numpy()]
        arrays = {k: v.detach().cpu().numpy() for k, v in stats.items() if torch.is_tensor(v)}
        self.stats = {k: v for k, v in stats.items() if k not in arrays}
        declared(self.logged, {**columns, **self.stats}, "progress.csv")
        self.kept.append((self.global_step, arrays))
        self.row(**columns, **self.stats)
        if self.updates % self.cfg.print_every == 0 or self.updates == 1 or show:
            elapsed, shown = time.time() - self.start_time, {**columns, **self.stats}
            numbers = "  ".join(f"{key} {shown[key]:{spec[0]}}" for key, spec in
                                self.logged.items() if spec[0] and shown[key] is not None)
            recent = f"return({self.window}) {self.recent_return():6.1f}  " if self.window else ""
            print(f"{self.unit} {self.global_step:>7}  {self.global_step / elapsed:6.0f} "
                  f"{self.unit}s/s  "
                  f"{recent}{numbers}  {elapsed:.1f}s", flush=True)

    def row(self, **columns):
        """A progress.csv row: the step, the episodes so far and their recent mean (if there
        is a solved rule), `columns`."""
        episodes = (dict(episodes=len(self.episodes), recent_return=self.recent_return())
                    if self.window else {})
        append_csv(self.dir / "progress.csv", dict(global_step=self.global_step, **episodes,
                                                   **columns))

    def stopped_row(self, **columns):
        """progress.csv's last row, where training stopped inside a rollout: no update, so its
        update numbers are empty (not measured)."""
        self.row(**columns, **dict.fromkeys(self.stats))

    @contextlib.contextmanager
    def saving_model(self, nets, **info):
        """Around the training loop: Ctrl-C ends it (`interrupted`), a nan that stopped a
        distribution ends it with one line (stop_if_diverged); either way, as it ends,
        episodes.csv and model.pt (`nets`' weights, `info`) are written as training left them."""
        try:
            yield self
        except KeyboardInterrupt:
            self.interrupted = True
        except (ValueError, RuntimeError):  # e.g. Categorical refusing nan logits: diverged?
            stop_if_diverged(self.global_step, {}, nets.values(), self.dir)  # if so
            raise
        finally:
            if self.dir.exists():  # stop_if_diverged removes a diverged run's folder
                for step, ep_return in self.episodes:
                    append_csv(self.dir / "episodes.csv", episode_row(step, ep_return))
                checkpoints.save_model(self.dir / "model.pt", self.script, self.cfg,
                                       self.global_step, nets, **info)


# What an evaluation writes besides evaluations.csv's row (report.after_evaluation):
# checkpoint.pt keeps a copy, which --resume puts back in place of those of later evaluations.
EVALUATION_FILES = ("model.pt", "best.pt", "best.gif", "curve.png", "inside.png")


class EvaluationLog:
    """The run folder of a script that evaluates every so many env steps: episodes.csv as
    episodes end, evaluations.csv (a row per evaluation: its mean and std, the training
    return before it, then the script's own columns, declared once in `logged` as for
    UpdateLog), progress lines with steps/s of learning (from step `learning_starts` on) and
    the time left. With cfg.resume, the folder of that run; its state_dict() goes into
    checkpoint.pt (every row as written, a copy of the files its evaluations wrote),
    load_state_dict() rewinds the logs and those files to it.
    `shipped`: a trained model of the script to point to while this one trains, if any."""

    def __init__(self, script, cfg, device, logged, learning_starts, eval_every, shipped=None,
                 step_size=1):
        self.script, self.cfg, self.logged = script, cfg, logged
        self.learning_starts = learning_starts
        labels, self.tags = labels_and_tags(logged)
        self.labels = {"eval_mean": "evaluation: mean return, deterministic actions",
                       "train_return_mean10": f"training: mean of the last {RECENT} episodes",
                       **labels}
        self.episodes, self.evaluations = [], []  # (step, return); evaluations.csv's rows
        now = time.time()
        self.timer = dict(start=now, step=0, time=now, rate=float("nan"))
        if cfg.resume:
            self.dir = Path(cfg.resume)
            return
        self.dir = make_run_dir(cfg.run_dir, script, cfg.env_id, cfg.seed)
        print(f"run folder: {self.dir}  (device: {device})", flush=True)
        first = max(eval_every * (learning_starts // eval_every + 1), eval_every)
        warm_up = (f"once in the warm-up (step {eval_every}), then "
                   if eval_every <= learning_starts else "")
        if step_size > 1:  # the steps come step_size at a time (a rollout), then an update
            first = -(-first // step_size) * step_size
            print(f"curve.png there is redrawn at every evaluation: after the update that "
                  f"reaches each multiple of {eval_every} steps (the first at step {first})",
                  flush=True)
        else:
            print(f"curve.png there is redrawn at every evaluation: {warm_up}from step {first} "
                  f"on, every {eval_every} steps", flush=True)
        if shipped is not None and Path(shipped).exists():
            print(f"meanwhile, a trained one: python {script}.py --eval {shipped} --gif "
                  f"{script}.gif (or --watch)", flush=True)

    def episode_ended(self, step, episode_return):
        self.episodes.append((step, float(episode_return)))
        append_csv(self.dir / "episodes.csv", episode_row(*self.episodes[-1]))

    def progress(self, step, losses, nets):
        """Every print_every steps a progress line with the script's `losses` (name -> number,
        None before learning starts). Before it, a check that they are finite (at every step,
        so that no nan reaches the next action) and the networks among `nets` (at each line):
        nan or inf stops the run in one line; a run without a checkpoint is removed."""
        if step > self.learning_starts:  # steps/s of learning: from this process's first update
            self.timer.setdefault("learning_since", (step, time.time()))
        line = step % self.cfg.print_every == 0
        if losses is not None:
            modules = [net for net in nets if isinstance(net, torch.nn.Module)] if line else ()
            stop_if_diverged(step, losses, modules, self.dir)
        if not line:
            return
        now, cfg, timer = time.time(), self.cfg, self.timer
        # steps/s of learning since the last line (or since learning began, if it was later)
        since_step, since = max((timer["step"], timer["time"]),
                                timer.get("learning_since", (step, 0)))
        if step > self.learning_starts and step > since_step:
            timer["rate"] = (step - since_step) / (now - since)
            left = (cfg.total_timesteps - step) / timer["rate"]
            speed = f"{timer['rate']:5.0f} steps/s  {hours_minutes(left)} to go"
        else:
            speed = "learning starts" if step > self.learning_starts else "warm-up (random actions)"
        recent = (f"{np.mean([r for _, r in self.episodes[-RECENT:]]):8.1f}" if self.episodes
                  else "     n/a")
        loss_text = "".join(f"  {name} {float(value):8.3f}" for name, value in
                            (losses or {}).items())
        print(f"step {step:>8}  {speed}  return({RECENT}) {recent}{loss_text}  "
              f"{clock(now - timer['start'])}", flush=True)
        self.clock_from(step)

    def clock_from(self, step):
        """The next progress line's steps/s counts from here (not an evaluation or a write)."""
        self.timer.update(step=step, time=time.time())

    def evaluation(self, step, returns, **columns):
        """An evaluation's row in evaluations.csv: the mean and std of its `returns`, the
        training return before it, then the script's `columns` (as declared). Returns whether
        it is the best so far."""
        mean, std = float(np.mean(returns)), float(np.std(returns))
        best = mean > max((e["eval_mean"] for e in self.evaluations), default=-float("inf"))
        declared(self.logged, columns, "evaluations.csv")
        columns = {k: v.item() if isinstance(v, (np.generic, torch.Tensor)) else v  # plain
                   for k, v in columns.items()}  # numbers: checkpoint.pt loads weights_only
        done = [ret for s, ret in self.episodes if s <= step]
        self.evaluations.append(dict(
            global_step=step, eval_mean=mean, eval_std=std, episodes=len(done),
            train_return_mean10=float(np.mean(done[-RECENT:])) if done else float("nan"),
            **columns))
        append_csv(self.dir / "evaluations.csv", self.evaluations[-1])
        print(f"evaluation at step {step}: {mean:.1f} +- {std:.1f} over {len(returns)} "
              f"episodes", flush=True)
        return best

    def state_dict(self):
        """The rows, the run's clock, and a copy of what the evaluations wrote besides the rows
        (EVALUATION_FILES, as they are now: bytes)."""
        files = {name: torch.from_numpy(np.frombuffer((self.dir / name).read_bytes(),
                                                      np.uint8).copy())
                 for name in EVALUATION_FILES if (self.dir / name).exists()}
        return dict(episodes=self.episodes, evaluations=self.evaluations,
                    elapsed=time.time() - self.timer["start"], files=files)

    def load_state_dict(self, state):
        """The logs as they were at the checkpoint: rows a killed run wrote after it go (the
        resumed run writes them again, identically), and so do the files of its evaluations
        past the checkpoint (put back as they were); the run's clock goes on from there."""
        self.episodes[:], self.evaluations[:] = state["episodes"], state["evaluations"]
        ours = {"global_step", "eval_mean", "eval_std", "episodes", "train_return_mean10",
                *self.logged}  # evaluation()'s columns
        theirs = set(self.evaluations[0]) if self.evaluations else ours
        if theirs != ours:  # a column added to the script (or taken out) since the run began
            raise UserError(f"{self.dir}'s evaluations.csv has the columns {sorted(theirs)}; "
                            f"this {self.script}.py logs {sorted(ours)}: resume it with the "
                            "version that began it, or begin a new run")
        self.timer["start"] -= state["elapsed"]
        for stale in self.dir.glob("*.tmp*"):  # a write that a kill cut short
            stale.unlink()
        path = self.dir / "evaluations.csv"
        on_disk = len(path.read_text().splitlines()[1:]) if path.exists() else 0
        for name, rows in (("episodes.csv", [episode_row(*e) for e in self.episodes]),
                           ("evaluations.csv", self.evaluations)):
            (self.dir / name).unlink(missing_ok=True)
            for row in rows:
                append_csv(self.dir / name, row)
        if "files" in state:
            self.put_back(state["files"])
        else:  # a checkpoint of an older version, without copies
            self.forget_the_future(cut=on_disk > len(self.evaluations))
        if self.cfg.tensorboard:  # its scalars, from the rows as they are now
            plots.to_tensorboard(self.dir, tags=self.tags)

    def put_back(self, files):
        """EVALUATION_FILES as they were at the checkpoint (`files`: their bytes); one that
        `files` lacks was first written past the checkpoint, and goes."""
        for name in EVALUATION_FILES:
            if name in files:
                with written_whole(self.dir / name) as tmp:
                    tmp.write_bytes(files[name].numpy().tobytes())
            else:
                (self.dir / name).unlink(missing_ok=True)

    def forget_the_future(self, cut):
        """Without copies: the pictures go if rows past the checkpoint were `cut`, and best.pt
        and best.gif if best.pt is of an evaluation past it (the next evaluations write them
        again); model.pt stays (the newest actor)."""
        gone = ["curve.png", "inside.png"] if cut else []
        best = self.dir / "best.pt"
        steps = {row["global_step"] for row in self.evaluations}
        if best.exists() and torch.load(best, weights_only=True)["global_step"] not in steps:
            gone += ["best.pt", "best.gif"]
        gone = [name for name in gone if (self.dir / name).exists()]
        for name in gone:
            (self.dir / name).unlink()
        if gone:
            print(f"{', '.join(gone)}: of evaluations past the checkpoint, removed (a checkpoint "
                  "of an older version keeps no copy of them)", flush=True)


def episode_row(step, ep_return):
    """An episodes.csv row, as every script writes it."""
    return {"global_step": step, "return": ep_return}
