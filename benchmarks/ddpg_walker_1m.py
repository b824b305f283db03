"""The headline DDPG and TD3 measurement: ddpg_walker.py (or td3_walker.py, --script) at its
defaults (Walker2d-v5, 1M steps) on seeds 0 to 4, one torch thread each. A run takes hours,
so this starts the runs in the background, continues any that stopped (--resume: the same
run, exactly), and copies each run's evaluations.csv into
benchmarks/results/<script>_1m/seed<k>/ as it grows.

    python benchmarks/ddpg_walker_1m.py start ~/ddpg-1m    # start or continue what is unfinished
    python benchmarks/ddpg_walker_1m.py status ~/ddpg-1m   # where each run is; copy the CSVs
    python benchmarks/ddpg_walker_1m.py table              # docs/results.md's table, from the copies
    python benchmarks/ddpg_walker_1m.py plot               # docs/ddpg_walker_1m.png, from the copies
    python benchmarks/ddpg_walker_1m.py start ~/td3-1m --script td3_walker --seeds 0 1
    python benchmarks/ddpg_walker_1m.py plot --script td3_walker   # TD3's runs beside DDPG's
    python benchmarks/ddpg_walker_1m.py at 300000          # DDPG, TD3 and SAC at equal steps
    python benchmarks/ddpg_walker_1m.py plot --script sac_walker   # the three, to SAC's last step
    python benchmarks/ddpg_walker_1m.py plot --lang zh     # the Chinese twin, *_1m.zh-CN.png
    python benchmarks/ddpg_walker_1m.py start ~/ppo-1m --script ppo_reacher   # PPO, 3 seeds
    python benchmarks/ddpg_walker_1m.py plot --script ppo_reacher  # PPO beside the three
    python benchmarks/ddpg_walker_1m.py at 500000 --script ppo_reacher   # the four at 500k

The measure (as in the TD3 paper's ablation table): per seed, the mean of the last 10
evaluations (each the mean return of 10 episodes without exploration noise); over the seeds,
their mean and its standard error (the spread between seeds, / sqrt(number of seeds)).
"""

import argparse
import csv
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import torch

sys.path.insert(0, str(Path(__file__).resolve().parent))
import settings  # noqa: E402  each record's flags, written out

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
import help_zh  # noqa: E402  --lang, read as the scripts read it

SCRIPT = "ddpg_walker"  # or td3_walker (--script)
SEEDS, BUDGET = (0, 1, 2, 3, 4), 1_000_000
ALL = SEEDS
# Each record's settings written out, not left to the scripts' defaults (benchmarks/settings.py):
# the off-policy three as the TD3 paper runs Walker2d (256-256 networks, batch 256, Adam 3e-4,
# tau 0.005, a 25,000-step random warm-up, a buffer of every step); PPO with CleanRL's settings
# for MuJoCo (--update minibatch, rollouts of 2000 steps (CleanRL: 2048), lambda 0.95, both
# step sizes 3e-4 annealed, gradient norms clipped at 0.5, rewards scaled by the return's std,
# no early stop), its records in benchmarks/results/ppo_walker_1m/
WALKER = dict(env_id="Walker2d-v5", total_timesteps=1_000_000, eval_every=5000, gamma=0.99,
              hidden=256, batch_size=256, actor_lr=3e-4, critic_lr=3e-4, tau=0.005,
              start_steps=25_000, buffer_size=1_000_000)
FLAGS = {"ddpg_walker": settings.flags(**WALKER, expl_noise=0.1),
         "td3_walker": settings.flags(**WALKER, expl_noise=0.1, policy_delay=2, target_noise=0.2,
                                      noise_clip=0.5),
         "sac_walker": settings.flags(**WALKER, alpha=None, alpha_lr=3e-4, target_entropy=None),
         "ppo_reacher": settings.flags(
             env_id="Walker2d-v5", total_timesteps=1_000_000, eval_every=5000, num_envs=1,
             num_steps=2000, gamma=0.99, lam=0.95, update="minibatch", update_epochs=10,
             num_minibatches=32, clip_ratio=0.2, pi_lr=3e-4, vf_lr=3e-4, target_kl=None,
             kl_stop_factor=1.5, train_pi_iters=80, train_v_iters=80, max_grad_norm=0.5,
             anneal_lr=True, hidden=64, log_std_init=-0.5, norm_obs=True, norm_reward=True)
         + ["--print-every", "10000", "--no-gifs"]}
