"""Loop exercise: A2C's bootstrap from a rollout, the values that close each step's future.

The piece of A2C's train() between collecting a rollout and the loss (tutorial 004 waits for
the episode's end; A2C cuts the rollout after T steps and estimates the rest with V). The
rollout was collected by gymnasium's vector envs in NEXT_STEP autoreset mode: the obs stored
at step t + 1 is the obs that step t led to, even after a done step (then it is that
episode's real final observation, as the done step returned it). The lines after the blank
are the script's own.

    python exercises/check.py a2c_targets
The reference answer: actor_critic_cartpole.a2c_targets (actor_critic_cartpole.py).

中文：循环练习：A2C 用 rollout 自举，补上每一步之后的未来。它是 A2C 的 train() 里采集完一批数据、
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
