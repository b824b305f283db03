"""Exercise: the DQN target and the Double DQN target (Mnih et al. 2015, Algorithm 1;
van Hasselt et al. 2016, eqs. 3 and 4).

From dqn_cartpole.py: Q(s, a) is trained toward y = r + gamma * (1 - terminated) * v(s'), where
the value of the next state comes from the target network Q':
    DQN:        v(s') = max_a Q'(s', a)                 Q' picks the action and values it
    Double DQN: v(s') = Q'(s', argmax_a Q(s', a))       the network Q picks, Q' values
The max picks and values with the same noisy estimates, so it is biased upward; Double DQN
takes the pick from the other network. No future after a termination; a time-limit truncation
keeps not_done = 1 and bootstraps. The lines after the blank are the script's own.

    python exercises/check.py dqn_target
The reference answer: dqn_cartpole.next_q and dqn_cartpole.td_target, as dqn_update calls them.

中文：练习：DQN 的目标和 Double DQN 的目标。Q(s, a) 朝 y = r + gamma * (1 - terminated) * v(s')
训练，下一个状态的价值来自目标网络 Q'：DQN 取 max_a Q'(s', a)（目标网络既选动作又估值）；
Double DQN 取 Q'(s', argmax_a Q(s', a))（当前网络选动作，目标网络估值）。回合真正结束
（not_done = 0）处没有未来；时间截断时 not_done 仍是 1，照样自举。空白后面的代码和脚本里的一样。
参考答案：dqn_cartpole.next_q 和 dqn_cartpole.td_target。
"""

import torch
import torch.nn as nn
import torch.nn.functional as F


def dqn_update(q_net, q_target, optimizer, batch, cfg):
    """One gradient step of Q on a minibatch toward the DQN target (cfg.double: Double DQN's).

    q_net(obs) and q_target(obs) give (B, n_actions): Q(s, .) and Q'(s, .).
    batch: obs (B, obs_dim), action (B,) int64, reward (B,), next_obs (B, obs_dim), not_done
    (B,: 1 - terminated). cfg.gamma, cfg.double, cfg.max_grad_norm.
    Both next-state values are logged (inside.png), whichever the target uses:

        next_max    = max_a Q'(s', a)                               (B,)
        next_double = Q'(s', argmax_a Q(s', a))                     (B,)
        y = reward + gamma * not_done * (next_double if cfg.double else next_max)

    Returns (loss, mean Q(s, a), mean next_max, mean next_double), stacked.

    在一个小批量上让 Q 朝 DQN 的目标走一个梯度步（cfg.double 为真时用 Double DQN 的目标）。
    q_net(obs) 和 q_target(obs) 给出 (B, n_actions)，即 Q(s, .) 和 Q'(s, .)。batch 里有
    obs (B, obs_dim)、action（(B,)，int64）、reward (B,)、next_obs (B, obs_dim) 和 not_done
    （(B,)，即 1 - terminated）；还要用到 cfg.gamma、cfg.double 和 cfg.max_grad_norm。
    两种下一状态的价值都要算出来并记进日志（inside.png），不管目标用的是哪一种：
    next_max 和 next_double 的形状都是 (B,)，公式见上。y 的形状也是 (B,)，和 Q(s, a) 一一对应。
    返回值是把 (loss, Q(s, a) 的均值, next_max 的均值, next_double 的均值) 叠在一起的张量。
    """
    obs, action, reward, next_obs, not_done = batch
    with torch.no_grad():  # the target is a constant: no gradient flows into it
        # Your code here (你的代码写在这里): next_max, next_double, then y.
        raise NotImplementedError("not written yet")
    # Huber loss of Q(s, a) - y (the script's own lines, compute_loss_q)
    q = q_net(obs).gather(-1, action[:, None]).squeeze(-1)  # Q(s, a) of the taken a, (B,)
    loss = F.smooth_l1_loss(q, y)
    optimizer.zero_grad()
    loss.backward()
    if cfg.max_grad_norm > 0:
        nn.utils.clip_grad_norm_(q_net.parameters(), cfg.max_grad_norm)
    optimizer.step()
    return torch.stack([loss.detach(), q.detach().mean(), next_max.mean(), next_double.mean()])
