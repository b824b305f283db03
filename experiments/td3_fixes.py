"""Question: what does each of TD3's three fixes do on its own? (TD3, Walker2d-v5)

The TD3 paper's ablation (Fujimoto et al. 2018, Table 2): start from DDPG and add one fix at a
time, then all three. td3_walker.py is DDPG plus the fixes, and each fix can be turned off:
  - clipped double Q off: the TD target takes the first target critic alone, as DDPG's does
    (td_target_of_q1_alone below, swapped in; the second critic is still trained, unused);
  - delayed policy updates off: --policy-delay 1 (the actor and the targets every step);
  - target policy smoothing off: --target-noise 0.
With all three off, the update is DDPG's (not bit for bit: the unused second critic is still
trained, and its initial weights shift the random streams). What to look for: the critic's estimate Q(s, mu(s))
on the evaluation states beside the discounted return mu really obtained from them (logged
in evaluations.csv as q_estimate and discounted_return; common.q_against_return), and their
gap, Q minus the return: DDPG's runs far above the return (docs/inside.md); which fix brings
it down? And the evaluation return. Walker2d-v5, 50,000 steps (10,000 of them the random
warm-up), an evaluation of 5 episodes every 5000 steps: a budget that shows the gap open,
not where the returns end (the 1M runs: docs/results.md).

    python experiments/td3_fixes.py --workers 16  # 5 variants x 5 seeds: 25 runs of ~7 min
    python experiments/td3_fixes.py --quick       # one seed, a smoke test
"""

import lab  # noqa: F401  (first: it puts the scripts on the path)

import csv

import common
import td3_walker


def td_target_of_q1_alone(reward, not_done, next_q1, next_q2, gamma):
    """Clipped double Q off: y = r + gamma * not_done * Q1'(s', a~), as DDPG's target."""
    return reward + gamma * not_done * next_q1


NO_MIN = [(td3_walker, "td_target", td_target_of_q1_alone)]
NO_DELAY, NO_SMOOTHING = {"policy_delay": 1}, {"target_noise": 0.0}
VARIANTS = {
    "DDPG: no fix": {"swap": NO_MIN, "config": {**NO_DELAY, **NO_SMOOTHING}},
    "+ clipped double Q only": {"config": {**NO_DELAY, **NO_SMOOTHING}},
    "+ delayed policy updates only": {"swap": NO_MIN, "config": NO_SMOOTHING},
    "+ target policy smoothing only": {"swap": NO_MIN, "config": NO_DELAY},
    "TD3: all three": {},
}
PANELS = [("q_estimate", "Q(s, mu(s)): the critic's estimate", False),
          ("discounted_return", "discounted return obtained", False)]
SETTINGS = dict(env_id="Walker2d-v5", start_steps=10_000, eval_every=5000, eval_episodes=5)


def save_every_evaluation(curves, path):
    """Every evaluation of every run (variant, seed, step, return, Q, discounted return, their
    gap) in one CSV: the record behind the docs' figures of this experiment."""
    with common.written_whole(path) as tmp, open(tmp, "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["variant", "seed_index", "global_step", "eval_mean", "q_estimate",
                         "discounted_return", "gap"])
        for variant, runs in curves.items():
            for seed_index, (steps, values, kept) in enumerate(runs):
                q, g = kept["q_estimate"][1], kept["discounted_return"][1]
                for step, value, qi, gi in zip(steps, values, q, g):
                    writer.writerow([variant, seed_index, int(step), f"{value:.6g}",
                                     f"{qi:.6g}", f"{gi:.6g}", f"{qi - gi:.6g}"])
    return path


def draw_gap(curves, path, start_steps):
    """The gap itself, Q(s, mu(s)) minus the discounted return obtained, per variant: the median
    over the seeds and their band (min to max), from the first evaluation after the
    `start_steps` of warm-up on."""
    plt = lab.plots.pyplot()
    fig, ax = plt.subplots(figsize=(10, 3.4))
    for color, (variant, runs) in enumerate(curves.items()):
        gaps = []
        for _, _, kept in runs:
            (steps, q), (_, g) = kept["q_estimate"], kept["discounted_return"]
            after = steps > start_steps  # the warm-up's untrained critic: left out
            gaps.append((steps[after], (q - g)[after]))
        lab.band(ax, gaps, color, f"{variant} (median of {len(runs)} seeds; band: min to max)")
    ax.axhline(0, color="k", lw=0.8)
    ax.set_ylabel("Q(s, mu(s)) - discounted return", fontsize=8)
    ax.set_xlabel("env steps")
    ax.set_title("td3_fixes: the critic's estimate minus what mu obtained (> 0: over)", fontsize=9)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1))
    fig.tight_layout()
    return lab.plots.save_whole(plt, fig, path, dpi=80)


def more(curves, folder, settings):
    """Beside the table and the figure: every evaluation, and the gap drawn (their paths)."""
    return [save_every_evaluation(curves, folder / "td3_fixes_evaluations.csv"),
            draw_gap(curves, folder / "td3_fixes_gap.png", settings["start_steps"])]


if __name__ == "__main__":
    lab.main("td3_fixes", td3_walker, VARIANTS, budget=50_000, solved=1000.0,
             what="evaluation return (no noise)", quick_budget=2500, panels=PANELS,
             quick_settings=dict(start_steps=1000, eval_every=2500), more=more, **SETTINGS)
