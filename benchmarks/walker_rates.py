"""Steps per second on Walker2d-v5 of the four walker settings, measured side by side: DDPG,
TD3 and SAC at their defaults, PPO as benchmarks/ddpg_walker_1m.py runs it (ppo_reacher.py with
CleanRL's settings). Each run: one torch thread, its learning phase only (the off-policy
scripts after a short random warm-up), the rate the script itself prints at its end
("learning phase: N steps at R steps/s"). The scripts run
in rounds, each round all four in a shuffled order, two at a time; the record keeps every
rate. With the 1M-step records, the rates turn equal wall-clock time into equal steps:
docs/results.md's table at equal time (--table).

    python benchmarks/walker_rates.py              # 2 rounds: ~2 minutes on 2 quiet cores
    python benchmarks/walker_rates.py --table      # the record's medians, the equal-time table
"""

import argparse
import json
import os
import random
import re
import statistics
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(Path(__file__).resolve().parent))
import ddpg_walker_1m as records  # noqa: E402  the 1M records and how they are read
from ddpg_walker_1m import FLAGS  # noqa: E402  PPO's Walker2d settings, once

RECORD = ROOT / "benchmarks" / "results" / "walker_rates.json"
WARM_UP = 25_000  # the random steps before DDPG's, TD3's and SAC's records learn (start_steps)
RATE = re.compile(r"^learning phase: (\d+) steps at ([\d.]+) steps/s")
OFF_POLICY = ["--start-steps", "1000", "--total-timesteps", "4000", "--eval-every", "5000"]
RUNS = {"ddpg_walker": OFF_POLICY, "td3_walker": OFF_POLICY, "sac_walker": OFF_POLICY,
        "ppo_reacher": [*FLAGS["ppo_reacher"], "--total-timesteps", "40000", "--eval-every",
                        "1000000", "--eval-episodes", "1"]}
# 40,000 PPO steps are 20 rollouts and updates; 3,000 learning steps of the others, one update
# each. No evaluation in either (PPO: one episode at the end), so the rate is learning's alone:
# the 1M runs' evaluations (10 episodes every 5000 steps) cost each script the same steps.


def rate(script, tmp):
    """One run of `script`: its learning phase's steps per second."""
    cmd = [sys.executable, str(ROOT / f"{script}.py"), *RUNS[script], "--no-gifs", "--no-curves",
           "--threads", "1", "--print-every", "1000000", "--run-dir", tmp]
    env = dict(os.environ, OMP_NUM_THREADS="1", CUDA_VISIBLE_DEVICES="")
    out = subprocess.run(cmd, capture_output=True, text=True, env=env).stdout
    found = [m for line in out.splitlines() if (m := RATE.match(line))]
    if not found:
        sys.exit(f"no rate from {script}:\n{out[-1500:]}")
    return float(found[0][2])


def budgets(rates):
    """The equal times of docs/results.md, in seconds: what PPO needs for its 1M steps, then 30
    and 60 minutes (PPO's record ends at 1M, reached in the first; the others' reach 1M, or
    525,000 steps and more for SAC and TD3)."""
    return records.BUDGET / statistics.median(rates["ppo_reacher"]), 1800, 3600


def at_equal_time(rates, seconds):
    """docs/results.md's table at equal wall-clock time: `seconds` of each script's learning
    phase at its median rate is rate x seconds env steps, after the off-policy records' random
    warm-up, counted as free (which favours them); down to the records' 5000-step grid, at most
    1M, where the records end. Per seed: the last 10 evaluations up to that step and the
    highest up to there; over the seeds whose record reaches it, their mean (se)."""
    print(f"| {seconds / 60:.1f} minutes | steps | seeds | last 10, each seed | their mean (se) | "
          "highest, each seed | their mean (se) |")
    print("|---|---|---|---|---|---|---|")
    for script, rate_of in rates.items():
        free = 0 if script == "ppo_reacher" else WARM_UP
        at = min((free + int(statistics.median(rate_of) * seconds)) // 5000 * 5000, records.BUDGET)
        seeds, lasts, highs = records.up_to(script, at)
        each = ", ".join
        print(f"| {records.NAMES[script]} | {at:,} | {each(map(str, seeds))} | "
              f"{each(f'{x:.0f}' for x in lasts)} | {records.mean_se(lasts)} | "
              f"{each(f'{x:.0f}' for x in highs)} | {records.mean_se(highs)} |")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--table", action="store_true")
    args = parser.parse_args()
    if not args.table:
        rates = {script: [] for script in RUNS}
        with tempfile.TemporaryDirectory() as tmp, ThreadPoolExecutor(2) as pool:
            for k in range(args.rounds):
                order = random.Random(k).sample(list(RUNS), len(RUNS))
                for script, got in zip(order, pool.map(lambda s: rate(s, tmp), order)):
                    rates[script].append(got)
                    print(f"round {k}: {script} {got:.1f} steps/s", flush=True)
        RECORD.write_text(json.dumps(dict(runs=RUNS, rates=rates), indent=1) + "\n")
    record = json.loads(RECORD.read_text())
    for script, values in record["rates"].items():
        print(f"{script:12} median {statistics.median(values):7.1f} steps/s over "
              f"{len(values)} runs: {', '.join(f'{v:.1f}' for v in values)}")
    for seconds in budgets(record["rates"]):
        print()
        at_equal_time(record["rates"], seconds)


if __name__ == "__main__":
    main()
