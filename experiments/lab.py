"""What the experiments share: run a script's train() over seeds, once per variant, and show
the difference as a table (median and spread over seeds) and a figure. A variant is a dict of
Config overrides and of code replaced for its runs only (`swap`: (object, attribute, new)),
so the learning path of the scripts has no `if bug:` branch and no flag for it; a variant may
also name another script (`script`), to set two algorithms side by side.

Each (variant, seed) run is independent: with --workers N (default: one per core) N of them
run at once, each in its own process with one torch thread, and give the very numbers that
one after another in this process gives (every run seeds all it draws from). Past one
machine, --cluster FOLDER hands each run to submitit (pip install submitit): a Slurm job
where Slurm is (--partition NAME), a local process otherwise; the same numbers again.
Ctrl-C stops it in one line: the runs that ended are kept, the same command goes on. SIGTERM
(`kill PID`, a Slurm time limit) does the same, with exit code 143.
"""

import contextlib
import csv
import difflib
import multiprocessing
import os
import re
import signal
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))  # the scripts, when run as `python experiments/<name>.py`

import common  # noqa: E402
import plots  # noqa: E402

DOCS = ROOT / "docs" / "experiments"  # the committed figures and CSVs (--docs refreshes them)
# Where a learner's own run writes them: in the folder the command runs in, as the scripts'
# runs/ is.
OUT = Path("runs") / "experiments"
# The README's DDPG-in-minutes settings (InvertedPendulum-v5, 20,000 steps), evaluated every
# 2500 steps over 5 episodes: the DDPG experiments' task.
DDPG_IN_MINUTES = dict(env_id="InvertedPendulum-v5", start_steps=1000, eval_every=2500,
                       eval_episodes=5, hidden=128, batch_size=128, actor_lr=1e-3,
                       critic_lr=1e-3, tau=0.01)


@contextlib.contextmanager
def swapped(swaps):
    """Within the block, each (owner, name, new) has owner.name = new; put back after."""
    saved = [(owner, name, getattr(owner, name)) for owner, name, _ in swaps]
    try:
        for owner, name, new in swaps:
            setattr(owner, name, new)
        yield
    finally:
        for owner, name, old in saved:
            setattr(owner, name, old)


def run(script, variants, seeds, budget, columns=(), workers=1, cluster=None, record=None,
        **settings):
    """{variant: [(steps, values, kept), one per seed]}: the train() of `script` (or of the
    variant's own "script") for each variant and seed, `budget` env steps, no solved stop, no
    GIFs. The values: the CartPole scripts' mean return of the last 20 episodes after each
    update; DDPG's evaluation returns. kept: {column: (steps, values)} for each of `columns`
    in the run's log (progress.csv, or DDPG's evaluations.csv). workers > 1: that many runs at
    once, each in a process of its own (forked, so a swap made here is there too). cluster:
    {"folder": ..., "partition": ...} for submitit, one job per run (see on_cluster). record:
    a folder where each run's log is kept the moment the run ends, and read back instead of
    running again: an experiment stopped halfway (a time limit, Ctrl-C) goes on where it was."""
    kept = {(name, seed): recorded(record, (name, seed), columns)
            for name in variants for seed in seeds}
    results = {job: curve for job, curve in kept.items() if curve is not None}
    for (name, seed), curve in results.items():
        print(f"{name:40} seed {seed}: final {curve[1][-1]:6.1f}  (recorded)", flush=True)
    jobs = [(name, seed) for name in variants for seed in seeds if (name, seed) not in results]
    if jobs and cluster is None:
        print(f"{len(jobs)} runs to go, {min(workers, len(jobs))} at a time"
              + (f"; each run's log is kept in {record} as it ends" if record else ""), flush=True)
    # Ctrl-C: the runs under way are dropped (their temporary folder goes); those kept stay.
    with tempfile.TemporaryDirectory(prefix="experiment_") as tmp, contextlib.ExitStack() as stack:
        task = (script, variants, budget, columns, settings, tmp)
        if cluster is not None:
            done = on_cluster(task, jobs, **cluster)
        elif workers == 1 or len(jobs) <= 1:
            done = (one_run(task, job) for job in jobs)
        else:  # a fresh process per run (maxtasksperchild=1): nothing carries from one to the next
            global _TASK
            _TASK = task
            pool = stack.enter_context(pool_deaf_to_ctrl_c(min(workers, len(jobs))))
            done = pool.imap_unordered(_one_run_of_task, jobs)
        for job, curve, seconds, log in done:
            if record is not None:  # kept at once: a later call reads it instead of running again
                keep(record, job, log)
            results[job] = curve
            print(f"{job[0]:40} seed {job[1]}: final {curve[1][-1]:6.1f}  ({seconds:.0f} s)",
                  flush=True)
    return {name: [results[(name, seed)] for seed in seeds] for name in variants}


