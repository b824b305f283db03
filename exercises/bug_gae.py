"""Find the bug (PPO on CartPole): this GAE runs without error, and PPO trains badly with it:
the mean return stays under 40 where the script's own solves CartPole in about 15,000 steps
(its curve beside the original's: docs/exercises.md). Find the mistake, fix it here, and
confirm:

    python exercises/check.py bug_gae

找错（PPO，CartPole）。这个 GAE 能运行，但用它训练，平均回报一直低于 40，原版大约
15000 步就能解决。找到错误，在这里改正，再用上面的命令确认。
"""

import torch


def gae(rewards, values, next_values, terminated, truncated, gamma, lam):
    """Advantages by generalized advantage estimation over a (T, N) rollout: values[t] is
    V(s_t), next_values[t] is V(s_{t+1}).

    对一批 (T, N) 的数据用广义优势估计算优势：values[t] 是 V(s_t)，next_values[t] 是 V(s_{t+1})。
    """
    advantages = torch.zeros_like(rewards)
    last = torch.zeros_like(rewards[0])
    not_terminated = (~terminated).to(rewards.dtype)
    not_done = (~(terminated | truncated)).to(rewards.dtype)
    for t in reversed(range(len(rewards))):
        delta = rewards[t] + gamma * values[t] * not_terminated[t] - values[t]
        last = advantages[t] = delta + gamma * lam * not_done[t] * last
    return advantages
