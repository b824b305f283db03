"""Question: what does the baseline buy REINFORCE? (CartPole-v1)

reinforce_cartpole.py weighs each step's grad log pi(a_t|s_t) by G_t - V(s_t), a learned
state-value baseline; the variant weighs it by G_t alone (--no-baseline, an option the script
already has). Both estimate the same gradient: subtracting anything that depends on s_t only
leaves the expectation as it is (docs/why.md). What changes is the noise. Every update, the
script measures the variance of the per-episode gradient estimates under both weightings, on
the same episodes (var_ratio: with the baseline over without). What to look for: a ratio
below 1 in both variants (the baseline would help either run), and whether the run that uses
it reaches 475 in fewer steps, by more than the seeds' spread.

    python experiments/reinforce_baseline.py          # 5 seeds x 2 variants
    python experiments/reinforce_baseline.py --quick  # one seed, a smoke test
"""

import lab  # noqa: F401  (first: it puts the scripts on the path)

import reinforce_cartpole

VARIANTS = {
    "original: G_t - V(s_t)": {},
    "variant: G_t alone (no baseline)": {"config": {"baseline": False}},
}
PANELS = [("var_ratio", "gradient variance, with the baseline / without", True)]

if __name__ == "__main__":
    lab.main("reinforce_baseline", reinforce_cartpole, VARIANTS, budget=150_000, panels=PANELS)
