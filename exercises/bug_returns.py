"""Find the bug (A2C on CartPole): these returns run without error, and A2C trains badly with
them: the mean return stays mostly under 150, where the script's own solves CartPole (its
curve beside the original's: docs/exercises.md). Find the mistake, fix it here, and confirm:

    python exercises/check.py bug_returns

找错（A2C，CartPole）。这个函数能运行，但用它训练，平均回报大多在 150 以下，原版能解决
CartPole。找到错误，在这里改正，再用上面的命令确认。
"""

import torch


def discounted_returns(rewards, next_values, terminated, truncated, gamma):
    """Reward-to-go G_t = r_t + gamma * G_{t+1} over a (T, N) rollout, bootstrapped with
    next_values (V(s_{t+1})) where the rollout is cut.

    在一批 (T, N) 的数据上算折扣回报 G_t = r_t + gamma * G_{t+1}，在这批数据的末尾和时间截断处
    用 next_values（V(s_{t+1})）自举。
    """
    returns = torch.zeros_like(rewards)
    future = next_values[-1]  # bootstrap past the rollout's end
    for t in reversed(range(len(rewards))):
        future = torch.where(truncated[t], next_values[t], future)  # time limit: V(final obs)
        returns[t] = future = rewards[t] + gamma * future
    return returns