SEEDS_OF = {"ppo_reacher": (0, 1, 2), "sac_walker": (0, 1, 2)}
RECORDS = {"ppo_reacher": "ppo_walker_1m"}
MILESTONES = (100_000, 300_000, 500_000, 1_000_000)


def record(seed, script=None):
    """The committed copy of a run's evaluations.csv:
    benchmarks/results/<script>_1m/seed<k>/evaluations.csv (script: SCRIPT unless given)."""
    script = script or SCRIPT
    return (ROOT / "benchmarks" / "results" / RECORDS.get(script, f"{script}_1m") / f"seed{seed}"
            / "evaluations.csv")


def run_of(parent, seed):
    """The run folder of `seed` under `parent` (the newest, if several), or None."""
    runs = sorted(Path(parent).glob(f"{SCRIPT}__Walker2d-v5__seed{seed}__*"))
    return runs[-1] if runs else None


def running(parent, seed):
    pid_file = Path(parent) / f"seed{seed}.pid"
    if not pid_file.exists():
        return False
    try:
        os.kill(int(pid_file.read_text()), 0)  # signal 0: is the process alive?
        return True
    except (ProcessLookupError, ValueError):
        return False


def saved_step(run):
    ckpt = run / "checkpoint.pt" if run else None
    return torch.load(ckpt, weights_only=True, mmap=True)["global_step"] if ckpt and ckpt.exists() else 0


def start(parent, seeds=SEEDS):
    parent.mkdir(parents=True, exist_ok=True)
    for seed in seeds:
        run = run_of(parent, seed)
        if running(parent, seed):
            print(f"seed {seed}: running ({run})")
            continue
        step = saved_step(run)
        if step >= BUDGET:
            print(f"seed {seed}: finished ({run})")
            continue
        committed = record(seed)
        if run is None and committed.exists() and read(committed)[-1][0] >= BUDGET:
            # e.g. on a new machine: the record is already complete; rerunning would only repeat it
            print(f"seed {seed}: finished (its record {committed.relative_to(ROOT)} reaches 1M)")
            continue
        how = (["--resume", str(run)] if step else
               ["--seed", str(seed), "--run-dir", str(parent), *FLAGS[SCRIPT]])
        log = open(parent / f"seed{seed}.log", "a")
        # nice: other work on the machine comes first; the runs use what is left.
        proc = subprocess.Popen(["nice", "-n", "19", sys.executable, str(ROOT / f"{SCRIPT}.py"),
                                 *how], stdout=log, stderr=subprocess.STDOUT, cwd=ROOT,
                                start_new_session=True)
        try:  # Linux groups a new session's processes: nice must be set for the group too
            Path(f"/proc/{proc.pid}/autogroup").write_text("19")
        except OSError:
            pass
        (parent / f"seed{seed}.pid").write_text(str(proc.pid))
        print(f"seed {seed}: {'continuing from step ' + str(step) if step else 'started'} "
              f"(pid {proc.pid}, log {parent / f'seed{seed}.log'})")