def pool_deaf_to_ctrl_c(processes):
    """A pool of `processes` worker processes, one fresh process per run, on which Ctrl-C has
    no hold: a terminal sends it to them too, and this process alone answers it (leaving the
    pool's `with` block ends them). They are forked with SIGINT blocked, by this thread and
    by the pool's own threads, which are started while it is: each inherits the block.
    SIGTERM, which this process turns into a Ctrl-C, ends a worker at once, as by default
    (the pool's `with` block ends its workers so): blocked at the fork as well, each worker
    puts it back to its default, then unblocks it."""
    blocked = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM})
    try:
        return multiprocessing.get_context("fork").Pool(processes, _sigterm_ends_it,
                                                        maxtasksperchild=1)
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, blocked)  # a signal held meanwhile: now


def _sigterm_ends_it():
    """A worker's first step: SIGTERM ends it, as in any process (the pool's way to end it)."""
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGTERM})


def one_run(task, job):
    """One (variant, seed) run of `task`: (job, (steps, values, kept), seconds, its log). A run
    that Ctrl-C cut short is no result: KeyboardInterrupt, as the scripts' train() ends it."""
    script, variants, budget, columns, settings, tmp = task
    name, seed = job
    variant = variants[name]
    module = variant.get("script", script)
    quiet = dict(seed=seed, total_timesteps=budget, gifs=False, curves=False,
                 print_every=10**9, run_dir=str(Path(tmp) / f"{name}{seed}"))
    if hasattr(module.Config, "stop_when_solved"):  # the CartPole scripts
        quiet.update(stop_when_solved=False, eval_episodes=1)
    cfg = module.Config(**{**quiet, **settings, **variant.get("config", {})})
    started = time.time()
    with swapped(variant.get("swap", [])), contextlib.redirect_stdout(None):
        result = module.train(cfg)
    if result.get("interrupted"):
        raise KeyboardInterrupt
    steps, values, _ = plots.curve_of(result["run_dir"])
    log = next(p for p in (Path(result["run_dir"]) / n for n in LOGS) if p.exists())
    return (job, (steps, values, kept_columns(result["run_dir"], columns)),
            time.time() - started, str(log))


LOGS = ("evaluations.csv", "progress.csv")  # DDPG's and TD3's log; the CartPole scripts'


def record_dir(record, job):
    """Where run `job` = (variant, seed) keeps its log in `record`."""
    name, seed = job
    return Path(record) / f"{re.sub(r'[^A-Za-z0-9]+', '_', name).strip('_')}__seed{seed}"


def keep(record, job, log):
    """A copy of run `job`'s `log` in `record`, written whole (Ctrl-C waits for it)."""
    folder = record_dir(record, job)
    folder.mkdir(parents=True, exist_ok=True)
    with common.written_whole(folder / Path(log).name) as tmp:
        tmp.write_bytes(Path(log).read_bytes())


def kept_runs(record, variants, seeds):
    """How many of the (variant, seed) runs have their log in `record`."""
    return sum(any((record_dir(record, (name, seed)) / n).exists() for n in LOGS)
               for name in variants for seed in seeds)


def recorded(record, job, columns):
    """The (steps, values, kept) of a run kept in `record`, or None if it is not there."""
    folder = None if record is None else record_dir(record, job)
    if folder is None or not any((folder / n).exists() for n in LOGS):
        return None
    steps, values, _ = plots.curve_of(folder)
    return steps, values, kept_columns(folder, columns)


_TASK = None  # run()'s task, for the forked workers
JOB_MINUTES = 24 * 60  # each job's time limit on the cluster (a run takes minutes)


