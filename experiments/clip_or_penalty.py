"""Question: what do PPO's clip and its KL penalty each do? (CartPole-v1)

PPO takes many gradient steps on one batch from pi_old: here 10 epochs of 4 minibatches.
Three ways to do it, side by side:
  no clip      maximize the ratio surrogate E[r_t A_t] alone, the PPO paper's "no clipping
               or penalty" (L^CPI, eq. 6): ppo_cartpole.py with compute_loss_pi below;
  the clip     ppo_cartpole.py as it is (L^CLIP, eq. 7);
  the penalty  ppo_kl_cartpole.py as it is (L^KLPEN, eq. 8, beta adapted after each update).
To see what each update did, every variant runs under the same wrapper around ppo_update: it
reads pi on the whole batch before and after the update and logs the exact KL(pi_old || pi)
and the ratio's smallest and largest value. It only reads, so it changes no number. What to
look for: how far one update moves pi (the KL) and how far the ratios leave 1, under each;
whether the clip keeps the ratio inside [0.8, 1.2] (it does not promise to); and what each
costs or gains in return.

    python experiments/clip_or_penalty.py          # 5 seeds x 3 variants
    python experiments/clip_or_penalty.py --quick  # one seed, a smoke test
"""

import lab  # noqa: F401  (first: it puts the scripts on the path)

import torch
from torch.distributions import Categorical
from torch.distributions import kl_divergence

import ppo_cartpole
import ppo_kl_cartpole


def compute_loss_pi_without_clip(policy, data, clip_coef):
    """The variant: ppo_cartpole.compute_loss_pi without its clamp; clip_coef is used only
    for clipfrac, the share of ratios outside [1 - eps, 1 + eps], which the log still shows."""
    obs, act, adv, logp_old = data["obs"], data["act"], data["adv"], data["logp"]
    dist = Categorical(logits=policy(obs))
    logp = dist.log_prob(act)
    ratio = torch.exp(logp - logp_old)
    loss_pi = -(ratio * adv).mean()  # L_CPI = E[r*A]  (Schulman et al. 2017, eq. 6)
    with torch.no_grad():
        log_ratio = logp - logp_old
        info = dict(approx_kl=((ratio - 1) - log_ratio).mean(),
                    clipfrac=((ratio - 1).abs() > clip_coef).float().mean(), ratio=ratio.detach())
    return loss_pi, dist.entropy().mean(), info


def measured(ppo_update):
    """ppo_update, plus three numbers in its stats (so in progress.csv): kl_after, the exact
    KL(pi_old || pi) over the batch, and ratio_low and ratio_high, the smallest and largest
    pi(a|s) / pi_old(a|s) over the batch, all after the update."""
    def update_and_measure(policy, value_net, optimizer, data, *rest):
        with torch.no_grad():
            old = Categorical(logits=policy(data["obs"]))  # pi_old: nothing has moved yet
        stats = ppo_update(policy, value_net, optimizer, data, *rest)
        with torch.no_grad():
            new = Categorical(logits=policy(data["obs"]))
            ratio = torch.exp(new.log_prob(data["act"]) - data["logp"])
            stats.update(kl_after=kl_divergence(old, new).mean().item(),
                         ratio_low=ratio.min().item(), ratio_high=ratio.max().item())
        return stats
    return update_and_measure


# The three numbers join what the script declares it logs (its LOGGED), for these runs only.
MEASURED = dict(kl_after=(None, "KL(pi_old || pi) after the update"),
                ratio_low=(None, "smallest ratio"), ratio_high=(None, "largest ratio"))
VARIANTS = {
    "original: the clip (ppo_cartpole)": {
        "swap": [(ppo_cartpole, "ppo_update", measured(ppo_cartpole.ppo_update)),
                 (ppo_cartpole, "LOGGED", {**ppo_cartpole.LOGGED, **MEASURED})]},
    "original: KL penalty (ppo_kl_cartpole)": {
        "script": ppo_kl_cartpole,
        "swap": [(ppo_kl_cartpole, "ppo_update", measured(ppo_kl_cartpole.ppo_update)),
                 (ppo_kl_cartpole, "LOGGED", {**ppo_kl_cartpole.LOGGED, **MEASURED})]},
    "variant: no clip (L_CPI)": {
        "swap": [(ppo_cartpole, "compute_loss_pi", compute_loss_pi_without_clip),
                 (ppo_cartpole, "ppo_update", measured(ppo_cartpole.ppo_update)),
                 (ppo_cartpole, "LOGGED", {**ppo_cartpole.LOGGED, **MEASURED})]},
}
PANELS = [("kl_after", "KL(pi_old || pi) after each update", True),
          ("ratio_high", "largest ratio after each update", True),
          ("ratio_low", "smallest ratio after each update", True)]

if __name__ == "__main__":
    lab.main("clip_or_penalty", ppo_cartpole, VARIANTS, budget=60_000, panels=PANELS)
