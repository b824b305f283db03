"""Exercise: PPO-penalty's loss (Schulman et al. 2017, eq. 8).

From tutorial 001 (PPO1: the KL penalty) : maximize mean(r A) - beta * KL(pi_old(.|s), pi(.|s)),
so the loss is its negative. With two actions the KL is exact (torch's kl_divergence of the
two Categorical distributions), no sample estimate needed. The lines around the blank are
the script's own.

    python exercises/check.py kl_penalty
The reference answer: ppo_kl_cartpole.compute_loss_pi (ppo_kl_cartpole.py).

练习：PPO-penalty 的损失（Schulman 等 2017 的式 8）。对照教程 001 的 PPO1：最大化
mean(r A) - beta * KL(pi_old, pi)，损失取负。KL 的方向是 pi_old 在前。参考答案：
ppo_kl_cartpole.compute_loss_pi。
"""

import torch
from torch.distributions import Categorical, kl_divergence


def compute_loss_pi(policy, data, beta):
    """(loss_pi, entropy, info with "kl") on a batch: data["obs"], ["act"], ["adv"], ["logp"]
    (log pi_old(a|s)) and ["logits_old"] (pi_old in full, (B, n_actions)).

        r_t     = exp(log pi(a_t|s_t) - log pi_old(a_t|s_t))
        kl      = mean over s of KL(pi_old(.|s) || pi(.|s))
        loss_pi = -mean(r_t * A_t) + beta * kl

    在一批数据上返回 (loss_pi, entropy, info)，info 里有 "kl"：data["obs"]、["act"]、["adv"]、
    ["logp"]（log pi_old(a|s)）和 ["logits_old"]（完整的 pi_old，(B, n_actions)）。公式见上：kl 是
    各状态上 KL(pi_old(.|s) || pi(.|s)) 的均值，loss_pi = -mean(r_t * A_t) + beta * kl。
    """
    obs, act, adv, logp_old = data["obs"], data["act"], data["adv"], data["logp"]
    dist = Categorical(logits=policy(obs))  # pi(.|s)
    logp = dist.log_prob(act)  # log pi(a|s) of the taken actions, (B,)
    # Your code here (你的代码写在这里): the ratio, kl, then loss_pi.
    raise NotImplementedError("not written yet")
    return loss_pi, dist.entropy().mean(), dict(kl=kl.detach())
