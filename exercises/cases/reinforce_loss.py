"""The checks of exercises/reinforce_loss.py, REINFORCE's loss: log pi weighted by G_t or G_t -
V(s_t) (V detached), and the baseline's loss: its worked cases, its named mistakes and its runs."""

import math

import torch

from checking import tr, t, scalar, Fixed, logits_names
import runs

SCRIPT = "reinforce_cartpole"
FUNCTION = "reinforce_loss"
ORDER = 20  # its row in docs/exercises.md's table
OUTPUTS = ("loss_pi", "loss_v", "weights")
LOSSES = (0, 1)  # the outputs whose gradients (a) compares
RUN = runs.CARTPOLE
LOOP = runs.REINFORCE_LOOP
LEARN = runs.REINFORCE_LEARN


def loop_hint():
    return runs.ON_REAL_DATA()


def reinforce_case(baseline):
    """pi(.|s) = (0.5, 0.5), (0.25, 0.75), (0.8, 0.2), the actions 0, 1, 1: log pi(a|s) = ln 0.5,
    ln 0.75, ln 0.2 (no two alike); G = (3, 2, 1), V = (1, 2.5, 0.5): G - V = (2, -0.5, 0.5)."""
    policy = Fixed(torch.log(t([0.5, 0.5], [0.25, 0.75], [0.8, 0.2])), names=logits_names())
    value_net = Fixed(t(1.0, 2.5, 0.5), names=(tr("V(s)", "V(s)"),))
    data = dict(obs=torch.zeros(3, 4), act=torch.tensor([0, 1, 1]), ret=t(3.0, 2.0, 1.0))
    return policy, value_net, data, baseline


def reinforce_by_hand(baseline, weights=None, reduce=None, probs=False, v_scale=0.5, v_sum=False):
    """(loss_pi, loss_v, weights) of reinforce_case in plain Python (and the mistakes')."""
    G, V = (3.0, 2.0, 1.0), (1.0, 2.5, 0.5)
    pi = (0.5, 0.75, 0.2)  # pi(a_t|s_t) of the actions taken
    w = weights or ([g - v for g, v in zip(G, V)] if baseline else list(G))
    terms = [(p if probs else math.log(p)) * x for p, x in zip(pi, w)]
    loss_pi = -sum(terms) / (1 if reduce == "sum" else 3)
    squares = [(v - g) ** 2 for v, g in zip(V, G)]
    loss_v = v_scale * sum(squares) / (1 if v_sum else 3)
    return scalar(loss_pi), scalar(loss_v), t(*w)


def cases():
    return [
        (tr("baseline = False: the weights are G = (3, 2, 1); pi(a|s) = 0.5, 0.75, 0.2; "
            "V = (1, 2.5, 0.5)", "baseline = False：权重就是 G = (3, 2, 1)；pi(a|s) = 0.5、0.75、0.2；"
            "V = (1, 2.5, 0.5)"), reinforce_case(False), reinforce_by_hand(False)),
        (tr("baseline = True: the weights are G - V = (2, -0.5, 0.5), the same batch",
            "baseline = True：权重是 G - V = (2, -0.5, 0.5)，同一批数据"), reinforce_case(True),
         reinforce_by_hand(True)),
    ]


