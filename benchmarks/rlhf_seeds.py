"""RLHF by PPO and by DPO against the supervised model they start from (docs/ppo_to_rlhf.md).

For each run: rlhf_addition.py with the flags of RUNS, one at a time, one torch thread.
Each run's stage lines (held-out true score and accuracy after supervision, after PPO,
after DPO; the reward model's held-out pair accuracy; seconds per stage) become a row of
benchmarks/results/rlhf_seeds.csv as the run ends, and its PPO rows (learned reward, true
score and KL of the sampled answers at each step) go to rlhf_overopt.csv: the numbers that
draw docs/rlhf_overoptimisation.png (--plot).

--grpo: GRPO with the verifier beside PPO-RLHF, seed by seed, from the same supervised model.
For each seed, rlhf_addition.py's supervised phase again (--ppo-steps 0 --no-dpo and a token
reward model: the supervised phase comes first and draws nothing that the later stages
change, so its model is the default run's), saved as grpo_addition.py's --start-from reads
it; then grpo_addition.py on the same two-digit sums and held-out split, with as many sampled
answers as the default PPO stage: 50 updates x 32 prompts x 8 answers = 50 x 256 x 1 = 12,800
(GRPO's other settings at its defaults). Both models are measured as the page measures PPO's
(rlhf_addition.evaluate: 500 held-out sums, 4 answers each, the judge's true score and the
share of right answers). A row of benchmarks/results/rlhf_grpo.csv as each seed ends; a seed
already there is skipped.

    nice -n 10 python benchmarks/rlhf_seeds.py           # about 5 minutes a run on 2 busy cores
    nice -n 10 python benchmarks/rlhf_seeds.py --grpo    # GRPO beside, seeds 0-4
    nice -n 10 python benchmarks/rlhf_seeds.py --judge   # the control (PPO on the judge), 0-4
    python benchmarks/rlhf_seeds.py --plot               # the figure, from the records
    python benchmarks/rlhf_seeds.py --plot --lang zh     # its Chinese twin (.zh-CN.png)
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
GRPO = ROOT / "benchmarks" / "results" / "rlhf_grpo.csv"
GRPO_SEEDS = (0, 1, 2, 3, 4)
# GRPO's sampled answers: as many as the default PPO stage's 50 updates x 256 prompts x 1
GRPO_FLAGS = ["--grpo-steps", "50", "--prompts", "32", "--group-size", "8"]
# the supervised phase alone, its model saved (a token reward model; no PPO, no DPO)
SFT_FLAGS = ["--ppo-steps", "0", "--no-dpo", "--pair-prompts", "50", "--rm-epochs", "1"]
FIGURE = ROOT / "docs" / "rlhf_overoptimisation.png"
# (seed, name, flags): the default run, seed 0 with a tight KL penalty, and with the judge's
# own score as PPO's reward (a verifier: what a perfect reward model would give)
RUNS = [(0, "default", []), (0, "beta 1", ["--beta", "1"]), (1, "default", []),
        (2, "default", []), (3, "default", []), (4, "default", [])]
# --judge: the control, PPO on the judge's score (on r's scale; V from the supervised model
# with a zero head), seeds 0-4, no DPO (it does not depend on PPO's reward); a row of
# rlhf_judge.csv per seed, with r's and the judge's std on the supervised model's answers
JUDGE = ROOT / "benchmarks" / "results" / "rlhf_judge.csv"
JUDGE_RUNS = [(seed, "judge", ["--reward-from", "judge", "--no-dpo"]) for seed in range(5)]
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
        if m := re.search(r"r has std ([\d.]+), the judge ([\d.]+)", line):
            row.update(r_std=m.group(1), judge_std=m.group(2))
    row["seconds"] = f"{time.time() - start:.0f}"
    (run,) = [d for d in Path(tmp).iterdir() if f"seed{seed}_" in d.name]
    ppo = [r for r in csv.DictReader(open(run / "progress.csv")) if r["phase"] == "ppo"]
    for d in Path(tmp).iterdir():
        for f in d.iterdir():
            f.unlink()
        d.rmdir()
    return row, [dict(seed=seed, run=name, ppo_step=i + 1, rm_score=r["rm_score"],
                      true_score=r["true_score"], kl=r["kl"]) for i, r in enumerate(ppo)]


def grpo_beside(seed, tmp):
    """One seed of --grpo: (the row, the supervised model's figures as rlhf_addition.py
    printed them)."""
    sys.path.insert(0, str(ROOT))
    import numpy as np
    import torch

    import checkpoints
    import grpo_addition
    import rlhf_addition as rlhf

    torch.set_num_threads(1)
    start, common = time.time(), ["--seed", str(seed), "--print-every", "100000", "--no-curves"]
    p = subprocess.run([sys.executable, str(ROOT / "rlhf_addition.py"), *common, "--run-dir",
                        f"{tmp}/sft", *SFT_FLAGS], capture_output=True, text=True)
    if p.returncode:
        sys.exit(p.stderr[-2000:])
    printed = next(m for m in map(STAGE.match, p.stdout.splitlines())
                   if m and m.group(1) == "supervised")  # its held-out figures, as printed
    (sft_dir,) = Path(tmp, "sft").iterdir()
    saved = checkpoints.load_checkpoint(sft_dir, script="rlhf_addition",
                                        required=("policy", "config"))
    cfg = rlhf.Config(**{**saved["config"], "eval": None, "gif": None})
    build = lambda: grpo_addition.TinyGPT(cfg.n_layer, cfg.d_model, cfg.n_head,  # noqa: E731
                                          3 * cfg.digits + 4)
    supervised = build()
    supervised.load_state_dict(saved["policy"])
    _, held_out = grpo_addition.split_pairs(cfg.digits, cfg.eval_prompts,
                                            np.random.default_rng(cfg.seed))
    before = rlhf.evaluate(supervised, held_out, cfg)
    start_pt = Path(tmp, f"start{seed}.pt")  # the same weights, as --start-from reads them
    checkpoints.save_model(start_pt, "grpo_addition", grpo_addition.Config(
        seed=seed, digits=cfg.digits, eval_prompts=cfg.eval_prompts, n_layer=cfg.n_layer,
        d_model=cfg.d_model, n_head=cfg.n_head), 0, dict(model=supervised))
    sft_seconds, start = time.time() - start, time.time()
    p = subprocess.run([sys.executable, str(ROOT / "grpo_addition.py"), *common, "--run-dir",
                        f"{tmp}/grpo", "--start-from", str(start_pt), "--digits",
                        str(cfg.digits), "--eval-prompts", str(cfg.eval_prompts), *GRPO_FLAGS],
                       capture_output=True, text=True)
    if p.returncode:
        sys.exit(p.stderr[-2000:])
    own = re.search(r"after grpo: held-out pass@1 ([\d.]+), pass@(\d+) ([\d.]+)", p.stdout)
    (grpo_dir,) = Path(tmp, "grpo").iterdir()
    after_model, _ = checkpoints.load_model(grpo_dir, "grpo_addition", "model",
                                            lambda _: build())
    after = rlhf.evaluate(after_model, held_out, cfg)
    steps, prompts, group = (int(GRPO_FLAGS[i]) for i in (1, 3, 5))
    row = dict(seed=seed, supervised_true=f"{before[0]:.3f}",
               supervised_accuracy=f"{before[1]:.3f}", grpo_true=f"{after[0]:.3f}",
               grpo_accuracy=f"{after[1]:.3f}",
               grpo_pass1_own=own.group(1), grpo_passG_own=own.group(3), G=own.group(2),
               sampled_answers=steps * prompts * group, supervised_seconds=f"{sft_seconds:.0f}",
               grpo_seconds=f"{time.time() - start:.0f}")
    for d in (sft_dir, grpo_dir):
        for f in d.iterdir():
            f.unlink()
        d.rmdir()
    start_pt.unlink()
    return row, printed.group(2, 3)


def append(path, rows):
    new = not path.exists()
    with open(path, "a", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        if new:
            writer.writeheader()
        writer.writerows(rows)


def summary(path=OUT, grpo_path=GRPO, judge_path=JUDGE):
    """The page's table, from the records: per stage, the held-out true score and accuracy of
    the default runs, of the judge control (--judge) and of GRPO beside them (--grpo), median
    [lowest, highest] over their seeds; the paired differences, seed by seed; r's std on the
    supervised model's answers; and the seeds."""
    import statistics

    rows = sorted((r for r in csv.DictReader(open(path)) if r["run"] == "default"),
                  key=lambda r: int(r["seed"]))
    grpo = {r["seed"]: r for r in csv.DictReader(open(grpo_path))}
    judge = {r["seed"]: r for r in csv.DictReader(open(judge_path))}
    for r in rows:  # GRPO's and the control's columns beside each seed's RLHF run
        r.update({k: v for k, v in grpo.get(r["seed"], {}).items() if k.startswith("grpo_")})
        r.update({k.replace("ppo_", "judge_"): v for k, v in judge.get(r["seed"], {}).items()
                  if k.startswith("ppo_")}, r_std=judge.get(r["seed"], {}).get("r_std"))

    def cell(values, sign=""):  # median [lowest, highest]
        low, mid, high = min(values), statistics.median(values), max(values)
        return f"{mid:{sign}.3f} [{low:{sign}.3f}, {high:{sign}.3f}]"

    cells = [[cell([float(r[f"{stage}_{k}"]) for r in rows]) for k in ("true", "accuracy")]
             for stage in ("supervised", "ppo", "judge", "dpo", "grpo")]
    for stage, base in (("ppo", "supervised"), ("judge", "supervised"), ("judge", "ppo"),
                        ("dpo", "supervised"), ("grpo", "supervised"),
                        ("grpo", "ppo")):  # paired: each seed's stage minus its own base
        cells.append([cell([float(r[f"{stage}_{k}"]) - float(r[f"{base}_{k}"]) for r in rows],
                           "+") for k in ("true", "accuracy")])
    cells.append([cell([float(r["rm_pair_accuracy"]) for r in rows])])
    cells.append([cell([float(r["r_std"]) for r in rows])])
    return cells, [int(r["seed"]) for r in rows]


