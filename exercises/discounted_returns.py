"""Exercise: the discounted return with the bootstrap at a cut (A2C's n-step targets).

From tutorial 004 (A2C: the critic is trained toward the return R_t, and A = R - V) and
Spinning Up's finish_path(last_val): each R_t = r_t + gamma * R_{t+1}, computed backwards.
Where the rollout is cut (its last step, or a time-limit truncation) the future is not 0:
it is estimated by V. Where the episode really ended (terminated), it is 0.

    python exercises/check.py discounted_returns
The reference answer: common.discounted_returns (common.py).

练习：在时间截断处自举的折扣回报（A2C 的 n 步目标）。对照教程 004：评论员的目标是回报 R_t，
优势 A = R - V。从后往前算 R_t = r_t + gamma * R_{t+1}；rollout 的最后一步和时间截断
（truncated）处用 V 估计未来，真正结束（terminated）处未来为 0。参考答案：common.discounted_returns。
"""

import torch


def discounted_returns(rewards, next_values, terminated, truncated, gamma):
    """Reward-to-go G_t = r_t + gamma * G_{t+1}, each input shaped (T, N) (T steps of N envs):

        future after step t:  0                 if terminated[t]   (termination wins)
                              next_values[t]    if truncated[t], or t = T - 1 (the cut)
                              G_{t+1}           otherwise
        G_t = rewards[t] + gamma * future

    next_values[t] is V(s_{t+1}), the value of the obs step t led to. Returns a (T, N) tensor
    shaped like `rewards`; the inputs are left as they are.

    折扣回报 G_t = r_t + gamma * G_{t+1}，每个输入的形状都是 (T, N)（N 个环境各 T 步）。第 t 步之后
    的未来：terminated[t] 时为 0（终止优先）；truncated[t] 时，或者 t = T - 1（这批数据的末尾）时，
    是 next_values[t]；其余情况是 G_{t+1}。next_values[t] 是 V(s_{t+1})，即第 t 步到达的观测的价值。
    返回和 rewards 形状相同的 (T, N) 张量，不要改动输入。
    """
    # Your code here (你的代码写在这里): a loop from t = T - 1 down to 0.
    raise NotImplementedError("not written yet")
