"""The checks of exercises/dqn_loss.py, DQN's TD loss with the Huber loss (delta = 1): its worked
cases, its named mistakes and its runs."""

import torch

from checking import tr, t, scalar, Fixed, only_if
import runs

SCRIPT = "dqn_cartpole"
FUNCTION = "compute_loss_q"
ORDER = 29  # its row in docs/exercises.md's table
OUTPUTS = ("loss", "q")
RUN = runs.DQN
LOOP = runs.DQN_LOOP
LEARN = runs.DQN_LEARN


def loop_hint():
    return tr("Q is trained with your loss at every gradient step: the logged loss differs "
              "first, at the first\n  gradient step where your loss differs on real data; Q "
              "and the next-state values follow.",
              "每个梯度步都用你的损失训练 Q：记录的 loss 最先不同，就在你的损失第一次在真实数据上"
              "\n  不同的那个梯度步；Q 和下一状态的价值随后也不同。")


def q_table(rows):
    """Q(s, .) of the states 0, 1, ... (obs holds a state's index): row i is state i's."""
    return Fixed(t(*rows), names=(tr("Q(s, .)", "Q(s, .)"),))


def cases():
    # The first case's errors x = Q(s, a) - y = (2.5, -0.5, -3, 0.25): two past 1, of both signs,
    # where the Huber loss is |x| - 0.5 (2, 2.5), not 0.5 x^2 (3.125, 4.5); two within 1. The
    # taken action is not the argmax in rows 2 and 3, so max_a Q(s, a) gives another Q.
    # The second: every error within 1 (-0.5, 0.75, 0.25), where Huber is 0.5 x^2: a squared
    # error not halved shows there alone, and three actions.
    return [
        (tr("B = 4, 2 actions: Q(s, .) = (1, 3), (2, -0.5), (0.5, 4), (1.5, 0.25), actions "
            "(1, 0, 0, 1), y = (0.5, 2.5, 3.5, 0):\n  errors Q(s, a) - y = (2.5, -0.5, -3, 0.25), "
            "two past 1, where Huber = |x| - 0.5",
            "B = 4，2 个动作：Q(s, .) = (1, 3)、(2, -0.5)、(0.5, 4)、(1.5, 0.25)，动作 (1, 0, 0, 1)，"
            "y = (0.5, 2.5, 3.5, 0)：\n  误差 Q(s, a) - y = (2.5, -0.5, -3, 0.25)，两个超过 1，"
            "那里 Huber = |x| - 0.5"),
         (q_table([[1.0, 3.0], [2.0, -0.5], [0.5, 4.0], [1.5, 0.25]]), t([0.0], [1.0], [2.0], [3.0]),
          torch.tensor([1, 0, 0, 1]), t(0.5, 2.5, 3.5, 0.0)),
         # (2 + 0.125 + 2.5 + 0.03125) / 4
         (scalar(4.65625 / 4), t(3.0, 2.0, 0.5, 0.25))),
        (tr("B = 3, 3 actions: Q(s, .) = (0.5, -1, 2), (1, 0, 0.25), (-0.5, 0.75, 0), actions "
            "(0, 2, 1), y = (1, -0.5, 0.5):\n  errors (-0.5, 0.75, 0.25), all within 1, where "
            "Huber = 0.5 x^2",
            "B = 3，3 个动作：Q(s, .) = (0.5, -1, 2)、(1, 0, 0.25)、(-0.5, 0.75, 0)，动作 (0, 2, 1)，"
            "y = (1, -0.5, 0.5)：\n  误差 (-0.5, 0.75, 0.25)，都在 1 以内，那里 Huber = 0.5 x^2"),
         (q_table([[0.5, -1.0, 2.0], [1.0, 0.0, 0.25], [-0.5, 0.75, 0.0]]), t([0.0], [1.0], [2.0]),
          torch.tensor([0, 2, 1]), t(1.0, -0.5, 0.5)),
         # 0.5 * (0.25 + 0.5625 + 0.0625) / 3
         (scalar(0.4375 / 3), t(0.5, 0.25, 0.75))),
    ]


def huber(x):
    return torch.where(x.abs() <= 1, 0.5 * x ** 2, x.abs() - 0.5)


