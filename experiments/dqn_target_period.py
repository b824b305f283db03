"""Question: how often should DQN copy its network into the target network? (DQN, CartPole-v1)

The target y = r + gamma * max_a Q'(s', a) comes from a copy Q' of the network, refreshed every
target_update_interval gradient steps (Mnih et al. 2015: every 10,000 on Atari). Between two
copies the regression target stands still; each copy lets Q look one step further ahead, so
frequent copies build Q faster, and a copy taken too often chases its own updates as no
target network would. The variants are the script's setting --target-update-interval:
every 16 gradient steps, the default 64 (two copies per learning phase of 128), and 512
(one per four phases), at the defaults otherwise. What to look for: the steps until the last
20 training episodes average 475, and Q(s, argmax Q) on the greedy policy's states beside the
discounted return obtained from them (no discounted return exceeds 100 here).

    python experiments/dqn_target_period.py          # 3 seeds x 3 variants
    python experiments/dqn_target_period.py --quick  # one seed, a smoke test
"""

import lab  # noqa: F401  (first: it puts the scripts on the path)

import dqn_cartpole

VARIANTS = {
    "variant: copy every 16 gradient steps": {"config": {"target_update_interval": 16}},
    "original: copy every 64 (the default)": {},
    "variant: copy every 512": {"config": {"target_update_interval": 512}},
}
PANELS = [("q_greedy", "Q(s, argmax Q): the network's estimate (log)", True),  # it may diverge
          ("mc_return", "discounted return obtained", False)]

if __name__ == "__main__":
    lab.main("dqn_target_period", dqn_cartpole, VARIANTS, seeds=(0, 1, 2), budget=50_000,
             quick_budget=1500, panels=PANELS,
             quick_settings=dict(q_check_every=2, start_steps=500))
