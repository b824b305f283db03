"""RLHF by PPO and by DPO against the supervised model they start from (docs/ppo_to_rlhf.md).

For each run: rlhf_addition.py with the flags of RUNS, one at a time, one torch thread.
Each run's stage lines (held-out true score and accuracy after supervision, after PPO,
after DPO; the reward model's held-out pair accuracy; seconds per stage) become a row of
benchmarks/results/rlhf_seeds.csv as the run ends, and its PPO rows (learned reward, true
score and KL of the sampled answers at each step) go to rlhf_overopt.csv: the numbers that
draw docs/rlhf_overoptimisation.png (--plot).

    nice -n 10 python benchmarks/rlhf_seeds.py           # about 5 minutes a run on 2 busy cores
    python benchmarks/rlhf_seeds.py --plot               # the figure, from the records
    python benchmarks/rlhf_seeds.py --table              # the page's table, from the record
"""

import csv
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "benchmarks" / "results" / "rlhf_seeds.csv"
CURVES = ROOT / "benchmarks" / "results" / "rlhf_overopt.csv"
FIGURE = ROOT / "docs" / "rlhf_overoptimisation.png"
# (seed, name, flags): the default run, seed 0 with a tight KL penalty, and with the judge's
# own score as PPO's reward (a verifier: what a perfect reward model would give)
RUNS = [(0, "default", []), (0, "beta 1", ["--beta", "1"]), (1, "default", []),
        (2, "default", []), (0, "judge", ["--reward-from", "judge"]), (3, "default", []),
        (4, "default", [])]
STAGE = re.compile(r"^(supervised|PPO|DPO): held-out true score ([\d.]+), accuracy ([\d.]+) "
                   r"\(took (\d+) s\)")


def one(seed, name, flags, tmp):
    start = time.time()
    p = subprocess.run([sys.executable, str(ROOT / "rlhf_addition.py"), "--seed", str(seed),
                        "--run-dir", tmp, "--print-every", "100000", "--no-curves", *flags],
                       capture_output=True, text=True)
    if p.returncode:
        sys.exit(p.stderr[-2000:])
    row = dict(seed=seed, run=name)
    for line in p.stdout.splitlines():
        if m := STAGE.match(line):
            stage = m.group(1).lower()
            row.update({f"{stage}_true": m.group(2), f"{stage}_accuracy": m.group(3),
                        f"{stage}_seconds": m.group(4)})
        if m := re.search(r"held-out pair accuracy ([\d.]+).*took (\d+) s", line):
            row.update(rm_pair_accuracy=m.group(1), rm_seconds=m.group(2))
    row["seconds"] = f"{time.time() - start:.0f}"
    (run,) = [d for d in Path(tmp).iterdir() if f"seed{seed}_" in d.name]
    ppo = [r for r in csv.DictReader(open(run / "progress.csv")) if r["phase"] == "ppo"]
    for d in Path(tmp).iterdir():
        for f in d.iterdir():
            f.unlink()
        d.rmdir()
    return row, [dict(seed=seed, run=name, ppo_step=i + 1, rm_score=r["rm_score"],
                      true_score=r["true_score"], kl=r["kl"]) for i, r in enumerate(ppo)]


def append(path, rows):
    new = not path.exists()
    with open(path, "a", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        if new:
            writer.writeheader()
        writer.writerows(rows)


def summary(path=OUT):
    """The page's table, from the record: per stage, the held-out true score and accuracy of
    the default runs, median [lowest, highest] over their seeds; and the seeds."""
    import statistics

    rows = [r for r in csv.DictReader(open(path)) if r["run"] == "default"]
    cells = []
    for stage in ("supervised", "ppo", "dpo"):
        cells.append([f"{statistics.median(v):.3f} [{min(v):.3f}, {max(v):.3f}]" for v in (
            [float(r[f"{stage}_{k}"]) for r in rows] for k in ("true", "accuracy"))])
    for stage in ("ppo", "dpo"):  # paired: each seed's stage minus its own supervised model
        cells.append([f"{statistics.median(v):+.3f} [{min(v):+.3f}, {max(v):+.3f}]" for v in (
            [float(r[f"{stage}_{k}"]) - float(r[f"supervised_{k}"]) for r in rows]
            for k in ("true", "accuracy"))])
    v = [float(r["rm_pair_accuracy"]) for r in rows]
    cells.append([f"{statistics.median(v):.3f} [{min(v):.3f}, {max(v):.3f}]"])
    return cells, sorted(int(r["seed"]) for r in rows)


def overopt(name, path=CURVES):
    """Seed 0's PPO run `name`: (learned reward, true score, KL) of the sampled answers,
    each the mean of the first 5 steps and of the last 5, as the page writes them."""
    rows = [r for r in csv.DictReader(open(path)) if r["run"] == name and r["seed"] == "0"]
    mean = lambda part, key: sum(float(r[key]) for r in part) / len(part)  # noqa: E731
    return [(f"{mean(rows[:5], k):{f}}", f"{mean(rows[-5:], k):{f}}")
            for k, f in (("rm_score", "+.2f"), ("true_score", ".3f"), ("kl", ".2f"))]


def overopt_has(name, path=CURVES):
    return any(r["run"] == name for r in csv.DictReader(open(path)))


def plot():
    """docs/rlhf_overoptimisation.png: learned reward and true score of PPO's samples against
    sqrt(KL to the supervised model), seed 0 at beta 0.1 (default) and at beta 1."""
    sys.path.insert(0, str(ROOT))
    import numpy as np

    import plots

    rows = list(csv.DictReader(open(CURVES)))
    plt = plots.pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.8), sharey=False)
    for ax, key, title in zip(axes, ("rm_score", "true_score"),
                              ("learned reward r(x, y)", "true (hidden) score")):
        for name, color in (("default", "C3"), ("beta 1", "C0"), ("judge", "C2")):
            mine = [r for r in rows if r["run"] == name and r["seed"] == "0"]
            if not mine:
                continue
            kl = np.sqrt(np.maximum([float(r["kl"]) for r in mine], 0))
            ax.plot(kl, [float(r[key]) for r in mine], ".-", color=color, ms=3, lw=0.8,
                    label={"default": "beta 0.1 (default)", "beta 1": "beta 1",
                           "judge": "beta 0.1, reward = the judge's score"}[name])
        ax.set(title=title, xlabel="sqrt(KL(pi || pi_sft)) per answer, nats^0.5")
        ax.legend(fontsize=7)
    fig.suptitle("PPO's sampled answers, seed 0, one dot per PPO step", fontsize=9)
    fig.tight_layout()
    plots.save_whole(plt, fig, FIGURE, dpi=90)
    print(f"wrote {FIGURE}")


def main():
    if "--plot" in sys.argv:
        return plot()
    if "--table" in sys.argv:
        cells, seeds = summary()
        print(f"seeds {seeds}\n" + "\n".join(" | ".join(c) for c in cells))
        names = [n for n in ("default", "beta 1", "judge") if overopt_has(n)]
        return print("\n".join(f"{n}: {overopt(n)}" for n in names))
    done = {(r["seed"], r["run"]) for r in csv.DictReader(open(OUT))} if OUT.exists() else set()
    with tempfile.TemporaryDirectory() as tmp:
        for seed, name, flags in RUNS:
            if (str(seed), name) in done:  # a record row per run, kept: run again to go on
                continue
            row, curve = one(seed, name, flags, tmp)
            append(OUT, [row])
            append(CURVES, curve)
            print(row, flush=True)


if __name__ == "__main__":
    main()