def mistakes(q_net, obs, action, y):
    with torch.no_grad():
        q_all = q_net(obs)
    q = q_all.gather(-1, action[:, None]).squeeze(-1)
    x = q - y
    past = bool((x.abs() > 1).any())  # where Huber and the halved square differ
    within = bool(((x.abs() < 1) & (x != 0)).any())  # where 0.5 x^2 and x^2 differ
    q_max = q_all.max(-1).values
    return [
        (tr("the squared error (MSE, F.mse_loss) where DQN's loss is the Huber loss: past "
            "|x| = 1 its gradient grows with\n    the error instead of staying at +-1 (Mnih et "
            "al.'s error clipping), and within 1 it is twice Huber's 0.5 x^2",
            "用了平方误差（MSE，F.mse_loss），DQN 的损失是 Huber 损失：|x| 超过 1 以后，它的梯度"
            "随误差变大，\n    而不是停在 ±1（Mnih 等的误差裁剪）；在 1 以内，它又是 Huber 的 "
            "0.5 x^2 的两倍"), ((x ** 2).mean(), q)),
        (tr("the halved squared error 0.5 x^2 everywhere: Huber's quadratic part also past "
            "|x| = 1, where the loss is |x| - 0.5\n    (linear: its gradient stays at +-1)",
            "处处都用了平方误差的一半 0.5 x^2：|x| 超过 1 的地方也用了 Huber 的二次部分，"
            "那里的损失是 |x| - 0.5\n    （线性的：梯度停在 ±1）"),
         only_if(past, ((0.5 * x ** 2).mean(), q))),
        (tr("Huber's quadratic part without its 1/2: x^2 within 1, where it is 0.5 x^2 (the "
            "two parts then do not meet at |x| = 1)",
            "Huber 的二次部分漏了 1/2：在 1 以内写成了 x^2，应该是 0.5 x^2（这样两段在 |x| = 1 "
            "处接不上）"),
         only_if(within, (torch.where(x.abs() <= 1, x ** 2, x.abs() - 0.5).mean(), q))),
        (tr("Huber's linear part without its - 0.5: |x| past 1, where it is |x| - 0.5 (the "
            "two parts then do not meet at |x| = 1)",
            "Huber 的线性部分漏了 - 0.5：超过 1 的地方写成了 |x|，应该是 |x| - 0.5（这样两段在 "
            "|x| = 1 处接不上）"),
         only_if(past, (torch.where(x.abs() <= 1, 0.5 * x ** 2, x.abs()).mean(), q))),
        (tr("the absolute error |x| (L1, F.l1_loss) everywhere: within 1 the Huber loss is "
            "0.5 x^2, whose gradient shrinks\n    with the error",
            "处处都用了绝对误差 |x|（L1，F.l1_loss）：在 1 以内 Huber 损失是 0.5 x^2，"
            "它的梯度随误差变小"), (x.abs().mean(), q)),
        (tr("the error clipped, not its gradient: 0.5 * clamp(x, -1, 1)^2 is flat past 1 (no "
            "gradient at all there), where\n    Huber's is +-1: Mnih et al. clip the error term "
            "of the update, the derivative, and the loss is |x| - 0.5",
            "裁剪的是误差本身，不是它的梯度：0.5 * clamp(x, -1, 1)^2 超过 1 以后是平的（那里完全"
            "没有梯度），\n    Huber 的梯度是 ±1：Mnih 等裁剪的是更新里的误差项，也就是导数，"
            "损失是 |x| - 0.5"),
         only_if(past, ((0.5 * x.clamp(-1, 1) ** 2).mean(), q))),
        (tr("the error clipped, not its gradient, and not halved: clamp(x, -1, 1)^2 is flat "
            "past 1 (no gradient there) and\n    twice 0.5 x^2 within 1; the Huber loss is "
            "0.5 x^2 within 1, |x| - 0.5 past it",
            "裁剪的是误差本身，不是它的梯度，也没有乘 0.5：clamp(x, -1, 1)^2 超过 1 以后是平的"
            "（那里没有梯度），\n    在 1 以内又是 0.5 x^2 的两倍；Huber 损失在 1 以内是 0.5 x^2，"
            "超过 1 是 |x| - 0.5"),
         ((x.clamp(-1, 1) ** 2).mean(), q)),
        (tr("a sum over the batch (.sum(), reduction='sum') where the script takes the mean: "
            "the step then grows with\n    the batch size (64 times larger at the defaults, "
            "at the same step size)",
            "对这批数据求了和（.sum()、reduction='sum'），脚本求的是均值：这样每一步的大小会随"
            "批量变大\n    （默认设置下大 64 倍，学习率却没变）"), (huber(x).sum(), q)),
        (tr("Q(s, a) as (B, 1) (gather without .squeeze(-1), or y[:, None]): Q(s, a) - y "
            "broadcasts to (B, B), so each\n    Q(s, a) is pulled toward every row's y, and the "
            "loss is the mean of B x B errors",
            "Q(s, a) 是 (B, 1)（gather 之后没有 .squeeze(-1)，或者写了 y[:, None]）：Q(s, a) - y "
            "广播成了 (B, B)，\n    于是每个 Q(s, a) 都被拉向每一行的 y，损失是 B x B 个误差的均值"),
         (huber(q[:, None] - y[None, :]).mean(), None)),
        (tr("max_a Q(s, a) where Q(s, a) of the action taken belongs (gather with action): "
            "the max is the target's,\n    at s'; the loss trains the value of what was done",
            "用了 max_a Q(s, a)，应该是做过的动作的 Q(s, a)（用 action 去 gather）：max 属于目标，"
            "\n    是在 s' 上取的；损失训练的是做过的那个动作的价值"),
         only_if(not torch.equal(q_max, q), (huber(q_max - y).mean(), q_max))),
    ]


def named_error(e):
    """The mistake an error of the answer's shows, or ''."""
    if "same number of dimensions" not in str(e):
        return ""
    return tr("\n  this is exactly what this mistake raises: gather(-1, action) with action "
              "(B,): gather's index needs\n    Q(s, .)'s two dimensions, action[:, None] "
              "(B, 1), then .squeeze(-1) back to (B,)",
              "\n  这正是这个常见错误会引发的：\n    gather(-1, action) 里的 action 是 (B,)：gather "
              "的下标要和 Q(s, .) 一样有两维，写 action[:, None]，\n    即 (B, 1)，然后用 "
              ".squeeze(-1) 变回 (B,)")


def cut():
    return tr("Q(s, a) computed without a gradient (torch.no_grad(), .detach() or .item() on "
              "Q(s, .) or Q(s, a)):\n    the loss's value is right and Q would never move; "
              "only the target y is a constant",
              "Q(s, a) 是在不带梯度的情况下算的（对 Q(s, .) 或 Q(s, a) 用了 torch.no_grad()、"
              ".detach() 或 .item()）：\n    损失的数值对，但 Q 永远不会变；是常数的只有目标 y")
