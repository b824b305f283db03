"""The docs' pictures that no single training run draws: PPO's clipped objective against the
ratio (the PPO paper's Figure 1, drawn here from the formula), for docs/why.md; and DDPG's
and TD3's Q against the discounted return side by side, from the committed evaluations of
two runs (seed 0, the defaults, the same first 200,000 steps), for docs/inside.md.

    python docs/draw_figures.py     # writes docs/ppo_clip_objective.png, docs/inside_td3_ddpg.png
    python docs/draw_figures.py --lang zh   # their Chinese twins, *.zh-CN.png
"""

import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import ddpg_walker  # noqa: E402
import help_zh  # noqa: E402
import plots  # noqa: E402


def clip_term(r, adv, eps):
    """One sample's term of L_CLIP: min(r A, clip(r, 1 - eps, 1 + eps) A)  (Schulman et al.
    2017, eq. 7), for ratios r (an array)."""
    return np.minimum(r * adv, np.clip(r, 1 - eps, 1 + eps) * adv)


def draw_clip_objective(path, eps=0.2):
    """L_CLIP's term against r for A = +1 and A = -1, beside L_CPI's r A (dashed)."""
    plt = plots.pyplot()
    r = np.linspace(0.0, 2.0, 401)
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.4))
    for ax, adv in zip(axes, (1.0, -1.0)):
        ax.plot(r, r * adv, color="gray", ls="--", lw=1, label="L_CPI: r A")
        ax.plot(r, clip_term(r, adv, eps), color="C0", lw=2,
                label="L_CLIP: min(r A, clip(r, 1-eps, 1+eps) A)")
        flat = r > 1 + eps if adv > 0 else r < 1 - eps
        ax.fill_between(r, -2.2, 2.2, where=flat, color="C0", alpha=0.1,
                        label="flat: no gradient")
        ax.axvline(1, color="k", lw=0.6)
        ax.plot([1], [adv], "o", color="C3", ms=5, label="r = 1: where each update starts")
        ax.set_ylim(-2.2, 2.2)
        ax.set_xlabel("r = pi(a|s) / pi_old(a|s)")
        ax.set_title(f"A = {adv:+g} (eps = {eps:g})", fontsize=10)
        ax.legend(fontsize=7, loc="lower right" if adv > 0 else "upper right")
    axes[0].set_ylabel("the sample's term of the objective")
    fig.tight_layout()
    return plots.save_whole(plt, fig, path, dpi=90)


def draw_q_against_return(path, upto=200_000):
    """Q(s, mu(s)) against the discounted return, DDPG beside TD3, seed 0, up to `upto`."""
    results = ROOT / "benchmarks" / "results"
    runs = {"DDPG (ddpg_walker.py)": results / "ddpg_walker_200k_inside" / "evaluations.csv",
            "TD3 (td3_walker.py)": results / "td3_walker_1m" / "seed0" / "evaluations.csv"}
    plt = plots.pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), sharey=True)
    for ax, (name, csv_path) in zip(axes, runs.items()):
        table = plots.read_csv(csv_path)
        keep = table["global_step"] <= upto
        table = {k: v[keep] for k, v in table.items()}
        labels = {k: what for k, (_, what) in ddpg_walker.LOGGED.items()}
        plots.lines("q_estimate", "discounted_return")[1](  # the warm-up shaded, its point
            [ax], dict(table=table, labels=labels, warm_up=25_000))  # not joined to the rest
        for line in ax.get_lines():
            line.set_marker(".")  # one point per evaluation
        ax.set_title(f"{name}, Walker2d-v5, seed 0, the first {upto:,} steps", fontsize=9)
    axes[0].set_ylabel("mean over the states of\nthe evaluation episodes", fontsize=8)
    fig.tight_layout()
    return plots.save_whole(plt, fig, path, dpi=110)  # 7-point Chinese legible


if __name__ == "__main__":
    zh = help_zh.wanted(sys.argv[1:])[2]  # --lang zh (or a Chinese locale), as the scripts
    if zh:  # the words from locale/output.zh-CN.md
        help_zh.print_in_chinese()
    suffix = ".zh-CN.png" if zh else ".png"
    print(draw_clip_objective(ROOT / "docs" / f"ppo_clip_objective{suffix}"))
    print(draw_q_against_return(ROOT / "docs" / f"inside_td3_ddpg{suffix}"))
