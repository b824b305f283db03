"""Exercise: generalized advantage estimation (Schulman et al. 2016, eq. 16), PPO's advantages.

From tutorials 000 and 002 (PPO's advantage) and the GAE paper: the TD error of each step,
summed backwards with weight gamma * lam, restarted where an episode ends. A time-limit
truncation still bootstraps in its TD error (the state was not terminal) but stops the sum
(what follows belongs to the next episode).

    python exercises/check.py gae
The reference answer: common.gae (common.py).

练习：GAE（广义优势估计，Schulman 等 2016 的式 16），PPO 的优势。对照教程 000、002。
每一步的 TD 误差按 gamma * lam 从后往前累加，回合结束处重新开始；时间截断（truncated）的那一步
在 TD 误差里仍然自举（状态不是终止状态），但累加到此为止。参考答案：common.gae。
"""

import torch


def gae(rewards, values, next_values, terminated, truncated, gamma, lam):
    """Advantages A_t, shaped like `rewards` (T, N):

        delta_t = r_t + gamma * V(s_{t+1}) * (1 - terminated_t) - V(s_t)
        A_t     = delta_t + gamma * lam * (1 - done_t) * A_{t+1},   done = terminated or truncated

    values[t] is V(s_t), next_values[t] is V(s_{t+1}); A_T (after the last step) is 0.
    The inputs are left as they are.

    优势 A_t，形状和 rewards 一样，是 (T, N)。公式见上：delta_t 里只有终止（terminated）才去掉
    V(s_{t+1})；累加到回合结束（done，即终止或时间截断）处就停。values[t] 是 V(s_t)，next_values[t]
    是 V(s_{t+1})；最后一步之后的 A_T 为 0。不要改动输入。
    """
    # Your code here (你的代码写在这里): a loop from t = T - 1 down to 0.
    raise NotImplementedError("not written yet")
