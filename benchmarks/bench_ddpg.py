"""Learning-phase throughput of ddpg_walker.py against tutorial 003's implementation.

The measure: env steps per second after the random warm-up, with one critic
and one actor update per env step, on the CPU with 2 torch threads,
evaluation pauses included. Both programs run the same budget (warm-up, then
learning steps with an evaluation of 10 episodes every 5000 steps) and print
their own learning-phase rate; runs alternate so drift hits both alike.

--threads-table measures ddpg_walker.py alone with 1 and 2 torch threads, on an
idle machine and with a second process spinning on one core (a busy machine).

    python benchmarks/bench_ddpg.py                  # 3 runs each, Walker2d-v5
    python benchmarks/bench_ddpg.py --threads-table  # ddpg_walker.py, 1 vs 2 threads, idle vs busy
"""

import argparse
import contextlib
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
RATE = re.compile(r"^learning phase: \d+ steps at ([\d.]+) steps/s")


def rate_of(cmd):
    env = dict(os.environ, OMP_NUM_THREADS="2", CUDA_VISIBLE_DEVICES="")  # the CPU, 2 threads
    out = subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=ROOT).stdout
    rates = [float(m.group(1)) for line in out.splitlines() if (m := RATE.match(line))]
    if not rates:
        sys.exit(f"no rate from {' '.join(cmd)}:\n{out[-2000:]}")
    return rates[0]


@contextlib.contextmanager
def busy_core():
    """A second process spinning on one core while the block runs."""
    spinner = subprocess.Popen([sys.executable, "-c", "while True: pass"])
    try:
        yield
    finally:
        spinner.kill()
        spinner.wait()


def threads_table(args, budget):
    rates = {}
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(args.repeats):
            for busy in (False, True):
                for threads in (1, 2):
                    cmd = [sys.executable, str(ROOT / "ddpg_walker.py"), *budget, "--no-cuda", "--no-gifs",
                           "--run-dir", tmp, "--print-every", "100000", "--threads", str(threads)]
                    with busy_core() if busy else contextlib.nullcontext():
                        rate = rate_of(cmd)
                    key = f"{'busy' if busy else 'idle'}, {threads} thread{'s' if threads > 1 else ''}"
                    rates.setdefault(key, []).append(rate)
                    print(f"run {i}: {key}: {rate:.1f} steps/s", flush=True)
    med = {k: statistics.median(v) for k, v in rates.items()}
    print(f"\n| machine, torch threads | learning steps/s (median of {args.repeats}) |\n|---|---|")
    for k, v in med.items():
        print(f"| {k} | {v:.0f} |")
    ratio = med["busy, 1 thread"] / med["idle, 1 thread"]
    print(("PASS" if ratio >= 0.5 else "FAIL") + f" busy/idle with the default 1 thread: {ratio:.2f} (target >= 0.5)")
    (ROOT / args.out).parent.mkdir(parents=True, exist_ok=True)
    (ROOT / args.out).write_text(json.dumps(dict(rates=rates, medians=med, args=vars(args)), indent=1))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--env-id", default="Walker2d-v5")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--start-steps", type=int, default=2000)
    parser.add_argument("--learn-steps", type=int, default=5000)
    parser.add_argument("--threads-table", action="store_true",
                        help="ddpg_walker.py alone: 1 and 2 threads, idle and busy machine")
    parser.add_argument("--out", help="JSON file for the figures (default: benchmarks/results/ddpg.json, "
                                      "or ddpg_threads.json with --threads-table)")
    args = parser.parse_args()
    default_out = "ddpg_threads.json" if args.threads_table else "ddpg.json"
    args.out = args.out or str(Path("benchmarks") / "results" / default_out)  # relative: no machine's path
    budget = ["--env-id", args.env_id, "--total-timesteps", str(args.start_steps + args.learn_steps),
              "--start-steps", str(args.start_steps), "--eval-every", "5000"]
    if args.threads_table:
        return threads_table(args, budget)
    rates = {"ddpg_walker": [], "tutorial_003": []}
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(args.repeats):
            rates["ddpg_walker"].append(rate_of([sys.executable, str(ROOT / "ddpg_walker.py"), *budget, "--no-cuda",
                                                 "--no-gifs", "--run-dir", tmp, "--print-every", "100000", "--threads", "2"]))
            rates["tutorial_003"].append(rate_of([sys.executable, str(ROOT / "benchmarks" / "ddpg_tutorial_walker.py"),
                                                  *budget]))
            print(f"run {i}: ddpg_walker {rates['ddpg_walker'][-1]:.1f} steps/s, "
                  f"tutorial {rates['tutorial_003'][-1]:.1f} steps/s", flush=True)
    ours, theirs = statistics.median(rates["ddpg_walker"]), statistics.median(rates["tutorial_003"])
    print(f"\n| implementation | learning steps/s (median of {args.repeats}) |\n|---|---|\n"
          f"| ddpg_walker.py | {ours:.0f} |\n| tutorial 003 | {theirs:.0f} |\nratio ours/tutorial: {ours / theirs:.2f}")
    print(("PASS" if ours / theirs >= 1.6 else "FAIL") + f" ratio {ours / theirs:.2f} (target >= 1.6)")
    (ROOT / args.out).parent.mkdir(parents=True, exist_ok=True)
    (ROOT / args.out).write_text(json.dumps(dict(rates=rates, ratio=ours / theirs, args=vars(args)), indent=1))


if __name__ == "__main__":
    main()
