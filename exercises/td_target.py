"""Exercise: DDPG's TD target (Lillicrap et al. 2016, Algorithm 1).

From tutorial 003: the critic is trained toward y = r + gamma * Q'(s', mu'(s')), the target
networks' estimate, with no future where the episode really ended.

    python exercises/check.py td_target
The reference answer: ddpg_walker.td_target (ddpg_walker.py).

练习：DDPG 的 TD 目标（Lillicrap 等 2016 的算法 1，对照教程 003）。y = r + gamma * Q'(s', mu'(s'))，
回合真正结束（not_done = 0）处没有未来。参考答案：ddpg_walker.td_target。
"""


def td_target(reward, not_done, next_q, gamma):
    """y = reward + gamma * not_done * next_q, each a (B,) tensor: not_done is 1 - terminated
    (a time-limit truncation keeps 1), next_q is Q'(s', mu'(s')). Returns a (B,) tensor.

    y = reward + gamma * not_done * next_q，每个量都是形状为 (B,) 的张量。not_done 是
    1 - terminated（时间截断时仍然是 1），next_q 是 Q'(s', mu'(s'))。返回形状为 (B,) 的张量。
    """
    # Your code here (你的代码写在这里)
    raise NotImplementedError("not written yet")
