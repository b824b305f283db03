"""The checks of exercises/kl_penalty.py, PPO-penalty's loss: surrogate minus beta times the KL:
its worked cases, its named mistakes and its runs."""

import math

import torch
from torch.distributions import Categorical, kl_divergence

from checking import tr, t, scalar, Fixed, logits_names
import runs

SCRIPT = "ppo_kl_cartpole"
FUNCTION = "compute_loss_pi"
ORDER = 4  # its row in docs/exercises.md's table
CONFIG_NAMES = dict(beta="beta_init")  # the first update's beta, Config's name
OUTPUTS = ("loss_pi", "entropy", "info")
RUN = runs.CARTPOLE
LOOP = dict(runs.CARTPOLE_LOOP, total_timesteps=1280)
LEARN = runs.PPO_LEARN


def loop_hint():
    return runs.ON_REAL_DATA()


def cases():
    # pi = (0.5, 0.5), pi_old = (0.25, 0.75): r = 2 for action 0, 2/3 for action 1: one ratio
    # above 1 and one below, so that pi_old / pi (1/2 and 3/2) shows.
    policy = Fixed(t([0.0, 0.0]).expand(2, 2), names=logits_names())
    logits_old = torch.log(t([0.25, 0.75], [0.25, 0.75]))
    data = dict(obs=torch.zeros(2, 1), act=torch.tensor([0, 1]), adv=t(1.0, -1.0),
                logp=torch.log(t(0.25, 0.75)), logits_old=logits_old)
    kl = 0.25 * math.log(0.25 / 0.5) + 0.75 * math.log(0.75 / 0.5)  # KL(pi_old || pi)
    surrogate = (2.0 * 1.0 + (2 / 3) * -1.0) / 2
    return [(tr(f"beta = {beta}: -mean(r A) + beta KL(pi_old || pi), KL = {kl:.4f}",
                f"beta = {beta}：-mean(r A) + beta KL(pi_old || pi)，KL = {kl:.4f}"),
             (policy, data, beta), (scalar(-surrogate + beta * kl), None, None))
            for beta in (0.5, 2.0)]


def mistakes(policy, data, beta):
    dist = Categorical(logits=policy(data["obs"]).detach())
    old = Categorical(logits=data["logits_old"])
    r = torch.exp(dist.log_prob(data["act"]) - data["logp"])
    s, kl, reverse = (r * data["adv"]).mean(), kl_divergence(old, dist).mean(), kl_divergence(
        dist, old).mean()
    inverted = (torch.exp(data["logp"] - dist.log_prob(data["act"])) * data["adv"]).mean()
    return [(tr("the ratio upside down: pi_old / pi, exp(logp_old - logp)",
                "比值倒过来了：π_old / π，即 exp(logp_old - logp)"), -inverted + beta * kl),
            (tr("the KL the other way round: KL(pi || pi_old); kl_divergence(p, q) is KL(p || q)",
                "KL 的方向反了：写成了 KL(π || π_old)；kl_divergence(p, q) 是 KL(p || q)"),
             -s + beta * reverse),
            (tr("the surrogate's sign: +mean(r A) where the loss has -mean(r A)",
                "代理目标的符号反了：损失里应该是 -mean(r A)"), s + beta * kl),
            (tr("the penalty's sign: - beta * KL where the loss adds it",
                "惩罚项的符号反了：损失里应该加上 β * KL"), -s - beta * kl),
            (tr("a sample estimate of the KL, mean(logp_old - logp), where the exact KL of the two "
                "distributions belongs (kl_divergence)", "用了 KL 的样本估计 mean(logp_old - logp)，"
                "应该用两个分布的精确 KL（kl_divergence）"),
             -s + beta * (data["logp"] - dist.log_prob(data["act"])).mean()),
            (tr("the ratio without exp: logp - logp_old, a log-ratio, where r = exp(logp - "
                "logp_old)", "比值没有取 exp：logp - logp_old 是对数比值，r = exp(logp - logp_old)"),
             -((dist.log_prob(data["act"]) - data["logp"]) * data["adv"]).mean() + beta * kl),
            (tr("the KL summed over the batch (.sum()) where its mean belongs (.mean())",
                "KL 对批量求了和（.sum()），应该求均值（.mean()）"),
             -s + beta * kl_divergence(old, dist).sum())]
