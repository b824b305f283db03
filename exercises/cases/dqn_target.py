"""The checks of exercises/dqn_target.py, the DQN target and the Double DQN target: its worked
cases, its named mistakes and its runs."""

from types import SimpleNamespace

import torch

from checking import tr, Failed, t, scalar, compare
import runs

SCRIPT = "dqn_cartpole"
FUNCTION = "dqn_update"
ORDER = 17  # its row in docs/exercises.md's table
OUTPUTS = ("stats",)
RUN = runs.DQN
LOOP = runs.DQN_LOOP
LEARN = runs.DQN_LEARN


def loop_hint():
    return tr("Q is trained toward your target at every gradient step (here with "
              "--double; both next-state values\n  are logged either way): the first "
              "gradient step that differs is where your target differs on real data.",
              "Q 每个梯度步都朝你的目标训练（这里开着 --double；两种下一状态的价值都会记录）："
              "\n  第一个不同的梯度步，就是你的目标在真实数据上开始不同的地方。")


def dqn_case(double):
    """Q and Q' as tables, a state's index in obs[:, 0]: the minibatch's states 0-2, their next
    states 3-5. Q(s, a) = 1.5 for the taken actions and every y within 1 of it, so the Huber
    gradient is linear and gives y back: dL/dQ(s, a) = (Q(s, a) - y) / B. The third transition
    terminated."""
    class Table(torch.nn.Module):
        def __init__(self, rows):
            super().__init__()
            self.table = torch.nn.Parameter(torch.tensor(rows, dtype=torch.float32))

        def forward(self, obs):
            return self.table[obs[:, 0].long()]

    class NoStep:
        def zero_grad(self):
            pass

        def step(self):
            pass

    # argmax_a Q(s, a) (0, 0, 0) is not argmax_a Q(s', a) (1, 0, 1) nor argmax_a Q'(s', a)
    # (0, 1, 1): an argmax taken at s is neither DQN's max nor Double DQN's pick
    #                    s: 0-2 (actions 0, 1, 0)     s': 3-5
    q_net = Table([[1.5, 0.0], [2.0, 1.5], [1.5, 0.0], [0.25, 0.5], [1.25, 0.25], [0.0, 0.25]])
    q_target = Table([[0.0, 0.0]] * 3 + [[0.75, 0.0], [0.5, 1.0], [0.25, 0.75]])
    obs, next_obs = t([0.0, 0.0], [1.0, 0.0], [2.0, 0.0]), t([3.0, 0.0], [4.0, 0.0], [5.0, 0.0])
    batch = (obs, torch.tensor([0, 1, 0]), t(1.0, 1.0, 1.0), next_obs, t(1.0, 1.0, 0.0))
    cfg = SimpleNamespace(gamma=0.5, double=double, max_grad_norm=0.0)
    return q_net, q_target, NoStep(), batch, cfg


def dqn_seen_y(q_net):
    """y as the Huber gradient on Q(s, a) shows it (dqn_case), or None without a gradient."""
    grad = q_net.table.grad
    if grad is None:
        return None
    return 1.5 - 3 * grad[torch.arange(3), torch.tensor([0, 1, 0])]


