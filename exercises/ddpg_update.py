"""Loop exercise: DDPG's learning step, one critic and one actor update and the soft target
update (Lillicrap et al. 2016, Algorithm 1).

The piece of DDPG's train() that learns, called once per env step after the warm-up with a
minibatch from the replay buffer. The traps are the loop's: the target comes from the
target networks (not the ones being trained) and is a constant (no gradient through it);
the actor's step must not change the critic; the targets move after both steps. The
functions it calls are the script's own (ddpg_walker.td_target, compute_loss_actor,
soft_update).

    python exercises/check.py ddpg_update
The reference answer: ddpg_walker.ddpg_update (ddpg_walker.py).

循环练习：DDPG 的学习步（Lillicrap 等 2016 的算法 1），即一次评论员更新、一次演员更新，然后
软更新目标网络。它是
DDPG 的 train() 里负责学习的那一段，预热之后每个环境步调用一次，输入是从回放缓冲区取的一个小批量。
陷阱都在循环里：TD 目标来自目标网络（不是正在训练的网络），并且是常数（不能有梯度流过）；演员的
更新不能改动评论员；两步都做完，目标网络才移动。参考答案：ddpg_walker.ddpg_update。
"""

import torch
import torch.nn.functional as F

from ddpg_walker import compute_loss_actor, soft_update, td_target  # noqa: F401


def ddpg_update(actor, critic, actor_target, critic_target, actor_opt, critic_opt, batch, cfg):
    """One critic step and one actor step on a minibatch, then the soft target update.

    batch: obs (B, obs_dim), action (B, act_dim), reward (B,), next_obs, not_done (B,: 1 -
    terminated). cfg.gamma, cfg.tau. In this order:

        y = td_target(reward, not_done, Q'(s', mu'(s')), gamma)       (a constant)
        critic_loss = mean (Q(s, a) - y)^2          one step of critic_opt
        actor_loss  = compute_loss_actor(actor, critic, obs)
                                                    one step of actor_opt, the critic unchanged
        soft_update the critic's target, then the actor's, by tau

    Returns (critic_loss, actor_loss), each detached.

    在一个小批量上做一步评论员更新和一步演员更新，再软更新目标网络。batch 里有 obs (B, obs_dim)、
    action (B, act_dim)、reward (B,)、next_obs 和 not_done（(B,)，即 1 - terminated）；还要用 cfg.gamma
    和 cfg.tau。按上面的顺序：先算 y（常数），评论员朝 y 走一步 critic_opt；再用 compute_loss_actor
    让演员走一步 actor_opt，评论员不变；最后按 tau 先软更新目标评论员，再软更新目标演员。返回
    (critic_loss, actor_loss)，两个都要 detach。
    """
    obs, action, reward, next_obs, not_done = batch
    # Your code here (你的代码写在这里)
    raise NotImplementedError("not written yet")
