"""Question: what if a time limit is treated as the episode's end? (DDPG, InvertedPendulum-v5)

The same question as truncation_as_termination.py, asked of DDPG. InvertedPendulum-v5 stops
an episode at 1000 steps by truncation, with the pole still up. ddpg_walker.py stores
not_done = 1 there (ReplayBuffer.add), so that transition's target bootstraps:
r + gamma * Q'(s', mu'(s')), about 100 for a balanced pole. The variant is the bug of a loop
written `done = terminated or truncated`: a wrapper that reports every truncation as a
termination, so the script stores not_done = 0 and the target is r = 1. The budget, 40,000
steps with the README's DDPG-in-minutes settings, gives the original 20,000 or more steps of
balancing the pole for all 1000 steps, so truncations happen. What to look for: unlike PPO's
GAE, which carries the wrong 0 back through the steps before it, DDPG's one-step target puts
it in one transition per 1000-step episode. The critic sees no clock in the obs, so it
averages that target into every similar state: like a discount of gamma * (1 - 1/1000)
instead of gamma, a value about 9% lower at most. Whether returns or Q show it is the question.

    python experiments/truncation_as_termination_ddpg.py          # 5 seeds x 2 variants
    python experiments/truncation_as_termination_ddpg.py --quick  # one seed, a smoke test
"""

import lab  # noqa: F401  (first: it puts the scripts on the path)

import gymnasium as gym

import common
import ddpg_walker


class TimeLimitAsTermination(gym.Wrapper):
    """The variant: the env, with terminated = terminated or truncated at every step."""

    def step(self, action):
        obs, reward, terminated, truncated, info = self.env.step(action)
        return obs, reward, terminated or truncated, truncated, info


def make_env_time_limit_as_termination(env_id):
    """The variant's env: common.make_continuous_env's, wrapped."""
    return TimeLimitAsTermination(ORIGINAL_MAKE_ENV(env_id))


ORIGINAL_MAKE_ENV = common.make_continuous_env
VARIANTS = {
    "original: bootstrap at the time limit": {},
    "variant: time limit as termination": {
        "swap": [(common, "make_continuous_env", make_env_time_limit_as_termination)]},
}
PANELS = [("q_estimate", "Q(s, mu(s)): the critic's estimate", False),
          ("discounted_return", "discounted return obtained", False)]

if __name__ == "__main__":
    lab.main("truncation_as_termination_ddpg", ddpg_walker, VARIANTS, budget=40_000,
             solved=1000.0, what="evaluation return (no noise)", quick_budget=1200,
             quick_settings=dict(start_steps=600, eval_every=600),
             panels=PANELS, **lab.DDPG_IN_MINUTES)
