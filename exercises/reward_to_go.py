"""Exercise: REINFORCE's reward-to-go (Williams 1992; Sutton & Barto 2018, section 13.3).

From reinforce_cartpole.py: each action's log-probability is pushed up by what followed it,
G_t = r_t + gamma * r_{t+1} + gamma^2 * r_{t+2} + ..., to the episode's end. Rewards before t
are left out (an action cannot change them), and each later reward is discounted by how far
after t it came. Computed backwards, G_t = r_t + gamma * G_{t+1}, from G_T = last_value:
0 where the pole fell (terminated), V(s_T) where a time limit cut the episode (truncated):
train() decides which and passes it in.

    python exercises/check.py reward_to_go
The reference answer: reinforce_cartpole.reward_to_go (reinforce_cartpole.py).

练习：REINFORCE 的回报（reward-to-go，Williams 1992；Sutton 和 Barto 2018 第 13.3 节）。每个动作的
对数概率按它之后拿到的回报 G_t = r_t + gamma * r_{t+1} + gamma^2 * r_{t+2} + ... 提高，一直算到回合结束。
t 之前的奖励不算（动作改变不了它们），之后的每个奖励按离 t 多远打折。从后往前算
G_t = r_t + gamma * G_{t+1}，G_T = last_value：杆倒了（终止）时是 0，时间截断时是 V(s_T)，由 train()
决定并传进来。参考答案：reinforce_cartpole.reward_to_go。
"""

import numpy as np


def reward_to_go(rewards, gamma, last_value=0.0):
    """The reward-to-go of one whole episode, a numpy array as long as `rewards` (a sequence
    of floats, r_0 .. r_{T-1}; train() passes a tuple):

        G_T = last_value                 (0 after a termination, V(s_T) after a truncation)
        G_t = rewards[t] + gamma * G_{t+1},   t = T - 1, ..., 0

    >>> reward_to_go([1.0, 1.0, 1.0], gamma=0.5)
    array([1.75, 1.5 , 1.  ])

    一个完整回合的回报，返回和 rewards 一样长的 numpy 数组（rewards 是一串浮点数 r_0 .. r_{T-1}，
    train() 传进来的是元组）。G_T = last_value（终止后是 0，时间截断后是 V(s_T)），再从 t = T - 1
    往回算到 0：G_t = rewards[t] + gamma * G_{t+1}。
    """
    # Your code here (你的代码写在这里): a loop from t = T - 1 down to 0.
    raise NotImplementedError("not written yet")
