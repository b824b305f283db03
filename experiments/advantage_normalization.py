"""Question: what does normalizing the advantages do? (PPO on CartPole-v1)

ppo_cartpole.py normalizes the advantages to mean 0 and std 1 within each minibatch, as
the PPO reference code does (one of "The 37 Implementation Details of PPO"). The variant
turns it off (--no-norm-adv, an option the script already has). What to look for: without
it the size of the policy's step follows the size of the advantages, which changes as V
learns and as rewards pile up; with reward scaling (0.05 here), Adam's per-parameter steps
and the gradient-norm clip, their raw scale may matter little. Expect a difference in speed, if
any, and say whether it is larger than the seeds' spread.

    python experiments/advantage_normalization.py          # 5 seeds x 2 variants
    python experiments/advantage_normalization.py --quick  # one seed, a smoke test
"""

import lab  # noqa: F401  (first: it puts the scripts on the path)

import ppo_cartpole

VARIANTS = {
    "original: advantages normalized": {},
    "variant: not normalized": {"config": {"norm_adv": False}},
}

if __name__ == "__main__":
    lab.main("advantage_normalization", ppo_cartpole, VARIANTS, budget=60_000)
