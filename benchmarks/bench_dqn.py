"""DQN on CartPole-v1 beside Stable-Baselines3's DQN with the rl-baselines3-zoo hyperparameters.

The criterion is the CartPole scripts' (benchmarks/bench_cartpole.py): solved at the first
step at which the mean return of the last 20 finished training episodes reaches 475; steps to
solve are env steps up to it, seconds to solve the wall time from the process's launch (imports
included) to its `solved:` line. Both then check the greedy policy as it is (10 episodes, env
seed 10001, at most once per learning phase) and stop only if it averages 475 too: the
`check ... it holds` line gives the steps and seconds to stop. dqn_cartpole.py runs at its
defaults (budget 100k steps), SB3 at the zoo's (lr 2.3e-3, batch 64, buffer 1e5,
learning_starts 1000, gamma 0.99, target_update_interval 10, train_freq 256, gradient_steps 128,
exploration_fraction 0.16, final eps 0.04, net_arch [256, 256], budget 5e4 steps); a run that
ends its budget unsolved counts as unsolved. One torch thread each, under `nice -n 10`, one run
at a time, seeds interleaved (ours seed k, SB3 seed k, ours seed k+1, ...), so that the
machine's drift hits both alike. Each run appends its row to the CSV as it ends; a run already
there is skipped, so the benchmark resumes where it stopped.

    pip install -r benchmarks/requirements.txt     # adds stable-baselines3
    python benchmarks/bench_dqn.py                 # seeds 0-4
    python benchmarks/bench_dqn.py --table         # the table of the CSV (docs/results.md's)
    python benchmarks/bench_dqn.py --held-out      # ours on seeds 5-9 (defaults chosen on 0-4)
"""

import argparse
import csv
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PY = sys.executable
OUT = ROOT / "benchmarks" / "results" / "dqn_sb3_cartpole.csv"
RUNNERS = {  # the command of one seed; ours skips the GIFs and pictures (after its solved line)
    "dqn_cartpole": lambda seed, out: [PY, str(ROOT / "dqn_cartpole.py"), "--seed", str(seed),
                                       "--run-dir", out, "--no-gifs", "--no-curves",
                                       "--threads", "1"],
    "sb3_dqn": lambda seed, out: [PY, str(ROOT / "benchmarks" / "sb3_cartpole.py"), "--algo", "dqn",
                                  "--seed", str(seed), "--threads", "1"],
}
FIELDS = ["seed", "runner", "solved_step", "solved_seconds", "checks", "stopped_step",
          "stopped_seconds", "greedy_eval_mean", "greedy_eval_min", "final_step", "total_seconds",
          "returncode", "load_avg_1min_at_start", "cpus", "commit"]
SOLVED = re.compile(r"^solved: .* at step (\d+)")
CHECK = re.compile(r"^check at step (\d+): .*averages")
HOLDS = "it holds"
FINAL = re.compile(r"^(?:trained (\d+) steps|end at step (\d+))")
GREEDY = re.compile(r"evaluation over \d+ episodes, greedy.*: mean ([\d.]+), min (\d+)"
                    r"|^greedy evaluation: mean ([\d.]+), min (\d+)")


def run_one(cmd, timeout):
    """Run cmd under nice; the row's measured fields, from its output lines as they come."""
    row = dict(checks=0)
    start = time.perf_counter()
    proc = subprocess.Popen(["nice", "-n", "10", *cmd], stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True, cwd=ROOT,
                            env=dict(os.environ, PYTHONUNBUFFERED="1"))
    tail = []
    for line in proc.stdout:
        now = round(time.perf_counter() - start, 1)
        if (m := SOLVED.match(line)) and "solved_step" not in row:
            row.update(solved_step=int(m.group(1)), solved_seconds=now)
        if m := CHECK.match(line):
            row["checks"] += 1
            if HOLDS in line:
                row.update(stopped_step=int(m.group(1)), stopped_seconds=now)
        if m := FINAL.match(line):
            row["final_step"] = int(m.group(1) or m.group(2))
        if m := GREEDY.search(line):
            row.update(greedy_eval_mean=float(m.group(1) or m.group(3)),
                       greedy_eval_min=int(m.group(2) or m.group(4)))
        tail = (tail + [line])[-5:]
        if now > timeout:
            proc.kill()
            break
    proc.wait()
    if proc.returncode:
        print("".join(tail), file=sys.stderr)
    return dict(row, total_seconds=round(time.perf_counter() - start, 1),
                returncode=proc.returncode)


def read_rows():
    if not OUT.exists():
        return []
    with open(OUT, newline="") as f:
        return list(csv.DictReader(f))


