"""Question: what does GAE's lambda trade? (PPO on CartPole-v1)

common.gae sums the TD errors delta_t with weights (gamma lam)^k. lam = 0 keeps only the
first: A_t = r_t + gamma V(s_{t+1}) - V(s_t), low variance but biased by whatever V gets
wrong. lam = 1 sums them all: the discounted rewards to the episode's end (or the rollout's,
bootstrapped) minus V(s_t), less biased but noisier. The default 0.95 sits between (the
variants are settings the script already has: --lam). What to look for: lam = 0 leans on a
critic that starts knowing nothing, so expect it to learn slowest at first; whether lam = 1's
noise costs anything on CartPole's short rollouts is the question.

    python experiments/gae_lambda.py          # 5 seeds x 3 variants
    python experiments/gae_lambda.py --quick  # one seed, a smoke test
"""

import lab  # noqa: F401  (first: it puts the scripts on the path)

import ppo_cartpole

VARIANTS = {
    "original: lam = 0.95": {},
    "variant: lam = 0 (one-step TD)": {"config": {"lam": 0.0}},
    "variant: lam = 1 (returns minus V)": {"config": {"lam": 1.0}},
}

if __name__ == "__main__":
    lab.main("gae_lambda", ppo_cartpole, VARIANTS, budget=60_000)