def on_cluster(task, jobs, folder, partition=None):
    """Each (variant, seed) run as a submitit job: on Slurm where `srun` is found (a job array,
    `partition` if given), else a local process. submitit pickles `one_run` (as a Job, which a
    preempted or timed-out job queues again) with the task (the swapped functions by value,
    the scripts by name), so the jobs import the scripts: their folders go on PYTHONPATH, and
    on Slurm `folder` must be on a filesystem the nodes share. Yields what one_run returns,
    as the jobs finish."""
    try:
        import submitit
    except ImportError:
        sys.exit("error: --cluster needs submitit: pip install submitit")
    paths = [str(ROOT), str(ROOT / "experiments"), os.environ.get("PYTHONPATH", "")]
    os.environ["PYTHONPATH"] = os.pathsep.join(p for p in paths if p)
    run_dir = Path(folder).resolve() / "runs"  # the runs' own folders: where the jobs write
    task = (*task[:5], str(run_dir))
    executor = submitit.AutoExecutor(folder=Path(folder) / "%j")
    executor.update_parameters(timeout_min=JOB_MINUTES, cpus_per_task=1, name="experiment",
                               **({"slurm_partition": partition} if partition else {}))
    submitted = executor.map_array(Job(), [task] * len(jobs), jobs)
    print(f"{len(submitted)} jobs on {executor.cluster} (logs: {folder})", flush=True)
    for job in submitit.helpers.as_completed(submitted):
        yield job.result()


class Job:
    """one_run as a submitit job. A job preempted or stopped at its time limit is asked for
    its `checkpoint` (submitit's name for it), which queues the same run again: it starts
    over, as a run keeps nothing halfway, and the runs that ended are kept by then."""

    def __call__(self, task, job):
        return one_run(task, job)

    def checkpoint(self, task, job):
        import submitit

        return submitit.helpers.DelayedSubmission(self, task, job)


def _one_run_of_task(job):
    return one_run(_TASK, job)


def kept_columns(run_dir, columns):
    """{column: (steps, values)} of a run's log, for each of `columns` it has."""
    log = Path(run_dir) / "evaluations.csv"
    table = plots.read_csv(log if log.exists() else Path(run_dir) / "progress.csv")
    return {c: (table["global_step"], table[c]) for c in columns if c in table}


def first_step_at(steps, values, level):
    """The first step where `values` reach `level`, or None."""
    hit = np.flatnonzero(np.nan_to_num(values, nan=-np.inf) >= level)
    return int(steps[hit[0]]) if len(hit) else None


