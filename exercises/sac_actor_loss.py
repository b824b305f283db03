"""Exercise: SAC's actor loss, with the tanh squash's log-probability correction (Haarnoja et
al. 2018b, eq. 9 and appendix C, eq. 26).

From sac_walker.py: the actor draws u ~ N(mean, sigma) by reparameterisation (u = mean + sigma
* eps, so the gradient passes through the sample), squashes it into the action box,
a = bias + scale * tanh(u), and pays for its entropy:
    log pi(a|s) = sum_i [log N(u_i; mean_i, sigma_i) - log(scale_i * (1 - tanh(u_i)^2))]
    J_pi = mean [alpha * log pi(a|s) - min(Q1(s, a), Q2(s, a))]
The second term of log pi is the change of variables from u to a: tanh squeezes the density,
so a's density is u's divided by the slope da/du. In float32, 1 - tanh(u)^2 rounds to 0 once
|u| > ~9; write log(1 - tanh(u)^2) as 2 * (log 2 - u - softplus(-2u)), the same number.

    python exercises/check.py sac_actor_loss
The reference answer: sac_walker.compute_loss_actor with sac_walker.Actor.sample and
sac_walker.squashed_log_prob (sac_walker.py): do not call actor.sample here, write it.

中文：练习：SAC 演员的损失，带 tanh 压缩的对数概率修正。用重参数化采样 u = mean + sigma * eps
（梯度能穿过采样），压缩到动作范围 a = bias + scale * tanh(u)；由变量替换，
log pi(a|s) = sum_i [log N(u_i; mean_i, sigma_i) - log(scale_i * (1 - tanh(u_i)^2))]，
损失 J_pi = mean [alpha * log pi(a|s) - min(Q1(s, a), Q2(s, a))]。float32 里 |u| > 9 左右时
1 - tanh(u)^2 会舍入成 0：用等值的 2 * (log 2 - u - softplus(-2u))。参考答案：
sac_walker.compute_loss_actor（以及 Actor.sample、squashed_log_prob）；这里不要调用 actor.sample。
"""

import math

import torch
import torch.nn.functional as F


def compute_loss_actor(actor, critic, critic2, obs, alpha):
    """The actor's loss on the states `obs` (B, obs_dim), actions newly drawn from pi.

    actor.distribution(obs): the Gaussian over u, a torch Normal of shape (B, act_dim) (use its
    rsample() and log_prob()); actor.scale and actor.bias: (act_dim,), the squash onto the
    action box. critic(obs, action) and critic2(obs, action) give (B,). alpha: a number (a
    tensor without gradient). Returns (loss, logp): the scalar J_pi and log pi(a|s), (B,),
    which the temperature's loss reuses.
    """
    # Your code here (你的代码写在这里): u, the action a, log pi(a|s), then the loss.
    raise NotImplementedError("not written yet")
