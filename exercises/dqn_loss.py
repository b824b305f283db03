"""Exercise: DQN's TD loss with the Huber loss (Mnih et al. 2015, Methods: "error clipping";
Huber 1964).

From dqn_cartpole.py: Q(s, a) of the action taken is regressed on the TD target y (computed
before, under torch.no_grad(): a constant here). The loss is not the squared error but the
Huber loss of the TD error x = Q(s, a) - y, with delta = 1:

    L(x) = 0.5 * x^2        if |x| <= 1
           |x| - 0.5        otherwise

Its gradient is x within +-1 and +-1 outside: Mnih et al. "clip the error term from the
update ... to be between -1 and 1", the error's gradient, not the error itself. This is
torch's smooth_l1_loss (beta = 1) and huber_loss (delta = 1); SB3's and CleanRL's DQN use it
too. The mean over the minibatch, not the sum.

    python exercises/check.py dqn_loss
The reference answer: dqn_cartpole.compute_loss_q (dqn_cartpole.py).

练习：用 Huber 损失算 DQN 的 TD 损失（Mnih 等 2015 的 Methods 一节里的“误差裁剪”；Huber 1964）。
做过的动作的 Q(s, a) 朝 TD 目标 y 回归（y 已经在 torch.no_grad() 下算好，这里是常数）。损失不是
平方误差，而是 TD 误差 x = Q(s, a) - y 的 Huber 损失（delta = 1）：|x| <= 1 时是 0.5 * x^2，
否则是 |x| - 0.5。它的梯度在 ±1 之内是 x，之外是 ±1：Mnih 等裁剪的是误差的梯度，不是误差本身。
这就是 torch 的 smooth_l1_loss（beta = 1）和 huber_loss（delta = 1），SB3 和 CleanRL 的 DQN
也用它。对小批量取均值，不是求和。参考答案：dqn_cartpole.compute_loss_q。
"""

import torch
import torch.nn.functional as F


def compute_loss_q(q_net, obs, action, y):
    """(loss, Q(s, a)) on a minibatch: q_net(obs) gives Q(s, .), (B, n_actions); action (B,),
    int64, the actions taken; y (B,), the TD target, a constant.

        q    = Q(s, a) of the action taken                    (B,), not (B, 1)
        loss = mean over the batch of L(q - y)                 L: the Huber loss above

    The gradient must reach q_net through q (no torch.no_grad(), no .detach() on it).

    在一个小批量上返回 (loss, Q(s, a))：q_net(obs) 给出 Q(s, .)，形状 (B, 动作数)；action 是做过的
    动作，(B,)，int64；y 是 TD 目标，(B,)，常数。q 是做过的动作的 Q(s, a)，形状 (B,)，不是 (B, 1)；
    loss 是 L(q - y) 对这批数据的均值，L 是上面的 Huber 损失。梯度要经过 q 传到 q_net
    （q 不能在 torch.no_grad() 下算，也不能 .detach()）。
    """
    # Your code here (你的代码写在这里): q, then loss.
    raise NotImplementedError("not written yet")
    return loss, q
