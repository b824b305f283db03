"""Question: what if the critic's output keeps its last dimension? (DDPG, InvertedPendulum-v5)

Spinning Up's exercise 2.2 plants this bug. ddpg_walker.py's Critic returns Q as (B,): it
squeezes the (B, 1) of its last layer. The variant leaves it (B, 1). Nothing fails: the TD
target r + gamma * not_done * Q'(s', mu'(s')), with r shaped (B,), broadcasts to a (B, B)
matrix: y[i, j] = r_j + gamma * not_done_j * Q'(s'_i), and Q_i is fit to their mean over j, so
it keeps its own s' but loses its own reward and termination (torch only warns). Look for:
the original balances the pole (return 1000, the maximum) within 20k steps; the variant
should not learn at all, or far worse.

    python experiments/critic_output_shape.py          # 5 seeds x 2 variants, ~10 minutes
    python experiments/critic_output_shape.py --quick  # one seed, a smoke test
"""

import lab  # noqa: F401  (first: it puts the scripts on the path)

import warnings

import torch
import torch.nn.functional as F

import ddpg_walker


def forward_keeping_its_dimension(self, obs, action):
    """The variant: Critic.forward without the final squeeze(-1), Q shaped (B, 1)."""
    q = F.relu(self.l1(obs))
    q = F.relu(self.l2(torch.cat([q, action], dim=-1)))
    return self.l3(q)


VARIANTS = {
    "original: Q shaped (B,)": {},
    "variant: Q left (B, 1)": {
        "swap": [(ddpg_walker.Critic, "forward", forward_keeping_its_dimension)]},
}

if __name__ == "__main__":
    warnings.filterwarnings("ignore", message="Using a target size")  # the variant's broadcast
    lab.main("critic_output_shape", ddpg_walker, VARIANTS, budget=20_000, solved=1000.0,
             what="evaluation return (no noise)", quick_budget=1200,
             quick_settings=dict(start_steps=600, eval_every=600), **lab.DDPG_IN_MINUTES)
