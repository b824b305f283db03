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
    python benchmarks/bench_dqn.py --summary       # the medians and ranges of the CSV
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
                                       "--run-dir", out, "--no-gifs", "--no-curves", "--threads", "1"],
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


def summary(rows):
    """Per runner: solved count, median and range of steps and seconds to solve and to stop;
    then the ratio of the medians, ours / SB3."""
    medians = {}
    for name in RUNNERS:
        runs = [r for r in rows if r["runner"] == name]
        print(f"{name}: {len(runs)} runs")
        for what in ("solved", "stopped"):
            done = [r for r in runs if r[f"{what}_step"]]
            steps = [int(r[f"{what}_step"]) for r in done]
            secs = [float(r[f"{what}_seconds"]) for r in done]
            print(f"  {what}: {len(done)}/{len(runs)}", end="")
            if done:
                medians[name, what] = statistics.median(steps), statistics.median(secs)
                print(f"; steps median {medians[name, what][0]:,.0f} ({min(steps):,} .. "
                      f"{max(steps):,}); seconds median {medians[name, what][1]:.1f} "
                      f"({min(secs):.1f} .. {max(secs):.1f})", end="")
            print()
    for what in ("solved", "stopped"):
        ours, peer = medians.get(("dqn_cartpole", what)), medians.get(("sb3_dqn", what))
        if ours and peer:
            print(f"ratio ours / SB3 ({what}): steps {ours[0] / peer[0]:.2f}, "
                  f"seconds {ours[1] / peer[1]:.2f}")
        else:
            print(f"ratio ours / SB3 ({what}): n/a (a side has no {what} run)")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seeds", type=int, default=5, help="seeds 0 .. N-1")
    parser.add_argument("--timeout", type=float, default=900, help="seconds before a run is killed")
    parser.add_argument("--summary", action="store_true", help="only summarize the CSV")
    args = parser.parse_args()
    if not args.summary:
        commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True,
                                text=True, cwd=ROOT).stdout.strip()
        done = {(r["seed"], r["runner"]) for r in read_rows()}
        OUT.parent.mkdir(parents=True, exist_ok=True)
        for seed in range(args.seeds):
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
                print(f"seed {seed}  {name:<13} " + ", ".join(
                    f"{k} {row.get(k)}" for k in ("solved_step", "solved_seconds", "stopped_step",
                                                  "stopped_seconds", "greedy_eval_mean")), flush=True)
    summary(read_rows())


if __name__ == "__main__":
    main()
