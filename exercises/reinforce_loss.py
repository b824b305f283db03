"""Exercise: REINFORCE's loss with a learned baseline (Williams 1992; Sutton & Barto 2018,
sections 13.3-13.4).

From reinforce_cartpole.py: the policy gradient, grad J = E[grad log pi(a_t|s_t) * (G_t - b(s_t))],
estimated on a batch of whole episodes and descended as its negative. The baseline b(s_t) is
the learned V(s_t): subtracting it leaves the gradient's expectation as it is and shrinks its
variance. V is a constant in pi's weight (detached); its own loss fits it to G_t.

    python exercises/check.py reinforce_loss
The reference answer: reinforce_cartpole.reinforce_loss (reinforce_cartpole.py).

练习：带学到的基线的 REINFORCE 损失（Williams 1992；Sutton 和 Barto 2018 第 13.3-13.4 节）。策略梯度
grad J = E[grad log pi(a_t|s_t) * (G_t - b(s_t))]，在一批完整的回合上估计，取负号后做梯度下降。
基线 b(s_t) 就是学到的 V(s_t)：减去它，梯度的期望不变、方差变小。在 π 的权重里 V 是常数（detach），
V 自己的损失让它拟合 G_t。参考答案：reinforce_cartpole.reinforce_loss。
"""

from torch.distributions import Categorical


def reinforce_loss(policy, value_net, data, baseline):
    """(loss_pi, loss_v, weights) on a batch: policy(obs) gives pi's logits (B, n_actions),
    value_net(obs) gives V(s) (B,); data["obs"], ["act"] (the actions taken, (B,)) and
    ["ret"] (the reward-to-go G_t, (B,)); baseline: True or False (--no-baseline).

        weights = G_t - V(s_t), V detached      if baseline
                  G_t                           if not
        loss_pi = -mean(log pi(a_t|s_t) * weights)
        loss_v  = 0.5 * mean((V(s_t) - G_t)^2)

    A mean, not a sum: the step must not grow with the batch's length. train() descends
    loss_pi + loss_v; loss_v alone trains V.

    在一批数据上返回 (loss_pi, loss_v, weights)：policy(obs) 给出 π 的 logits (B, 动作数)，value_net(obs)
    给出 V(s) (B,)；data["obs"]、["act"]（做过的动作，(B,)）和 ["ret"]（回报 G_t，(B,)）；baseline 是
    True 或 False（--no-baseline）。公式见上：有基线时权重是 G_t - V(s_t)，V 要 detach；没有基线时
    权重就是 G_t。用均值，不是求和：每一步的大小不能随这批数据的长度变大。train() 对 loss_pi + loss_v
    做梯度下降；只有 loss_v 训练 V。
    """
    obs, act, ret = data["obs"], data["act"], data["ret"]
    values = value_net(obs)
    # Your code here (你的代码写在这里): weights, loss_pi, loss_v.
    raise NotImplementedError("not written yet")
    return loss_pi, loss_v, weights
