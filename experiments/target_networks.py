"""Question: what do DDPG's target networks do? (DDPG, InvertedPendulum-v5)

The TD target r + gamma * not_done * Q'(s', mu'(s')) uses slow copies of the critic and the
actor, moved toward them by soft_update with rate tau after every step. tau = 1 copies the
networks whole each step: no target networks, the critic chases a target that moves with every
one of its own updates. The TD3 paper (Fujimoto et al. 2018, Figure 3) shows the value
estimate then unstable, on Hopper-v1. The variants are the setting the script already has
(--tau): the script's default 0.005 against 1, with the README's DDPG-in-minutes settings
otherwise. What to look for: the evaluation return, and the critic's estimate Q(s, mu(s)) on
the evaluation states beside the discounted return mu really obtained from them (logged in
evaluations.csv as q_estimate and discounted_return); for a balanced pole the discounted
return is about 100 (gamma = 0.99, reward 1 per step).

    python experiments/target_networks.py          # 5 seeds x 2 variants
    python experiments/target_networks.py --quick  # one seed, a smoke test
"""

import lab  # noqa: F401  (first: it puts the scripts on the path)

import ddpg_walker

VARIANTS = {
    "original: tau = 0.005": {"config": {"tau": 0.005}},
    "variant: tau = 1 (no target networks)": {"config": {"tau": 1.0}},
}
PANELS = [("q_estimate", "Q(s, mu(s)): the critic's estimate", False),
          ("discounted_return", "discounted return obtained", False)]

if __name__ == "__main__":
    lab.main("target_networks", ddpg_walker, VARIANTS, budget=20_000, solved=1000.0,
             what="evaluation return (no noise)", quick_budget=1200,
             quick_settings=dict(start_steps=600, eval_every=600), panels=PANELS,
             **lab.DDPG_IN_MINUTES)