def status(parent):
    for seed in SEEDS:
        run = run_of(parent, seed)
        out = record(seed).parent
        if run is None or not (run / "evaluations.csv").exists():
            rows = read(out / "evaluations.csv") if (out / "evaluations.csv").exists() else []
            print(f"seed {seed}: no evaluations here yet" + (
                f"; the committed record reaches step {rows[-1][0]}, last 10: {last10(rows):.0f}"
                if rows else ""))
            continue
        out.mkdir(parents=True, exist_ok=True)
        new, old = (run / "evaluations.csv").read_text(), ""
        if (out / "evaluations.csv").exists():
            old = (out / "evaluations.csv").read_text()
        note = ""
        if len(new) >= len(old):
            shutil.copy(run / "evaluations.csv", out / "evaluations.csv")
        else:  # a rerun (e.g. on a new machine) behind the copy: keep the longer record
            same = "the same rows so far" if old.startswith(new) else "OTHER rows: another machine?"
            at = read(run / "evaluations.csv")[-1][0]
            note = f"; kept the longer copy (this run is at step {at}, {same})"
        rows = read(out / "evaluations.csv")
        print(f"seed {seed}: evaluated up to step {rows[-1][0]}, checkpoint at {saved_step(run)}"
              f"{', running' if running(parent, seed) else ''}; last 10: {last10(rows):.0f}{note}")


def read(path):
    with open(path) as f:
        return [(int(r["global_step"]), float(r["eval_mean"])) for r in csv.DictReader(f)]


def last10(rows, upto=None):
    means = [m for step, m in rows if upto is None or step <= upto][-10:]
    return sum(means) / len(means) if means else float("nan")


def table():
    lines = ["| seed | " + " | ".join(f"{m // 1000}k" for m in MILESTONES) + " |",
             "|---|" + "---|" * len(MILESTONES)]
    finals, peaks = [], []
    for seed in SEEDS:
        path = record(seed)
        rows = read(path) if path.exists() else []
        reached = rows[-1][0] if rows else 0
        cells = [f"{last10(rows, m):.0f}" if reached >= m else "-" for m in MILESTONES]
        lines.append(f"| {seed} | " + " | ".join(cells) + " |")
        if reached >= BUDGET:
            finals.append(last10(rows, BUDGET))
            peaks.append(max(m for step, m in rows if step <= BUDGET))
    print("\n".join(lines))
    print("\nEach cell: the mean of the last 10 evaluations up to that step (- : not reached).")
    print(summary(finals))
    if len(peaks) >= 2:  # the TD3 paper's table 1 measure: each run's highest evaluation
        print(summary(peaks, "at 1M, by each one's highest evaluation"))


def summary(finals, what="at 1M"):
    """'Over the N seeds at 1M: mean M, standard error S' (or how many are there yet)."""
    if len(finals) < 2:
        return f"{len(finals)} of {len(SEEDS)} runs have reached 1M steps: no mean yet"
    mean, se = mean_and_se(finals)
    done = "" if len(finals) == len(SEEDS) else f" (of {len(SEEDS)}; the others have not reached 1M)"
    return f"Over the {len(finals)} seeds {what}{done}: mean {mean:.0f}, standard error {se:.0f}"


def mean_and_se(values):
    """The mean over seeds and its standard error (the spread between seeds / sqrt(n))."""
    mean = sum(values) / len(values)
    sd = (sum((x - mean) ** 2 for x in values) / (len(values) - 1)) ** 0.5  # between seeds
    return mean, sd / len(values) ** 0.5


NAMES = {"ddpg_walker": "DDPG", "td3_walker": "TD3", "sac_walker": "SAC",
         "ppo_reacher": "PPO (ppo_reacher.py, CleanRL's settings)"}


def at_equal_steps(at, scripts=("ddpg_walker", "td3_walker", "sac_walker")):
    """docs/results.md's SAC table: each script's committed records at `at` env steps, side by
    side. Per seed: the mean of the last 10 evaluations up to `at`, and the highest evaluation
    up to `at`; over the seeds that have reached `at`: their mean and its standard error."""
    k = f"{at // 1000}k"
    print(f"| algorithm | seeds | last 10 up to {k}, each seed | their mean (se) | "
          f"highest up to {k}, each seed | their mean (se) |")
    print("|---|---|---|---|---|---|")
    for script in scripts:
        seeds, lasts, highs = up_to(script, at)
        print(f"| {NAMES[script]} | {', '.join(map(str, seeds))} | "
              f"{', '.join(f'{x:.0f}' for x in lasts)} | {mean_se(lasts)} | "
              f"{', '.join(f'{x:.0f}' for x in highs)} | {mean_se(highs)} |")


