"""Question: how much does exploring on the cliff's edge cost Q-learning, against Sarsa, as
epsilon changes? (q_learning_cliffwalking.py, CliffWalking-v1)

Q-learning learns Q*, whose greedy path runs along the cliff's edge (13 steps, return -13),
and keeps exploring there: each random step off the edge costs -100 and the walk back. Sarsa
learns the value of the epsilon-greedy policy it follows, falls included, so its greedy path
keeps its distance, the farther the more it explores. Both agents of each run share the seed;
the variants are --epsilon, the other settings S&B example 6.6's (500 episodes, alpha 0.5,
gamma 1). What to look for: the online return (the mean of the last 100 episodes, while
exploring) of each agent, and its greedy path's return once exploring stops. Q-learning's
greedy return is -13 at every epsilon, and its online return falls as epsilon grows (seeds
0-4, medians: -16 at 0.01, -51 at 0.1, -107 at 0.2). Sarsa's falls less (-16, -26, -51):
at 0.01 the two are level, the edge being nearly safe, and Sarsa's greedy path comes closer
to it (15 steps, against 17 at 0.1). At 0.2 Sarsa's greedy path loops in 3 of 5 seeds:
with alpha 0.5 its values follow the last few episodes (a move into the wall can edge out the
right one by a few hundredths). Five seeds;
a run takes under a second, so they run one after another in this process (--workers is
accepted and changes nothing; --cluster is refused).

    python experiments/sarsa_vs_q_learning.py          # 3 epsilons x 5 seeds
    python experiments/sarsa_vs_q_learning.py --quick  # one seed, 50 episodes: a smoke test
"""

import contextlib
import csv
import io
import statistics
import sys
import tempfile
import time

import numpy as np

import lab  # first: it puts the scripts on the path

import common
import plots
import q_learning_cliffwalking as tabular

NAME = "sarsa_vs_q_learning"
VARIANTS = {  # --epsilon; S&B's 0.1 the original
    "original: epsilon 0.1 (S&B example 6.6)": 0.1,
    "variant: epsilon 0.01": 0.01,
    "variant: epsilon 0.2": 0.2,
}
SETTINGS = dict(total_episodes=500, alpha=0.5, gamma=1.0)  # S&B example 6.6
LAST = 100  # the episodes the online return averages
SEEDS = (0, 1, 2, 3, 4)


def one_run(epsilon, seed, episodes, folder):
    """{agent: (online returns, greedy path's return: nan if it loops, its length)}."""
    cfg = tabular.Config(**{**SETTINGS, "total_episodes": episodes}, epsilon=epsilon, seed=seed,
                         run_dir=folder, curves=False, gifs=False, print_every=10**9)
    with contextlib.redirect_stdout(io.StringIO()):
        result = tabular.train(cfg)
    if result["interrupted"]:
        raise KeyboardInterrupt
    return {agent: (result["returns"][agent], result["paths"][agent][1],
                    len(result["paths"][agent][0])) for agent in tabular.AGENTS}


def spread(values):
    """'median [min, max]' of the values that are numbers; '(k loop)' for the nan ones."""
    kept = [v for v in values if not np.isnan(v)]
    loops = len(values) - len(kept)
    text = f"{statistics.median(kept):6.1f} [{min(kept):.1f}, {max(kept):.1f}]" if kept else "-"
    return text + (f" ({loops} loop{'s' * (loops > 1)})" if loops else "")


def report(runs, folder, keep):
    """Print the table; with `keep`, write <NAME>.csv and <NAME>.png into `folder`."""
    print(f"\n{'variant':42} {'agent':11} {'online return, last ' + str(LAST):>30} "
          f"{'greedy path return':>26}")
    rows = []
    for variant, seeds in runs.items():
        for agent, name in tabular.AGENTS.items():
            online = [float(np.mean(r[agent][0][-LAST:])) for r in seeds]
            greedy = [float(r[agent][1]) for r in seeds]
            print(f"{variant:42} {name:11} {spread(online):>30} {spread(greedy):>26}")
            rows += [dict(variant=variant, epsilon=VARIANTS[variant], seed_index=i, agent=agent,
                          online_last100=o, greedy_return="" if np.isnan(g) else g,
                          greedy_steps=r[agent][2]) for i, (o, g, r) in
                     enumerate(zip(online, greedy, seeds))]
    if not keep:
        return
    folder.mkdir(parents=True, exist_ok=True)
    with common.written_whole(folder / f"{NAME}.csv") as tmp, open(tmp, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    plt = plots.pyplot()
    fig, axes = plt.subplots(1, len(runs), figsize=(4 * len(runs), 3.6), sharey=True)
    for ax, (variant, seeds) in zip(axes, runs.items()):
        for color, (agent, name) in enumerate(tabular.AGENTS.items()):
            curves = [(np.arange(1, len(r[agent][0]) + 1), plots.running_mean(r[agent][0], LAST))
                      for r in seeds]
            lab.band(ax, curves, color, f"{name} (median of {len(seeds)} seeds; band: range)")
        ax.axhline(-13, color="gray", ls="--", lw=1)  # V*(start): the optimal path's return
        ax.set(title=variant, xlabel="episode", ylim=(-120, 0))
    axes[0].set_ylabel(f"online return, mean of the last {LAST} episodes")
    axes[0].legend(fontsize=7, loc="lower right")
    fig.tight_layout()
    print(f"\nwrote {plots.save_whole(plt, fig, folder / f'{NAME}.png', dpi=80)} and {NAME}.csv")


def main():
    if {"-h", "--help"} & set(sys.argv[1:]):
        print(__doc__.strip())
        raise SystemExit(0)
    given = lab.options(sys.argv[1:])
    if given["cluster"]:
        lab.wrong("--cluster: these runs take seconds, one after another in this process")
    seeds, episodes = ((0,), 50) if given["quick"] else (SEEDS, SETTINGS["total_episodes"])
    started, runs = time.time(), {}
    try:  # SIGTERM (kill PID) as Ctrl-C, as lab.main has it
        with common.sigterm_as_ctrl_c(), tempfile.TemporaryDirectory(prefix="experiment_") as tmp:
            for variant, epsilon in VARIANTS.items():
                runs[variant] = [one_run(epsilon, seed, episodes, tmp) for seed in seeds]
    except KeyboardInterrupt:
        how, code = common.stopped_by()
        print(f"\ninterrupted ({how}): nothing kept; run it again (seconds)", file=sys.stderr)
        raise SystemExit(code) from None
    report(runs, lab.DOCS if given["docs"] else lab.OUT, keep=not given["quick"])
    print(f"\n{len(VARIANTS)} variants x {len(seeds)} seeds x {episodes} episodes in "
          f"{time.time() - started:.0f} s")


if __name__ == "__main__":
    main()