def mistakes(policy, value_net, data, baseline):
    G, V = [3.0, 2.0, 1.0], [1.0, 2.5, 0.5]
    right = reinforce_by_hand(baseline)
    w = right[2].tolist()
    mean = sum(w) / 3
    std = math.sqrt(sum((x - mean) ** 2 for x in w) / 2)
    return [
        (tr("the sign: +mean(log pi * weights) where the loss is its negative (descending it "
            "would make the actions taken\n    less likely the better they did)",
            "符号反了：损失应该是 -mean(log π * 权重)（如果对不带负号的式子做梯度下降，"
            "\n    回报越高的动作反而越不容易再被选中）"), (-right[0], right[1], right[2])),
        (tr("a sum over the batch (.sum()) where the script takes the mean (.mean()): the step "
            "then grows with the batch's length\n    (longer episodes, bigger steps, at the same "
            "step size)", "对这批数据求了和（.sum()），脚本求的是均值（.mean()）：这样每一步的大小"
            "会随这批数据的长度变大\n    （回合越长，步子越大，学习率却没变）"),
         reinforce_by_hand(baseline, reduce="sum")),
        (tr("the baseline added, G + V, where it is subtracted: G - V(s_t)",
            "基线加上去了，写成了 G + V；应该减去：G - V(s_t)"),
         reinforce_by_hand(baseline, weights=[g + v for g, v in zip(G, V)]) if baseline
         else None),
        (tr("the weight the other way round, V(s_t) - G_t: G_t - V(s_t) says how much better "
            "than expected the return was", "权重反过来了，写成了 V(s_t) - G_t：G_t - V(s_t) "
            "说的是回报比预期好多少"),
         reinforce_by_hand(baseline, weights=[v - g for g, v in zip(G, V)]) if baseline
         else None),
        (tr("baseline ignored: the weights are G_t alone where baseline = True asks for "
            "G_t - V(s_t)", "忽略了 baseline：baseline = True 时权重应该是 G_t - V(s_t)，"
            "你用的只是 G_t"), reinforce_by_hand(baseline, weights=G) if baseline else None),
        (tr("baseline ignored: G_t - V(s_t) where baseline = False (--no-baseline) asks for "
            "G_t alone", "忽略了 baseline：baseline = False（--no-baseline）时权重就是 G_t，"
            "你减去了 V(s_t)"),
         None if baseline else reinforce_by_hand(baseline, weights=[g - v for g, v in zip(G, V)])),
        (tr("the weights normalized, (w - mean) / std, as PPO's advantages are: this script "
            "uses them as they are", "把权重归一化了，(w - mean) / std，像 PPO 的优势那样："
            "这个脚本直接用它们"),
         reinforce_by_hand(baseline, weights=[(x - mean) / (std + 1e-8) for x in w])),
        (tr("pi(a|s) where log pi(a|s) belongs (the probability, not its log: dist.log_prob)",
            "用了 π(a|s)，应该是 log π(a|s)（用概率代替了它的对数：要用 dist.log_prob）"),
         reinforce_by_hand(baseline, probs=True)),
        (tr("the baseline's loss not halved: 0.5 * mean((V - G)^2)",
            "基线的损失没有乘 0.5：应该是 0.5 * mean((V - G)^2)"),
         reinforce_by_hand(baseline, v_scale=1.0)),
        (tr("the baseline's loss summed over the batch (.sum()) where the script takes the mean",
            "基线的损失对这批数据求了和（.sum()），脚本求的是均值"),
         reinforce_by_hand(baseline, v_sum=True))]


def gradient_mistake(loss, kind):
    """The mistake a gradient failure of `loss` ("loss_pi" or "loss_v") shows, or ''."""
    if loss == "loss_pi" and kind == "stray":
        return tr("V(s_t) not detached in the weight G_t - V(s_t): pi's loss then trains V too, "
                  "pushing every V(s_t) up\n    (by -log pi(a_t|s_t) >= 0, whatever G_t is), not "
                  "toward G_t: values.detach() in the weight, values as they are in loss_v",
                  "权重 G_t - V(s_t) 里的 V(s_t) 没有 detach：这样 π 的损失也会训练 V，不管 G_t 是多少，"
                  "\n    都把每个 V(s_t) 往上推（力度是 -log π(a_t|s_t) >= 0），而不是让 V 拟合 G_t："
                  "权重里用 values.detach()，loss_v 里用 values 本身")
    if loss == "loss_pi" and kind == "cut":
        return tr("log pi(a|s) computed without a gradient (torch.no_grad(), .detach() or "
                  ".item()): pi would never move", "log π(a|s) 是在不带梯度的情况下算的"
                  "（torch.no_grad()、.detach() 或 .item()）：π 永远不会变")
    if loss == "loss_v" and kind == "cut":
        return tr("V(s_t) detached in loss_v too: the baseline would never learn; detach it in "
                  "pi's weight only", "loss_v 里的 V(s_t) 也 detach 了：基线永远学不到东西；"
                  "只在 π 的权重里 detach")
    return ""
