"""Question: what if a time limit is treated as the episode's end? (PPO on CartPole-v1)

CartPole-v1 stops any episode that reaches 500 steps: a truncation, the pole still up,
and the state had a future. The original GAE (common.gae) bootstraps from V(final obs)
there; the variant below, the bug of many hand-written loops (and an open question in
CleanRL's issues), treats it like a termination: no future, a value target of about 0 for
states near step 500. What to look for: the variant learns as fast at first (its episodes
are short), then its return sags or wobbles once episodes reach the limit, because V is told
that good states near the limit are worth nothing.

    python experiments/truncation_as_termination.py          # 5 seeds x 2 variants
    python experiments/truncation_as_termination.py --quick  # one seed, a smoke test
"""

import lab  # noqa: F401  (first: it puts the scripts on the path)

import common
import ppo_cartpole


def gae_truncation_as_termination(rewards, values, next_values, terminated, truncated, gamma,
                                  lam):
    """The variant: common.gae with every truncation passed as a termination (no bootstrap)."""
    return ORIGINAL_GAE(rewards, values, next_values, terminated | truncated, truncated, gamma,
                        lam)


ORIGINAL_GAE = common.gae
VARIANTS = {
    "original: bootstrap at the time limit": {},
    "variant: time limit as termination": {
        "swap": [(common, "gae", gae_truncation_as_termination)]},
}

if __name__ == "__main__":
    lab.main("truncation_as_termination", ppo_cartpole, VARIANTS, budget=60_000)
