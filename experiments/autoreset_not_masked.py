"""Question: what if the vector env's autoreset step is not masked? (PPO on CartPole-v1)

gymnasium 1.x's vector envs (default NEXT_STEP mode) reset an env one step after it ended:
that step's action is ignored, its reward is 0, and its obs starts the new episode. The
original RolloutBuffer marks it (valid = False) and the update drops it. The variant below
stores it as an ordinary transition: an action that did nothing is credited with what the
next episode brings, and the final obs of one episode is paired with the first of the next.
What to look for: with 8 envs and episodes of tens to hundreds of steps, only a small share
of the batch is such steps, so expect a small effect on CartPole; say so if it is within the
seeds' spread.

    python experiments/autoreset_not_masked.py          # 5 seeds x 2 variants
    python experiments/autoreset_not_masked.py --quick  # one seed, a smoke test
"""

import lab  # noqa: F401  (first: it puts the scripts on the path)

import ppo_cartpole


def store_without_mask(self, t, obs, action, reward, terminated, truncated, valid):
    """The variant: RolloutBuffer.store that keeps every step, the autoreset ones included."""
    ORIGINAL_STORE(self, t, obs, action, reward, terminated, truncated, valid=True)


ORIGINAL_STORE = ppo_cartpole.RolloutBuffer.store
VARIANTS = {
    "original: autoreset steps dropped": {},
    "variant: autoreset steps kept": {
        "swap": [(ppo_cartpole.RolloutBuffer, "store", store_without_mask)]},
}

if __name__ == "__main__":
    lab.main("autoreset_not_masked", ppo_cartpole, VARIANTS, budget=60_000)
