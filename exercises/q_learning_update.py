"""Exercise: Q-learning's update, off-policy TD control (Watkins 1989; Sutton & Barto 2018,
eq. 6.8).

From q_learning_cliffwalking.py: after each step (S, A, R, S') the table moves Q(S, A) a step
alpha toward the target R + gamma * max_a' Q(S', a'): the best action in S', whatever the
agent then does (the Bellman optimality backup from one sample). So Q learns Q* while the
agent explores, and its greedy path is the optimal one, along the cliff's edge. After a
termination (the goal) there is no S' to value: the target is R alone. dqn_cartpole.py keeps
this target, a network in place of the table.

    python exercises/check.py q_learning_update
The reference answer: q_learning_cliffwalking.q_learning_update (q_learning_cliffwalking.py).

练习：Q 学习（Q-learning）的更新，异策略的 TD 控制（Watkins 1989；Sutton 和 Barto 2018 的式 6.8）。每走一步
(S, A, R, S')，Q(S, A) 朝目标 R + gamma * max_a' Q(S', a') 走 alpha 那么大的一步：用的是 S' 里最好的动作，
不管智能体接下来真的做什么。所以智能体一边探索，Q 一边学到 Q*，贪心路径就是贴着悬崖的最优路径。终止（到达
终点）之后没有 S' 可估值：目标只有 R。dqn_cartpole.py 用的是同一个目标，只是把表换成了网络。
参考答案：q_learning_cliffwalking.q_learning_update。
"""


def q_learning_update(Q, s, a, r, s_next, terminated, alpha, gamma):
    """Update the numpy table Q (n_states, n_actions) in place at (s, a), and return the TD
    error delta as a float:

        delta   = r + gamma * (1 - terminated) * max_a' Q[s_next, a'] - Q[s, a]
        Q[s, a] = Q[s, a] + alpha * delta

    s, a, s_next are ints; r a number; terminated a bool (True at the goal). Only Q[s, a]
    changes.

    原地更新 numpy 表 Q（形状 (状态数, 动作数)）在 (s, a) 处的值，返回 TD 误差 delta（一个浮点数）。
    公式见上。s、a、s_next 是整数；r 是一个数；terminated 是布尔值（到达终点时为 True）。
    只有 Q[s, a] 会变。
    """
    # Your code here (你的代码写在这里)
    raise NotImplementedError("not written yet")