def up_to(script, at):
    """`script`'s committed records up to `at` env steps: the seeds that reached it, and per
    seed the mean of the last 10 evaluations up to `at` and the highest evaluation up to it."""
    seeds, lasts, highs = [], [], []
    for seed in SEEDS_OF.get(script, ALL):
        path = record(seed, script)
        rows = read(path) if path.exists() else []
        if rows and rows[-1][0] >= at:
            seeds.append(seed)
            lasts.append(last10(rows, at))
            highs.append(max(m for step, m in rows if step <= at))
    return seeds, lasts, highs


def mean_se(values):
    """'mean (se)' for a table cell, '-' below 2 seeds."""
    return "-" if len(values) < 2 else "{:.0f} ({:.0f})".format(*mean_and_se(values))


def plot(suffix=".png"):
    """docs/<script>_1m<suffix> from the committed records, drawn as plots.py draws run folders:
    each seed a thin line, the mean where every seed has a value thick; TD3's beside DDPG's."""
    sys.path.insert(0, str(ROOT))
    import plots
    scripts = {"ddpg_walker": ["ddpg_walker"], "td3_walker": ["ddpg_walker", "td3_walker"],
               "sac_walker": ["ddpg_walker", "td3_walker", "sac_walker"],
               "ppo_reacher": list(NAMES)}[SCRIPT]
    # SAC's picture: the three at equal steps, to 300,000 (docs/results.md's SAC section)
    upto = 300_000 if SCRIPT == "sac_walker" else BUDGET
    with tempfile.TemporaryDirectory() as tmp:
        runs = []
        for script in scripts:
            for seed in SEEDS_OF.get(script, ALL):
                path = record(seed, script)
                if path.exists():  # in a folder named as run folders are: plots.py knows its script
                    run = Path(tmp) / f"{script}__Walker2d-v5__seed{seed}__record"
                    run.mkdir()
                    head, *rows = path.read_text().splitlines(keepends=True)
                    (run / "evaluations.csv").write_text(head + "".join(
                        row for row in rows if int(row.split(",")[0]) <= upto))
                    runs.append(run)
        print(f"wrote {plots.compare(runs, ROOT / 'docs' / f'{SCRIPT}_1m{suffix}')}")


def main():
    global SCRIPT, SEEDS
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("action", choices=("start", "status", "table", "plot", "at"))
    parser.add_argument("parent", nargs="?", help="folder of the five run folders (at: the step)")
    parser.add_argument("--script", default=SCRIPT, choices=tuple(NAMES))
    parser.add_argument("--seeds", type=int, nargs="+", default=None,
                        help="start: only these seeds (the others wait for a later start)")
    argv, _, zh = help_zh.wanted(sys.argv[1:])  # --lang zh (or a Chinese locale): plot's words
    args = parser.parse_args(argv)
    if zh and args.action == "plot":  # from locale/output.zh-CN.md, as the scripts' pictures
        help_zh.print_in_chinese()
    SCRIPT = args.script
    SEEDS = SEEDS_OF.get(SCRIPT, ALL)  # the script's seeds: status and table
    if args.action in ("start", "status", "at") and args.parent is None:
        parser.error(f"{args.action} needs the folder of the runs, e.g. ~/ddpg-1m"
                     if args.action != "at" else "at needs a step, e.g. at 300000")
    {"start": lambda: start(Path(args.parent), args.seeds or SEEDS),
     "status": lambda: status(Path(args.parent)), "table": table,
     "plot": lambda: plot(".zh-CN.png" if zh else ".png"),
     "at": lambda: at_equal_steps(int(args.parent), *(  # --script ppo_reacher: PPO too
         [list(NAMES)] if SCRIPT == "ppo_reacher" else []))}[args.action]()


if __name__ == "__main__":
    main()