def overopt(name, path=CURVES):
    """Seed 0's PPO run `name`: (learned reward, true score, KL) of the sampled answers,
    each the mean of the first 5 steps and of the last 5, as the page writes them."""
    rows = [r for r in csv.DictReader(open(path)) if r["run"] == name and r["seed"] == "0"]
    mean = lambda part, key: sum(float(r[key]) for r in part) / len(part)  # noqa: E731
    return [(f"{mean(rows[:5], k):{f}}", f"{mean(rows[-5:], k):{f}}")
            for k, f in (("rm_score", "+.2f"), ("true_score", ".3f"), ("kl", ".2f"))]


def overopt_has(name, path=CURVES):
    return any(r["run"] == name for r in csv.DictReader(open(path)))


def plot(chinese=False):
    """docs/rlhf_overoptimisation.png: learned reward and true score of PPO's samples against
    sqrt(KL to the supervised model), seed 0 at beta 0.1 (default) and at beta 1; `chinese`:
    its words from locale/output.zh-CN.md, as .zh-CN.png."""
    sys.path.insert(0, str(ROOT))
    import numpy as np

    import help_zh
    import plots

    if chinese:
        help_zh.print_in_chinese()

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
        ax.set(title=title, xlabel="sqrt(KL(pi || pi_ref)) per answer, nats^0.5")
        ax.legend(fontsize=7)
    fig.suptitle("PPO's sampled answers, seed 0, one dot per PPO step", fontsize=9)
    fig.tight_layout()
    path = FIGURE.with_suffix(".zh-CN.png") if chinese else FIGURE
    plots.save_whole(plt, fig, path, dpi=90)
    print(f"wrote {path}")


