"""Question: what does learning the temperature alpha change? (SAC, Walker2d-v5)

SAC's first version (Haarnoja et al. 2018a) fixed the entropy's weight alpha (on Walker2d as a
reward scale of 5, that is alpha = 0.2); the second (2018b, section 5) learns it, so that the
policy's entropy stays near a target, -dim(A) = -6 on Walker2d. sac_walker.py learns it by
default, and --alpha fixes it. The variants are that flag: learned (from alpha = 1) against
alpha fixed at 0.2. What to look for: the entropy estimate -mean log pi(a|s) of the last
minibatch before each evaluation beside its target (evaluations.csv: entropy and
target_entropy), alpha, and the evaluation return of the mean action tanh(mean). A fixed 0.2
pays for entropy at the same rate throughout; a learned alpha falls as long as the entropy is
above its target. Walker2d-v5, 50,000 steps (10,000 of them the random warm-up), an
evaluation of 5 episodes every 5000 steps, as experiments/td3_fixes.py: a budget that shows
how the entropy and alpha move, not where the returns end (the 1M runs: docs/results.md).
Three seeds, as dqn_target_period.py: each 50,000-step SAC run took 17 to 49 min on a busy CPU.

    python experiments/sac_temperature.py --workers 6  # 2 variants x 3 seeds: 6 runs
    python experiments/sac_temperature.py --quick       # one seed, a smoke test
"""

import lab  # noqa: F401  (first: it puts the scripts on the path)

import sac_walker

VARIANTS = {
    "learned alpha (the default)": {},
    "alpha fixed at 0.2 (--alpha 0.2)": {"config": {"alpha": 0.2}},
}
PANELS = [("entropy", "entropy: -mean log pi(a|s)", False),
          ("alpha", "alpha", True),
          ("q_estimate", "Q1(s, tanh(mean)): the critic's estimate", False)]
SETTINGS = dict(env_id="Walker2d-v5", start_steps=10_000, eval_every=5000, eval_episodes=5)

if __name__ == "__main__":
    lab.main("sac_temperature", sac_walker, VARIANTS, seeds=(0, 1, 2), budget=50_000, solved=1000.0,
             what="evaluation return (tanh(mean), no sampling)", quick_budget=2500,
             panels=PANELS, quick_settings=dict(start_steps=1000, eval_every=1250), **SETTINGS)
