"""Exercise: Sarsa's update, on-policy TD control (Sutton & Barto 2018, eq. 6.7).

From q_learning_cliffwalking.py: after each step (S, A, R, S', A') the table moves Q(S, A)
a step alpha toward the target R + gamma * Q(S', A'), where A' is the action the agent will
really take in S', exploration included. So Q learns the value of the epsilon-greedy policy
it follows, its falls off the cliff counted, and its greedy path keeps away from the edge.
After a termination (the goal) there is no S' to value: the target is R alone.

    python exercises/check.py sarsa_update
The reference answer: q_learning_cliffwalking.sarsa_update (q_learning_cliffwalking.py).

练习：Sarsa 的更新，同策略的 TD 控制（Sutton 和 Barto 2018 的式 6.7）。每走一步 (S, A, R, S', A')，
Q(S, A) 朝目标 R + gamma * Q(S', A') 走 alpha 那么大的一步；A' 是智能体在 S' 真的要做的动作，
探索的动作也算。所以 Q 学到的是它自己这个 ε-贪心策略的价值（掉下悬崖也算在内），贪心路径离悬崖远一些。
终止（到达终点）之后没有 S' 可估值：目标只有 R。参考答案：q_learning_cliffwalking.sarsa_update。
"""


def sarsa_update(Q, s, a, r, s_next, a_next, terminated, alpha, gamma):
    """Update the numpy table Q (n_states, n_actions) in place at (s, a), and return the TD
    error delta as a float:

        delta   = r + gamma * (1 - terminated) * Q[s_next, a_next] - Q[s, a]
        Q[s, a] = Q[s, a] + alpha * delta

    s, a, s_next, a_next are ints; r a number; terminated a bool (True at the goal). Only
    Q[s, a] changes.

    原地更新 numpy 表 Q（形状 (状态数, 动作数)）在 (s, a) 处的值，返回 TD 误差 delta（一个浮点数）。
    公式见上。s、a、s_next、a_next 是整数；r 是一个数；terminated 是布尔值（到达终点时为 True）。
    只有 Q[s, a] 会变。
    """
    # Your code here (你的代码写在这里)
    raise NotImplementedError("not written yet")
