"""Sarsa and Q-learning on CliffWalking-v1, seeds 0-9, at Sutton & Barto's example 6.6
settings, named here (not taken from the script's defaults): 500 episodes, alpha 0.5,
epsilon 0.1, gamma 1. For each seed and agent, from q_learning_cliffwalking.train():

    online_last100   the mean online (epsilon-greedy) return of the last 100 episodes
    greedy_steps     the greedy path's length from the start (None: it loops for ever)
    greedy_return    its return (None: it loops), beside v_star_start, value iteration's V*(start)
    q_error_greedy   mean |Q(s, a) - Q*(s, a)| over the (s, a) pairs the greedy path takes

then, per agent, each figure's median and range over the seeds (a looping path's length and
return are left out of theirs, and counted). One run at a time in this process, each in a
temporary folder; a few seconds in all. The record: benchmarks/results/tabular_cliffwalking.json.

    python benchmarks/tabular_cliffwalking.py            # run the seeds, write the record
    python benchmarks/tabular_cliffwalking.py --table    # the table of the record
"""

import contextlib
import hashlib
import io
import json
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import gymnasium
import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
import q_learning_cliffwalking as tabular  # noqa: E402

OUT = ROOT / "benchmarks" / "results" / "tabular_cliffwalking.json"
SEEDS = range(10)
SETTINGS = dict(total_episodes=500, alpha=0.5, epsilon=0.1, gamma=1.0)  # S&B example 6.6
LAST = 100  # the episodes the online return averages
FIGURES = ("online_last100", "greedy_steps", "greedy_return", "q_error_greedy")


def one_seed(seed, folder):
    """The figures of both agents for one seed: {agent: {figure: value}}, v_star_start."""
    cfg = tabular.Config(**SETTINGS, seed=seed, run_dir=folder, curves=False, gifs=False,
                         print_every=10**9)
    with contextlib.redirect_stdout(io.StringIO()):
        result = tabular.train(cfg)
    row = dict(seed=seed, v_star_start=float(result["v_star"][result["start"]]))
    for agent in tabular.AGENTS:
        path, ret = result["paths"][agent]
        loops = bool(np.isnan(ret))
        row[agent] = dict(
            online_last100=float(np.mean(result["returns"][agent][-LAST:])),
            greedy_steps=None if loops else len(path),
            greedy_return=None if loops else float(ret),
            q_error_greedy=tabular.q_error(result["tables"][agent], result["q_star"], path))
    return row


def summary(rows):
    """{agent: {figure: {median, min, max, seeds}}}; a looping path counts in `loops`."""
    out = {}
    for agent in tabular.AGENTS:
        out[agent] = {"loops": sum(r[agent]["greedy_steps"] is None for r in rows)}
        for figure in FIGURES:
            values = [r[agent][figure] for r in rows if r[agent][figure] is not None]
            out[agent][figure] = dict(median=statistics.median(values), min=min(values),
                                      max=max(values), seeds=len(values))
    return out


def table(record):
    """The record as lines: a row per seed and agent, then the medians and ranges."""
    lines = [f"settings: {record['settings']}; V*(start) = {record['rows'][0]['v_star_start']:g}",
             "| seed | agent | online return, last 100 | greedy path: steps | return | "
             "mean abs(Q - Q*) on it |", "|---|---|---|---|---|---|"]
    for row in record["rows"]:
        for agent, name in tabular.AGENTS.items():
            f = row[agent]
            ret = "loops" if f["greedy_return"] is None else f"{f['greedy_return']:.0f}"
            lines.append(f"| {row['seed']} | {name} | {f['online_last100']:.1f} | "
                         f"{f['greedy_steps'] or 'loops'} | {ret} | {f['q_error_greedy']:.2f} |")
    for agent, name in tabular.AGENTS.items():
        s = record["summary"][agent]
        parts = [f"{figure} {s[figure]['median']:.4g} [{s[figure]['min']:.4g}, "
                 f"{s[figure]['max']:.4g}]" for figure in FIGURES]
        lines.append(f"{name}: median [min, max] over the seeds: {'; '.join(parts)}; "
                     f"greedy path loops in {s['loops']} of {len(record['rows'])} seeds")
    return lines


def summary_rows(record):
    """The results pages' table: per agent, each figure's median [min, max] over the seeds."""
    rows = ["| agent | online return, last 100 | greedy path: steps | its return | "
            "mean abs(Q - Q*) on it | greedy path loops |", "|---|---|---|---|---|---|"]
    for agent, name in tabular.AGENTS.items():
        s = record["summary"][agent]
        cells = [f"{s[figure]['median']:{spec}} [{s[figure]['min']:{spec}}, "
                 f"{s[figure]['max']:{spec}}]" for figure, spec in zip(FIGURES, (".1f", ".0f",
                                                                              ".0f", ".2f"))]
        rows.append(f"| {name} | {' | '.join(cells)} | {s['loops']} of "
                    f"{len(record['rows'])} seeds |")
    return rows


def main():
    if "--table" in sys.argv[1:]:
        record = json.loads(OUT.read_text())
        print("\n".join(table(record) + [""] + summary_rows(record)))
        return
    started, rows = time.time(), []
    with tempfile.TemporaryDirectory(prefix="tabular_") as folder:
        for seed in SEEDS:
            rows.append(one_seed(seed, folder))
            print(f"seed {seed}: " + "; ".join(
                f"{name} {rows[-1][agent]}" for agent, name in tabular.AGENTS.items()),
                flush=True)
    script = (ROOT / "q_learning_cliffwalking.py").read_bytes()
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True,
                            text=True, cwd=ROOT).stdout.strip()
    record = dict(settings=SETTINGS, seeds=list(SEEDS), rows=rows, summary=summary(rows),
                  seconds=round(time.time() - started, 1), commit=commit,
                  script_sha256=hashlib.sha256(script).hexdigest()[:16],
                  versions=dict(python=platform.python_version(), numpy=np.__version__,
                                gymnasium=gymnasium.__version__))
    tmp = OUT.with_suffix(".json.tmp")
    tmp.write_text(json.dumps(record, indent=1) + "\n")
    tmp.replace(OUT)
    print("\n".join(table(record)))
    print(f"record: {OUT}")


if __name__ == "__main__":
    main()
