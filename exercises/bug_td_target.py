"""Find the bug (DDPG on InvertedPendulum): this TD target runs without error, and DDPG
balances the pole for a while, then loses it again, where the script's own holds it at
1000 (their curves: docs/exercises.md). Find the mistake, fix it here, and confirm:

    python exercises/check.py bug_td_target

找错（DDPG，InvertedPendulum）。这个 TD 目标能运行，用它训练，杆子立住一阵又倒了，
原版能一直保持 1000。找到错误，在这里改正，再用上面的命令确认。
"""


def td_target(reward, not_done, next_q, gamma):
    """The critic's target from a minibatch: rewards, not_done (1 - terminated), the target
    networks' Q'(s', mu'(s')), each (B,).

    由一个小批量算评论员的目标：rewards、not_done（1 - terminated）和目标网络给出的
    Q'(s', mu'(s'))，形状都是 (B,)。
    """
    return reward + gamma * next_q