def median_and_range(values, spec):
    return (f"median {statistics.median(values):{spec}} [{min(values):{spec}}, "
            f"{max(values):{spec}}]")


def table(rows):
    """The page's lines: a row per seed (steps and seconds to solve for each runner, "-" where
    unsolved, and the greedy policy's mean at the end), then per runner the solved count with
    the median [min, max] of steps and seconds, then the ratio of the medians, ours / SB3."""
    by = {(r["runner"], r["seed"]): r for r in rows}
    seeds = sorted({int(r["seed"]) for r in rows})
    sb3 = "sb3_dqn" in RUNNERS  # not with --held-out: ours alone
    head = ["seed"] + [f"{who}: {what}" for name, who in (("dqn_cartpole", "ours"),
                                                          ("sb3_dqn", "SB3")) if name in RUNNERS
                       for what in ("steps to solve", "seconds")]
    head += ["SB3: greedy at its end"] if sb3 else []
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for seed in seeds:
        cells = []
        for name in RUNNERS:
            r = by.get((name, str(seed)), {})
            cells += ([f"{int(r['solved_step']):,}", r["solved_seconds"]]
                      if r.get("solved_step") else ["-", "-"])
        if sb3:
            cells.append(by.get(("sb3_dqn", str(seed)), {}).get("greedy_eval_mean") or "-")
        lines.append(f"| {seed} | " + " | ".join(cells) + " |")
    medians = {}
    for name in RUNNERS:
        runs = [r for r in rows if r["runner"] == name]
        done = [r for r in runs if r["solved_step"]]
        whole = [float(r["total_seconds"]) for r in runs]
        line = (f"{name}: solved {len(done)} of {len(runs)} (the whole process: seconds "
                f"{median_and_range(whole, '.1f')})")
        if done:
            steps = [int(r["solved_step"]) for r in done]
            secs = [float(r["solved_seconds"]) for r in done]
            medians[name] = statistics.median(steps), statistics.median(secs)
            line += (f"; steps {median_and_range(steps, ',.0f')}; seconds "
                     f"{median_and_range(secs, '.1f')}")
        lines.append(line + ".")
    if len(medians) == 2:
        (os_, oS), (ps, pS) = medians["dqn_cartpole"], medians["sb3_dqn"]
        lines.append(f"The ratio of the medians, ours / SB3: steps {os_ / ps:.2f}, seconds "
                     f"{oS / pS:.2f}.")
    elif sb3:
        lines.append("The ratio of the medians, ours / SB3: none (a side solved no seed).")
    return lines


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seeds", type=int, default=5, help="seeds 0 .. N-1")
    parser.add_argument("--held-out", action="store_true",
                        help="ours alone on seeds 5-9, which no default was chosen on "
                             "(dqn_heldout_seeds.csv)")
    parser.add_argument("--timeout", type=float, default=900, help="seconds before a run is killed")
    parser.add_argument("--table", action="store_true", help="only the table of the CSV")
    args = parser.parse_args()
    global OUT, RUNNERS
    if args.held_out:  # the defaults were chosen on seeds 0-4: these five test them
        OUT = OUT.with_name("dqn_heldout_seeds.csv")
        RUNNERS = {"dqn_cartpole": RUNNERS["dqn_cartpole"]}
    seeds = range(5, 10) if args.held_out else range(args.seeds)
    if not args.table:
        commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True,
                                text=True, cwd=ROOT).stdout.strip()
        done = {(r["seed"], r["runner"]) for r in read_rows()}
        OUT.parent.mkdir(parents=True, exist_ok=True)
        for seed in seeds:
            for name, cmd in RUNNERS.items():
                if (str(seed), name) in done:
                    continue
                load = os.getloadavg()[0]
                with tempfile.TemporaryDirectory() as tmp:
                    row = run_one(cmd(seed, tmp), args.timeout)
                row.update(seed=seed, runner=name, load_avg_1min_at_start=round(load, 1),
                           cpus=os.cpu_count(), commit=commit)
                new = not OUT.exists()
                with open(OUT, "a", newline="") as f:  # each run's row as it ends: resumable
                    writer = csv.DictWriter(f, FIELDS)
                    if new:
                        writer.writeheader()
                    writer.writerow(row)
                shown = ("solved_step", "solved_seconds", "stopped_step", "stopped_seconds",
                         "greedy_eval_mean")
                print(f"seed {seed}  {name:<13} " + ", ".join(f"{k} {row.get(k)}" for k in shown),
                      flush=True)
    print("\n".join(table(read_rows())))


if __name__ == "__main__":
    main()
