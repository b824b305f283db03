"""GRPO beside its two baselines, seed by seed, each arm from the same supervised model
(docs/ppo_to_grpo.md's table).

For each seed: grpo_addition.py's supervised phase alone (--grpo-steps 0), then, each with
--start-from that model, the three arms at their defaults:
    grpo         GRPO (300 steps of 32 prompts x 8 sampled answers)
    rft          --rft: the same prompts and sampled answers, the same optimizer and step
                 size; cross-entropy on the answers the verifier accepts
    more_labels  --more-labels: 2,500 more steps imitating the noisy labels (no verifier)
Held-out pass@1 and pass@G (500 sums, G = 8 answers each) before and after each arm. A row is
appended to benchmarks/results/grpo_seeds_arms.csv as each seed ends; a seed already there is
skipped, and a run already finished in the work folder is read back, not run again, so an
interrupted benchmark goes on where it stopped. One run at a time, one torch thread, under
nice.

    python benchmarks/grpo_seeds.py                 # seeds 0-19; 18 to 24 minutes a seed on
                                                    # the crowded 2-core machine of the record
    python benchmarks/grpo_seeds.py --seeds 5 6 7   # those seeds only
    python benchmarks/grpo_seeds.py --table         # the page's table from the record
"""

import argparse
import csv
import os
import re
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "benchmarks" / "results" / "grpo_seeds_arms.csv"
WORK = ROOT / "runs" / "grpo_seeds"  # the run folders (not committed)
ARMS = {"grpo": [], "rft": ["--rft"], "more_labels": ["--more-labels"]}
COLUMNS = (["seed", "before_pass1", "before_passG"]
           + [f"{arm}_{m}" for arm in ARMS for m in ("pass1", "passG")]
           + ["supervised_seconds"] + [f"{arm}_seconds" for arm in ARMS] + ["machine"])
LINE = re.compile(r"pass@1 ([\d.]+), pass@\d+ ([\d.]+) \(phase (\w+) took (\d+) s\)")


def run(seed, name, args):
    """One run of grpo_addition.py into WORK/seed<k>/<name>/, or its log if it finished
    before: {phase: (pass@1, pass@G, seconds)} from its two phase lines."""
    folder = WORK / f"seed{seed}" / name
    log = folder / "stdout.txt"
    if not (log.exists() and "after" in log.read_text()):
        folder.mkdir(parents=True, exist_ok=True)
        for old in folder.glob("grpo_addition__*"):  # a run cut short: start it again
            for f in old.iterdir():
                f.unlink()
            old.rmdir()
        p = subprocess.run(["nice", "-n", "10", sys.executable, str(ROOT / "grpo_addition.py"),
                            "--seed", str(seed), "--run-dir", str(folder), "--threads", "1",
                            "--print-every", "100000", "--no-curves"] + args,
                           capture_output=True, text=True, cwd=ROOT)
        if p.returncode:
            sys.exit(f"seed {seed} {name}: {p.stderr[-2000:]}")
        log.write_text(p.stdout)
    found = {m.group(3): (m.group(1), m.group(2), m.group(4))
             for m in LINE.finditer(log.read_text())}
    return found, next(folder.glob("grpo_addition__*"))


def one_seed(seed):
    found, supervised = run(seed, "supervised", ["--grpo-steps", "0"])
    row = dict(seed=seed, before_pass1=found["supervised"][0], before_passG=found["supervised"][1],
               supervised_seconds=found["supervised"][2], machine=os.uname().nodename)
    for arm, args in ARMS.items():
        found, _ = run(seed, arm, ["--start-from", str(supervised)] + args)
        assert found["supervised"][:2] == (row["before_pass1"], row["before_passG"]), found
        row.update({f"{arm}_pass1": found[arm][0], f"{arm}_passG": found[arm][1],
                    f"{arm}_seconds": found[arm][2]})
    return row


def read_record():
    if not OUT.exists():
        return []
    with open(OUT, newline="") as f:
        return list(csv.DictReader(f))


PAIRS = (("grpo", "rft"), ("grpo", "more_labels"), ("rft", "more_labels"), ("grpo", "before"),
         ("rft", "before"), ("more_labels", "before"))


def table_rows(rows):
    """docs/ppo_to_grpo.md's two tables, their cells after the first column (numbers only, the
    same in both languages): per arm, median [lowest, highest] of pass@1 and pass@G; per pair
    of arms, the median of the per-seed differences [lowest, highest] (on how many seeds it is
    above 0 / of how many)."""
    get = lambda r, k: float(r[k])  # noqa: E731
    out = []
    for arm in ["before"] + list(ARMS):
        cells = []
        for m in ("pass1", "passG"):
            v = [get(r, f"{arm}_{m}") for r in rows]
            cells.append(f"{statistics.median(v):.3f} [{min(v):.3f}, {max(v):.3f}]")
        out.append(cells)
    for a, b in PAIRS:
        cells = []
        for m in ("pass1", "passG"):
            d = [round(get(r, f"{a}_{m}") - get(r, f"{b}_{m}"), 3) for r in rows]
            cells.append(f"{statistics.median(d):+.3f} [{min(d):+.3f}, {max(d):+.3f}] "
                         f"({sum(x > 0 for x in d)}/{len(d)})")
        out.append(cells)
    return out


def summary(rows):
    """The record in a few lines: its seeds, then the page's rows, first column named."""
    names = ["supervised"] + list(ARMS) + [f"{a} - {b}" for a, b in PAIRS]
    return ([f"{len(rows)} seeds: {', '.join(r['seed'] for r in rows)}"]
            + [f"| {name} | " + " | ".join(cells) + " |"
               for name, cells in zip(names, table_rows(rows))])


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=list(range(20)))
    parser.add_argument("--table", action="store_true", help="print the record's summary")
    args = parser.parse_args()
    if args.table:
        print("\n".join(summary(read_record())))
        return
    for seed in args.seeds:
        if str(seed) in {r["seed"] for r in read_record()}:
            continue
        start = time.time()
        row = one_seed(seed)
        new = not OUT.exists()
        with open(OUT, "a", newline="") as f:  # one row as each seed ends
            writer = csv.DictWriter(f, fieldnames=COLUMNS)
            if new:
                writer.writeheader()
            writer.writerow(row)
        print(f"seed {seed}: {time.time() - start:.0f} s; "
              + ", ".join(f"{k} {row[k]}" for k in COLUMNS if k.endswith("pass1")), flush=True)
    print("\n".join(summary(read_record())))


if __name__ == "__main__":
    main()
