"""GRPO against a supervised-only control, seeds 0-4 (docs/ppo_to_grpo.md's table).

For each seed: grpo_addition.py at its defaults (supervise, then GRPO), and with --control
(supervise on, for about as long as GRPO runs). Both start from the same supervised model
(same seed, same steps): held-out pass@1 and pass@G before, after GRPO, after the control.
Runs two at a time, one torch thread each; writes benchmarks/results/grpo_seeds.csv.

    python benchmarks/grpo_seeds.py            # about 20 minutes on 2 cores
"""

import csv
import re
import statistics
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "benchmarks" / "results" / "grpo_seeds.csv"
SEEDS = (0, 1, 2, 3, 4)
LINE = re.compile(r"pass@1 ([\d.]+), pass@(\d+) ([\d.]+)")


# Seed 0 again with beta, the KL penalty's weight, far from its 0.04: none, and 25 times it.
EXTRAS = {"beta 0": ["--beta", "0"], "beta 1": ["--beta", "1"]}


def one(seed, control, tmp, extra=None):
    start = time.time()
    p = subprocess.run([sys.executable, str(ROOT / "grpo_addition.py"), "--seed", str(seed),
                        "--run-dir", tmp, "--print-every", "100000"]
                       + (["--control"] if control else []) + EXTRAS.get(extra, []),
                       capture_output=True, text=True)
    if p.returncode:
        sys.exit(p.stderr[-2000:])
    (before, after) = [LINE.search(line).groups() for line in p.stdout.splitlines()
                       if line.startswith(("supervised:", "after"))]
    phases = re.findall(r"phase ([a-z]+) took ([\d.]+) s", p.stdout)
    return dict(seed=seed, run=extra or ("control" if control else "grpo"), before_pass1=before[0],
                before_passG=before[2], after_pass1=after[0], after_passG=after[2],
                seconds=f"{time.time() - start:.0f}", **{f"{k}_seconds": v for k, v in phases})


def main():
    with tempfile.TemporaryDirectory() as tmp, ThreadPoolExecutor(2) as pool:
        jobs = [(s, c, None) for s in SEEDS for c in (False, True)]
        jobs += [(0, False, extra) for extra in EXTRAS]
        rows = list(pool.map(lambda job: one(job[0], job[1], tmp, job[2]), jobs))
    OUT.parent.mkdir(parents=True, exist_ok=True)
    keys = sorted({k for r in rows for k in r}, key=lambda k: list(rows[0]).index(k) if k in rows[0] else 99)
    with open(OUT, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=keys)
        writer.writeheader()
        writer.writerows(rows)
    for run in ("grpo", "control"):
        for key in ("before_pass1", "after_pass1", "before_passG", "after_passG"):
            values = [float(r[key]) for r in rows if r["run"] == run]
            print(f"{run:8} {key:13} median {statistics.median(values):.3f}  "
                  f"[{min(values):.3f}, {max(values):.3f}]")
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()