def report(name, curves, folder, solved=475.0, what="mean return of the last 20 episodes",
           panels=()):
    """Print and save (<folder>/<name>.csv) per variant: the final value (`what`) and the first
    step it reached `solved`, each as median [min, max] over seeds; draw <folder>/<name>.png:
    the median curve and the band of the seeds. panels: (column, label, log) of kept columns:
    each seed's median, min and max of it go into the CSV; printed, the median [min, max] of
    the seeds' medians and the extremes of any seed; drawn below, the same way as the curve."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    rows = []
    print(f"\n{'variant':40} {'final':>26} {'steps to ' + str(int(solved)):>28}")
    for variant, runs in curves.items():
        finals = [float(v[-1]) for _, v, _ in runs]
        hits = [first_step_at(s, v, solved) for s, v, _ in runs]
        reached = sorted(h for h in hits if h is not None)
        spread = "never" if not reached else steps_median_and_range(hits)
        print(f"{variant:40} {statistics.median(finals):9.1f} [{min(finals):5.1f}, "
              f"{max(finals):5.1f}]   {spread} ({len(reached)}/{len(hits)} seeds)")
        for seed_index, (final, hit, (_, _, kept)) in enumerate(zip(finals, hits, runs)):
            row = dict(variant=variant, seed_index=seed_index, final=final,
                       steps_to_solved=hit if hit is not None else "")
            for column, _, _ in panels:  # this seed's median, min and max of the column
                values = kept[column][1][np.isfinite(kept[column][1])]
                row.update({f"{column}_median": float(np.median(values)),
                            f"{column}_min": float(values.min()),
                            f"{column}_max": float(values.max())})
            rows.append(row)
    for column, label, _ in panels:  # the numbers the CSV holds, summarized over the seeds
        print(f"\n{label}: each seed's median over the run, their median [min, max]; "
              "the smallest and largest value of any seed")
        for variant in curves:
            seeds = [row for row in rows if row["variant"] == variant]
            medians = [row[f"{column}_median"] for row in seeds]
            print(f"{variant:40} {np.median(medians):10.4g} [{min(medians):.4g}, "
                  f"{max(medians):.4g}]; {min(r[f'{column}_min'] for r in seeds):.4g} to "
                  f"{max(r[f'{column}_max'] for r in seeds):.4g}")
    with common.written_whole(folder / f"{name}.csv") as tmp, open(tmp, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    plt = plots.pyplot()
    fig, axes = plt.subplots(1 + len(panels), 1, figsize=(7, 4 + 2.6 * len(panels)),
                             sharex=True, squeeze=False)
    ax = axes[0, 0]
    for color, (variant, runs) in enumerate(curves.items()):
        band(ax, [(s, v) for s, v, _ in runs], color,
             f"{variant} (median of {len(runs)} seeds; band: min to max)")
    ax.axhline(solved, color="gray", ls="--", lw=1)
    ax.set_ylabel(what)
    ax.set_title(name, fontsize=9)
    ax.legend(fontsize=7, loc="lower right")
    for (column, label, log), (ax,) in zip(panels, axes[1:]):
        for color, (variant, runs) in enumerate(curves.items()):
            band(ax, [measured(*kept[column]) for _, _, kept in runs], color)
        ax.set_ylabel(label, fontsize=8)
        if log:
            ax.set_yscale("log")
    axes[-1, 0].set_xlabel("env steps")
    fig.tight_layout()
    return plots.save_whole(plt, fig, folder / f"{name}.png", dpi=80)


def measured(steps, values):
    """The steps where a column was measured (a column logged at some rows only is nan at the
    others)."""
    ok = np.isfinite(values)
    return steps[ok], values[ok]


def steps_median_and_range(hits):
    """"median [min, max]" of the steps at which the seeds reached the level; a seed that never
    did counts as later than all (so the median is over every seed): "never" where it lands.

    >>> steps_median_and_range([53760, 24576, None, 21504, 21504])
    '24576 [21504, never]'
    """
    ordered = sorted(hits, key=lambda h: (h is None, h or 0))
    show = ["never" if h is None else str(h) for h in ordered]
    middle = show[len(show) // 2] if len(show) % 2 else (
        "never" if None in ordered[len(show) // 2 - 1:len(show) // 2 + 1]
        else f"{statistics.median(ordered[len(show) // 2 - 1:len(show) // 2 + 1]):.0f}")
    return f"{middle} [{show[0]}, {show[-1]}]"


def band(ax, runs, color, label=None):
    """On `ax`: the median over seeds of runs [(steps, values)] (a line) and their min to max
    (a band), on a grid of 200 steps where every run has a value."""
    grid = np.linspace(max(s[0] for s, _ in runs), min(s[-1] for s, _ in runs), 200)
    values = np.array([np.interp(grid, s, np.nan_to_num(v)) for s, v in runs])
    ax.fill_between(grid, values.min(0), values.max(0), color=f"C{color}", alpha=0.15)
    ax.plot(grid, np.median(values, 0), color=f"C{color}", lw=2, label=label)


FLAGS = ("--quick", "--docs")  # the options without a value
VALUED = {"--workers": "N", "--cluster": "FOLDER", "--partition": "NAME"}  # and with one
OPTIONS = ("the options are --quick, --docs, --workers N (N >= 1) and --cluster FOLDER "
           "[--partition NAME] (see --help)")


def options(args):
    """The command line (without --help): dict(quick, docs, workers (None: one per core),
    cluster (None, or {"folder": ..., "partition": ...})). A mistake: one line, exit 2."""
    given, args = {}, list(args)
    while args:
        flag, equals, value = args.pop(0).partition("=")
        if flag not in FLAGS and flag not in VALUED:
            close = difflib.get_close_matches(flag, [*FLAGS, *VALUED], n=1)
            wrong(f"unknown argument {flag}{f' (did you mean {close[0]}?)' if close else ''}; "
                  f"{OPTIONS}")
        if flag in given:
            wrong(f"{flag} given twice")
        if flag in FLAGS and equals:
            wrong(f"{flag} takes no value")
        if flag in VALUED and not equals:
            if not args or args[0].startswith("--"):
                wrong(f"{flag} needs a value: {flag} {VALUED[flag]}")
            value = args.pop(0)
        given[flag] = value if flag in VALUED else True
    workers = given.get("--workers")
    if workers is not None and not (re.fullmatch("[0-9]+", workers) and int(workers) >= 1):
        wrong(f"--workers {workers}: N, the runs at once, must be a whole number, 1 or more")
    if "--partition" in given and "--cluster" not in given:
        wrong("--partition NAME goes with --cluster FOLDER")
    cluster = None if "--cluster" not in given else {
        "folder": given["--cluster"],
        **({"partition": given["--partition"]} if "--partition" in given else {})}
    return dict(quick="--quick" in given, docs="--docs" in given,
                workers=None if workers is None else int(workers), cluster=cluster)


def wrong(message):
    """A mistake on the command line: one line, exit 2."""
    print(f"error: {message}", file=sys.stderr)
    raise SystemExit(2)


def main(name, script, variants, seeds=(0, 1, 2, 3, 4), budget=50_000, solved=475.0,
         what="mean return of the last 20 episodes", quick_budget=2048, panels=(),
         quick_settings=None, more=None, **settings):
    """python experiments/<name>.py [--quick] [--docs] [--workers N] [--cluster FOLDER
    [--partition NAME]]: every variant over `seeds` at `budget` steps, then the table and the
    figure in runs/experiments/ of the folder it runs in (--docs: the repository's
    docs/experiments/, the committed ones). --quick: one seed, `quick_budget` steps (2048 for
    CartPole, 2500 for DDPG), the figure drawn in a temporary folder and removed (a smoke
    test; the tests run it). more(curves, folder, settings): what else the experiment writes
    there (returns their paths); settings: those of its runs, --quick's included.
    Ctrl-C: exit 130 and one line, the runs that ended kept (a rerun goes on from them);
    SIGTERM the same, exit 143."""
    cores = os.cpu_count() or 1
    if {"-h", "--help"} & set(sys.argv[1:]):
        print(sys.modules["__main__"].__doc__.strip())  # the experiment's question and what to see
        print(f"\nWrites runs/experiments/{name}.png and {name}.csv in the current folder; "
              f"--docs writes the repository's docs/experiments/{name}.png and .csv instead "
              "(the committed ones: the same numbers on the same machine); --quick writes "
              "nothing (one seed, a few steps: it checks that the experiment runs). --workers N: "
              f"N runs at once, one process and one torch thread each (default: one per core, "
              f"here {cores}); the numbers do not depend on it. --cluster FOLDER: each run a "
              "submitit job instead (Slurm where there is one, --partition NAME; else a local "
              "process), its logs in FOLDER (pip install submitit). Ctrl-C (or kill PID: exit "
              "143): the runs that ended are kept; the same command again goes on from there.")
        raise SystemExit(0)
    given = options(sys.argv[1:])
    workers = given["workers"] or cores
    started = time.time()
    if given["quick"]:  # quick_settings: overrides of `settings` that a quick budget needs
        seeds, budget, settings = seeds[:1], quick_budget, {**settings, **(quick_settings or {})}
    with contextlib.ExitStack() as stack:
        stack.enter_context(common.sigterm_as_ctrl_c())
        folder = (Path(stack.enter_context(tempfile.TemporaryDirectory(prefix="experiment_")))
                  if given["quick"] else DOCS if given["docs"] else OUT)
        record = None if given["quick"] else folder / f"{name}_runs"  # each run's log, as it ends
        try:
            curves = run(script, variants, seeds, budget, [c for c, _, _ in panels], workers,
                         given["cluster"], record, **settings)
            paths = [report(name, curves, folder, solved, what, panels),
                     *(more(curves, folder, settings) if more is not None else [])]
        except KeyboardInterrupt:
            how, code = common.stopped_by()
            print(f"\ninterrupted ({how}): {stopped(record, variants, seeds)}", file=sys.stderr)
            raise SystemExit(code) from None
        shown = ("not kept (--quick)" if given["quick"] else str(paths[0]) if len(paths) == 1
                 else f"{paths[0]} (and {', '.join(map(str, paths[1:]))})")
    print(f"\n{len(variants)} variants x {len(seeds)} seeds x {budget} steps in "
          f"{time.time() - started:.0f} s with {workers} worker(s); figure: {shown}")
    return curves


def stopped(record, variants, seeds):
    """What an experiment stopped by Ctrl-C (or SIGTERM) leaves, and how to go on: one line."""
    if record is None:
        return "--quick keeps nothing; run it again to start over"
    kept, runs = kept_runs(record, variants, seeds), len(variants) * len(seeds)
    if kept == runs:
        return (f"all {runs} runs kept in {record}; the same command again draws the table "
                "and the figure from them")
    return f"{kept} of {runs} runs kept in {record}; the same command again goes on from there"
