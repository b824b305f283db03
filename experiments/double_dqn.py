"""Question: does DQN's max overestimate, and what does Double DQN's cure cost? (DQN, CartPole-v1)

DQN's target r + gamma * max_a Q'(s', a) lets the target network both pick and value the next
action, so its noise is picked upward: the max of noisy estimates is biased high (van Hasselt
et al. 2016). Double DQN picks with the network and values with the target network,
Q'(s', argmax_a Q(s', a)). The variants are the script's flag --double, at its defaults
otherwise. What to look for: Q(s, argmax Q), the network's estimate on the states the greedy
policy visits, beside the discounted return it really obtains from them (progress.csv's
q_greedy and mc_return, measured every 10 learning phases); their gap, per seed, is written
to double_dqn_checks.csv. With a reward of 1 per step and gamma 0.99, no discounted return
exceeds 100. And the learning: the steps until the last 20 training episodes average 475.

    python experiments/double_dqn.py          # 5 seeds x 2 variants
    python experiments/double_dqn.py --quick  # one seed, a smoke test
"""

import csv

import numpy as np

import lab  # noqa: F401  (first: it puts the scripts on the path)

import common
import dqn_cartpole

VARIANTS = {
    "original: DQN, max_a Q'(s', a) (the default)": {},
    "variant: Double DQN, Q'(s', argmax_a Q(s', a)) (--double)": {"config": {"double": True}},
}
PANELS = [("q_greedy", "Q(s, argmax Q): the network's estimate", False),
          ("mc_return", "discounted return obtained", False)]


def save_checks(curves, path):
    """Every check of Q against the return (variant, seed, step, Q, return, their gap) in one
    CSV, and per variant the seeds' median gap printed: median [min, max] over the seeds."""
    print("\nQ(s, argmax Q) - discounted return at the checks: each seed's median, their "
          "median [min, max]")
    with common.written_whole(path) as tmp, open(tmp, "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["variant", "seed_index", "global_step", "q_greedy", "mc_return", "gap"])
        for variant, runs in curves.items():
            medians = []
            for seed_index, (_, _, kept) in enumerate(runs):
                (steps, q), (_, g) = kept["q_greedy"], kept["mc_return"]
                checked = np.isfinite(q) & np.isfinite(g)
                for step, qi, gi in zip(steps[checked], q[checked], g[checked]):
                    writer.writerow([variant, seed_index, int(step), f"{qi:.6g}", f"{gi:.6g}",
                                     f"{qi - gi:.6g}"])
                medians.append(float(np.median((q - g)[checked])))
            print(f"{variant:50} {np.median(medians):+8.2f} [{min(medians):+.2f}, "
                  f"{max(medians):+.2f}]")
    return path


def more(curves, folder, settings):
    return [save_checks(curves, folder / "double_dqn_checks.csv")]


if __name__ == "__main__":
    lab.main("double_dqn", dqn_cartpole, VARIANTS, budget=50_000, quick_budget=1500,
             panels=PANELS, more=more, quick_settings=dict(q_check_every=2, start_steps=500))