def main():
    if "--plot" in sys.argv:
        sys.path.insert(0, str(ROOT))
        import help_zh
        return plot(chinese=help_zh.wanted(sys.argv[1:])[2])  # --lang zh, as the scripts read it
    if "--table" in sys.argv:
        cells, seeds = summary()
        print(f"seeds {seeds}\n" + "\n".join(" | ".join(c) for c in cells))
        names = [n for n in ("default", "beta 1", "judge") if overopt_has(n)]
        return print("\n".join(f"{n}: {overopt(n)}" for n in names))
    if "--grpo" in sys.argv:
        done = {r["seed"] for r in csv.DictReader(open(GRPO))} if GRPO.exists() else set()
        with tempfile.TemporaryDirectory() as tmp:
            for seed in GRPO_SEEDS:
                if str(seed) in done:  # a record row per seed, kept: run again to go on
                    continue
                row, printed = grpo_beside(seed, tmp)
                if printed != (row["supervised_true"], row["supervised_accuracy"]):
                    sys.exit(f"seed {seed}: the supervised model measured {row} here, but "
                             f"rlhf_addition.py printed {printed}: not the same model")
                append(GRPO, [row])
                print(row, flush=True)
        return
    out, runs = (JUDGE, JUDGE_RUNS) if "--judge" in sys.argv else (OUT, RUNS)
    done = {(r["seed"], r["run"]) for r in csv.DictReader(open(out))} if out.exists() else set()
    with tempfile.TemporaryDirectory() as tmp:
        for seed, name, flags in runs:
            if (str(seed), name) in done:  # a record row per run, kept: run again to go on
                continue
            row, curve = one(seed, name, flags, tmp)
            append(out, [row])
            append(CURVES, curve)
            print(row, flush=True)


if __name__ == "__main__":
    main()
