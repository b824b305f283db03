"""The checks of exercises/bradley_terry_loss.py, the reward model's Bradley-Terry loss on
preference pairs: its worked cases, its named mistakes and its runs."""

import math

import torch
from torch.nn.functional import logsigmoid

from checking import only_if, scalar, t, tr
import runs

SCRIPT = "rlhf_addition"
FUNCTION = "bradley_terry_loss"
ORDER = 23  # its row in docs/exercises.md's table
OUTPUTS = ("loss",)
RUN = runs.RLHF
LOOP = runs.RLHF_LOOP
LEARN = runs.RLHF_RM_LEARN


def loop_hint():
    return tr("The reward model is trained on your loss: the first rm row's loss differs, then "
              "every later stage\n  (PPO is paid the reward model's r).",
              "奖励模型用你的损失训练：第一行 rm 的 loss 就不同，之后每个阶段都跟着不同"
              "\n  （PPO 拿到的奖励就是奖励模型的 r）。")


def by_hand(gaps):
    """-mean log sigmoid(gap), one pair at a time in plain Python."""
    return scalar(sum(math.log(1 + math.exp(-g)) for g in gaps) / len(gaps))


def cases():
    # Three pairs, gaps r_w - r_l of +1, -1.5 and +3 (the judge's choice ranked wrong by r in
    # the second): not symmetric, so chosen and rejected swapped gives another loss. Then two
    # pairs with gaps 0 and +0.5, where the chosen scores are negative.
    return [(tr("3 pairs: r_w = (1.5, -0.5, 2), r_l = (0.5, 1, -1): gaps +1, -1.5, +3",
                "3 对：r_w = (1.5, -0.5, 2)，r_l = (0.5, 1, -1)：分差 +1、-1.5、+3"),
             (t(1.5, -0.5, 2.0).requires_grad_(), t(0.5, 1.0, -1.0).requires_grad_()),
             by_hand([1.0, -1.5, 3.0])),
            (tr("2 pairs: r_w = (-2, -0.5), r_l = (-2, -1): gaps 0 (P = 1/2) and +0.5",
                "2 对：r_w = (-2, -0.5)，r_l = (-2, -1)：分差 0（P = 1/2）和 +0.5"),
             (t(-2.0, -0.5).requires_grad_(), t(-2.0, -1.0).requires_grad_()),
             by_hand([0.0, 0.5])),
            (tr("2 pairs: r_w = (0, 40), r_l = (120, 0): gaps -120 and +40, where sigmoid rounds "
                "to 0 and to 1 in float32",
                "2 对：r_w = (0, 40)，r_l = (120, 0)：分差 -120 和 +40，float32 里 sigmoid 会舍入成 0 和 1"),
             (t(0.0, 40.0).requires_grad_(), t(120.0, 0.0).requires_grad_()),
             by_hand([-120.0, 40.0]))]


def mistakes(r_chosen, r_rejected):
    w, l = r_chosen.detach(), r_rejected.detach()
    gap = w - l
    return [(tr("chosen and rejected swapped: -log sigmoid(r_l - r_w) makes the rejected answer "
                "the likely one", "被选中的和被拒绝的弄反了：-log sigmoid(r_l - r_w) 让被拒绝的回答"
                "变得可能"), -logsigmoid(-gap).mean()),
            (tr("the sign: log sigmoid(gap), the log-likelihood, where the loss is its negative",
                "符号反了：log sigmoid(分差) 是对数似然，损失应该取负"), logsigmoid(gap).mean()),
            (tr("sigmoid without the log: -sigmoid(r_w - r_l) is not the pairs' log-likelihood "
                "(its gradient vanishes where the model is most wrong)",
                "sigmoid 外面没有取 log：-sigmoid(r_w - r_l) 不是这些偏好对的对数似然（模型错得最"
                "厉害的地方梯度反而消失）"), -torch.sigmoid(gap).mean()),
            (tr("summed over the pairs (.sum()) where the loss is their mean (.mean())",
                "对偏好对求了和（.sum()），损失应该求均值（.mean()）"), -logsigmoid(gap).sum()),
            (tr("a margin (hinge) loss, max(0, 1 - (r_w - r_l)), where Bradley-Terry has "
                "-log sigmoid(r_w - r_l)", "用了带间隔的（hinge）损失 max(0, 1 - (r_w - r_l))，"
                "Bradley-Terry 是 -log sigmoid(r_w - r_l)"), (1 - gap).clamp_min(0).mean()),
            (tr("each answer classified on its own, -log sigmoid(r_w) - log(1 - sigmoid(r_l)): "
                "only the gap is learned, r is free up to a constant per prompt",
                "把每个回答单独当成分类：-log sigmoid(r_w) - log(1 - sigmoid(r_l))；只有分差是学到的，"
                "对每个题目 r 可以整体加一个常数"), -(logsigmoid(w) + logsigmoid(-l)).mean()),
            (tr("torch.log(torch.sigmoid(gap)): sigmoid rounds to 0 for a gap far below 0, and "
                "its log is -inf; logsigmoid(gap) never does",
                "写成了 torch.log(torch.sigmoid(分差))：分差远小于 0 时 sigmoid 舍入成 0，取 log 得 "
                "-inf；logsigmoid(分差) 不会这样"),
             only_if(bool((gap < -90).any()), -torch.log(torch.sigmoid(gap)).mean())),
            (tr("the mean gap inside the log: -log sigmoid(mean(r_w - r_l)), where the loss is "
                "the mean over the pairs of -log sigmoid(r_w - r_l)",
                "先对分差求均值再取 log：写成了 -log sigmoid(mean(r_w - r_l))，损失应该是每对的 "
                "-log sigmoid(r_w - r_l) 的均值"), -logsigmoid(gap.mean()))]


def learned(result):
    runs.rm_ranks(result)
