"""Question: tutorial 002's update or ppo_cartpole.py's minibatch epochs, on the arm? (Reacher-v5)

Two ways to spend one batch of 4000 steps, the rest of ppo_reacher.py alike (its defaults):
  tutorial 002's   up to 80 policy steps on the whole batch, each a full-batch gradient,
                   stopped before the step at which approx_kl > 1.5 x 0.01; then 80 value
                   steps (Spinning Up's update(); --update full_batch, the default)
  minibatch        10 passes over the batch in 32 shuffled minibatches of 125: 320 policy
                   and 320 value steps, each on 125 samples, with the same early stop
                   (ppo_cartpole.py's ppo_update, CleanRL's scheme; --update minibatch)
What to look for: the evaluation return of the mean action (gymnasium's reward threshold for
Reacher is -3.75); how many policy steps each scheme takes before the early stop ends them
(pi_steps), how far pi moves per batch (approx_kl after the update) and how fast sigma
shrinks (std_max). 200,000 steps each (a fifth of the default budget: where the curves
separate, if they do; docs/results.md has the 1M runs), an evaluation every 20,000 steps.

    python experiments/ppo_update_scheme.py            # 2 variants x 5 seeds
    python experiments/ppo_update_scheme.py --quick    # one seed, a smoke test
"""

import lab  # noqa: F401  (first: it puts the scripts on the path)

import ppo_reacher

VARIANTS = {
    "tutorial 002's update (the default)": {},
    "minibatch epochs (--update minibatch)": {"config": {"update": "minibatch"}},
}
PANELS = [("pi_steps", "policy steps taken on each batch", False),
          ("approx_kl", "approx_kl after the update", False),
          ("std_max", "sigma, largest dimension", False)]

if __name__ == "__main__":
    lab.main("ppo_update_scheme", ppo_reacher, VARIANTS, budget=200_000, solved=-3.75,
             what="evaluation return (the mean action)", quick_budget=1000, panels=PANELS,
             quick_settings=dict(num_steps=250, eval_every=500, train_pi_iters=5,
                                 train_v_iters=5), eval_every=20_000)
