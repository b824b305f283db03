"""Learning-phase throughput of ddpg_walker.py against tutorial 003's implementation.

../shared/BENCHMARK.md: env steps per second after the random warm-up, with one
critic and one actor update per env step, on the CPU with 2 threads,
evaluation pauses included. Both programs run the same budget (warm-up, then
learning steps with an evaluation of 10 episodes every 5000 steps) and print
their own learning-phase rate; runs alternate so drift hits both alike.

    python benchmarks/bench_ddpg.py                  # 3 runs each, Walker2d-v5
"""

import argparse
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


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--env-id", default="Walker2d-v5")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--start-steps", type=int, default=2000)
    parser.add_argument("--learn-steps", type=int, default=5000)
    parser.add_argument("--out", default=str(ROOT / "benchmarks" / "results" / "ddpg.json"))
    args = parser.parse_args()
    budget = ["--env-id", args.env_id, "--total-timesteps", str(args.start_steps + args.learn_steps),
              "--start-steps", str(args.start_steps), "--eval-every", "5000"]
    rates = {"ddpg_walker": [], "tutorial_003": []}
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(args.repeats):
            rates["ddpg_walker"].append(rate_of([sys.executable, str(ROOT / "ddpg_walker.py"), *budget, "--no-cuda",
                                                 "--no-gifs", "--run-dir", tmp, "--print-every", "100000"]))
            rates["tutorial_003"].append(rate_of([sys.executable, str(ROOT / "benchmarks" / "ddpg_tutorial_walker.py"),
                                                  *budget]))
            print(f"run {i}: ddpg_walker {rates['ddpg_walker'][-1]:.1f} steps/s, "
                  f"tutorial {rates['tutorial_003'][-1]:.1f} steps/s", flush=True)
    ours, theirs = statistics.median(rates["ddpg_walker"]), statistics.median(rates["tutorial_003"])
    print(f"\n| implementation | learning steps/s (median of {args.repeats}) |\n|---|---|\n"
          f"| ddpg_walker.py | {ours:.0f} |\n| tutorial 003 | {theirs:.0f} |\nratio ours/tutorial: {ours / theirs:.2f}")
    print(("PASS" if ours / theirs >= 1.6 else "FAIL") + f" ratio {ours / theirs:.2f} (target >= 1.6)")
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(dict(rates=rates, ratio=ours / theirs, args=vars(args)), indent=1))


if __name__ == "__main__":
    main()
