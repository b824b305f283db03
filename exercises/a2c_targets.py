"""Loop exercise: A2C's bootstrap from a rollout, the values that close each step's future.

The piece of A2C's train() between collecting a rollout and the loss (tutorial 004 waits for
the episode's end; A2C cuts the rollout after T steps and estimates the rest with V). The
rollout was collected by gymnasium's vector envs in NEXT_STEP autoreset mode: the obs stored
at step t + 1 is the obs that step t led to, even after a done step (then it is that
episode's real final observation, as the done step returned it). The lines after the blank
are the script's own.

    python exercises/check.py a2c_targets
The reference answer: actor_critic_cartpole.a2c_targets (actor_critic_cartpole.py).

循环练习：A2C 在一批数据（rollout）上的自举，补上每一步之后的未来。它是 A2C 的 train() 里采集完一批数据、
计算损失之前的那一段。数据由 gymnasium 的向量环境以 NEXT_STEP 自动重置模式采集：第 t + 1 步存下的
观测就是第 t 步到达的观测，回合结束之后也是（那时它是那个回合真正的最后一个观测）。空白后面的代码
和脚本里的一样。参考答案：actor_critic_cartpole.a2c_targets。
"""

import torch

import common


def a2c_targets(model, rollout, next_obs, cfg):
    """Critic targets R_t and advantages A_t of one rollout, each (T, N).

    model(obs) gives (logits, V(obs)) for obs of any leading shape; rollout["obs"] is
    (T, N, obs_dim), rollout["rewards"], ["terminated"], ["truncated"] are (T, N); next_obs
    (N, obs_dim, a numpy array) is what the rollout's last step led to. Write:

        values      = V(s_t) for every stored obs, (T, N)
        next_values = V(s_{t+1}), (T, N): the next stored obs's value, and for the last step
                      V(next_obs)

    Both are targets, constants for the loss: no gradient may flow through them.

    一批数据的评论员目标 R_t 和优势 A_t，形状都是 (T, N)。model(obs) 对任意前导形状的 obs
    给出 (logits, V(obs))；rollout["obs"] 是 (T, N, obs_dim)，rollout["rewards"]、["terminated"]、
    ["truncated"] 是 (T, N)；next_obs（(N, obs_dim) 的 numpy 数组）是这批数据最后一步到达的观测。
    要写的是：values 是每个存下的观测的 V(s_t)，(T, N)；next_values 是 V(s_{t+1})，(T, N)，即下一个
    存下的观测的价值，最后一步用 V(next_obs)。两者都是目标，对损失来说是常数，不能有梯度流过它们。
    """
    # Your code here (你的代码写在这里): values and next_values, (T, N) each.
    raise NotImplementedError("not written yet")
    if cfg.lam is None:  # the n-step returns, A = R - V (the script's own lines)
        returns = common.discounted_returns(rollout["rewards"], next_values,
                                            rollout["terminated"], rollout["truncated"],
                                            cfg.gamma)
        return returns, returns - values
    advantages = common.gae(rollout["rewards"], values, next_values, rollout["terminated"],
                            rollout["truncated"], cfg.gamma, cfg.lam)
    return advantages + values, advantages
