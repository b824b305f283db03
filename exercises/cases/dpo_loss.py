"""The checks of exercises/dpo_loss.py, DPO's loss on preference pairs: its worked cases, its
named mistakes and its runs."""

import math

import torch
from torch.nn.functional import logsigmoid

from checking import scalar, t, tr
import runs

SCRIPT = "rlhf_addition"
FUNCTION = "dpo_loss"
ORDER = 26  # its row in docs/exercises.md's table
OUTPUTS = ("loss",)
CONFIG_NAMES = {"beta": "dpo_beta"}  # its beta is Config's dpo_beta (beta is PPO's KL weight)
RUN = runs.RLHF
LOOP = runs.RLHF_LOOP
LEARN = runs.RLHF_DPO_LEARN


def learned(result):
    runs.dpo_improves(result)


def loop_hint():
    return tr("The DPO stage trains on your loss: its first dpo row's loss differs, or, where "
              "yours gives log 2 there\n  too (pi is still pi_ref: every gap is 0), its second.",
              "DPO 阶段用你的损失训练：第一行 dpo 的 loss 就不同；要是你的在那里也是 log 2"
              "\n  （π 还是 π_ref：每个分差都是 0），就是第二行不同。")


def by_hand(logp_w, logp_l, ref_w, ref_l, beta):
    """-mean log sigmoid(beta * gap), pair by pair in plain Python."""
    gaps = [beta * ((float(a) - float(c)) - (float(b) - float(d)))
            for a, b, c, d in zip(logp_w, logp_l, ref_w, ref_l)]
    return scalar(sum(math.log(1 + math.exp(-g)) for g in gaps) / len(gaps))


def cases():
    # Three pairs. log pi / pi_ref: chosen +1, -0.5, +0.25; rejected -1, +0.5, -1.75: gaps
    # +2, -1, +2 (the second pair ranked wrong by the policy), not symmetric
    logp_w, logp_l = t(-1.0, -2.5, -1.25), t(-3.0, -1.0, -2.75)
    ref_w, ref_l = t(-2.0, -2.0, -1.5), t(-2.0, -1.5, -1.0)
    return [(tr(f"3 pairs, log pi / pi_ref of (+1, -0.5, +0.25) chosen, (-1, +0.5, -1.75) "
                f"rejected, beta = {beta}", f"3 对，被选中的回答 log π / π_ref 为 (+1, -0.5, +0.25)，"
                f"被拒绝的为 (-1, +0.5, -1.75)，β = {beta}"),
             (logp_w.clone().requires_grad_(), logp_l.clone().requires_grad_(), ref_w, ref_l,
              beta), by_hand(logp_w, logp_l, ref_w, ref_l, beta)) for beta in (0.5, 0.25)]


def mistakes(logp_w, logp_l, ref_w, ref_l, beta):
    w, l = logp_w.detach() - ref_w, logp_l.detach() - ref_l  # log pi / pi_ref
    gap = w - l
    return [(tr("chosen and rejected swapped (or log pi_ref - log pi where log pi - log pi_ref "
                "belongs): the sign of the gap flipped", "被选中的和被拒绝的弄反了（或者把 "
                "log π - log π_ref 写成了 log π_ref - log π）：分差的符号反了"),
             -logsigmoid(-beta * gap).mean()),
            (tr("the reference left out: beta * (log pi(y_w) - log pi(y_l)), where each answer's "
                "log pi is measured against pi_ref's", "漏了参考策略：写成了 β * (log π(y_w) - "
                "log π(y_l))，每个回答的 log π 都要减去 π_ref 的"),
             -logsigmoid(beta * (logp_w.detach() - logp_l.detach())).mean()),
            (tr("beta outside: -beta * log sigmoid(gap), where beta scales the gap inside the "
                "sigmoid", "β 放在了外面：-β * log sigmoid(分差)；β 应该在 sigmoid 里面乘分差"),
             -beta * logsigmoid(gap).mean()),
            (tr("beta on the chosen answer's term only: beta * log(pi / pi_ref)(y_w) - "
                "log(pi / pi_ref)(y_l)", "β 只乘了被选中的回答那一项：β * log(π / π_ref)(y_w) - "
                "log(π / π_ref)(y_l)"), -logsigmoid(beta * w - l).mean()),
            (tr("beta left out: -log sigmoid(gap)", "漏了 β：-log sigmoid(分差)"),
             -logsigmoid(gap).mean()),
            (tr("the sign: log sigmoid(...), the log-likelihood, where the loss is its negative",
                "符号反了：log sigmoid(...) 是对数似然，损失应该取负"),
             logsigmoid(beta * gap).mean()),
            (tr("sigmoid without the log: -sigmoid(beta * gap)",
                "sigmoid 外面没有取 log：-sigmoid(β * 分差)"), -torch.sigmoid(beta * gap).mean()),
            (tr("summed over the pairs (.sum()) where the loss is their mean (.mean())",
                "对偏好对求了和（.sum()），损失应该求均值（.mean()）"),
             -logsigmoid(beta * gap).sum()),
            (tr("ratios of probabilities, pi / pi_ref = exp(log pi - log pi_ref), where DPO's "
                "reward has their log", "用了概率之比 π / π_ref = exp(log π - log π_ref)；DPO 的奖励"
                "用的是它的对数"), -logsigmoid(beta * (w.exp() - l.exp())).mean())]