def dqn_mistakes(double):
    """(label, y) of the known mistakes, for dqn_case: Q'(s') rows (0.75, 0), (0.5, 1),
    (0.25, 0.75); Q(s') rows (0.25, 0.5), (1.25, 0.25), (0, 0.25); r = 1, gamma = 0.5."""
    def y(v, not_done=t(1.0, 1.0, 0.0), gamma=0.5):
        return 1.0 + gamma * not_done * t(*v)
    max_t, double_v = (0.75, 1.0, 0.75), (0.0, 0.5, 0.75)
    right = double_v if double else max_t
    found = [
        (tr("max_a Q(s', a) of the network being trained, where the target network Q' belongs",
            "用了正在训练的当前网络的 max_a Q(s', a)，应该用目标网络 Q'"), y((0.5, 1.25, 0.25))),
        (tr("the action picked by the target network and valued by the network, Q(s', argmax Q'): "
            "Double DQN the other way round", "目标网络选动作、当前网络估值 Q(s', argmax Q')：Double DQN "
            "反过来了"), y((0.25, 0.25, 0.0))),
        (tr("no not_done: a future after a termination", "没有乘 not_done：终止之后还加了未来"),
         y(right, not_done=t(1.0, 1.0, 1.0))),
        (tr("(1 - not_done): not_done is already 1 - terminated",
            "写成了 (1 - not_done)：not_done 本身就是 1 - terminated"),
         y(right, not_done=t(0.0, 0.0, 1.0))),
        (tr("gamma left out", "漏了 gamma"), y(right, gamma=1.0)),
        (tr("a (B, 1) next-state value (keepdim or gather without squeeze(-1)): y broadcasts "
            "to (B, B) against Q(s, a), so each row's Q(s, a) is pulled toward r + gamma * "
            "not_done * (the mean of the B next-state values): the numbers after \"got\" above",
            "下一状态的价值是 (B, 1)（keepdim，或 gather 之后没有 squeeze(-1)）：y 和 Q(s, a) "
            "广播成了 (B, B)，于是每一行的 Q(s, a) 都被拉向 r + gamma * not_done * （B 个下一状态"
            "价值的平均），就是上面“得到的是”后面那几个数"), y((sum(right) / 3,) * 3))]
    if double:
        found.append((tr("max_a Q'(s', a), DQN's target, where --double asks for Double DQN's "
                         "Q'(s', argmax_a Q(s', a))", "用了 DQN 的 max_a Q'(s', a)，--double 要的是 "
                         "Double DQN 的 Q'(s', argmax_a Q(s', a))"), y(max_t)))
    else:
        found.append((tr("Double DQN's Q'(s', argmax_a Q(s', a)) where cfg.double is False (DQN: "
                         "max_a Q'(s', a))", "cfg.double 是 False，却用了 Double DQN 的 "
                         "Q'(s', argmax_a Q(s', a))（DQN 要 max_a Q'(s', a)）"), y(double_v)))
    return y(right), found


def worked_cases(fn):
    logged = []
    for double in (False, True):  # y in each case first: a wrong y is named by its mistake
        what = tr("Double DQN (cfg.double = True)", "Double DQN（cfg.double = True）") if double \
            else tr("DQN (cfg.double = False)", "DQN（cfg.double = False）")
        what += tr(": r = 1, gamma = 0.5, the third terminated; Q'(s') = (0.75, 0), (0.5, 1), "
                   "(0.25, 0.75); Q(s') = (0.25, 0.5), (1.25, 0.25), (0, 0.25)",
                   "：r = 1，gamma = 0.5，第三个终止；Q'(s') = (0.75, 0)、(0.5, 1)、(0.25, 0.75)；"
                   "Q(s') = (0.25, 0.5)、(1.25, 0.25)、(0, 0.25)")
        q_net, q_target, optimizer, batch, cfg = dqn_case(double)
        logged.append((what, fn(q_net, q_target, optimizer, batch, cfg)))
        expected, mistakes = dqn_mistakes(double)
        got = dqn_seen_y(q_net)
        try:
            if got is None:
                raise Failed(tr("no gradient reached Q(s, a): the lines after the blank must stay "
                                "as they are", "梯度没有传到 Q(s, a)：空白后面的代码要保持原样"))
            compare(tr("y (the target each row's Q(s, a) is pulled toward, read from the loss's "
                       "gradient)", "y（每一行的 Q(s, a) 被拉向的目标，从损失的梯度读出）"),
                    got, expected)
            if q_target.table.grad is not None and q_target.table.grad.abs().max() > 0:
                raise Failed(tr("a gradient reached the target network Q': the target is a "
                                "constant (torch.no_grad())", "梯度传进了目标网络 Q'：目标是常数"
                                "（torch.no_grad()）"))
            if q_net.table.grad[3:].abs().max() > 0:
                raise Failed(tr("a gradient reached Q at the next states: the target is a "
                                "constant (torch.no_grad())", "梯度传进了下一个状态的 Q：目标是常数"
                                "（torch.no_grad()）"))
        except Failed as e:
            named = [label for label, value in mistakes
                     if got is not None and torch.allclose(got, value, atol=1e-5)]
            raise Failed(tr("case: ", "例子：") + f"{what}\n  {e.plain if named else e}" + (tr(
                "\n  this is exactly what this mistake gives: ", "\n  这正是这个错误会得到的值：")
                + named[0] if named else "")) from None
    for what, stats in logged:  # then what is logged of both next-state values
        try:
            compare(tr("the logged mean of next_max (max_a Q'(s', a))",
                       "记录的 next_max（max_a Q'(s', a)）的均值"), stats[2], scalar(2.5 / 3))
            compare(tr("the logged mean of next_double (Q'(s', argmax_a Q(s', a)))",
                       "记录的 next_double（Q'(s', argmax_a Q(s', a))）的均值"), stats[3],
                    scalar(1.25 / 3))
        except Failed as e:
            raise Failed(tr("case: ", "例子：") + f"{what}\n  {e}") from None
