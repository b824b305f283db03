"""Check an exercise: python exercises/check.py gae   (no name: a table of all of them)

Three stages, each stopped at the first that fails:
  (a) worked cases: your function on hand-computed examples, the traps included; for a loss,
      its gradient too, against the script's own function's (cut, reversed, or wrong); a wrong
      value that a known mistake gives is named;
  (b) the real loop: the script's own train() on a fixed seed, for a few updates, once with
      your function swapped in and once with the script's own; their logs are compared update
      by update, and the first quantity that differs is named with both values (and a loop
      that never calls your function fails loudly);
  (c) learning: the script with your function does what it is for (docs/exercises.md gives
      each one's bar and time). --no-learning stops after (b).
Your function reaches the script as the experiments' variants do (experiments/lab.swapped):
the script itself has no branch and no flag for it. Messages in Chinese or English: --lang,
else the locale. Exit status 0 only when every stage run passed.

检查练习，分三关：(a) 手算的例子（损失函数还比较梯度）；(b) 把你的函数换进脚本自己的 train()，
和原版逐次更新比较日志；(c) 用你的函数把任务学会。--lang zh 显示中文（不写时看系统语言）。
"""

import argparse
import contextlib
import copy
import csv
import importlib
import importlib.util
import inspect
import io
import math
import sys
import tempfile
import time
from pathlib import Path
from types import SimpleNamespace

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE.parent / "experiments"))

import numpy as np  # noqa: E402
import torch  # noqa: E402
import torch.nn.functional as F  # noqa: E402
from torch.distributions import Categorical, kl_divergence  # noqa: E402  (the mistakes' values)

import common  # noqa: E402
import help_zh  # noqa: E402
from lab import DDPG_IN_MINUTES, swapped  # noqa: E402

NOT_WRITTEN = "not written yet"

# The messages' language: --lang zh|en, else the locale (LC_ALL, LC_MESSAGES, LANG: zh_CN.UTF-8
# and the like give Chinese), else English. The terms are those of README.zh-CN.md's glossary.
LANG = "en"


def locale_lang():
    return "zh" if help_zh.chinese_locale() else "en"  # the scripts' --help reads it alike


def tr(en, zh):
    """The message in the learner's language."""
    return zh if LANG == "zh" else en


class Failed(Exception):
    """A stage failed: the message says what differs."""


# ==== Stage (a): worked cases ==============================================================


def t(*rows):
    return torch.tensor(rows, dtype=torch.float32)


def scalar(x):
    return torch.tensor(x, dtype=torch.float32)


def flags(*rows):
    return torch.tensor(rows, dtype=torch.bool)


class Fixed(torch.nn.Module):
    """A 'network' that returns the same outputs for any batch of observations; `names` say
    what each output is, for the messages about its gradient."""

    def __init__(self, *outputs, names=()):
        super().__init__()
        self.outputs = [torch.nn.Parameter(o.clone()) for o in outputs]
        self.names = list(names) + [f"output {i}" for i in range(len(names), len(outputs))]
        for i, p in enumerate(self.outputs):
            self.register_parameter(f"out{i}", p)

    def forward(self, obs):
        # o * 1, not o: a new tensor from the graph, as a network's output is, so that an
        # output computed under torch.no_grad() carries no gradient here either
        out = [o * 1 for o in self.outputs]
        return out[0] if len(out) == 1 else tuple(out)


def returns_cases():
    # V(s_1) = (8, 7) differs from V(s_2) = 9: a bootstrap from the wrong step shows
    r, v = t([1.0, 1.0], [1.0, 1.0], [1.0, 1.0]), t([8.0, 7.0], [9.0, 9.0], [4.0, 4.0])
    no = flags([False, False], [False, False], [False, False])
    at1 = flags([False, False], [True, True], [False, False])
    env0 = flags([False, False], [True, False], [False, False])
    return [
        (tr("no episode ends: bootstrap with V(s_3) = 4 at the rollout's end",
            "没有回合结束：在这批数据的末尾用 V(s_3) = 4 自举"),
         (r, v, no, no, 0.5), t([2.25, 2.25], [2.5, 2.5], [3.0, 3.0])),
        (tr("terminated at t = 1 (both envs): no future after it",
            "t = 1 处终止（两个环境都是）：之后没有未来"),
         (r, v, at1, no, 0.5), t([1.5, 1.5], [1.0, 1.0], [3.0, 3.0])),
        (tr("truncated at t = 1 (a time limit): bootstrap with V(final obs) = 9 there",
            "t = 1 处时间截断：在那里用 V(最后的观测) = 9 自举"),
         (r, v, no, at1, 0.5), t([3.75, 3.75], [5.5, 5.5], [3.0, 3.0])),
        (tr("terminated and truncated at once: termination wins",
            "同一步既终止又时间截断：按终止算"),
         (r, v, at1, at1, 0.5), t([1.5, 1.5], [1.0, 1.0], [3.0, 3.0])),
        (tr("env 0 truncated at t = 1, env 1 not: each column on its own",
            "t = 1 处环境 0 时间截断，环境 1 没有：每一列各算各的"),
         (r, v, no, env0, 0.5), t([3.75, 2.25], [5.5, 2.5], [3.0, 3.0])),
    ]


def gae_cases():
    r, v, nv = t([1.0, 1.0], [1.0, 1.0]), t([1.0, 1.0], [2.0, 2.0]), t([2.0, 2.0], [4.0, 4.0])
    no, at0 = flags([False, False], [False, False]), flags([True, True], [False, False])
    env1 = flags([False, True], [False, False])
    return [
        (tr("lam = 1, no episode ends: A_1 = delta_1 = 1, A_0 = delta_0 + 0.5 * A_1",
            "lam = 1，没有回合结束：A_1 = delta_1 = 1，A_0 = delta_0 + 0.5 * A_1"),
         (r, v, nv, no, no, 0.5, 1.0), t([1.5, 1.5], [1.0, 1.0])),
        (tr("lam = 0.5: A_0 = delta_0 + gamma * lam * A_1 = 1 + 0.25",
            "lam = 0.5：A_0 = delta_0 + gamma * lam * A_1 = 1 + 0.25"),
         (r, v, nv, no, no, 0.5, 0.5), t([1.25, 1.25], [1.0, 1.0])),
        (tr("terminated at t = 0: delta_0 = r_0 - V(s_0) = 0, and A_1 (a new episode) not added",
            "t = 0 处终止：delta_0 = r_0 - V(s_0) = 0，A_1（新回合的）不加进来"),
         (r, v, nv, at0, no, 0.5, 1.0), t([0.0, 0.0], [1.0, 1.0])),
        (tr("truncated at t = 0: delta_0 keeps gamma * V(final obs) = 1, A_1 not added",
            "t = 0 处时间截断：delta_0 保留 gamma * V(最后的观测) = 1，A_1 不加进来"),
         (r, v, nv, no, at0, 0.5, 1.0), t([1.0, 1.0], [1.0, 1.0])),
        (tr("terminated and truncated at once at t = 0: termination wins, delta_0 = 0",
            "t = 0 处同时终止和时间截断：按终止算，delta_0 = 0"),
         (r, v, nv, at0, at0, 0.5, 1.0), t([0.0, 0.0], [1.0, 1.0])),
        (tr("env 1 truncated at t = 0, env 0 not: each column on its own",
            "t = 0 处环境 1 时间截断，环境 0 没有：每一列各算各的"),
         (r, v, nv, no, env1, 0.5, 1.0), t([1.5, 1.0], [1.0, 1.0])),
        (tr("truncated at t = 0, V(final obs) = next_values[0] = 6, here not values[1] = 2 "
            "(next_values is the input to use): delta_0 = 1 + 0.5 * 6 - 1 = 3",
            "t = 0 处时间截断，V(最后的观测) = next_values[0] = 6，这里不等于 values[1] = 2"
            "（要用的是输入 next_values）：delta_0 = 1 + 0.5 * 6 - 1 = 3"),
         (r, v, t([6.0, 6.0], [4.0, 4.0]), no, at0, 0.5, 1.0), t([3.0, 3.0], [1.0, 1.0])),
    ]


def logits_names():
    return (tr("pi's logits", "π 的 logits"),)


def clip_cases():
    # pi = (0.5, 0.5) everywhere; pi_old of the taken action 0.25, 0.8 or 0.45, so the ratios
    # r = 2, 0.625, 1.111 are not reciprocal pairs: exp(logp_old - logp) gives other values.
    policy = Fixed(t([0.0, 0.0]).expand(6, 2), names=logits_names())
    data = dict(obs=torch.zeros(6, 1), act=torch.tensor([0, 0, 1, 1, 0, 1]),
                adv=t(1.0, -1.0, 1.0, -1.0, 2.0, -3.0),
                logp=torch.log(t(0.25, 0.25, 0.8, 0.8, 0.45, 0.45)))
    # min(r A, clip(r, 0.8, 1.2) A) per sample: min(2, 1.2) = 1.2; min(-2, -1.2) = -2;
    # min(0.625, 0.8) = 0.625; min(-0.625, -0.8) = -0.8; r = 10/9 inside the band: 20/9, -30/9.
    # The loss is minus their mean.
    terms = [1.2, -2.0, 0.625, -0.8, 20 / 9, -30 / 9]
    return [(tr("r = 2, 2, 0.625, 0.625, 10/9, 10/9 against A = 1, -1, 1, -1, 2, -3; eps = 0.2",
                "r = 2, 2, 0.625, 0.625, 10/9, 10/9，A = 1, -1, 1, -1, 2, -3；eps = 0.2"),
             (policy, data, 0.2), (scalar(-sum(terms) / 6), None, None))]


def kl_cases():
    # pi = (0.5, 0.5), pi_old = (0.25, 0.75): r = 2 for action 0, 2/3 for action 1.
    policy = Fixed(t([0.0, 0.0]).expand(2, 2), names=logits_names())
    logits_old = torch.log(t([0.25, 0.75], [0.25, 0.75]))
    data = dict(obs=torch.zeros(2, 1), act=torch.tensor([0, 1]), adv=t(1.0, -1.0),
                logp=torch.log(t(0.25, 0.75)), logits_old=logits_old)
    kl = 0.25 * math.log(0.25 / 0.5) + 0.75 * math.log(0.75 / 0.5)  # KL(pi_old || pi)
    surrogate = (2.0 * 1.0 + (2 / 3) * -1.0) / 2
    return [(tr(f"beta = {beta}: -mean(r A) + beta KL(pi_old || pi), KL = {kl:.4f}",
                f"beta = {beta}：-mean(r A) + beta KL(pi_old || pi)，KL = {kl:.4f}"),
             (policy, data, beta), (scalar(-surrogate + beta * kl), None, None))
            for beta in (0.0, 2.0)]


def beta_cases():
    cfg = SimpleNamespace(d_targ=0.01, kl_tolerance=1.5, beta_factor=2.0)
    return [(tr(f"beta = 1, d = {d:g} (d_targ = 0.01, tolerance 1.5, factor 2)",
                f"β = 1，d = {d:g}（d_targ = 0.01，容差 1.5，倍数 2）"), (1.0, d, cfg),
             expected) for d, expected in ((0.001, 0.5), (0.02, 2.0), (0.01, 1.0),
                                           (0.01 / 1.5, 1.0), (0.01 * 1.5, 1.0))]


def a2c_cases():
    # pi = (0.5, 0.5): log pi(a|s) = -ln 2, entropy ln 2; V = (1, 2); R = (2, 2.5). The
    # advantages given, (0.5, -1), are not R - V = (1, 0.5): an answer that recomputes A
    # from the critic gets another loss_pi (and sends the actor's gradient into V).
    model = Fixed(t([0.0, 0.0]).expand(2, 2), t(1.0, 2.0),
                  names=(tr("pi's logits", "π 的 logits"), tr("V(s)", "V(s)")))
    data = dict(obs=torch.zeros(2, 1), act=torch.tensor([0, 1]), adv=t(0.5, -1.0),
                ret=t(2.0, 2.5))
    cfg = SimpleNamespace(vf_coef=0.5, ent_coef=0.01)
    loss_pi, loss_v, entropy = math.log(2) * (0.5 - 1.0) / 2, 0.5 * (1.0 + 0.25) / 2, math.log(2)
    loss = loss_pi + 0.5 * loss_v - 0.01 * entropy
    return [(tr("A = (0.5, -1) as given (not R - V = (1, 0.5)); c1 = 0.5, c2 = 0.01",
                "A = (0.5, -1)，照给的用（不是 R - V = (1, 0.5)）；c1 = 0.5，c2 = 0.01"),
             (model, data, cfg),
             (scalar(loss), dict(loss_pi=loss_pi, loss_v=loss_v, entropy=entropy)))]


def td_cases():
    return [(tr("r = (1, 2, 3), terminated at the second, Q' = (10, 10, -4), gamma = 0.9",
                "r = (1, 2, 3)，第二个终止，Q' = (10, 10, -4)，gamma = 0.9"),
             (t(1.0, 2.0, 3.0), t(1.0, 0.0, 1.0), t(10.0, 10.0, -4.0), 0.9), t(10.0, 2.0, -0.6))]


def actor_cases():
    actor = Fixed(t([2.0], [4.0]), names=(tr("mu(s)", "mu(s)"),))  # mu(s) for the two states
    critic = lambda obs, action: (obs * action).sum(-1)  # noqa: E731  Q(s, a) = s . a
    return [(tr("mu(s) = (2, 4) at s = (1, 2), Q(s, a) = s * a: Q(s, mu(s)) = (2, 8)",
                "s = (1, 2) 处 mu(s) = (2, 4)，Q(s, a) = s * a：Q(s, mu(s)) = (2, 8)"),
             (actor, critic, t([1.0], [2.0])), scalar(-5.0))]


def group_cases():
    # Two groups of G = 4: (1, 0, 0, 0): mean 0.25, std 0.5 (n - 1); (1, 1, 0, 1): mean 0.75,
    # std 0.5. A flat group (1, 1, 1, 1): 0, not nan.
    r = t(1.0, 0.0, 0.0, 0.0, 1.0, 1.0, 0.0, 1.0)
    s = 0.5 + 1e-4
    return [
        (tr("G = 4, groups (1, 0, 0, 0) and (1, 1, 0, 1): means 0.25, 0.75, stds 0.5 (n - 1)",
            "G = 4，两组 (1, 0, 0, 0) 和 (1, 1, 0, 1)：均值 0.25、0.75，标准差 0.5（n - 1）"),
         (r, 4, True), t(0.75 / s, -0.25 / s, -0.25 / s, -0.25 / s,
                         0.25 / s, 0.25 / s, -0.75 / s, 0.25 / s)),
        (tr("scale = False (Dr. GRPO): r - mean of the group only",
            "scale = False（Dr. GRPO）：只减去组内均值"),
         (r, 4, False), t(0.75, -0.25, -0.25, -0.25, 0.25, 0.25, -0.75, 0.25)),
        (tr("a flat group (1, 1, 1, 1) beside (1, 0, 0, 0): 0 for the flat one, not nan",
            "全相同的一组 (1, 1, 1, 1) 和 (1, 0, 0, 0)：全相同的那组是 0，不是 nan"),
         (t(1.0, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0), 4, True),
         t(0.0, 0.0, 0.0, 0.0, 0.75 / s, -0.25 / s, -0.25 / s, -0.25 / s)),
    ]


def group_mistakes(rewards, G, scale):
    def adv(view=lambda r: r.view(-1, G), unbiased=True, eps=1e-4, whole=False):
        r = rewards.view(1, -1) if whole else view(rewards)
        a = r - r.mean(1, keepdim=True)
        if scale:
            a = a / (r.std(1, keepdim=True, unbiased=unbiased) + eps)
        return a.reshape(-1) if not whole else a.reshape(-1)
    return [(tr("the std without Bessel's correction (n, not n - 1; torch's .std() is n - 1)",
                "标准差没有用贝塞尔校正（除以 n，不是 n - 1；torch 的 .std() 除以 n - 1）"),
             adv(unbiased=False)),
            (tr("the mean and std over the whole batch, not each prompt's group",
                "均值和标准差是对整个批量算的，不是对每道题的那一组"), adv(whole=True)),
            (tr("the groups read down the columns (view(G, -1)): a group is G consecutive rewards",
                "分组分错了（view(G, -1)）：一组是连续的 G 个奖励"),
             (lambda r: (r - r.mean(0, keepdim=True)) / (
                 r.std(0, keepdim=True) + 1e-4 if scale else 1))(rewards.view(G, -1)).reshape(-1)),
            (tr("the 1e-4 left out of the denominator", "分母里漏了 1e-4"), adv(eps=0.0)),
            (tr("the 1e-4 as a floor (std.clamp_min(1e-4)) where it is added (std + 1e-4)",
                "把 1e-4 当成了下限（std.clamp_min(1e-4)），应该是加上去（std + 1e-4）"),
             adv(eps=0.0)),
            (tr("1e-8 added where this project adds 1e-4 (std + 1e-4)",
                "加的是 1e-8，本项目加的是 1e-4（std + 1e-4）"), adv(eps=0.0)),
            (tr("scale ignored: divided by the std where scale = False asks for r - mean only",
                "忽略了 scale：scale = False 时只减均值，不除以标准差"),
             (lambda r: ((r - r.mean(1, keepdim=True)) / (r.std(1, keepdim=True) + 1e-4)))(
                 rewards.view(-1, G)).reshape(-1))]


def group_eps_mistake(fn):
    """Which denominator `fn` uses, told apart on a group whose std (5e-6) is far below 1e-4:
    the last advantage is 7.5e-6 / (5e-6 + 1e-4) = 0.0714 right, 0.075 clamped at 1e-4, 1.497
    with 1e-8 added, 1.5 with nothing."""
    try:
        a = float(fn(t(0.0, 0.0, 0.0, 1e-5), 4, True)[3])
    except Exception:  # noqa: BLE001  the first case's message stands alone
        return None
    return (2 if abs(a - 0.075) < 1e-3 else 3 if abs(a - 1.497) < 2e-3
            else 1 if abs(a - 1.5) < 1e-3 or math.isnan(a) else None)


def grpo_by_hand(logp, logp_old, logp_ref, adv, mask, cfg, kl_reversed=False, no_mask=False,
                 token_mean=False, kl_sign=1.0, no_clip=False, ratio_one=False,
                 kl_unmasked=False, always_norm=False, k1=False, all_mean=False):
    """The loss element by element, in plain Python (and the named mistakes' versions)."""
    eps, per_completion, total, tokens = cfg.clip_coef, [], 0.0, 0.0
    for i in range(len(adv)):
        row = 0.0
        for j in range(logp.shape[1]):
            r = 1.0 if ratio_one else math.exp(float(logp[i, j] - logp_old[i, j]))
            a = float(adv[i])
            s = r * a if no_clip else min(r * a, min(max(r, 1 - eps), 1 + eps) * a)
            x = float(logp[i, j] - logp_ref[i, j]) if kl_reversed else float(
                logp_ref[i, j] - logp[i, j])
            d = -x if k1 else math.exp(x) - x - 1
            m = 1.0 if no_mask else float(mask[i, j])
            row += s * m - kl_sign * cfg.beta * d * (1.0 if kl_unmasked else m)
            tokens += float(mask[i, j])
        total += row
        n = float(mask[i].sum()) if cfg.length_norm or always_norm else logp.shape[1]
        per_completion.append(row / n)
    if all_mean:  # one mean over every (B, L) entry, the padding's zeros counted
        return scalar(-total / logp.numel())
    return scalar(-total / tokens if token_mean else -sum(per_completion) / len(adv))


def grpo_cases():
    # Two completions of 3 tokens, the first with 2 of its own (its third is padding). Ratios
    # 1.5, 0.9, 1.1 / 0.7, 1.05, 1.3 against A = 1.5, -0.5; pi_ref / pi of 2, 0.5, 0.76, ...
    # (the padding token's pi_ref / pi is not 1: its KL term, and its gradient, are not 0, so
    # a KL left unmasked shows)
    logp_old = torch.log(t([0.4, 0.5, 0.6], [0.5, 0.4, 0.3]))
    logp = (torch.log(t([0.6, 0.45, 0.66], [0.35, 0.42, 0.39]))).requires_grad_()
    logp_ref = torch.log(t([0.3, 0.9, 0.5], [0.7, 0.21, 0.5]))
    adv, mask = t(1.5, -0.5), t([1.0, 1.0, 0.0], [1.0, 1.0, 1.0])
    cases = []
    for norm in (True, False):
        cfg = SimpleNamespace(clip_coef=0.2, beta=0.1, length_norm=norm)
        args = (logp, logp_old, logp_ref, adv, mask, cfg)
        cases.append((tr(f"2 completions of 3 tokens, the first's third masked; eps = 0.2, "
                         f"beta = 0.1, length_norm = {norm}",
                         f"2 个回答各 3 个 token，第一个的第三个被掩掉；eps = 0.2，β = 0.1，"
                         f"length_norm = {norm}"), args,
                      (grpo_by_hand(*(a.detach() if torch.is_tensor(a) else a for a in args)),
                       None)))
    return cases


def grpo_mistakes(logp, logp_old, logp_ref, adv, mask, cfg):
    args = [a.detach() if torch.is_tensor(a) else a for a in (logp, logp_old, logp_ref, adv, mask)]
    return [(tr("k3 the other way round: pi / pi_ref where k3 of KL(pi || pi_ref) has pi_ref / pi",
                "k3 的方向反了：用了 π / π_ref，KL(π || π_ref) 的 k3 用 π_ref / π"),
             grpo_by_hand(*args, cfg, kl_reversed=True)),
            (tr("the mask not applied: the padding after the first \".\" counted",
                "没有乘掩码：第一个 \".\" 之后的填充也算进去了"),
             grpo_by_hand(*args, cfg, no_mask=True)),
            (tr("the KL term not masked: padding tokens pay a KL ((surrogate - beta * D) * mask: "
                "the mask covers both terms)", "KL 项没有乘掩码：填充的 token 也付了 KL 惩罚（应该是 "
                "(surrogate - β * D) * mask：掩码管两项）"),
             grpo_by_hand(*args, cfg, kl_unmasked=True)),
            (tr("k1, log(pi / pi_ref), where this loss uses k3, pi_ref / pi - log(pi_ref / pi) - 1 "
                "(never negative)", "用了 k1，即 log(π / π_ref)；这个损失用的是 k3，即 "
                "π_ref / π - log(π_ref / π) - 1（永远不为负）"), grpo_by_hand(*args, cfg, k1=True)),
            (tr("one mean over all (B, L) entries, the padding's zeros counted: each completion "
                "is averaged over its own tokens first", "对全部 (B, L) 个位置求了一个均值，把填充的 0 "
                "也算进去了：应该先在每个回答自己的 token 上平均"), grpo_by_hand(*args, cfg, all_mean=True)),
            (tr("length_norm ignored: each completion divided by its own length where "
                "length_norm = False divides by the longest possible one (L, the same for all)",
                "忽略了 length_norm：length_norm = False 时应该除以最长可能的长度 L（大家都一样），"
                "而你除以了每个回答自己的长度"),
             grpo_by_hand(*args, cfg, always_norm=True) if not cfg.length_norm else None),
            (tr("one mean over all the batch's tokens, where each completion is averaged over its "
                "own tokens first", "对整个批量的所有 token 求了一个均值，应该先在每个回答自己的 token "
                "上平均"), grpo_by_hand(*args, cfg, token_mean=True)),
            (tr("the KL penalty's sign: + beta * D where the objective subtracts it",
                "KL 惩罚的符号反了：目标函数里应该减去 β * D"),
             grpo_by_hand(*args, cfg, kl_sign=-1.0)),
            (tr("no clip: r * A alone, without min(.., clip(r) A)",
                "没有裁剪：只用了 r * A，没有 min(.., clip(r) A)"),
             grpo_by_hand(*args, cfg, no_clip=True)),
            (tr("the ratio against logp itself (always 1): pi_old is logp_old",
                "比值的分母用了 logp 自己（比值总是 1）：π_old 是 logp_old"),
             grpo_by_hand(*args, cfg, ratio_one=True)),
            (tr("the sign: the objective returned, where the loss is its negative",
                "符号反了：返回的是目标函数，损失应该取负"), -grpo_by_hand(*args, cfg))]


class ValueOfFirst(torch.nn.Module):
    """A model whose V(s) is the obs's first number (a Linear layer with weights (1, 0) and
    a parameter, so a value computed outside torch.no_grad() carries a gradient); logits 0."""

    def __init__(self):
        super().__init__()
        self.v = torch.nn.Linear(2, 1)
        with torch.no_grad():
            self.v.weight.copy_(t([1.0, 0.0]))
            self.v.bias.zero_()

    def forward(self, obs):
        return torch.zeros(*obs.shape[:-1], 2), self.v(obs).squeeze(-1)


def a2c_targets_case(lam):
    obs = torch.stack([t([1.0, 0.0], [2.0, 0.0]), t([3.0, 0.0], [4.0, 0.0]),
                       t([5.0, 0.0], [6.0, 0.0])])  # V(s_t) = (1, 2), (3, 4), (5, 6)
    rollout = dict(obs=obs, rewards=torch.ones(3, 2), terminated=flags(
        [False, False], [False, True], [False, False]), truncated=flags(
        [True, False], [False, False], [False, False]))
    next_obs = obs.new_tensor([[7.0, 0.0], [8.0, 0.0]]).numpy()  # V = (7, 8)
    return ValueOfFirst(), rollout, next_obs, SimpleNamespace(gamma=0.5, lam=lam)


def a2c_targets_cases():
    # next_values = (3, 4), (5, 6), (7, 8). lam none: env 0 truncated at t = 0 (bootstraps
    # with V = 3), env 1 terminated at t = 1. R = (2.5, 1.5), (3.25, 1), (4.5, 5); A = R - V.
    # lam = 0.5: deltas (1.5, 1), (0.5, -3), (-0.5, -1); A_t = delta_t + 0.25 * A_{t+1} where
    # no episode ended at t: A = (1.5, 0.25), (0.375, -3), (-0.5, -1); R = A + V.
    return [
        (tr("lam none: V(s_t) = (1, 2), (3, 4), (5, 6), V(next_obs) = (7, 8); env 0 truncated "
            "at t = 0, env 1 terminated at t = 1; gamma = 0.5",
            "lam 为 none：V(s_t) = (1, 2), (3, 4), (5, 6)，V(next_obs) = (7, 8)；t = 0 处环境 0 "
            "时间截断，t = 1 处环境 1 终止；gamma = 0.5"), None,
         (t([2.5, 1.5], [3.25, 1.0], [4.5, 5.0]), t([1.5, -0.5], [0.25, -3.0], [-0.5, -1.0]))),
        (tr("the same rollout, lam = 0.5 (GAE)", "同一批数据，lam = 0.5（GAE）"), 0.5,
         (t([2.5, 2.25], [3.375, 1.0], [4.5, 5.0]), t([1.5, 0.25], [0.375, -3.0], [-0.5, -1.0]))),
    ]


def a2c_targets_mistakes(rollout, values, last):
    r, term, trunc = rollout["rewards"], rollout["terminated"], rollout["truncated"]

    def with_next(nv):
        return common.discounted_returns(r, nv, term, trunc, 0.5)
    return [(tr("next_values = values: V(s_t) where V(s_{t+1}) belongs (not shifted by one)",
                "next_values = values：用了 V(s_t)，应该是 V(s_{t+1})（没有错开一步）"),
             with_next(values)),
            (tr("no bootstrap at the rollout's end: V(next_obs) replaced by 0",
                "这批数据的末尾没有自举：V(next_obs) 换成了 0"),
             with_next(torch.cat([values[1:], torch.zeros_like(last)[None]]))),
            (tr("shifted the wrong way: V(next_obs) put first, torch.cat([last, values[:-1]])",
                "错开的方向反了：把 V(next_obs) 放在了最前面，torch.cat([last, values[:-1]])"),
             with_next(torch.cat([last[None], values[:-1]])))]


def check_a2c_targets(fn):
    for what, lam, (returns, advantages) in a2c_targets_cases():
        model, rollout, next_obs, cfg = a2c_targets_case(lam)
        got = fn(model, rollout, next_obs, cfg)
        try:
            if not isinstance(got, tuple) or len(got) != 2:
                raise Failed(tr(f"expected (returns, advantages), got {type(got).__name__}",
                                f"应该返回 (returns, advantages)，得到的是 {type(got).__name__}"))
            compare("returns", got[0], returns)
            compare("advantages", got[1], advantages)
            if got[0].requires_grad or got[1].requires_grad:
                raise Failed(tr(
                    "the values are right, and they carry a gradient into the critic: compute V "
                    "under torch.no_grad() (the targets are constants; A2C's actor loss would "
                    "otherwise train the critic)",
                    "数值对，但它们带着梯度连到评论员：要在 torch.no_grad() 下计算 V（目标是常数；"
                    "否则 A2C 演员的损失会去训练评论员）"))
        except Failed as e:
            named = ""
            if lam is None and isinstance(got, tuple) and torch.is_tensor(got[0]):
                values = rollout["obs"][..., 0]
                for label, value in a2c_targets_mistakes(rollout, values, t(7.0, 8.0)):
                    if got[0].shape == value.shape and torch.allclose(got[0].detach(), value):
                        named = tr("\n  this is exactly what this mistake gives: ",
                                   "\n  你的值恰好是这个常见错误会得到的值：\n    ") + label
            raise Failed(tr("case: ", "例子：") + f"{what}\n  {e}{named}") from None


def small_ddpg(seed=0):
    """Tiny DDPG networks and a minibatch (3 states, 1 action), every one seeded."""
    ddpg = importlib.import_module("ddpg_walker")
    torch.manual_seed(seed)
    low, high = torch.tensor([-2.0]).numpy(), torch.tensor([2.0]).numpy()
    nets = ddpg.build(3, 1, low.astype("float64"), high.astype("float64"),
                      SimpleNamespace(hidden=8, actor_lr=1e-2, critic_lr=1e-2), "cpu")
    # the targets apart from the networks, as after some training (a target = its network
    # would hide a target taken from the network being trained)
    with torch.no_grad():
        for net in (nets["actor_target"], nets["critic_target"]):
            for p in net.parameters():
                p.add_(0.3 * torch.randn_like(p))
    batch = (torch.randn(4, 3), torch.rand(4, 1) * 4 - 2, torch.randn(4), torch.randn(4, 3),
             t(1.0, 0.0, 1.0, 1.0))
    return nets, batch, SimpleNamespace(gamma=0.9, tau=0.1)


def ddpg_critic_mistakes(nets, batch, cfg):
    obs, action, reward, next_obs, not_done = batch
    c, a, ct, at = nets["critic"], nets["actor"], nets["critic_target"], nets["actor_target"]
    with torch.no_grad():
        q = c(obs, action)
        return [(tr("the target from the networks being trained, Q(s', mu(s')), not the target "
                    "networks Q'(s', mu'(s'))", "TD 目标用了正在训练的当前网络 Q(s', mu(s'))，"
                    "不是目标网络 Q'(s', mu'(s'))"),
                 F.mse_loss(q, reward + cfg.gamma * not_done * c(next_obs, a(next_obs)))),
                (tr("the target from the critic being trained, Q(s', mu'(s')), not the target "
                    "critic Q'", "TD 目标用了正在训练的评论员 Q(s', mu'(s'))，不是目标评论员 Q'"),
                 F.mse_loss(q, reward + cfg.gamma * not_done * c(next_obs, at(next_obs)))),
                (tr("the target's action from the actor being trained, mu(s'), not mu'(s')",
                    "目标里的动作用了正在训练的演员 mu(s')，不是 mu'(s')"),
                 F.mse_loss(q, reward + cfg.gamma * not_done * ct(next_obs, a(next_obs)))),
                (tr("the target at s, not s' (obs and next_obs mixed up)",
                    "目标在 s 处取值，不是 s'（obs 和 next_obs 弄混了）"),
                 F.mse_loss(q, reward + cfg.gamma * not_done * ct(obs, at(obs)))),
                (tr("Q(s', a) compared with the target (next_obs where obs belongs)",
                    "用 Q(s', a) 去和目标比（该用 obs 的地方用了 next_obs）"),
                 F.mse_loss(c(next_obs, action), reward + cfg.gamma * not_done * ct(
                     next_obs, at(next_obs))))]


def ddpg_update_keeping(nets, batch, cfg, kept):
    """The script's update with one optimizer's zero_grad() left out (kept: "critic" or
    "actor"): the gradients of the update before are added to this one's."""
    ddpg = importlib.import_module("ddpg_walker")
    actor, critic, actor_target, critic_target, actor_opt, critic_opt = nets.values()
    obs, action, reward, next_obs, not_done = batch
    with torch.no_grad():
        y = ddpg.td_target(reward, not_done, critic_target(next_obs, actor_target(next_obs)),
                           cfg.gamma)
    critic_loss = F.mse_loss(critic(obs, action), y)
    if kept != "critic":
        critic_opt.zero_grad()
    critic_loss.backward()
    critic_opt.step()
    actor_loss = ddpg.compute_loss_actor(actor, critic, obs)
    if kept != "actor":
        actor_opt.zero_grad()
    actor_loss.backward(inputs=list(actor.parameters()))
    actor_opt.step()
    ddpg.soft_update(critic_target, critic, cfg.tau)
    ddpg.soft_update(actor_target, actor, cfg.tau)


def gap(p, q):
    return float((p - q).detach().abs().max())


def check_ddpg_update(fn):
    own = importlib.import_module("ddpg_walker").ddpg_update
    theirs, batch, cfg = small_ddpg()
    yours = copy.deepcopy(theirs)
    mistakes = ddpg_critic_mistakes(yours, batch, cfg)
    with torch.no_grad():  # the actor's loss on the critic before its step: the steps swapped
        actor_first = float(-yours["critic"](batch[0], yours["actor"](batch[0])).mean())
    expected = own(*theirs.values(), batch, cfg)
    got = fn(*yours.values(), batch, cfg)
    case = tr("case: one update of tiny networks (3 states, 1 action, 4 samples, the second "
              "terminated), gamma = 0.9, tau = 0.1, beside the script's own\n  ",
              "例子：小网络上的一次更新（状态 3 维、动作 1 维、4 个样本，第二个终止），gamma = 0.9，"
              "tau = 0.1，和脚本自己的并排比较\n  ")
    if not isinstance(got, tuple) or len(got) != 2:
        raise Failed(case + tr(f"expected (critic_loss, actor_loss), got {type(got).__name__}",
                               f"应该返回 (critic_loss, actor_loss)，得到的是 {type(got).__name__}"))
    for name in ("critic_target", "actor_target"):
        if any(p.grad is not None for p in yours[name].parameters()):
            raise Failed(case + tr(
                f"a gradient reached {name}: the target was computed with the graph (put it "
                f"under torch.no_grad(); the target is a constant)",
                f"梯度传到了 {name}：TD 目标是带着计算图算的（放进 torch.no_grad()；目标是常数）"))
    try:
        compare("critic_loss", got[0], expected[0])
    except Failed as e:
        named = [label for label, value in mistakes if abs(float(got[0]) - float(value)) < 1e-5]
        raise Failed(case + str(e) + (tr("\n  this is exactly what this mistake gives: ",
                                         "\n  你的值恰好是这个常见错误会得到的值：\n    ") + named[0]
                                      if named else "")) from None
    steps = [("critic", tr("the critic after its step", "评论员更新之后")),
             ("actor", tr("the actor after its step", "演员更新之后")),
             ("critic_target", tr("the critic's target after the soft update",
                                  "软更新之后的目标评论员")),
             ("actor_target", tr("the actor's target after the soft update",
                                 "软更新之后的目标演员"))]
    swapped_steps = ""
    if any(torch.is_tensor(x) and x.requires_grad for x in got):
        raise Failed(case + tr(
            "the losses returned with their graph: return critic_loss.detach(), "
            "actor_loss.detach() (the loop only logs them;\n  a graph kept with each would "
            "hold every step's tensors)",
            "返回的损失还带着计算图：应该 return critic_loss.detach(), actor_loss.detach()（循环"
            "只是记录它们；\n  带着图，每一步的张量都不能释放）"))
    try:
        got_actor = float(got[1])
    except (TypeError, ValueError, RuntimeError):
        got_actor = math.nan
    if abs(got_actor - float(expected[1])) > 1e-5 and abs(got_actor - actor_first) < 1e-5:
        swapped_steps = tr("\n  this is exactly what this mistake gives: the actor's step taken "
                           "before the critic's (the actor must learn from the updated critic)",
                           "\n  你的值恰好是这个常见错误会得到的值：\n"
                           "    演员在评论员之前更新了（演员要用更新过的评论员来学）")
    for name, what in steps:
        for (pname, p), q in zip(yours[name].named_parameters(), theirs[name].parameters()):
            if not torch.allclose(p, q, atol=1e-6):
                hint = dict(
                    critic=tr("one critic step toward y (critic_opt.zero_grad(), backward, step)",
                              "朝 y 做一步评论员更新（critic_opt.zero_grad()、backward、step）"),
                    actor=tr("the actor's step comes after the critic's, on the updated critic, "
                             "and changes only the actor (backward(inputs=actor's parameters) "
                             "or zero the critic's gradients)",
                             "演员在评论员更新之后、用更新过的评论员来更新，并且只改演员"
                             "（backward(inputs=演员的参数)，或者清掉评论员的梯度）"),
                    critic_target=tr("soft_update(critic_target, critic, tau) after both steps",
                                     "两步都做完之后 soft_update(critic_target, critic, tau)"),
                    actor_target=tr("soft_update(actor_target, actor, tau) after both steps",
                                    "两步都做完之后 soft_update(actor_target, actor, tau)"))[name]
                raise Failed(case + tr(f"{what}: {pname} differs from the script's own "
                                       f"(largest difference {gap(p, q):.3g}): ",
                                       f"{what}：{pname} 和脚本自己的不同（最大相差 "
                                       f"{gap(p, q):.3g}）：") + hint
                             + (swapped_steps if name == "actor" else ""))
    try:
        compare("actor_loss", got[1], expected[1])
    except Failed as e:
        raise Failed(case + str(e) + swapped_steps) from None
    # A second update on another minibatch, right after: what the first left in a .grad shows
    # here. The actor's backward without inputs= fills the critic's .grad too; harmless when
    # the critic's step zeroes it first (as the script's does), not when it is zeroed after.
    leftover = any(p.grad is not None and (q.grad is None or not torch.allclose(p.grad, q.grad))
                   for p, q in zip(yours["critic"].parameters(), theirs["critic"].parameters()))
    gen = torch.Generator().manual_seed(1)
    batch2 = (torch.randn(4, 3, generator=gen), torch.rand(4, 1, generator=gen) * 4 - 2,
              torch.randn(4, generator=gen), torch.randn(4, 3, generator=gen),
              t(1.0, 1.0, 0.0, 1.0))
    kept = {}  # what each zero_grad() left out gives, from the script's state after update 1
    for name in ("critic", "actor"):
        kept[name] = copy.deepcopy(theirs)  # deepcopy leaves .grad behind: copied here
        for key in ("critic", "actor"):
            for p, q in zip(kept[name][key].parameters(), theirs[key].parameters()):
                p.grad = None if q.grad is None else q.grad.clone()
        ddpg_update_keeping(kept[name], batch2, cfg, name)
    expected, got = own(*theirs.values(), batch2, cfg), fn(*yours.values(), batch2, cfg)
    case = tr("case: a second update right after the first, on another minibatch (the fourth "
              "sample terminated)\n  ", "例子：紧接着第一次之后的第二次更新，换一个小批量（第四个样本"
              "终止）\n  ")
    for name, what in steps:
        for (pname, p), q in zip(yours[name].named_parameters(), theirs[name].parameters()):
            if not torch.allclose(p, q, atol=1e-6):
                named = tr(
                    "\n  the first update left the actor's gradient in the critic's .grad (its "
                    "backward without inputs=),\n  and the critic's next step added it in: "
                    "backward(inputs=list(actor.parameters())), or\n  critic_opt.zero_grad() "
                    "right before critic_loss.backward()",
                    "\n  第一次更新把演员的梯度留在了评论员的 .grad 里（backward 没有写 inputs=），"
                    "\n  评论员下一步更新时把它也加了进去：用 backward(inputs=list(actor.parameters()))，"
                    "\n  或者紧挨着 critic_loss.backward() 之前调用 critic_opt.zero_grad()"
                ) if name == "critic" and leftover else ""
                if not named and name in kept and all(
                        torch.allclose(a, b, atol=1e-6) for a, b in
                        zip(yours[name].parameters(), kept[name][name].parameters())):
                    opt = f"{name}_opt.zero_grad()"
                    named = tr(f"\n  this is exactly what this mistake gives: gradients "
                               f"accumulated across updates: {opt} missing\n    (backward() "
                               f"adds to .grad; the first update's gradient was added to the "
                               f"second's)",
                               f"\n  你的值恰好是这个常见错误会得到的值：\n    梯度在两次更新之间"
                               f"累加了：漏了 {opt}\n    （backward() 是往 .grad 上加；第一次更新"
                               f"的梯度被加进了第二次的）")
                raise Failed(case + tr(f"{what}: {pname} differs from the script's own "
                                       f"(largest difference {gap(p, q):.3g})",
                                       f"{what}：{pname} 和脚本自己的不同（最大相差 "
                                       f"{gap(p, q):.3g}）") + named)
    try:
        compare("critic_loss", got[0], expected[0])
        compare("actor_loss", got[1], expected[1])
    except Failed as e:
        raise Failed(case + str(e)) from None


def check_soft_update(fn):
    target, source = torch.nn.Linear(2, 1), torch.nn.Linear(2, 1)
    with torch.no_grad():
        for p, q in zip(target.parameters(), source.parameters()):
            p.fill_(0.0)
            q.fill_(1.0)
    before = [id(p) for p in target.parameters()]
    for expected in (0.1, 0.19):
        fn(target, source, 0.1)
        got = [round(float(x), 6) for p in target.parameters() for x in p.detach().flatten()]
        if got != [expected] * 3:
            first = expected == 0.1  # what each mistake gives after the first update
            known = {0.9 if first else 0.99: tr(
                         "tau and 1 - tau swapped (the target jumps most of the way)",
                         "tau 和 1 - tau 放反了（目标网络一下子移动了大部分距离）"),
                     0.0: tr("the target did not move: assign in place (p_target.mul_/add_ or "
                             "copy_), and move the target, not the source\n    (p_target = ... "
                             "only rebinds a name; the network keeps its old tensor)",
                             "目标网络没有动：要原地赋值（p_target.mul_/add_ 或 copy_），并且动的是"
                             "目标网络，不是当前网络\n    （p_target = ... 只是让这个名字指向新张量，"
                             "网络里还是原来的那个）"),
                     1.0: tr("a hard copy: tau = 1 (the target becomes the network at once)",
                             "硬拷贝：相当于 tau = 1（目标网络一下子变成了当前网络）"),
                     0.09 if first else 0.171: tr(
                         "the two steps in the wrong order: add_(tau * theta) then mul_(1 - "
                         "tau) scales theta too;\n    mul_(1 - tau) first, then add_(tau * "
                         "theta)", "两步的顺序反了：先 add_(tau * theta) 再 mul_(1 - tau)，"
                         "把 theta 也缩小了；\n    应该先 mul_(1 - tau)，再 add_(tau * theta)")}
            label = known.get(got[0]) if len(set(got)) == 1 else None
            raise Failed(tr(
                f"case: theta' = 0, theta = 1, tau = 0.1: two soft updates in a row, 0.1 after "
                f"the first, 0.19 after the second\n  target's weights and bias after soft_update: "
                f"expected {expected} each (theta' = tau * theta + (1 - tau) * theta'), got {got}",
                f"例子：theta' = 0，theta = 1，tau = 0.1：连续软更新两次，第一次后应为 0.1，第二次后应为 "
                f"0.19\n  软更新后目标网络的权重和偏置：应该都是 {expected}（theta' = tau * theta + "
                f"(1 - tau) * theta'），得到的是 {got}") + (tr(
                    "\n  this is exactly what this mistake gives: ",
                    "\n  你的值恰好是这个常见错误会得到的值：\n    ") + label if label else ""))
    if [id(p) for p in target.parameters()] != before:
        raise Failed(tr("the target's parameters were replaced, not updated in place",
                        "目标网络的参数被换成了新的张量，而不是原地更新"))
    if [float(x) for p in source.parameters() for x in p.detach().flatten()] != [1.0] * 3:
        raise Failed(tr("soft_update changed the source network; only the target moves",
                        "soft_update 改了当前网络；应该只动目标网络"))


def td3_case(sigma, c, low, high):
    """nets whose targets are simple functions of s' (act_dim 1): mu'(s') = s'_2,
    Q1'(s', a) = s'_0 + (a - s'_2)^2, Q2'(s', a) = s'_1 + 2 (a - s'_2)^2; the critics give 0
    for every batch, so the gradient of the critics' loss gives y back: dL/dQ = 2 (Q - y) / B.
    The online actor, mu(s') = s'_2 + 1, is not the target's: a target taken from it shows."""
    class Zero(torch.nn.Module):
        def __init__(self):
            super().__init__()
            self.q = torch.nn.Parameter(torch.zeros(3))

        def forward(self, obs, action):
            return self.q

    class NoStep:
        def zero_grad(self):
            pass

        def step(self):
            pass

    nets = dict(actor_target=lambda s: s[:, 2:3], actor=lambda s: s[:, 2:3] + 1.0,
                critic_target=lambda s, a: s[:, 0] + ((a - s[:, 2:3]) ** 2).sum(-1),
                critic2_target=lambda s, a: s[:, 1] + 2 * ((a - s[:, 2:3]) ** 2).sum(-1),
                critic=Zero(), critic2=Zero(), critic_opt=NoStep())
    next_obs = t([3.0, 4.0, 0.0], [5.0, 2.0, 0.0], [1.0, 1.0, 0.0])
    batch = (torch.zeros(3, 3), torch.zeros(3, 1), t(1.0, 1.0, 1.0), next_obs, t(1.0, 1.0, 0.0))
    cfg = SimpleNamespace(gamma=0.5, target_noise=sigma, noise_clip=c, tau=0.005, policy_delay=2)
    return nets, batch, t(2.0), t(low), t(high), cfg


def td3_cases():
    # min(Q1', Q2') at a~: rows (3 + d, 4 + 2d), (5 + d, 2 + 2d), (1 + d, 1 + 2d), d = (a~ - mu')^2
    return [
        (tr("sigma = 0 (no smoothing): Q1' = (3, 5, 1), Q2' = (4, 2, 1), the third terminated: "
            "y = 1 + 0.5 * min", "σ = 0（不平滑）：Q1' = (3, 5, 1)，Q2' = (4, 2, 1)，第三个终止："
            "y = 1 + 0.5 * min"), (0.0, 0.5, [-3.0], [3.0]), t(2.5, 2.0, 1.0),
         [(tr("max where clipped double Q takes the smaller", "取了较大的，裁剪双 Q 要取较小的"),
           t(3.0, 3.5, 1.0)),
          (tr("Q1' alone (the second target critic unused)", "只用了 Q1'（没用第二个目标评论员）"),
           t(2.5, 3.5, 1.0)),
          (tr("the mean of Q1' and Q2' where their min belongs", "取了 Q1' 和 Q2' 的平均，应该取较小的"),
           t(2.75, 2.75, 1.0)),
          (tr("no not_done: a future after a termination",
              "没有乘 not_done，终止之后还加上了未来的价值"),
           t(2.5, 2.0, 1.5)),
          (tr("the critics being trained, nets[\"critic\"] and nets[\"critic2\"], where the target "
              "critics Q1', Q2' belong (here they give 0, so y = r)",
              "用了正在训练的当前评论员 nets[\"critic\"]、nets[\"critic2\"]，应该用目标评论员 "
              "Q1'、Q2'（这里它们给出 0，所以 y = r）"), t(1.0, 1.0, 1.0)),
          (tr("the actor being trained, nets[\"actor\"], where the target actor mu' belongs "
              "(here mu(s') = mu'(s') + 1)", "用了正在训练的当前演员 nets[\"actor\"]，应该用目标演员 "
              "mu'（这里 mu(s') = mu'(s') + 1）"), t(3.0, 3.0, 1.0))]),
        (tr("sigma = 10000, c = 0.5, half_width = 2: eps always clipped, |a~ - mu'(s')| = 1",
            "σ = 10000，c = 0.5，half_width = 2：噪声总被裁剪，|a~ - mu'(s')| = 1"),
         (1e4, 0.5, [-3.0], [3.0]), t(3.0, 3.0, 1.0),
         [(tr("eps not scaled by half_width (or clipped after the scaling): |a~ - mu'| = 0.5",
              "噪声没有乘 half_width（或者乘了之后才裁剪）：|a~ - mu'| = 0.5"), t(2.625, 2.25, 1.0)),
          (tr("the noise not clipped to [-c, c]: with sigma = 10000, a~ lands on the action "
              "box's edge, |a~ - mu'| = 3", "噪声没有裁剪到 [-c, c]：σ = 10000 时，a~ 落在动作范围的"
              "边上，|a~ - mu'| = 3"), t(7.0, 8.0, 1.0))]),
        (tr("sigma = 0.3, c = 10, the box [-100, 100] (noise neither clipped nor boxed), "
            "torch.manual_seed(0) before the call:\n  one draw eps = torch.randn_like(action), "
            "both critics at the same a~",
            "σ = 0.3，c = 10，动作范围 [-100, 100]（噪声既不被裁剪也不被限制），调用前 "
            "torch.manual_seed(0)：\n  只抽一次 eps = torch.randn_like(action)，两个评论员在同一个 a~ "
            "上取值"), (0.3, 10.0, [-100.0], [100.0]), "noise",
         [(tr("two noise draws, one per critic: both critics must be evaluated at the same a~",
              "抽了两次噪声，每个评论员各一次：两个评论员要在同一个 a~ 上取值"), "two draws")]),
        (tr("the same noise, the action box [-0.5, 0.5]: a~ = +-1 clipped into the box, to +-0.5",
            "同样的噪声，动作范围 [-0.5, 0.5]：a~ = ±1 要限制到范围内，成为 ±0.5"),
         (1e4, 0.5, [-0.5], [0.5]), t(2.625, 2.25, 1.0),
         [(tr("a~ not clipped into the action box [low, high]", "a~ 没有限制在动作范围 [low, high] 内"),
           t(3.0, 3.0, 1.0))]),
    ]


def td3_noisy_y(batch, sigma, c, draws):
    """y where eps ~ N(0, sigma^2) is drawn (after torch.manual_seed(0)) once for both
    critics, or once per critic (draws = 2); half_width 2, mu'(s') = 0, the box wide."""
    torch.manual_seed(0)
    d = [((2.0 * (torch.randn_like(batch[1]) * sigma).clamp(-c, c)) ** 2).sum(-1)
         for _ in range(draws)]
    s, reward, not_done = batch[3], batch[2], batch[4]
    return reward + 0.5 * not_done * torch.min(s[:, 0] + d[0], s[:, 1] + 2 * d[-1])


def check_td3_target(fn):
    for what, settings, expected, mistakes in td3_cases():
        nets, batch, half_width, low, high, cfg = td3_case(*settings)
        if isinstance(expected, str):  # the noise drawn: y from the same seed
            expected = td3_noisy_y(batch, *settings[:2], draws=1)
            mistakes = [(label, td3_noisy_y(batch, *settings[:2], draws=2))
                        for label, _ in mistakes]
        torch.manual_seed(0)
        fn(nets, batch, half_width, low, high, cfg)
        y1, y2 = (None if nets[k].q.grad is None else -nets[k].q.grad * 3 / 2
                  for k in ("critic", "critic2"))
        try:
            if y1 is None or y2 is None:
                raise Failed(tr("no gradient reached the critics: the lines after the blank "
                                "must stay as they are", "梯度没有传到评论员：空白后面的代码要保持原样"))
            compare("y", y1, expected)
            compare("y (critic2)", y2, expected)
        except Failed as e:
            named = [label for label, value in mistakes
                     if torch.allclose(y1, value, atol=1e-4)] if y1 is not None else []
            if y1 is not None and (y1 - expected).abs().max() > 100:  # sigma = 10000 here
                named = [tr("the noise not clipped to [-c, c] (sigma is 10000 in this case)",
                            "噪声没有裁剪到 [-c, c]（这个例子里 σ 是 10000）")]
            raise Failed(tr("case: ", "例子：") + f"{what}\n  {e}" + (tr(
                "\n  this is exactly what this mistake gives: ",
                "\n  你的值恰好是这个常见错误会得到的值：\n    ") + named[0] if named else "")) from None


# ---- the store-and-advance steps (loop exercises): the buffer's rows and what the loop gets back


def as_list(x):
    """A returned obs or mask as plain numbers, or None if it is not one (a tuple from
    env.reset(), say)."""
    if x is None:
        return None
    try:
        return np.asarray(x, dtype=np.float64).tolist()
    except (TypeError, ValueError):
        return None


class ResetCounter:
    """An env as DDPG's loop resets it: counts the resets, gives the new episode's first obs."""
    FIRST = [9.0, 9.0]

    def __init__(self):
        self.resets = 0

    def reset(self, seed=None, options=None):
        self.resets += 1
        return np.array(self.FIRST), {}


def ddpg_store_cases():
    # (what, terminated, truncated, not_done stored)
    return [(tr("no episode ends", "回合没有结束"), False, False, 1.0),
            (tr("terminated (the pole fell)", "终止（杆倒了）"), True, False, 0.0),
            (tr("truncated (the time limit): not terminal, so not_done = 1",
                "时间截断：不是终止，所以 not_done = 1"), False, True, 1.0),
            (tr("terminated and truncated at once: terminated, not_done = 0",
                "同一步既终止又时间截断：按终止算，not_done = 0"), True, True, 0.0)]


def ddpg_store_mistake(key, got, term, trunc):
    """The name of the mistake a differing field shows, or ''."""
    s, s2, first = [1.0, 2.0], [3.0, 4.0], ResetCounter.FIRST
    ended = term or trunc
    if key == "not_done" and trunc and not term and got["not_done"] == 0.0:
        return tr("terminated or truncated stored as the episode's end: a time-limit truncation "
                  "is not terminal, and its target must bootstrap from Q'(s', mu'(s'))",
                  "把 terminated or truncated 当成回合结束存了：时间截断不是终止，它的目标还要用 "
                  "Q'(s', mu'(s')) 自举")
    if key == "not_done" and not term and got["not_done"] == 0.0 and not trunc:
        return tr("the flag the other way round: buffer.add takes terminated (True where the "
                  "episode ended) and stores not_done = 1 - terminated itself",
                  "标志反了：buffer.add 接收的是 terminated（回合结束时为 True），它自己会存 "
                  "not_done = 1 - terminated")
    if key == "not_done" and term and got["not_done"] == 1.0:
        return tr("the termination not stored (not_done = 1 after the pole fell): the target "
                  "would add a future after the episode really ended",
                  "没有存下终止（杆倒了之后 not_done 还是 1）：目标会在回合真正结束之后还加上未来")
    if key == "obs" and got["obs"] == s2:
        return (tr("obs and next_obs swapped: s is where the action was chosen, s' where it led",
                   "obs 和 next_obs 弄反了：s 是选动作的地方，s' 是动作到达的地方")
                if got["next_obs"] == s else
                tr("next_obs stored as s: the action was chosen in obs",
                   "把 next_obs 存成了 s：动作是在 obs 上选的"))
    if key == "next_obs" and got["next_obs"] == first:
        return tr("the new episode's first obs stored as s': the env was reset before the "
                  "transition was stored (s' is the obs this step led to)",
                  "把新回合的第一个观测存成了 s'：先重置了环境，才存这个转移（s' 是这一步到达的观测）")
    if key == "next_obs" and got["next_obs"] == s:
        return tr("obs stored as s' too: s' is next_obs", "把 obs 也存成了 s'：s' 是 next_obs")
    if key == "returned":
        if got["raw"] is None:
            return tr("nothing returned: the loop needs the obs its next action is chosen in",
                      "没有返回值：循环需要知道下一个动作在哪个观测上选")
        if isinstance(got["raw"], tuple) and len(got["raw"]) == 2:
            return tr("env.reset() returns (obs, info): the obs is its first item, "
                      "obs, _ = env.reset()", "env.reset() 返回的是 (obs, info)：观测是第一项，"
                      "obs, _ = env.reset()")
        if got["returned"] == s:
            return tr("obs not advanced (obs = next_obs left out): the next action would be "
                      "chosen in s again", "观测没有前进（漏了 obs = next_obs）：下一个动作还会在 s 上选")
        if ended and got["returned"] == s2:
            return (tr("no new episode after a time-limit truncation: the episode is over, "
                       "though not terminal (reset on terminated or truncated)",
                       "时间截断之后没有开始新回合：回合已经结束了，虽然不是终止（terminated 或 "
                       "truncated 都要重置）") if trunc and not term else
                    tr("no new episode after the episode ended: the next action would continue "
                       "a finished episode (env.reset())",
                       "回合结束之后没有开始新回合：下一个动作会接着一个已经结束的回合（env.reset()）"))
        if ended and got["resets"] == 1 and got["returned"] != first:
            return tr("the env was reset, and the new episode's first obs not returned",
                      "重置了环境，却没有返回新回合的第一个观测")
    if key == "resets" and not ended and got["resets"]:
        return tr("a reset where no episode ended", "回合没有结束，却重置了环境")
    return ""


def check_ddpg_store(fn):
    ddpg = importlib.import_module("ddpg_walker")
    action, reward = [0.5], 1.5
    for what, term, trunc, not_done in ddpg_store_cases():
        env, buffer = ResetCounter(), ddpg.ReplayBuffer(2, 1, 4, "cpu")
        out = fn(env, buffer, np.array([1.0, 2.0]), np.array(action), reward,
                 np.array([3.0, 4.0]), term, trunc)
        ended = term or trunc
        want = dict(stored=1, obs=[1.0, 2.0], action=action, reward=reward, next_obs=[3.0, 4.0],
                    not_done=not_done, returned=ResetCounter.FIRST if ended else [3.0, 4.0],
                    resets=int(ended))
        got = dict(stored=buffer.size, obs=buffer.obs[0].tolist(),
                   action=buffer.action[0].tolist(), reward=float(buffer.reward[0]),
                   next_obs=buffer.next_obs[0].tolist(), not_done=float(buffer.not_done[0]),
                   returned=as_list(out), resets=env.resets, raw=out)
        field = dict(stored=tr("transitions stored", "存下的转移数"),
                     returned=tr("the obs returned (where the next action is chosen)",
                                 "返回的观测（下一个动作在这里选）"),
                     resets=tr("env.reset() calls", "env.reset() 调用次数"))
        for key, value in want.items():
            if got[key] != value:
                label = field.get(key, tr(f"the stored {key}", f"存下的 {key}"))
                shown = got[key] if got[key] is not None else repr(out)
                named = ddpg_store_mistake(key, got, term, trunc)
                raise Failed(
                    tr("case: ", "例子：") + tr(
                        f"s = [1, 2], a = [0.5], r = 1.5, s' = [3, 4], {what}; env.reset() gives "
                        f"[9, 9]", f"s = [1, 2]，a = [0.5]，r = 1.5，s' = [3, 4]，{what}；"
                        f"env.reset() 给出 [9, 9]")
                    + f"\n  {label}" + tr(f": expected {value}, got {shown}",
                                            f"：应该是 {value}，得到的是 {shown}")
                    + (tr("\n  this is exactly what this mistake gives: ",
                          "\n  这正是这个错误会得到的值：") + named if named else ""))


def ppo_rollout_case():
    """3 envs, 4 steps. env 0 hits the time limit at t = 1; env 1 terminates at t = 0; env 2
    terminates and hits the time limit at once at t = 1. The step after each is that env's
    reset step (reward 0). Env e's obs at step t is 10 e + t: what step t led to is 10 e + t + 1
    (at a done step, the real final obs)."""
    T, N = 4, 3
    obs = [np.array([[10.0 * e + t] for e in range(N)]) for t in range(T + 1)]
    term = np.zeros((T, N), dtype=bool)
    trunc = np.zeros((T, N), dtype=bool)
    term[0, 1] = trunc[1, 0] = term[1, 2] = trunc[1, 2] = True
    rewards = np.ones((T, N), dtype=np.float32)
    rewards[2, 0] = rewards[1, 1] = rewards[2, 2] = 0.0  # the reset steps
    actions = np.array([[(t + e) % 2 for e in range(N)] for t in range(T)])
    valid = np.ones((T, N), dtype=bool)
    valid[1:] = ~(term | trunc)[:-1]  # the step after a done step is a reset step
    return obs, actions, rewards, term, trunc, valid


def ppo_rollout_mistake(key, got, t, term, trunc, valid, autoreset, stored_trunc):
    """The name of the mistake a differing field shows, or ''."""
    done = term[t] | trunc[t]
    if key == "terminated":
        if np.array_equal(got, done):
            return tr("terminated or truncated stored as terminated: GAE would not bootstrap "
                      "from V(final obs) at a time-limit truncation (env 0 at t = 1), which is "
                      "not terminal", "把 terminated or truncated 存成了 terminated：在时间截断处"
                      "（t = 1 的环境 0）GAE 就不会用 V(最后的观测) 自举了，而时间截断不是终止")
        if (term[t] & ~got & stored_trunc).any():
            return tr("the termination stored as a time-limit truncation (the two flags swapped, "
                      "or the end stored as truncated): GAE would bootstrap from V(final obs) "
                      "after the pole fell, where the episode really ended",
                      "把终止存成了时间截断（两个标志弄反了，或者把回合结束存成了 truncated）："
                      "杆倒了、回合真正结束之后，GAE 还会用 V(最后的观测) 自举")
        if (term[t] & ~got).any():
            return tr("a termination not stored as one: GAE would bootstrap from V(final obs) "
                      "after the episode really ended, and run its sum on into the next episode",
                      "终止没有存成终止：回合真正结束之后，GAE 还会用 V(最后的观测) 自举，并且一直"
                      "累加到下一个回合里")
    if key == "truncated":
        if np.array_equal(got, done):
            return tr("terminated or truncated stored as truncated: keep each flag as the env "
                      "gave it", "把 terminated or truncated 存成了 truncated：两个标志都按环境给的"
                      "原样存")
        if np.array_equal(got, np.zeros_like(got)) and trunc[t].any():
            return tr("the time limit not stored (truncated dropped): GAE's sum would run on "
                      "past it into the next episode", "没有存下时间截断（丢了 truncated）："
                      "GAE 的累加会越过它，进入下一个回合")
    if key == "valid":
        if got.all() and not valid[t].all():
            return tr("the autoreset step not masked: the reset step's ignored action and 0 "
                      "reward would train pi (valid = ~autoreset)", "没有掩掉自动重置步：重置步"
                      "被忽略的动作和 0 奖励会拿去训练 π（valid = ~autoreset）")
        if np.array_equal(got, autoreset):
            return tr("valid = autoreset: the mask says where the reset steps are, valid where "
                      "the rows train (valid = ~autoreset)", "valid = autoreset：掩码标的是重置步"
                      "在哪里，valid 标的是哪些行拿去训练（valid = ~autoreset）")
        if np.array_equal(got, ~done):
            return tr("the step that ended the episode masked, not the reset step after it: "
                      "valid = ~autoreset, the previous step's flags",
                      "掩掉的是结束回合的那一步，不是它后面的重置步：valid = ~autoreset，用的是上"
                      "一步的标志")
    if key == "obs":
        return tr("next_obs stored as obs: the action was chosen in obs (obs and next_obs "
                  "mixed up)", "把 next_obs 存成了 obs：动作是在 obs 上选的（obs 和 next_obs "
                  "弄混了）") if got.tolist() == [[10.0 * e + t + 1] for e in range(3)] else ""
    if key == "returned obs":
        return tr("obs not advanced (obs = next_obs left out): step t + 1 would act in s_t "
                  "again", "观测没有前进（漏了 obs = next_obs）：第 t + 1 步还会在 s_t 上选动作") \
            if got == [[10.0 * e + t] for e in range(3)] else ""
    if key == "returned autoreset":
        if got == as_list(autoreset):
            return tr("the mask not updated: the returned autoreset is the one passed in",
                      "掩码没有更新：返回的 autoreset 就是传进来的那个")
        if got == as_list(term[t]):
            return tr("the mask from terminated alone: a truncated env resets too (terminated "
                      "| truncated)", "掩码只看了 terminated：时间截断的环境也会重置（terminated "
                      "| truncated）")
        if got == as_list(~done):
            return tr("the mask the wrong way round: True where the next step is a reset step",
                      "掩码反了：下一步是重置步的地方才是 True")
        if got == as_list(autoreset | done):
            return tr("the mask kept from the steps before (autoreset | ...): only this step's "
                      "flags say where step t + 1 is a reset step",
                      "把之前的掩码也留下来了（autoreset | ...）：第 t + 1 步是不是重置步，只看这一步"
                      "的标志")
    return ""


def check_ppo_rollout(fn):
    ppo = importlib.import_module("ppo_cartpole")
    obs, actions, rewards, term, trunc, valid = ppo_rollout_case()
    T, N = actions.shape
    buffer = ppo.RolloutBuffer(T, N, 1)
    current, autoreset = obs[0].copy(), np.zeros(N, dtype=bool)
    case = tr("case: 3 envs, 4 steps, env e's obs at step t = 10 e + t; env 1 terminated at t = 0, "
              "env 0 truncated (time limit) at t = 1, env 2 terminated and truncated at t = 1; "
              "the step after each is its reset step",
              "例子：3 个环境，4 步，环境 e 在第 t 步的观测是 10 e + t；t = 0 处环境 1 终止，t = 1 处"
              "环境 0 时间截断，t = 1 处环境 2 同时终止和时间截断；它们各自的下一步是重置步")
    for t in range(T):
        out = fn(buffer, t, current, actions[t].copy(), rewards[t].copy(), obs[t + 1].copy(),
                 term[t].copy(), trunc[t].copy(), autoreset.copy())
        where = tr(f"\n  step t = {t}: ", f"\n  第 t = {t} 步：")
        if not isinstance(out, tuple) or len(out) != 2:
            raise Failed(case + where + tr(
                f"expected (obs, autoreset), got {type(out).__name__}",
                f"应该返回 (obs, autoreset)，得到的是 {type(out).__name__}"))
        rows = dict(obs=(buffer.obs[t], obs[t].astype(np.float32)),
                    actions=(buffer.actions[t], actions[t]),
                    rewards=(buffer.rewards[t], rewards[t]),
                    terminated=(buffer.terminated[t], term[t]),
                    truncated=(buffer.truncated[t], trunc[t]),
                    valid=(buffer.valid[t], valid[t]))
        returned = {"returned obs": (as_list(out[0]), as_list(obs[t + 1])),
                    "returned autoreset": (as_list(out[1]), as_list(term[t] | trunc[t]))}
        for key, (got, want) in rows.items():
            if not np.array_equal(got, want):
                named = ppo_rollout_mistake(key, got, t, term, trunc, valid, autoreset,
                                            buffer.truncated[t])
                raise Failed(case + where + tr(f"the buffer's {key}[{t}]: expected "
                                               f"{want.tolist()}, got {got.tolist()}",
                                               f"缓冲区的 {key}[{t}]：应该是 {want.tolist()}，"
                                               f"得到的是 {got.tolist()}")
                             + (tr("\n  this is exactly what this mistake gives: ",
                                   "\n  这正是这个错误会得到的值：") + named if named else ""))
        for key, (got, want) in returned.items():
            if got != want:
                named = ppo_rollout_mistake(key, got, t, term, trunc, valid, autoreset,
                                            buffer.truncated[t])
                label = dict(obs=tr("the obs returned (where step t + 1 acts)",
                                    "返回的 obs（第 t + 1 步在这里选动作）"),
                             autoreset=tr("the autoreset mask returned (for step t + 1)",
                                          "返回的 autoreset 掩码（给第 t + 1 步用）"))[key.split()[1]]
                raise Failed(case + where + tr(f"{label}: expected {want}, got {got}",
                                               f"{label}：应该是 {want}，得到的是 {got}")
                             + (tr("\n  this is exactly what this mistake gives: ",
                                   "\n  这正是这个错误会得到的值：") + named if named else ""))
        current, autoreset = np.asarray(out[0]), np.asarray(out[1], dtype=bool)


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

    #                    s: 0-2 (actions 0, 1, 0)     s': 3-5
    q_net = Table([[1.5, 0.0], [0.0, 1.5], [1.5, 0.0], [0.25, 0.5], [1.25, 0.25], [0.0, 0.25]])
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


def check_dqn_target(fn):
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
            raise Failed(tr("case: ", "例子：") + f"{what}\n  {e}" + (tr(
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


# ---- REINFORCE (reinforce_cartpole.py): the reward-to-go, and the loss with its baseline


def reward_to_go_cases():
    # (what, (rewards, gamma, last_value), G by hand); rewards as train() passes them, a tuple
    return [
        (tr("terminated after 3 steps (last_value = 0), gamma = 0.5: G_2 = 3, G_1 = 2 + 0.5 * 3, "
            "G_0 = 1 + 0.5 * 3.5", "3 步后终止（last_value = 0），gamma = 0.5：G_2 = 3，"
            "G_1 = 2 + 0.5 * 3，G_0 = 1 + 0.5 * 3.5"), ((1.0, 2.0, 3.0), 0.5, 0.0),
         (2.75, 3.5, 3.0)),
        (tr("the same rewards cut by a time limit, last_value = V(s_T) = 4: G_2 = 3 + 0.5 * 4",
            "同样的奖励，被时间截断，last_value = V(s_T) = 4：G_2 = 3 + 0.5 * 4"),
         ((1.0, 2.0, 3.0), 0.5, 4.0), (3.25, 4.5, 5.0)),
        (tr("terminated after 4 steps, gamma = 0.9: G_3 = 1, G_2 = -1 + 0.9, G_1 = 0 + 0.9 * G_2, "
            "G_0 = 2 + 0.9 * G_1", "4 步后终止，gamma = 0.9：G_3 = 1，G_2 = -1 + 0.9，"
            "G_1 = 0 + 0.9 * G_2，G_0 = 2 + 0.9 * G_1"), ((2.0, 0.0, -1.0, 1.0), 0.9, 0.0),
         (1.919, -0.09, -0.1, 1.0)),
        (tr("one step, cut by a time limit: G_0 = 5 + 0.5 * 2", "只有一步，被时间截断：G_0 = 5 + 0.5 * 2"),
         ((5.0,), 0.5, 2.0), (6.0,)),
    ]


def reward_to_go_mistakes(rewards, gamma, last_value):
    """(label, G as the mistake computes it) for each known mistake."""
    r, T = list(rewards), len(rewards)

    def back(step, start):  # G = step(r_t, G) from G_T = start, t = T - 1 down to 0
        out, G = [0.0] * T, start
        for i in reversed(range(T)):
            out[i] = G = step(r[i], G)
        return out
    right = back(lambda x, G: x + gamma * G, last_value)
    forward, G = [], 0.0
    for x in r:
        G = x + gamma * G
        forward.append(G)
    return [
        (tr("the whole episode's return G_0 for every step: each action is weighted by rewards "
            "that came before it too\n    (the reward-to-go G_t starts at t: an action cannot "
            "change what came before it)", "每一步都用了整个回合的回报 G_0：每个动作也被它之前的"
            "奖励加了权\n    （回报 G_t 从 t 开始算：动作改变不了它之前的奖励）"), [right[0]] * T),
        (tr("the sum run forward, G_t = r_t + gamma * G_{t-1}: the rewards before t counted, those "
            "after it left out;\n    go backwards, from t = T - 1 down to 0",
            "累加的方向反了，写成了 G_t = r_t + gamma * G_{t-1}：算进了 t 之前的奖励，漏了 t 之后的；"
            "\n    要从 t = T - 1 往回算到 0"), forward),
        (tr("a running sum from the episode's start, sum_{k <= t} gamma^k r_k: the rewards before "
            "t counted, those after it left out", "从回合开始累加，即 sum_{k <= t} gamma^k r_k："
            "算进了 t 之前的奖励，漏了 t 之后的"),
         [sum(gamma ** k * r[k] for k in range(i + 1)) for i in range(T)]),
        (tr("gamma^k counted from the episode's start, sum_{k >= t} gamma^k r_k: r_k's discount "
            "is gamma^(k - t),\n    by how far after t it came (G_t = r_t + gamma * G_{t+1} gives "
            "it)", "gamma 的指数从回合开始数，即 sum_{k >= t} gamma^k r_k：r_k 的折扣是 "
            "gamma^(k - t)，\n    按它离 t 多远算（G_t = r_t + gamma * G_{t+1} 自然就是这样）"),
         [sum(gamma ** k * r[k] for k in range(i, T)) + gamma ** T * last_value
          for i in range(T)]),
        (tr("the reward itself discounted, G_t = gamma * (r_t + G_{t+1}): r_t comes at t, "
            "undiscounted; only the future is, r_t + gamma * G_{t+1}",
            "奖励本身也打了折，写成了 G_t = gamma * (r_t + G_{t+1})：r_t 就在 t 时刻拿到，"
            "不打折；打折的只是未来，即 r_t + gamma * G_{t+1}"),
         back(lambda x, G: gamma * (x + G), last_value)),
        (tr("gamma left out: G_t = r_t + G_{t+1}", "漏了 gamma：写成了 G_t = r_t + G_{t+1}"),
         back(lambda x, G: x + G, last_value)),
        (tr("last_value ignored: the sum starts from 0, where a time limit cut the episode and "
            "G_T = last_value = V(s_T)\n    (the episode did not end: its tail is the critic's "
            "guess)", "忽略了 last_value：从 0 开始累加，可回合是被时间截断的，G_T = last_value = "
            "V(s_T)\n    （回合没有真正结束：剩下的部分用 V 估计）"),
         back(lambda x, G: x + gamma * G, 0.0)),
        (tr("last_value not discounted: G_{T-1} = r_{T-1} + last_value, where last_value is "
            "G_T, one step later:\n    r_{T-1} + gamma * last_value",
            "last_value 没有打折：写成了 G_{T-1} = r_{T-1} + last_value；last_value 是晚一步的 "
            "G_T，\n    应该是 r_{T-1} + gamma * last_value"),
         [g + gamma ** (T - 1 - i) * last_value
          for i, g in enumerate(back(lambda x, G: x + gamma * G, 0.0))]),
        (tr("the returns in reverse order: appended in the backward loop and not turned round "
            "(returns[T - 1 - t] holds G_t)", "回报的顺序反了：在往回的循环里 append，最后没有"
            "倒过来（returns[T - 1 - t] 里放的是 G_t）"), right[::-1])]


def check_reward_to_go(fn):
    for what, (rewards, gamma, last_value), expected in reward_to_go_cases():
        got = fn(rewards, gamma, last_value)
        values = as_list(got)
        inputs = (tr("\n  input: ", "\n  输入：")
                  + f"rewards={rewards}, gamma={gamma}, last_value={last_value}")
        try:
            if values is None or np.ndim(values) != 1:
                raise Failed(tr(f"expected an array of {len(rewards)} numbers (one G_t per step), "
                                f"got {type(got).__name__} {got!r}",
                                f"应该返回 {len(rewards)} 个数的数组（每一步一个 G_t），得到的是 "
                                f"{type(got).__name__} {got!r}"))
            compare("G", torch.tensor(values, dtype=torch.float64), t(*expected))
        except Failed as e:
            named = [label for label, value in reward_to_go_mistakes(rewards, gamma, last_value)
                     if values is not None and np.shape(values) == np.shape(value)
                     and np.allclose(values, value, atol=1e-5)]
            raise Failed(tr("case: ", "例子：") + what + inputs + f"\n  {e}" + (tr(
                "\n  this is exactly what this mistake gives: ",
                "\n  你的值恰好是这个常见错误会得到的值：\n    ") + named[0] if named else "")) from None


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


def reinforce_cases():
    return [
        (tr("baseline = False: the weights are G = (3, 2, 1); pi(a|s) = 0.5, 0.75, 0.2; "
            "V = (1, 2.5, 0.5)", "baseline = False：权重就是 G = (3, 2, 1)；pi(a|s) = 0.5、0.75、0.2；"
            "V = (1, 2.5, 0.5)"), reinforce_case(False), reinforce_by_hand(False)),
        (tr("baseline = True: the weights are G - V = (2, -0.5, 0.5), the same batch",
            "baseline = True：权重是 G - V = (2, -0.5, 0.5)，同一批数据"), reinforce_case(True),
         reinforce_by_hand(True)),
    ]


def reinforce_mistakes(policy, value_net, data, baseline):
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


def reinforce_gradient_mistake(loss, kind):
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


# ---- Tabular TD control (q_learning_cliffwalking.py): Sarsa's update and Q-learning's


def tabular_table():
    """Q of three states, four actions. In s' = 1 the best action is 1 (-1.5), the next action
    taken is 2 (an exploring step, -20) and the action just taken, 0, is worth -3: a target
    that values s' any other way than the right one gives another number. Row 2 holds the
    table's largest value (2), for the case where s' = s (a step into a wall)."""
    return np.array([[-2.0, -4.0, 0.5, -1.0], [-3.0, -1.5, -20.0, -6.0], [2.0, -5.0, -8.0, -7.0]])


def tabular_cases(sarsa):
    """(what, (s, a, r, s_next, a_next, terminated, alpha, gamma)); r and the states as the env
    gives them (ints), terminated a Python bool."""
    row = tr("Q(s', .) = (-3, -1.5, -20, -6): the best action 1 (-1.5), ",
             "Q(s', .) = (-3, -1.5, -20, -6)：最好的动作是 1（-1.5），")
    nxt = tr("the next action a' = 2 (an exploring step, -20); ",
             "下一个动作 a' = 2（探索的一步，-20）；") if sarsa else ""
    return [
        (tr("s = 0, a = 0 (Q = -2), r = -1, s' = 1, not terminated; ", "s = 0，a = 0（Q = -2），"
            "r = -1，s' = 1，没有终止；") + row + nxt
         + tr("alpha = 0.25, gamma = 0.9", "alpha = 0.25，gamma = 0.9"),
         (0, 0, -1, 1, 2, False, 0.25, 0.9)),
        (tr("the same step, terminated (the goal): the target is r alone, whatever Q(s', .)",
            "同样的一步，但终止了（到达终点）：目标只有 r，不管 Q(s', .) 是多少"),
         (0, 0, -1, 1, 2, True, 0.25, 0.9)),
        (tr("a step into a wall, s' = s = 2, a = 3 (Q = -7)", "撞墙的一步，s' = s = 2，a = 3（Q = -7）")
         + (tr(", a' = 3 again", "，a' 还是 3") if sarsa else "")
         + tr(": Q(s', .) = (2, -5, -8, -7); alpha = 0.5, gamma = 1",
              "：Q(s', .) = (2, -5, -8, -7)；alpha = 0.5，gamma = 1"),
         (2, 3, -1, 2, 3, False, 0.5, 1.0)),
    ]


def tabular_by_hand(Q, s, a, r, s_next, a_next, terminated, alpha, gamma, sarsa, value=None,
               not_done=None, discount=None, step=None, sign=1.0):
    """(Q[s, a] after the update, the TD error) in plain Python, and the mistakes' versions:
    value, the value of s' used; not_done, the factor that cuts it; discount, gamma's place;
    step, alpha's; sign, delta's."""
    q = Q[s, a]
    value = (Q[s_next, a_next] if sarsa else Q[s_next].max()) if value is None else value
    not_done = (0.0 if terminated else 1.0) if not_done is None else not_done
    target = r + (gamma if discount is None else discount) * not_done * value
    delta = sign * (target - q)
    return q + (alpha if step is None else step) * delta, delta


def tabular_mistakes(Q, s, a, r, s_next, a_next, terminated, alpha, gamma, sarsa):
    """(label, (Q[s, a] after, the TD error returned)) of each known mistake."""
    case = (Q, s, a, r, s_next, a_next, terminated, alpha, gamma, sarsa)
    q_new, delta = tabular_by_hand(*case)
    target = delta + Q[s, a]
    if sarsa:
        values = [
            (tr("max_a' Q(s', a') where Sarsa takes the next action a' (that is Q-learning's "
                "target: Sarsa values s' by the action it will\n    really take there, "
                "exploration included)", "用了 max_a' Q(s', a')，Sarsa 要的是下一个动作 a'（那是 "
                "Q 学习的目标：Sarsa 按它在 s' 真的要做的动作估值，\n    探索的动作也算）"),
             Q[s_next].max()),
            (tr("Q(s', a), the action just taken, where Sarsa takes the next action a_next",
                "用了 Q(s', a)，即刚做过的那个动作，Sarsa 要的是下一个动作 a_next"), Q[s_next, a])]
    else:
        values = [
            (tr("Q(s', a), the action just taken valued at s', where Q-learning takes the best "
                "action there, max_a' Q(s', a')\n    (Q-learning has no next action: whatever "
                "the agent does next, the target takes the max)",
                "用了 Q(s', a)，即把刚做过的动作放到 s' 去估值；Q 学习要的是那里最好的动作 "
                "max_a' Q(s', a')\n    （Q 学习没有“下一个动作”：不管智能体接下来做什么，目标都取最大值）"),
             Q[s_next, a]),
            (tr("the mean over the actions of s', where Q-learning takes the max",
                "对 s' 的各个动作取了平均，Q 学习要取最大值"), Q[s_next].mean()),
            (tr("argmax (an action's index) where the max (its value) belongs: Q[s_next].max()",
                "用了 argmax（动作的编号），应该用 max（它的价值）：Q[s_next].max()"),
             float(np.argmax(Q[s_next]))),
            (tr("the max at s, not at s' (Q[s].max())", "在 s 处取的最大值，应该在 s' 处（写成了 Q[s].max()）"),
             Q[s].max()),
            (tr("the max over the whole table (Q.max()), not over s_next's row",
                "对整张表取了最大值（Q.max()），应该只在 s_next 这一行取"), Q.max())]
    found = [(label, tabular_by_hand(*case, value=v)) for label, v in values]
    found += [
        (tr("a bootstrap at a termination: after the goal there is no s' to value, the target "
            "is r alone ((1 - terminated))", "终止处还在自举：到达终点之后没有 s' 可估值，目标只有 r"
            "（要乘 (1 - terminated)）"), tabular_by_hand(*case, not_done=1.0)),
        (tr("~terminated on a Python bool: ~False is -1 and ~True is -2, not 1 and 0: use "
            "(1 - terminated) or (not terminated)", "对 Python 的布尔值用了 ~terminated：~False 是 "
            "-1，~True 是 -2，不是 1 和 0：要用 (1 - terminated) 或 (not terminated)"),
         tabular_by_hand(*case, not_done=-2.0 if terminated else -1.0)),
        (tr("gamma left out: r + Q(s', .) where the target is r + gamma * Q(s', .)",
            "漏了 gamma：写成了 r + Q(s', .)，目标是 r + gamma * Q(s', .)"),
         tabular_by_hand(*case, discount=1.0)),
        (tr("alpha left out: Q[s, a] = target, a full replacement, where Q moves a step alpha "
            "toward it (Q[s, a] += alpha * delta)", "漏了 alpha：Q[s, a] = 目标，整个换掉了；应该朝目标"
            "走 alpha 那么大的一步（Q[s, a] += alpha * delta）"), tabular_by_hand(*case, step=1.0)),
        (tr("the TD error's sign: delta = Q[s, a] - target, so Q moves away from the target "
            "(delta = target - Q[s, a])", "TD 误差的符号反了：写成了 delta = Q[s, a] - 目标，Q 就"
            "离目标越来越远（delta = 目标 - Q[s, a]）"), tabular_by_hand(*case, sign=-1.0)),
        (tr("the TD error returned with its sign flipped (Q[s, a] - target); the update itself "
            "is right", "返回的 TD 误差符号反了（Q[s, a] - 目标）；更新本身是对的"),
         (q_new, -delta)),
        (tr("the TD error computed after the update (target - the new Q[s, a], which is "
            "(1 - alpha) * delta): compute delta first,\n    then move Q[s, a]",
            "TD 误差是在更新之后算的（目标 - 新的 Q[s, a]，即 (1 - alpha) * delta）：先算 delta，"
            "\n    再更新 Q[s, a]"), (q_new, target - q_new)),
        (tr("the step alpha * delta returned where the TD error delta belongs",
            "返回的是这一步的大小 alpha * delta，应该返回 TD 误差 delta"), (q_new, alpha * delta))]
    return found


def check_td_control(fn, sarsa):
    for what, (s, a, r, s_next, a_next, terminated, alpha, gamma) in tabular_cases(sarsa):
        Q = tabular_table()
        before = Q.copy()
        args = (s, a, r, s_next) + ((a_next,) if sarsa else ()) + (terminated, alpha, gamma)
        got = fn(Q, *args)
        case = (before, s, a, r, s_next, a_next, terminated, alpha, gamma, sarsa)
        q_new, delta = tabular_by_hand(*case)
        try:
            td = float(got)
        except (TypeError, ValueError):
            td = None
        changed = [(int(i), int(j)) for i, j in zip(*np.nonzero(Q != before))]
        named = []
        try:
            if not isinstance(Q, np.ndarray) or Q.shape != before.shape:
                raise Failed(tr("the table Q was replaced: update its entry in place",
                                "Q 表被换掉了：要原地更新它的那一项"))
            others = [ij for ij in changed if ij != (s, a)]
            if others and any(i == s_next for i, _ in others):
                named = [tr("the entry of s' updated (Q[s_next, ...]) where Q[s, a] belongs: the "
                            "update moves the pair just left, (s, a)",
                            "更新的是 s' 的那一项（Q[s_next, ...]），应该是 Q[s, a]：要更新的是"
                            "刚离开的那一对 (s, a)")]
            if others:
                raise Failed(tr(f"entries other than Q[s, a] = Q[{s}, {a}] changed: {others} "
                                f"(only Q[s, a] moves)", f"除了 Q[s, a] = Q[{s}, {a}] 之外，"
                                f"还有别的项变了：{others}（只有 Q[s, a] 会变）"))
            if not changed and abs(q_new - before[s, a]) > 1e-9:
                raise Failed(tr("Q did not change: update the table in place (Q[s, a] += ...); "
                                "Q = ... or Q.copy() leaves the caller's table as it was",
                                "Q 没有变：要原地更新这张表（Q[s, a] += ...）；Q = ... 或 Q.copy() "
                                "不会改动调用者手里的那张表"))
            if abs(Q[s, a] - q_new) > 1e-6:
                same_q = [(label, d) for label, (q, d) in tabular_mistakes(*case)
                          if abs(Q[s, a] - q) < 1e-6]
                named = [label for label, d in same_q if td is None or abs(td - d) < 1e-6] or [
                    label for label, _ in same_q]
                raise Failed(tr(f"Q[{s}, {a}] after the update: expected {q_new:.6g}, got "
                                f"{Q[s, a]:.6g}", f"更新之后的 Q[{s}, {a}]：应该是 {q_new:.6g}，"
                                f"得到的是 {Q[s, a]:.6g}"))
            if td is None or abs(td - delta) > 1e-6:
                named = [label for label, (q, d) in tabular_mistakes(*case)
                         if td is not None and abs(q - q_new) < 1e-9 and abs(td - d) < 1e-6]
                shown = f"{td:.6g}" if td is not None else repr(got)
                raise Failed(tr(f"the TD error returned: expected {delta:.6g}, got {shown}",
                                f"返回的 TD 误差：应该是 {delta:.6g}，得到的是 {shown}") + (tr(
                    " (nothing returned: return delta, the TD error, as a float)",
                    "（没有返回值：要返回 TD 误差 delta，一个浮点数）") if got is None else ""))
        except Failed as e:
            raise Failed(tr("case: ", "例子：") + what + f"\n  {e}" + (tr(
                "\n  this is exactly what this mistake gives: ",
                "\n  你的值恰好是这个常见错误会得到的值：\n    ") + named[0] if named else "")) from None


class FixedNoise(torch.distributions.Normal):
    """A Normal whose draws use a given eps: u = mean + sigma * eps (rsample); sample() is the
    same number without the gradient, as torch's."""

    def __init__(self, loc, scale, eps):
        super().__init__(loc, scale)
        self.eps = eps

    def rsample(self, sample_shape=torch.Size()):
        return self.loc + self.scale * self.eps

    def sample(self, sample_shape=torch.Size()):
        return self.rsample().detach()


class SacActor(torch.nn.Module):
    """The actor of a worked case: the mean and log sigma as parameters (B, act_dim), a fixed
    eps, and sac_walker.Actor's scale, bias and sample() (the reference answer calls it; the
    exercise asks you to write what it does)."""

    def __init__(self, mean, log_std, eps, scale, bias):
        super().__init__()
        self.mean = torch.nn.Parameter(mean.clone())
        self.log_std = torch.nn.Parameter(log_std.clone())
        self.eps = eps
        self.register_buffer("scale", scale)
        self.register_buffer("bias", bias)

    def distribution(self, obs):
        return FixedNoise(self.mean, self.log_std.exp(), self.eps)

    def sample(self, obs):
        return importlib.import_module("sac_walker").Actor.sample(self, obs)


def sac_case(mean, log_std, eps, low, high):
    """obs (B, 2); Q1(s, a) = s_0 + sum(a), Q2(s, a) = s_1 + 2 sum(a): the smaller one differs
    from row to row; alpha = 0.5."""
    mean, log_std, eps = t(*mean), t(*log_std), t(*eps)
    low, high = t(*low), t(*high)
    obs = t([0.0, 1.0], [1.0, -0.5])
    return (mean, log_std, eps, (high - low) / 2, (high + low) / 2, obs, scalar(0.5))


def sac_by_hand(mean, log_std, eps, scale, bias, obs, alpha):
    """The loss and log pi in float64, by the change of variables written out directly
    (1 - tanh(u)^2 does not round to 0 in float64 for |u| < ~18)."""
    m, s, e, sc, b, o = (x.double() for x in (mean, log_std.exp(), eps, scale, bias, obs))
    u = m + s * e
    log_n = -0.5 * ((u - m) / s) ** 2 - torch.log(s) - 0.5 * math.log(2 * math.pi)
    logp = (log_n - torch.log(sc * (1 - torch.tanh(u) ** 2))).sum(-1)
    a = b + sc * torch.tanh(u)
    q = torch.min(o[:, 0] + a.sum(-1), o[:, 1] + 2 * a.sum(-1))
    return (alpha.double() * logp - q).mean().float(), logp.float()


def sac_critics():
    return (lambda obs, a: obs[:, 0] + a.sum(-1)), (lambda obs, a: obs[:, 1] + 2 * a.sum(-1))


def sac_variant(actor, obs, alpha, correction="exact", q_at="a", logp_of="u", reduce="sum",
                critics="min", entropy=1.0, draw="rsample", detach_logp=False, detach_a=False):
    """The loss and log pi as a known mistake computes them, in float32 (so that log(0) shows)."""
    critic, critic2 = sac_critics()
    u_dist = actor.distribution(obs)
    u = u_dist.rsample() if draw == "rsample" else u_dist.sample()
    a = actor.bias + actor.scale * torch.tanh(u)
    log_slope = {"exact": torch.log(actor.scale) + 2 * (math.log(2) - u - F.softplus(-2 * u)),
                 "none": torch.zeros_like(u),
                 "flipped": -(torch.log(actor.scale) + 2 * (math.log(2) - u - F.softplus(-2 * u))),
                 "direct": torch.log(actor.scale * (1 - torch.tanh(u) ** 2)),
                 "epsilon": torch.log(actor.scale * (1 - torch.tanh(u) ** 2 + 1e-6)),
                 "no_scale": 2 * (math.log(2) - u - F.softplus(-2 * u))}[correction]
    per_dim = u_dist.log_prob(u if logp_of == "u" else a) - log_slope
    logp = per_dim.sum(-1) if reduce == "sum" else per_dim.mean(-1)
    at = {"a": a, "u": u, "tanh": torch.tanh(u)}[q_at]
    at = at.detach() if detach_a else at
    pick = torch.min if critics == "min" else torch.max
    q = pick(critic(obs, at), critic2(obs, at))
    return (entropy * alpha * (logp.detach() if detach_logp else logp) - q).mean(), logp


def sac_value_mistakes():
    return [
        (tr("no tanh correction: log pi is the Gaussian's log density of u alone",
            "没有 tanh 的修正：log π 只用了 u 的高斯对数密度"), dict(correction="none")),
        (tr("the correction's sign flipped: + log(scale * (1 - tanh(u)^2)), where the change of "
            "variables subtracts it", "修正项的符号反了：变量替换要减去 log(scale * (1 - tanh(u)^2))，"
            "不是加上"), dict(correction="flipped")),
        (tr("log(1 - tanh(u)^2) computed directly: in float32 it is log(0) = -inf once |u| > ~9; "
            "use 2 * (log 2 - u - softplus(-2u))", "直接算了 log(1 - tanh(u)^2)：float32 里 |u| > 9 "
            "左右时它是 log(0) = -inf；用 2 * (log 2 - u - softplus(-2u))"), dict(correction="direct")),
        (tr("log(1 - tanh(u)^2 + 1e-6), as some implementations write it: the epsilon keeps it "
            "finite and moves the value,\n  a little here, and far in the tail it is no longer "
            "the density (at u = 12: log 1e-6 = -13.8, the exact value -22.6);\n  the script "
            "writes 2 * (log 2 - u - softplus(-2u)), exact everywhere",
            "log(1 - tanh(u)^2 + 1e-6)，有些实现这样写：加上 epsilon 不会变成无穷，但数值变了，"
            "\n  这里变得少，尾部就完全不是真正的密度了（u = 12 时 log 1e-6 = -13.8，准确值是 -22.6）；"
            "\n  脚本写的是处处准确的 2 * (log 2 - u - softplus(-2u))"),
         dict(correction="epsilon")),
        (tr("the action box's scale left out of the correction: a = bias + scale * tanh(u), so "
            "da/du = scale * (1 - tanh(u)^2)", "修正项漏了动作范围的 scale：a = bias + scale * tanh(u)，"
            "所以 da/du = scale * (1 - tanh(u)^2)"), dict(correction="no_scale")),
        (tr("the critics valued at the pre-squash sample u, not at the action a = bias + scale * "
            "tanh(u)", "评论员在压缩前的样本 u 处取值，应该在动作 a = bias + scale * tanh(u) 处"),
         dict(q_at="u")),
        (tr("the critics valued at tanh(u), without the action box's scale and bias",
            "评论员在 tanh(u) 处取值，漏了动作范围的 scale 和 bias"), dict(q_at="tanh")),
        (tr("the Gaussian's log density taken at the squashed action a, not at u",
            "高斯的对数密度在压缩后的动作 a 处取值，应该在 u 处"), dict(logp_of="a")),
        (tr("log pi averaged over the action's dimensions, not summed (the density of a vector is "
            "the product of its dimensions')", "log π 对动作的各维求了平均，应该求和（向量的密度是"
            "各维密度的乘积）"), dict(reduce="mean")),
        (tr("max(Q1, Q2) where SAC takes the smaller", "取了 max(Q1, Q2)，SAC 取较小的"),
         dict(critics="max")),
        (tr("the entropy term's sign: the loss is alpha * log pi - Q (a lower log pi, more "
            "entropy, lowers it)", "熵那一项的符号反了：损失是 alpha * log π - Q（log π 越小、熵越大，损失越小）"),
         dict(entropy=-1.0))]


def sac_gradient_mistakes():
    return [
        (tr("u drawn with sample(), not rsample(): no gradient passes through the sample "
            "(the reparameterisation lost)", "u 用 sample() 抽取，不是 rsample()：梯度穿不过采样"
            "（丢了重参数化）"), dict(draw="sample")),
        (tr("log pi detached in the loss: the entropy term no longer trains the actor",
            "损失里的 log π 被 detach 了：熵那一项不再训练演员"), dict(detach_logp=True)),
        (tr("the action detached before the critics: Q's gradient no longer reaches the actor",
            "动作在送进评论员之前被 detach 了：Q 的梯度传不到演员"), dict(detach_a=True))]


def sac_cases():
    return [
        (tr("scale 1, two action dimensions: u = mean + sigma * eps = (0.5, -1) and (1, 2)",
            "scale 1，两维动作：u = mean + σ * eps = (0.5, -1) 和 (1, 2)"),
         sac_case([[0.5, -1.0], [0.0, 1.0]], [[0.0, 0.0], [0.0, 0.0]], [[0.0, 0.0], [1.0, 1.0]],
                  [-1.0, -1.0], [1.0, 1.0])),
        (tr("the action box [-1, 3] x [-2, 2]: scale (2, 2), bias (1, 0); u as above",
            "动作范围 [-1, 3] x [-2, 2]：scale (2, 2)，bias (1, 0)；u 同上"),
         sac_case([[0.5, -1.0], [0.0, 1.0]], [[0.0, 0.0], [0.0, 0.0]], [[0.0, 0.0], [1.0, 1.0]],
                  [-1.0, -2.0], [3.0, 2.0])),
        (tr("far in the tail: u = (12, 0) and (1, 2) (tanh(12) rounds to 1 in float32)",
            "尾部很远：u = (12, 0) 和 (1, 2)（float32 里 tanh(12) 舍入成 1）"),
         sac_case([[12.0, 0.0], [0.0, 1.0]], [[0.0, 0.0], [0.0, 0.0]], [[0.0, 0.0], [1.0, 1.0]],
                  [-1.0, -1.0], [1.0, 1.0])),
    ]


def sac_named(got, actor, obs, alpha):
    """The label of the known mistake whose loss and log pi `got` gives (an infinite loss
    matches an infinite one), or ''."""
    def close(a, b):
        return (torch.is_tensor(a) and a.shape == b.shape
                and torch.allclose(a.detach(), b.detach(), atol=1e-6, rtol=1e-6))
    for label, mistake in sac_value_mistakes():
        loss, logp = sac_variant(actor(), obs, alpha, **mistake)
        if not torch.isfinite(loss) and torch.is_tensor(got[0]) and not torch.isfinite(
                got[0]).all() or close(got[0], loss) and close(got[1], logp):
            return label
    return ""


def check_sac_actor_loss(fn):
    own = importlib.import_module("sac_walker").compute_loss_actor
    critic, critic2 = sac_critics()
    for what, (mean, log_std, eps, scale, bias, obs, alpha) in sac_cases():
        def actor(case=(mean, log_std, eps, scale, bias)):
            return SacActor(*case)
        yours = actor()
        out = fn(yours, critic, critic2, obs, alpha)
        loss, logp = sac_by_hand(mean, log_std, eps, scale, bias, obs, alpha)
        inputs = tr(f"\n  input: mean={rounded(mean)}, sigma={rounded(log_std.exp())}, "
                    f"eps={rounded(eps)}, scale={rounded(scale)}, bias={rounded(bias)}, alpha=0.5;"
                    f" Q1 = s_0 + sum(a), Q2 = s_1 + 2 sum(a), s = {rounded(obs)}",
                    f"\n  输入：mean={rounded(mean)}，σ={rounded(log_std.exp())}，"
                    f"eps={rounded(eps)}，scale={rounded(scale)}，bias={rounded(bias)}，alpha=0.5；"
                    f"Q1 = s_0 + sum(a)，Q2 = s_1 + 2 sum(a)，s = {rounded(obs)}")
        named = ""
        try:
            if not isinstance(out, tuple) or len(out) != 2:
                raise Failed(tr(f"expected (loss, logp), got {type(out).__name__}",
                                f"应该返回 (loss, logp)，得到的是 {type(out).__name__}"))
            try:
                compare("loss", out[0], loss)
                compare("logp", out[1], logp)
            except Failed:
                named = sac_named(out, actor, obs, alpha)
                raise
            reference = actor()
            own(reference, critic, critic2, obs, alpha)[0].backward()
            if not out[0].requires_grad:
                raise Failed(tr("gradient cut: the loss is right and carries no gradient at all "
                                "(computed under torch.no_grad(), or from .item() or .detach())",
                                "梯度被切断：损失数值对，但完全不带梯度（在 torch.no_grad() 下算的，"
                                "或经过了 .item()、.detach()）"))
            out[0].backward()
            for name in ("mean", "log_std"):
                r, g = getattr(reference, name).grad, getattr(yours, name).grad
                g = torch.zeros_like(r) if g is None else g
                if torch.allclose(g, r, atol=1e-5, rtol=1e-4):
                    continue
                for label, mistake in sac_gradient_mistakes():
                    variant = actor()
                    sac_variant(variant, obs, alpha, **mistake)[0].backward()
                    v = getattr(variant, name).grad
                    if v is not None and torch.allclose(g, v, atol=1e-5, rtol=1e-4):
                        named = label
                        break
                raise Failed(tr(f"wrong gradient: the values are right, and the gradient with "
                                f"respect to the actor's {name} is not the loss's:\n  expected "
                                f"{rounded(r)}, got {rounded(g)}",
                                f"梯度不对：数值对，但对演员的 {name} 的梯度不是这个损失的梯度：\n  "
                                f"应该是 {rounded(r)}，得到的是 {rounded(g)}"))
        except Failed as e:
            raise Failed(tr("case: ", "例子：") + what + inputs + f"\n  {e}" + (tr(
                "\n  this is exactly what this mistake gives: ", "\n  这正是这个错误会得到的值：")
                + named if named else "")) from None


def compare(name, got, expected):
    """Raise Failed at the first difference between `got` and `expected` (tensors or numbers)."""
    if expected is None:
        return
    if isinstance(expected, dict):
        for key, value in expected.items():
            compare(f"{name}[{key!r}]", got.get(key) if isinstance(got, dict) else None, value)
        return
    if torch.is_tensor(expected):
        if not torch.is_tensor(got):
            raise Failed(tr(f"{name}: expected a tensor of shape {tuple(expected.shape)}, got "
                            f"{type(got).__name__} {got!r}",
                            f"{name}：应该是形状为 {tuple(expected.shape)} 的张量，得到的是 "
                            f"{type(got).__name__} {got!r}"))
        if got.shape != expected.shape:
            raise Failed(tr(f"{name}: expected shape {tuple(expected.shape)}, got "
                            f"{tuple(got.shape)} (a (B, 1) against a (B,) broadcasts silently)",
                            f"{name}：形状应该是 {tuple(expected.shape)}，得到的是 "
                            f"{tuple(got.shape)}（(B, 1) 和 (B,) 相减会悄悄广播成 (B, B)）"))
        close = torch.isclose(got.detach().float(), expected, atol=1e-5, rtol=1e-5)
        if not close.all() and expected.dim() == 0:
            raise Failed(tr(f"{name}: expected {expected.item():.6g}, got {got.item():.6g}",
                            f"{name}：应该是 {expected.item():.6g}，得到的是 {got.item():.6g}"))
        if not close.all():
            wrong = [tuple(int(k) for k in i) for i in (~close).nonzero()]
            i = wrong[0]
            also = (tr(" (all that differ: ", "（所有不同的位置：") + ", ".join(map(str, wrong[:8]))
                    + tr(")", "）")) if len(wrong) > 1 else ""
            raise Failed(tr(f"{name}: first difference at index {i}: expected "
                            f"{expected[i].item():.6g}, got {got[i].item():.6g}{also}",
                            f"{name}：第一个不同在下标 {i}：应该是 {expected[i].item():.6g}，"
                            f"得到的是 {got[i].item():.6g}{also}")
                         + tr("\n  expected ", "\n  应该是 ") + str(rounded(expected))
                         + tr("\n  got      ", "\n  得到的是 ") + str(rounded(got)))
        return
    if not isinstance(got, (int, float)) or abs(float(got) - float(expected)) > 1e-5:
        raise Failed(tr(f"{name}: expected {expected:.6g}, got {got!r}",
                        f"{name}：应该是 {expected:.6g}，得到的是 {got!r}"))


def rounded(x):
    """A tensor as nested lists of numbers to 6 significant digits (float32's noise left out)."""
    x = x.detach().tolist()
    if isinstance(x, list) and x and isinstance(x[0], list):
        return [rounded(torch.tensor(v)) for v in x]
    return [float(f"{v:.6g}") for v in x] if isinstance(x, list) else float(f"{x:.6g}")


def show(ex, args):
    """The case's inputs, named as the function's parameters: tensors as lists, a batch dict
    by its keys, networks and settings left out."""
    def one(a):
        if isinstance(a, dict):
            return "{" + ", ".join(f"{k}: {one(v)}" for k, v in a.items() if k != "obs") + "}"
        if torch.is_tensor(a):
            return str(a.tolist() if not a.is_floating_point() else rounded(a))
        return repr(a)
    names = inspect.signature(getattr(ex.owner(), ex.function)).parameters
    return ", ".join(f"{name}={one(a)}" for name, a in zip(names, args)
                     if not callable(a) and not isinstance(a, SimpleNamespace))


def gradients(f, args, parameters, index=0):
    """{network output's name: its gradient} after backward() of f(*args)'s loss (its output
    `index`, the first by default), on copies of the case's inputs; None if the loss carries no
    gradient at all."""
    args = copy.deepcopy(args)
    out = f(*args)
    loss = out[index] if isinstance(out, tuple) and len(out) > index else out
    if not (torch.is_tensor(loss) and loss.requires_grad):
        return None
    loss.backward()
    leaves = [(name, p) for a in args if isinstance(a, Fixed)
              for name, p in zip(a.names, a.outputs)]
    leaves += [(name, a) for name, a in zip(parameters, args)
               if torch.is_tensor(a) and a.requires_grad]
    return {name: torch.zeros_like(p) if p.grad is None else p.grad for name, p in leaves}


def compare_gradients(ex, fn, args):
    """Where values cannot tell, the gradient can: the loss's gradient with respect to each
    network output of the case, yours against the script's own function's. An exercise whose
    function returns several losses (ex.losses: their indices among its outputs) has each one's
    gradient compared, the message saying which."""
    if not any(isinstance(a, Fixed) or torch.is_tensor(a) and a.requires_grad for a in args):
        return
    own = getattr(ex.owner(), ex.function)
    parameters = list(inspect.signature(own).parameters)
    losses = getattr(ex, "losses", (0,))
    for index in losses:
        loss = ex.outputs[index]
        reference = gradients(own, args, parameters, index)
        if reference is None:
            continue
        yours = gradients(fn, args, parameters, index)
        try:
            compare_loss_gradients(reference, yours, lambda kind: gradient_named(ex, loss, kind))
        except Failed as e:
            raise Failed((tr(f"{loss}: ", f"{loss}：") if len(losses) > 1 else "") + str(e)) \
                from None


def gradient_named(ex, loss, kind):
    """The mistake a gradient failure of this kind ("cut", "stray": where none belongs) of the
    output `loss` shows, as a line to add to the message, or ''."""
    hook = getattr(ex, "gradient_mistake", None)
    label = hook(loss, kind) if hook else ""
    if not label and kind == "cut" and getattr(ex, "cut", None):
        label = ex.cut()
    return (tr("\n  this is exactly what this mistake does: ",
               "\n  这正是这个常见错误的表现：\n    ") + label) if label else ""


def compare_loss_gradients(reference, yours, named):
    """One loss's gradients, yours against the reference's; `named(kind)`: the known mistake's
    line, or ''."""
    if yours is None:
        raise Failed(tr(
            "gradient cut: your loss has the right value and carries no gradient at all (it was "
            "computed\n  under torch.no_grad(), from .item() or .detach(), or from a tensor made "
            "anew): the optimizer\n  would change nothing",
            "梯度被切断：你的损失数值对，但完全不带梯度（它是在 torch.no_grad() 下算的，或经过了 "
            ".item()、\n  .detach()，或由新建的张量算出）：优化器什么也改不了") + named("cut"))
    for name, r in reference.items():
        g = yours[name]
        if torch.allclose(g, r, atol=1e-6, rtol=1e-4):
            continue
        if r.abs().max() > 1e-8 and g.abs().max() <= 1e-8:
            raise Failed(tr(
                f"gradient cut: the value is right, and no gradient reaches {name} (a .detach(), "
                f"or a tensor made\n  anew, on the way from {name} to the loss): expected "
                f"{rounded(r)}, got zeros",
                f"梯度被切断：数值对，但梯度传不到 {name}（从 {name} 到损失的路上有 .detach() "
                f"或新建的张量）：\n  应该是 {rounded(r)}，得到的是 0") + named("cut"))
        if r.abs().max() <= 1e-8:
            raise Failed(tr(
                f"a gradient where none belongs: the value is right, and your loss sends a "
                f"gradient into {name},\n  which this loss must not train (a quantity that "
                f"should be a constant, e.g. an advantage\n  recomputed from the live network, "
                f"carries it): "
                f"got {rounded(g)}, expected zeros",
                f"多出来的梯度：数值对，但你的损失把梯度传进了 {name}，这个损失不该训练它（本该是常数的"
                f"量带着梯度，\n  例如用正在训练的网络重新算的优势）：得到 {rounded(g)}，应该是 0")
                + named("stray"))
        if torch.allclose(g, -r, atol=1e-6, rtol=1e-4):
            raise Failed(tr(
                f"gradient reversed: the value is right, and the gradient with respect to {name} "
                f"has the\n  opposite sign: training would move it the wrong way: expected "
                f"{rounded(r)}, got {rounded(g)}",
                f"梯度方向反了：数值对，但对 {name} 的梯度符号相反，训练会把它往反方向推：\n  应该是 "
                f"{rounded(r)}，得到的是 {rounded(g)}"))
        raise Failed(tr(
            f"wrong gradient: the value is right, and the gradient with respect to {name} is "
            f"not the loss's:\n  expected {rounded(r)}, got {rounded(g)} (a term that should "
            f"be a constant, or one cut\n  from the graph, changes it)",
            f"梯度不对：数值对，但对 {name} 的梯度不是这个损失的梯度：\n  应该是 {rounded(r)}，得到的是 "
            f"{rounded(g)}（某一项该是常数却带着梯度，或者该带梯度却被切断了）"))


def worked_cases(ex, fn):
    if ex.function == "soft_update":
        return check_soft_update(fn)
    if ex.function == "update_critics":
        return check_td3_target(fn)
    if ex.function == "a2c_targets":
        return check_a2c_targets(fn)
    if ex.function == "ddpg_update":
        return check_ddpg_update(fn)
    if ex.name == "ddpg_store_step":
        return check_ddpg_store(fn)
    if ex.name == "ppo_rollout_step":
        return check_ppo_rollout(fn)
    if ex.script == "dqn_cartpole" and ex.function == "dqn_update":
        return check_dqn_target(fn)
    if ex.script == "sac_walker" and ex.function == "compute_loss_actor":
        return check_sac_actor_loss(fn)
    if ex.function == "reward_to_go":
        return check_reward_to_go(fn)
    if ex.script == "q_learning_cliffwalking":
        return check_td_control(fn, sarsa=ex.function == "sarsa_update")
    for what, args, expected in ex.cases():
        saved = [a.clone() if torch.is_tensor(a) else a for a in args]
        try:
            got = fn(*args)
        except RuntimeError as e:
            if ex.name == "group_advantages" and "must match the size" in str(e):
                raise Failed(tr("case: ", "例子：") + f"{what}\n  " + tr("input: ", "输入：")
                             + f"{show(ex, args)}\n  " + tr("your function raised ", "你的函数抛出了 ")
                             + error(e) + tr(
                                 "\n  this is exactly what this mistake raises: mean/std without "
                                 "keepdim=True: (B/G,) cannot broadcast against (B/G, G)",
                                 "\n  这正是这个常见错误会引发的：\n    mean/std 没有写 "
                                 "keepdim=True：形状 (B/G,) 不能和 (B/G, G) 广播")) from None
            raise
        for a, b in zip(args, saved):
            if torch.is_tensor(a) and not torch.equal(a, b):
                raise Failed(tr(f"{what}: your function changed one of its inputs in place",
                                f"{what}：你的函数原地改了它的一个输入"))
        try:
            if isinstance(expected, tuple):
                if not isinstance(got, tuple) or len(got) < len(expected):
                    raise Failed(tr(f"expected a tuple of {len(expected)}, got "
                                    f"{type(got).__name__}",
                                    f"应该返回 {len(expected)} 个值的元组，得到的是 "
                                    f"{type(got).__name__}"))
                for i, e in enumerate(expected):
                    compare(ex.outputs[i], got[i], e)
            else:
                compare(ex.outputs[0], got, expected)
            compare_gradients(ex, fn, args)
        except Failed as e:
            raise Failed(tr("case: ", "例子：") + f"{what}\n  " + tr("input: ", "输入：")
                         + f"{show(ex, args)}\n  {e}"
                         + named_mistake(ex, args, got, fn, expected)) from None


# ==== Known mistakes: where a wrong value is exactly what a named mistake gives, say so =========


def returns_with(r, nv, term, trunc, gamma, cut=True, trunc_boots=True, term_wins=True,
                 term_resets=True, shift=0):
    out, future = torch.zeros_like(r), (nv[-1] if cut else torch.zeros_like(r[0]))
    zero = torch.zeros_like(r[0])
    for t in reversed(range(len(r))):
        boot = (nv[t - shift] if trunc_boots else zero)
        ended = term[t] if term_resets else torch.zeros_like(term[t])
        if term_wins:
            future = torch.where(ended, zero, torch.where(trunc[t], boot, future))
        else:
            future = torch.where(trunc[t], boot, torch.where(ended, zero, future))
        out[t] = future = r[t] + gamma * future
    return out


def gae_with(r, v, nv, term, trunc, gamma, lam, trunc_boots=True, cut_at_trunc=True,
             term_wins=True, next_v=True, term_resets=True, shifted=False):
    adv, last = torch.zeros_like(r), torch.zeros_like(r[0])
    if shifted:  # values[t + 1] read as V(s_{t+1}), next_values only at the end
        nv = torch.cat([v[1:], nv[-1:]])
    for t in reversed(range(len(r))):
        boots = ~term[t] if term_wins else (~term[t] | trunc[t])
        boots = boots & ~trunc[t] if not trunc_boots else boots
        keep = ~(term[t] | trunc[t]) if cut_at_trunc else ~term[t]
        keep = keep if term_resets else torch.ones_like(keep)
        delta = r[t] + gamma * (nv[t] if next_v else v[t]) * boots.float() - v[t]
        last = adv[t] = delta + gamma * lam * keep.float() * last
    return adv


def returns_mistakes(r, nv, term, trunc, gamma):
    return [(tr("no bootstrap at the rollout's end (after step T - 1 the future is V(s_T), not 0)",
                "这批数据的末尾没有自举（第 T - 1 步之后的未来是 V(s_T)，不是 0）"),
             returns_with(r, nv, term, trunc, gamma, cut=False)),
            (tr("a time-limit truncation treated as a termination (no bootstrap there)",
                "把时间截断当成了终止（那里没有自举）"),
             returns_with(r, nv, term, trunc, gamma, trunc_boots=False)),
            (tr("truncation ignored: the sum runs on past a truncation into the next episode "
                "(there the future is V(final obs) = next_values[t])",
                "忽略了时间截断：累加越过了时间截断，进入了下一个回合（那里的未来是 "
                "V(最后的观测) = next_values[t]）"),
             returns_with(r, nv, term, torch.zeros_like(trunc), gamma)),
            (tr("truncation wins where both flags are set (termination must win)",
                "两个标志都在时按时间截断算了（应该按终止算）"),
             returns_with(r, nv, term, trunc, gamma, term_wins=False)),
            (tr("at a truncation, the value of the step before, next_values[t - 1], where "
                "V(final obs) is next_values[t]", "时间截断处用了前一步的 next_values[t - 1]，"
                "V(最后的观测) 是 next_values[t]"),
             returns_with(r, nv, term, trunc, gamma, shift=1)),
            (tr("the future is not reset where an episode terminated (the next episode's "
                "rewards leak in)", "回合终止处没有把未来清零（下一个回合的奖励漏了进来）"),
             returns_with(r, nv, term, trunc, gamma, term_resets=False))]


def gae_mistakes(r, v, nv, term, trunc, gamma, lam):
    return [(tr("a time-limit truncation treated as a termination in delta (no bootstrap there)",
                "在 delta 里把时间截断当成了终止（那里没有自举）"),
             gae_with(r, v, nv, term, trunc, gamma, lam, trunc_boots=False)),
            (tr("the sum runs on past a truncation (what follows belongs to the next episode)",
                "累加越过了时间截断（后面属于下一个回合）"),
             gae_with(r, v, nv, term, trunc, gamma, lam, cut_at_trunc=False)),
            (tr("truncation wins where both flags are set: delta bootstraps at a termination",
                "两个标志都在时按时间截断算了：终止处的 delta 还在自举"),
             gae_with(r, v, nv, term, trunc, gamma, lam, term_wins=False)),
            (tr("lam left out of the sum (gamma * A_{t+1}, not gamma * lam * A_{t+1})",
                "累加时漏了 lam（写成了 gamma * A_{t+1}，应该是 gamma * lam * A_{t+1}）"),
             gae_with(r, v, nv, term, trunc, gamma, 1.0)),
            (tr("gamma * lam left out of the sum (A_t = delta_t + A_{t+1}: tutorial 000's bug)",
                "累加时整个漏了 gamma * lam（写成了 A_t = delta_t + A_{t+1}：这正是教程 000 的错误，"
                "见 README.zh-CN.md 路线一第 3 步）"),
             gae_with(r, v, nv, term, trunc, gamma, 1.0 / gamma)),
            (tr("V(s_t) where V(s_{t+1}) belongs in delta (values[t], not next_values[t])",
                "delta 里用了 V(s_t)，应该是 V(s_{t+1})（用了 values[t]，不是 next_values[t]）"),
             gae_with(r, v, nv, term, trunc, gamma, lam, next_v=False)),
            (tr("the sum is not cut where an episode ended", "回合结束处没有切断累加"),
             gae_with(r, v, nv, term, trunc, gamma, lam, term_resets=False)),
            (tr("values[t + 1] where next_values[t] belongs: use next_values; they coincide "
                "with values[t + 1] in this project's\n    loops (NEXT_STEP autoreset stores the "
                "final obs at t + 1), not under every autoreset convention\n    (e.g. where the "
                "final obs is kept apart and the obs at t + 1 is the next episode's first)",
                "用了 values[t + 1]，应该是 next_values[t]：要用 next_values。在本项目的循环里"
                "两者相同\n    （NEXT_STEP 自动重置在 t + 1 处存的是最后的观测），但不是每种自动重置方式"
                "都这样\n    （例如最后的观测另外存放，t + 1 处是下一个回合的第一个观测）"),
             gae_with(r, v, nv, term, trunc, gamma, lam, shifted=True))]


def surrogate(policy, data, eps, inverted=False, use_max=False, clip_product=False,
              renormalized=False, upper_only=False, min_of_clipped_product=False,
              ratio_min=False):
    logp = Categorical(logits=policy(data["obs"])).log_prob(data["act"]).detach()
    r = torch.exp(data["logp"] - logp) if inverted else torch.exp(logp - data["logp"])
    a = data["adv"]
    if renormalized:
        a = (a - a.mean()) / (a.std() + 1e-8)
    if upper_only:
        return -torch.min(r * a, r.clamp(max=1 + eps) * a).mean()
    if ratio_min:
        return -(torch.min(r, r.clamp(1 - eps, 1 + eps)) * a).mean()
    if min_of_clipped_product:
        return -torch.min(r * a, (r * a).clamp(1 - eps, 1 + eps)).mean()
    if clip_product:
        return -(r * a).clamp(1 - eps, 1 + eps).mean()
    return -(torch.max if use_max else torch.min)(r * a, r.clamp(1 - eps, 1 + eps) * a).mean()


def clip_mistakes(policy, data, eps):
    right = surrogate(policy, data, eps)
    return [(tr("the ratio upside down: pi_old / pi, exp(logp_old - logp)",
                "比值倒过来了：π_old / π，即 exp(logp_old - logp)"),
             surrogate(policy, data, eps, inverted=True)),
            (tr("max where the pessimistic bound takes min", "用了 max，悲观的下界要取 min"),
             surrogate(policy, data, eps, use_max=True)),
            (tr("the product r * A clipped, not the ratio r", "裁剪了乘积 r * A，而不是比值 r"),
             surrogate(policy, data, eps, clip_product=True)),
            (tr("the product r * A clipped inside the min, min(r A, clip(r A, 1 - eps, 1 + eps)): "
                "clip the ratio, then multiply, min(r A, clip(r, 1 - eps, 1 + eps) A)",
                "在 min 里裁剪了乘积 r * A，即 min(r A, clip(r A, 1 - eps, 1 + eps))：应该先裁剪比值，"
                "再乘 A，即 min(r A, clip(r, 1 - eps, 1 + eps) A)"),
             surrogate(policy, data, eps, min_of_clipped_product=True)),
            (tr("the min taken over the ratios, min(r, clip(r)) * A, where it is over the "
                "products, min(r A, clip(r) A):\n    for A < 0 the pessimistic bound takes the "
                "larger ratio", "min 取在比值上，即 min(r, clip(r)) * A，应该取在乘积上，即 "
                "min(r A, clip(r) A)：\n    A < 0 时，悲观的下界要用较大的那个比值"),
             surrogate(policy, data, eps, ratio_min=True)),
            (tr("the sign: the objective L_CLIP returned, where the loss is -L_CLIP",
                "符号反了：返回的是目标 L_CLIP，损失应该是 -L_CLIP"), -right),
            (tr("a sum over the batch where the mean belongs", "对批量求了和，应该求均值"),
             right * len(data["adv"])),
            (tr("the advantages normalized again inside the loss (they come normalized: use them "
                "as they are)", "在损失里又把优势归一化了一次（给的优势已经归一化过，直接用）"),
             surrogate(policy, data, eps, renormalized=True)),
            (tr("the ratio clipped from above only (clamp(max=1 + eps)): the band has two edges",
                "只从上面裁剪了比值（clamp(max=1 + eps)）：区间有上下两个边"),
             surrogate(policy, data, eps, upper_only=True))]


def kl_mistakes(policy, data, beta):
    dist = Categorical(logits=policy(data["obs"]).detach())
    old = Categorical(logits=data["logits_old"])
    r = torch.exp(dist.log_prob(data["act"]) - data["logp"])
    s, kl, reverse = (r * data["adv"]).mean(), kl_divergence(old, dist).mean(), kl_divergence(
        dist, old).mean()
    return [(tr("the KL the other way round: KL(pi || pi_old); kl_divergence(p, q) is KL(p || q)",
                "KL 的方向反了：写成了 KL(π || π_old)；kl_divergence(p, q) 是 KL(p || q)"),
             -s + beta * reverse),
            (tr("the surrogate's sign: +mean(r A) where the loss has -mean(r A)",
                "代理目标的符号反了：损失里应该是 -mean(r A)"), s + beta * kl),
            (tr("the penalty's sign: - beta * KL where the loss adds it",
                "惩罚项的符号反了：损失里应该加上 β * KL"), -s - beta * kl),
            (tr("a sample estimate of the KL, mean(logp_old - logp), where the exact KL of the two "
                "distributions belongs (kl_divergence)", "用了 KL 的样本估计 mean(logp_old - logp)，"
                "应该用两个分布的精确 KL（kl_divergence）"),
             -s + beta * (data["logp"] - dist.log_prob(data["act"])).mean()),
            (tr("the KL summed over the batch (.sum()) where its mean belongs (.mean())",
                "KL 对批量求了和（.sum()），应该求均值（.mean()）"),
             -s + beta * kl_divergence(old, dist).sum())]


def a2c_mistakes(model, data, cfg):
    logits, values = (x.detach() for x in model(data["obs"]))
    dist = Categorical(logits=logits)
    logp, ent = dist.log_prob(data["act"]), dist.entropy().mean()
    loss_pi, loss_v = -(logp * data["adv"]).mean(), 0.5 * ((values - data["ret"]) ** 2).mean()
    return [(tr("A recomputed as R - V from the critic, where data[\"adv\"] is given (a constant)",
                "用评论员重新算了 A = R - V，应该直接用给的 data[\"adv\"]（常数）"),
             -(logp * (data["ret"] - values)).mean() + cfg.vf_coef * loss_v - cfg.ent_coef * ent),
            (tr("the entropy bonus with the wrong sign (+ ent_coef * H; the bonus is subtracted "
                "from the loss)", "熵正则项的符号反了（损失里应该减去 ent_coef * H）"),
             loss_pi + cfg.vf_coef * loss_v + cfg.ent_coef * ent),
            (tr("the critic's loss not halved (0.5 * mean((V - R)^2))",
                "评论员的损失没有乘 0.5（应该是 0.5 * mean((V - R)^2)）"),
             loss_pi + cfg.vf_coef * 2 * loss_v - cfg.ent_coef * ent),
            (tr("the actor's sign: +mean(log pi * A) (the loss is minus it)",
                "演员项的符号反了：损失应该是 -mean(log π * A)"),
             -loss_pi + cfg.vf_coef * loss_v - cfg.ent_coef * ent)]


def td_mistakes(reward, not_done, next_q, gamma):
    return [(tr("no not_done: a future added after a termination",
                "没有乘 not_done，终止之后还加上了未来的价值"),
             reward + gamma * next_q),
            (tr("(1 - not_done): not_done is already 1 - terminated",
                "写成了 (1 - not_done)：not_done 本身就是 1 - terminated"),
             reward + gamma * (1 - not_done) * next_q),
            (tr("gamma left out", "漏了 gamma"), reward + not_done * next_q),
            (tr("(r + gamma * Q') * not_done: the reward itself zeroed at a termination; only "
                "the future is cut, r + gamma * not_done * Q'",
                "写成了 (r + gamma * Q') * not_done：终止时连奖励本身也被清零了；只该切掉未来，"
                "即 r + gamma * not_done * Q'"), (reward + gamma * next_q) * not_done)]


def actor_mistakes(actor, critic, obs):
    q = critic(obs, actor(obs).detach())
    return [(tr("+Q: the actor must ascend Q, so its loss is -Q", "+Q：演员要提高 Q，所以损失是 -Q"),
             q.mean()),
            (tr("a sum over the batch where the mean belongs", "对批量求了和，应该求均值"), -q.sum())]


def beta_mistakes(beta, d, cfg):
    lo, hi = cfg.d_targ / cfg.kl_tolerance, cfg.d_targ * cfg.kl_tolerance
    return [(tr("the two rules swapped: beta must shrink when d is small, grow when it is large",
                "两条规则反了：d 小时 β 应该变小，d 大时变大"),
             beta * cfg.beta_factor if d < lo else beta / cfg.beta_factor if d > hi else beta),
            (tr("the tolerance (1.5) used as the factor (2)", "把容差（1.5）当成了倍数（2）"),
             beta / cfg.kl_tolerance if d < lo else beta * cfg.kl_tolerance if d > hi else beta),
            (tr("<= or >= at the band's edges, where the paper's rules are strict (< and >)",
                "区间边界用了 <= 或 >=，论文的规则是严格的 < 和 >"),
             beta / cfg.beta_factor if d <= lo else beta * cfg.beta_factor if d >= hi else beta)]


def same_value(got, value):
    """True where `got` is `value`: tensors of one shape, close; or numbers, equal."""
    try:
        if torch.is_tensor(value):
            return (torch.is_tensor(got) and got.shape == value.shape
                    and torch.allclose(got.detach().float(), value.float(), atol=1e-5, rtol=1e-5))
        return isinstance(got, (int, float)) and abs(got - value) < 1e-9
    except (TypeError, RuntimeError):
        return False


def same_outputs(got, value):
    """`value` a tuple (a mistake's outputs, None where any will do): each output matches;
    else the first output (or `got` itself) is `value`."""
    if isinstance(value, tuple):
        return (isinstance(got, tuple) and len(got) >= len(value)
                and all(v is None or same_value(g, v) for g, v in zip(got, value)))
    return same_value(got[0] if isinstance(got, tuple) else got, value)


def named_mistake(ex, args, got, fn=None, expected=None):
    """The name of a known mistake whose value `got` (the function's first output, or all of
    them where the mistake gives a tuple) is, or ''. A mistake that gives the right value
    (`expected`) in this case is never named: a wrong gradient with the right value is not it."""
    if ex.mistakes is None:
        return ""
    mistakes = ex.mistakes(*args)
    if ex.name == "group_advantages" and fn is not None:  # three denominators, one value here
        pick = group_eps_mistake(fn)
        eps = [m for m in mistakes if "1e-" in m[0]]
        if pick is not None:
            mistakes = [m for m in mistakes if m not in eps] + [eps[pick - 1]]
        else:
            mistakes = [m for m in mistakes if m not in eps[1:]]
    for label, value in mistakes:
        if value is None:  # this mistake gives the right value in this case
            continue
        if expected is not None and same_outputs(expected, value):
            continue
        if same_outputs(got, value):
            return tr("\n  this is exactly what this mistake gives: ",
                      "\n  你的值恰好是这个常见错误会得到的值：\n    ") + label
    return ""


# ==== Stage (b): the real loop, beside the script's own function ============================


# The off-policy scripts' update functions, and what each logs at every gradient step in stage (b)
UPDATES = dict(ddpg_walker=("ddpg_update", ("critic_loss", "actor_loss")),
               td3_walker=("update_critics", ("critic_loss",)),
               sac_walker=("update_actor_and_targets", ("actor_loss", "entropy")),
               dqn_cartpole=("dqn_update", ("loss", "q", "next_max", "next_double")))


def loop_logs(ex, fn, tmp):
    """The run's logs, per update: rows of numbers, with the learner's `fn` swapped in (or the
    script's own, fn=None)."""
    script = importlib.import_module(ex.script)
    swaps = [] if fn is None else [(ex.owner(), ex.function, fn)]
    losses = []  # the off-policy scripts: every gradient step's numbers, to 6 significant digits
    update_fn, names = UPDATES.get(ex.script, (None, ()))
    if update_fn:
        # the learner's function where it is the update itself, else the script's own
        update = fn if fn is not None and ex.function == update_fn else getattr(script, update_fn)

        def recorded(*args):
            out = update(*args)
            values = list(out) if isinstance(out, tuple) else list(out.reshape(-1))
            losses.append({k: f"{float(v):.6g}" for k, v in zip(names, values)})
            return out
        swaps = [s for s in swaps if s[1] != update_fn] + [(script, update_fn, recorded)]
    with swapped(swaps), contextlib.redirect_stdout(io.StringIO()):
        result = script.train(script.Config(**ex.loop, run_dir=str(tmp)))
    run = Path(result["run_dir"])
    if ex.script == "dqn_cartpole":  # gradient steps, then the learning phases' progress.csv
        return [dict(row, step=str(i + 1)) for i, row in enumerate(losses)] + [
            dict(r, where="progress") for r in csv.DictReader(open(run / "progress.csv"))]
    if update_fn:  # one update per env step after the warm-up, then the evaluations
        steps = [dict(row, step=str(ex.loop["start_steps"] + i + 1))
                 for i, row in enumerate(losses)]
        return steps + [dict(r, where="evaluation")
                        for r in csv.DictReader(open(run / "evaluations.csv"))]
    return list(csv.DictReader(open(run / "progress.csv")))


REFERENCE = {}  # the script's own logs per loop setting, run once per process
ROUNDING = 1e-5  # a first difference in (b) this small (relative) is float rounding, not a bug


def relative(a, b):
    a, b = float(a), float(b)
    return abs(a - b) / max(abs(a), abs(b), 1e-30)


def rounding_only(a, b):
    """True where two logged numbers differ in their last digits only."""
    try:
        return math.isfinite(float(a)) and math.isfinite(float(b)) and relative(a, b) < ROUNDING
    except (TypeError, ValueError):
        return False


def never_called(ex, stage):
    return Failed(tr(
        f"{ex.script}.train() never called {ex.function} in {stage}: the script no longer uses "
        f"the function this\n  exercise checks (its settings or its code changed), so the stage "
        f"would pass whatever you wrote.\n  This is the checker's fault, not yours: please "
        f"report it.",
        f"{ex.script}.train() 在{stage}里一次也没有调用 {ex.function}：脚本已经不用这个练习检查的函数了"
        f"（它的设置或代码变了），\n  所以这一关无论你写什么都会通过。这是检查程序的问题，不是你的：请报告它。"))


def real_loop(ex, fn):
    with tempfile.TemporaryDirectory() as tmp:
        key = (ex.script, tuple(sorted(ex.loop.items())))
        if key not in REFERENCE:
            REFERENCE[key] = loop_logs(ex, None, Path(tmp) / "reference")
        reference = REFERENCE[key]
        if ex.script == "grpo_addition" and not any(
                r.get("flat_groups") not in (None, "", "nan") and float(r["flat_groups"]) < 1
                for r in reference):
            raise Failed(tr(
                "in stage (b)'s run every group's rewards are equal: every advantage is 0, so "
                "the stage would pass\n  answers that differ. This is the checker's fault, not "
                "yours: please report it.",
                "第 (b) 关的训练里每一组的奖励都相同：优势全是 0，所以不同的答案在这一关也分不出来。"
                "\n  这是检查程序的问题，不是你的：请报告它。"))
        calls = [0]

        def counted(*args, **kw):
            calls[0] += 1
            return fn(*args, **kw)

        counted.__name__ = ex.function
        try:
            yours = loop_logs(ex, counted, Path(tmp) / "yours")
        except Exception as e:  # noqa: BLE001  the learner's error, named in one line
            raise Failed(tr(f"in {ex.script}.train(), at call {calls[0]} of your function: ",
                            f"在 {ex.script}.train() 里，你的函数第 {calls[0]} 次被调用时出错：")
                         + error(e, first_line=True))
    if calls[0] == 0:
        raise never_called(ex, tr("stage (b)", "第 (b) 关"))
    unit = (tr("step", "第 {} 步") if ex.script in ("ddpg_walker", "td3_walker", "sac_walker")
            else tr("gradient step", "第 {} 个梯度步") if ex.script == "dqn_cartpole"
            else tr("episode", "第 {} 个回合") if ex.script == "q_learning_cliffwalking"
            else tr("update", "第 {} 次更新"))
    for i, (a, b) in enumerate(zip(reference, yours)):
        for key in a:
            if key in ("sps",) or a[key] == b.get(key):
                continue
            n = a["step"] if "step" in a else i + 1
            where = (tr(f"evaluation at step {a['global_step']}", f"第 {a['global_step']} 步的评估")
                     if a.get("where") == "evaluation" else
                     tr(f"the learning phase ending at step {a['global_step']} (progress.csv)",
                        f"在第 {a['global_step']} 步结束的那次学习（progress.csv）")
                     if a.get("where") == "progress" else
                     (f"{unit} {n}" if LANG == "en" else unit.format(n)))
            if rounding_only(a[key], b.get(key)):
                # (a) passed and the first difference is in the last digits: the same formula
                # with its float operations in another order (e.g. lerp_, or add_(tau * (p -
                # p')), for mul_ then add_); from there the two runs drift apart, as any would
                return tr(f"the logs first differ at {where}, in {key}, by rounding only "
                          f"({a[key]} vs {b.get(key)}): probably only the order of float "
                          f"operations;\n  your function is right in value (written in the "
                          f"script's own order, it gives identical logs)",
                          f"日志第一次不同是在{where}，{key}，只差在舍入上（{a[key]} 对 "
                          f"{b.get(key)}）：多半只是浮点运算的顺序不同；\n  你的函数在数值上"
                          f"是对的（按脚本自己的运算顺序写，日志会完全相同）")
            raise Failed(tr(f"{ex.script}.train() with your function: the logs first differ at "
                            f"{where}, in {key}: the script's own gives {a[key]}, yours "
                            f"{b.get(key)}",
                            f"换上你的函数后，{ex.script}.train() 的日志第一次不同是在{where}，"
                            f"{key}：脚本自己的是 {a[key]}，你的是 {b.get(key)}")
                         + f"\n  {ex.loop_hint()}")
    if len(reference) != len(yours):
        raise Failed(tr(f"{ex.script}.train() with your function logged {len(yours)} rows, the "
                        f"script's own {len(reference)}",
                        f"换上你的函数后，{ex.script}.train() 记了 {len(yours)} 行日志，"
                        f"脚本自己的是 {len(reference)} 行"))


# ==== Stage (c): learning ===================================================================

HOLD = 2  # DDPG, TD3: the last HOLD evaluations must be at the maximum, not only one of them


def learns(ex, fn):
    script = importlib.import_module(ex.script)
    calls = [0]

    def counted(*args, **kw):
        calls[0] += 1
        return fn(*args, **kw)

    with tempfile.TemporaryDirectory() as tmp, swapped([(ex.owner(), ex.function, counted)]):
        with contextlib.redirect_stdout(io.StringIO()):
            result = script.train(script.Config(**ex.learn, run_dir=tmp))
    if calls[0] == 0:
        raise never_called(ex, tr("stage (c)", "第 (c) 关"))
    if ex.script == "grpo_addition":  # held-out pass@1 after GRPO, from the supervised start
        (before, _), (after, _) = result["before"], result["after"]
        if after < GRPO_BAR:
            raise Failed(tr(
                f"held-out pass@1 after GRPO is {after:.3f} (from {before:.3f} after supervision), "
                f"under {GRPO_BAR} (the script's own: 0.94 to 0.96 on seeds 0-4)",
                f"GRPO 之后留出题目上的 pass@1 是 {after:.3f}（监督学习之后是 {before:.3f}），低于 "
                f"{GRPO_BAR}（脚本自己的在种子 0 到 4 上是 0.94 到 0.96）"))
    elif ex.script == "q_learning_cliffwalking":
        cliff_walked(ex, result)
    elif "evaluations" in result:  # DDPG, TD3 on InvertedPendulum-v5: the pole held to the end
        means = [e["eval_mean"] for e in result["evaluations"]]
        last = means[-HOLD:]
        if min(last) < 1000:
            steps = f"{result['global_step']:,}"
            raise Failed(tr(
                f"InvertedPendulum-v5 in {steps} steps: the last {HOLD} evaluations are "
                f"{', '.join(f'{m:.0f}' for m in last)}, not all 1000 (the maximum, held by the "
                f"script's own to the end)\n  every evaluation: "
                f"{', '.join(f'{m:.0f}' for m in means)}",
                f"InvertedPendulum-v5 练 {steps} 步：最后 {HOLD} 次评估是 "
                f"{', '.join(f'{m:.0f}' for m in last)}，不全是 1000（满分；脚本自己的一直保持到最后）"
                f"\n  每次评估：{', '.join(f'{m:.0f}' for m in means)}"))
    elif not result["solved"]:
        recent = sum(result["episode_returns"][-20:]) / max(len(result["episode_returns"][-20:]), 1)
        raise Failed(tr(f"CartPole-v1 not solved in {result['global_step']} steps (the script's "
                        f"own solves it): the last 20 episodes' mean return is {recent:.1f}",
                        f"CartPole-v1 练了 {result['global_step']} 步还没解决（脚本自己的能解决）："
                        f"最后 20 个回合的平均回报是 {recent:.1f}"))
    return result


def cliff_walked(ex, result):
    """Stage (c) on CliffWalking: Sarsa's greedy path is the safe one (to the goal, longer than
    13 steps, never on the cliff's edge); Q-learning's the optimal one, its Q there Q*."""
    script = importlib.import_module(ex.script)
    agent = "sarsa" if ex.function == "sarsa_update" else "q_learning"
    (path, G), optimal = result["paths"][agent], result["optimal"]
    cells = [s for s, _ in path]
    shown = tr(f"\n  its greedy path from the start: cells {cells}, return {G:.0f}",
               f"\n  它从起点出发的贪心路径：格子 {cells}，回报 {G:.0f}")
    if agent == "sarsa" and (math.isnan(G) or len(path) <= 13 or CLIFF_EDGE & set(cells)):
        raise Failed(tr(
            "Sarsa's greedy path after 500 episodes (seed 0) is not the safe one: the script's own "
            "reaches the goal in 17 steps,\n  keeping a row away from the cliff's edge (cells "
            "25-34); Sarsa values the epsilon-greedy policy it follows, falls included",
            "练了 500 个回合（种子 0）之后，Sarsa 的贪心路径不是安全的那条：脚本自己的用 17 步到达"
            "终点，\n  和悬崖边（格子 25-34）隔着一行；Sarsa 估的是它自己这个 ε-贪心策略的价值，"
            "掉下悬崖也算在内") + shown)
    if agent == "q_learning":
        error = script.q_error(result["tables"]["q_learning"], result["q_star"], optimal)
        best = result["v_star"][result["start"]]
        if path != optimal or error > 1e-6:
            raise Failed(tr(
                f"Q-learning after 500 episodes (seed 0): its greedy path is not the optimal one "
                f"(13 steps along the cliff's edge,\n  return {best:.0f} "
                f"= V*(start)), or its Q on that path is not Q* (mean |Q - Q*| = {error:.3g}; "
                f"the script's own: 0)",
                f"练了 500 个回合（种子 0）之后，Q 学习的贪心路径不是最优的那条（沿着悬崖边 13 步，"
                f"\n  回报 {best:.0f} = V*(起点)），或者它在这条路径上的 Q "
                f"不是 Q*（|Q - Q*| 的平均是 {error:.3g}；脚本自己的是 0）") + shown)


# ==== The exercises =========================================================================

CARTPOLE_LOOP = dict(seed=0, stop_when_solved=False, gifs=False, curves=False,
                     eval_episodes=1, print_every=10**6)
CARTPOLE_LEARN = dict(seed=0, gifs=False, curves=False, eval_episodes=5, print_every=10**6)
# PPO's two scripts: their defaults with 60,000 steps, not 100,000; seeds 0-9 solve by 41,440
# (PPO-clip) and 26,992 (PPO-penalty, docs/results.md), so a right answer stops well before, and
# a wrong one is told sooner
PPO_LEARN = dict(CARTPOLE_LEARN, total_timesteps=60_000)
DDPG_LOOP = dict(DDPG_IN_MINUTES, seed=0, total_timesteps=600, start_steps=300, eval_every=100,
                 eval_episodes=1, print_every=1, gifs=False, curves=False, cuda=False)
# DDPG: the README's settings, 15,000 steps of its 20,000: seed 0 holds 1000 from step 10,000
# on, while bug_td_target's 1000 at 10,000 and 12,500 falls to 5 at 15,000 (at 20,000: 61, 104)
DDPG_LEARN = dict(DDPG_IN_MINUTES, seed=0, total_timesteps=15_000, print_every=10**6,
                  gifs=False, curves=False, cuda=False)
# TD3 on the same task and settings, 25,000 steps, seed 2: its delayed actor starts slower
# (seeds 0-3 hold 1000 from step 27,500, 25,000, 22,500 and 22,500 on, docs/exercises.md)
TD3_LOOP, TD3_LEARN = DDPG_LOOP, dict(DDPG_LEARN, seed=2, total_timesteps=25_000)
# GRPO: a short supervised phase, then a few GRPO steps (the loop); the default run (learning).
# One-digit sums, so that after 60 supervised steps some groups already mix right and wrong
# answers (seed 0: 3 to 5 of the 8 groups in each of the 4 steps): with every reward 0, every
# advantage and KL would be 0, and (b) could not tell answers apart (real_loop checks it)
GRPO_LOOP = dict(seed=0, digits=1, sft_steps=60, grpo_steps=4, prompts=8, eval_every=20,
                 eval_prompts=20, curves=False, print_every=10**6)
GRPO_LEARN = dict(seed=0, curves=False, print_every=10**6)
GRPO_BAR = 0.9  # held-out pass@1 after GRPO: seeds 0-4 gave 0.941 to 0.955, the start 0.70-0.76

# DQN: the tests' short run, Double DQN (both next-state values logged either way), 4 gradient
# steps per phase; learning: the defaults, CartPole-v1 solved (seed 0: at 35,378 steps)
DQN_LOOP = dict(seed=0, total_timesteps=1200, start_steps=200, train_freq=100, gradient_steps=4,
                q_check_every=2, stop_when_solved=False, double=True, gifs=False, curves=False,
                eval_episodes=1, print_every=10**6)
DQN_LEARN = CARTPOLE_LEARN
# SAC: the DDPG loop's task; learning: tests/test_sac_walker.py's run (InvertedPendulum-v5,
# step sizes 3e-3, seed 1, 15,000 steps: it holds 1000 from step 12,500 on; over 20,000 steps
# seeds 0, 2 and 4 held it from 15,000, seeds 1 and 3 from 12,500, docs/exercises.md)
SAC_FAST = dict(env_id="InvertedPendulum-v5", start_steps=1000, eval_every=2500, hidden=128,
                batch_size=128, actor_lr=3e-3, critic_lr=3e-3, alpha_lr=3e-3, gifs=False,
                curves=False, cuda=False, seed=0)
SAC_LOOP = dict(SAC_FAST, total_timesteps=600, start_steps=300, eval_every=100, eval_episodes=1,
                print_every=1)
SAC_LEARN = dict(SAC_FAST, seed=1, total_timesteps=15_000, print_every=10**6)


# REINFORCE: a few updates of 4 whole episodes (the pole falls within tens of steps at first);
# learning: the defaults, 150,000 steps of their 500,000 (seeds 0-9 solve by 76,659, in 4 to
# 10 s), so that a wrong answer is told in seconds rather than minutes
REINFORCE_LOOP = dict(CARTPOLE_LOOP, total_timesteps=1000)
REINFORCE_LEARN = dict(CARTPOLE_LEARN, total_timesteps=150_000)
# Sarsa and Q-learning on CliffWalking: the first 30 episodes (the first ones are long random
# walks: thousands of updates); learning: the defaults (S&B example 6.6, 500 episodes, seed 0),
# under a second, the run tests/test_q_learning_cliffwalking.py checks
TABULAR_LOOP = dict(seed=0, total_episodes=30, gifs=False, curves=False, print_every=10**6)
TABULAR_LEARN = dict(seed=0, gifs=False, curves=False, print_every=10**6)
CLIFF_EDGE = set(range(25, 35))  # the cells right above the cliff (row 2, columns 1 to 10)


def ON_REAL_DATA():
    return tr("Your function passed the worked cases, and on the script's real data it gives "
              "another number:\n  compare its inputs there (their shapes, several envs, the "
              "flags) with the cases'.",
              "你的函数通过了手算的例子，但在脚本的真实数据上得出的数不同：\n  比较那里的输入"
              "（形状、多个环境、各个标志）和例子里的有什么不同。")


def OFF_POLICY():
    return tr("Each step's actor update changes the next step's critic loss (through the "
              "targets): the first\n  quantity that differs may come from another function "
              "than the one it is named after.",
              "每一步演员的更新都会（通过目标网络）改变下一步评论员的损失：第一个不同的量，"
              "\n  可能来自别的函数，而不是名字上对应的那个。")


def exercise(name, script, function, owner, cases, loop, learn, hint, outputs=("output",),
             mistakes=None, cut=None, losses=(0,), gradient_mistake=None):
    """cut: the mistake's name where the value is right and the gradient cut, if one fits;
    losses: the outputs whose gradients (a) compares (their indices); gradient_mistake(loss,
    kind): the mistake a gradient failure of output `loss` shows ("cut", "stray"), or ''."""
    return SimpleNamespace(name=name, script=script, function=function, cases=cases,
                           owner=lambda: importlib.import_module(owner), loop=loop,
                           learn=learn, loop_hint=hint, outputs=outputs, mistakes=mistakes,
                           cut=cut, losses=losses, gradient_mistake=gradient_mistake)


EXERCISES = {ex.name: ex for ex in (
    exercise("discounted_returns", "actor_critic_cartpole", "discounted_returns", "common",
             returns_cases, dict(CARTPOLE_LOOP, total_timesteps=1600), CARTPOLE_LEARN,
             lambda: tr("A2C's critic targets R_t come from your returns: the first update "
                        "that differs is\n  where your returns differ on real rollouts "
                        "(several envs, autoreset steps).",
                        "A2C 评论员的目标 R_t 来自你的回报：第一次不同的那次更新，就是你的回报在"
                        "\n  真实采集的数据上（多个环境、自动重置步）开始不同的地方。"),
             outputs=("returns",), mistakes=returns_mistakes),
    exercise("gae", "ppo_cartpole", "gae", "common", gae_cases,
             dict(CARTPOLE_LOOP, total_timesteps=1280), PPO_LEARN,
             lambda: tr("PPO's advantages and value targets come from your GAE: the first "
                        "update that\n  differs is where your GAE differs on real rollouts.",
                        "PPO 的优势和价值目标来自你的 GAE：第一次不同的那次更新，就是你的 GAE 在"
                        "\n  真实采集的数据上开始不同的地方。"), outputs=("advantages",),
             mistakes=gae_mistakes),
    exercise("clipped_surrogate", "ppo_cartpole", "compute_loss_pi", "ppo_cartpole",
             clip_cases, dict(CARTPOLE_LOOP, total_timesteps=1280), PPO_LEARN,
             ON_REAL_DATA, outputs=("loss_pi", "entropy", "info"), mistakes=clip_mistakes),
    exercise("kl_penalty", "ppo_kl_cartpole", "compute_loss_pi", "ppo_kl_cartpole", kl_cases,
             dict(CARTPOLE_LOOP, total_timesteps=1280), PPO_LEARN, ON_REAL_DATA,
             outputs=("loss_pi", "entropy", "info"), mistakes=kl_mistakes),
    exercise("adapt_beta", "ppo_kl_cartpole", "adapt_beta", "ppo_kl_cartpole", beta_cases,
             dict(CARTPOLE_LOOP, total_timesteps=2560), PPO_LEARN,
             lambda: tr("Each update's beta comes from your rule.", "每次更新的 β 都来自你的规则。"),
             outputs=("beta",), mistakes=beta_mistakes),
    exercise("a2c_loss", "actor_critic_cartpole", "a2c_loss", "actor_critic_cartpole",
             a2c_cases, dict(CARTPOLE_LOOP, total_timesteps=1600), CARTPOLE_LEARN, ON_REAL_DATA,
             outputs=("loss", "stats"), mistakes=a2c_mistakes),
    exercise("td_target", "ddpg_walker", "td_target", "ddpg_walker", td_cases, DDPG_LOOP,
             DDPG_LEARN, lambda: tr(
                 "The critic is trained toward your targets: critic_loss differs first, at the "
                 "first step where your y\n  differs; actor_loss follows, through the critic.",
                 "评论员朝你的目标训练：critic_loss 最先不同，就在你的 y 第一次不同的那一步；"
                 "\n  actor_loss 随后也不同，因为它经过评论员。"), outputs=("y",),
             mistakes=td_mistakes),
    exercise("actor_loss", "ddpg_walker", "compute_loss_actor", "ddpg_walker", actor_cases,
             DDPG_LOOP, DDPG_LEARN, lambda: tr(
                 "The actor descends your loss: actor_loss differs at the first step where its "
                 "value differs; where only\n  its gradient differs, critic_loss differs "
                 "first, a step later: its target Q'(s', mu'(s')) uses the\n  actor's target "
                 "network, which follows the actor.",
                 "演员沿你的损失下降：损失的数值不同时，actor_loss 在第一个不同的步就不同；只有梯度"
                 "不同时，\n  critic_loss 会晚一步先不同：它的目标 Q'(s', mu'(s')) 用到目标演员，"
                 "而目标演员跟着演员走。"),
             outputs=("actor_loss",), mistakes=actor_mistakes,
             cut=lambda: tr("the action computed without a gradient: torch.no_grad() or "
                            ".detach() around actor(obs) cuts the actor off\n    (Q(s, mu(s)) "
                            "must reach mu(s): only the critic's parameters stay out of the step)",
                            "动作是在不带梯度的情况下算的：actor(obs) 外面的 torch.no_grad() 或 "
                            ".detach() 把演员切断了\n    （Q(s, mu(s)) 的梯度要传到 mu(s)；"
                            "不更新的只是评论员的参数）")),
    exercise("soft_update", "ddpg_walker", "soft_update", "ddpg_walker", lambda: [], DDPG_LOOP,
             DDPG_LEARN, lambda: tr(
                 "The target networks moved by your function; the critic's loss differs first "
                 "because its target,\n  Q'(s', mu'(s')), uses those networks.",
                 "目标网络是由你的函数移动的；评论员的损失最先不同，是因为它的目标 Q'(s', mu'(s'))"
                 "\n  用的就是这两个目标网络。")),
    exercise("td3_target", "td3_walker", "update_critics", "td3_walker", lambda: [], TD3_LOOP,
             TD3_LEARN, lambda: tr("Both critics are trained toward your target; the noise comes "
                                   "from torch's generator in\n  the script's order "
                                   "(torch.randn_like(action), one draw per update). ",
                                   "两个评论员都朝你的目标训练；噪声来自 torch 的随机数生成器，"
                                   "顺序和脚本一样\n  （torch.randn_like(action)，每次更新抽一次）。")
             + OFF_POLICY(), outputs=("critic_loss",)),
    exercise("group_advantages", "grpo_addition", "group_advantages", "grpo_addition",
             group_cases, GRPO_LOOP, GRPO_LEARN,
             lambda: tr("Every update's advantages come from your function.", "每次更新的优势都来自你的函数。"),
             outputs=("adv",), mistakes=group_mistakes),
    exercise("grpo_loss", "grpo_addition", "grpo_loss", "grpo_addition", grpo_cases, GRPO_LOOP,
             GRPO_LEARN, ON_REAL_DATA, outputs=("loss", "info"), mistakes=grpo_mistakes),
    exercise("a2c_targets", "actor_critic_cartpole", "a2c_targets", "actor_critic_cartpole",
             lambda: [], dict(CARTPOLE_LOOP, total_timesteps=1600), CARTPOLE_LEARN,
             lambda: tr("A2C's targets and advantages come from your function: the first update "
                        "that differs is\n  where they differ on real rollouts (several envs, "
                        "autoreset steps).",
                        "A2C 的目标和优势来自你的函数：第一次不同的那次更新，就是它们在真实采集的"
                        "\n  数据上（多个环境、自动重置步）开始不同的地方。"), outputs=("returns", "advantages")),
    exercise("ddpg_update", "ddpg_walker", "ddpg_update", "ddpg_walker", lambda: [], DDPG_LOOP,
             DDPG_LEARN, OFF_POLICY, outputs=("critic_loss", "actor_loss")),
    exercise("ddpg_store_step", "ddpg_walker", "store_and_advance", "ddpg_walker", lambda: [],
             DDPG_LOOP, DDPG_LEARN,
             lambda: tr("Every minibatch is sampled from what your function stored, and every "
                        "action is chosen in the obs\n  it returned: the first step that differs "
                        "is where they first differ.",
                        "每个小批量都是从你的函数存下的数据里抽的，每个动作都在它返回的观测上选："
                        "\n  第一个不同的步就是它们开始不同的地方。")),
    exercise("ppo_rollout_step", "ppo_cartpole", "store_and_advance", "ppo_cartpole", lambda: [],
             dict(CARTPOLE_LOOP, total_timesteps=1280), PPO_LEARN,
             lambda: tr("Every rollout is stored by your function, and every action is chosen in "
                        "the obs it returned: the\n  first update that differs is where they "
                        "differ on real steps (8 envs, autoreset steps).",
                        "每批 rollout 都由你的函数存下，每个动作都在它返回的观测上选：第一次不同的"
                        "更新，\n  就是它们在真实的步上（8 个环境、自动重置步）开始不同的地方。"),
             outputs=("obs", "autoreset")),
    exercise("dqn_target", "dqn_cartpole", "dqn_update", "dqn_cartpole", lambda: [],
             DQN_LOOP, DQN_LEARN,
             lambda: tr("Q is trained toward your target at every gradient step (here with "
                        "--double; both next-state values\n  are logged either way): the first "
                        "gradient step that differs is where your target differs on real data.",
                        "Q 每个梯度步都朝你的目标训练（这里开着 --double；两种下一状态的价值都会记录）："
                        "\n  第一个不同的梯度步，就是你的目标在真实数据上开始不同的地方。"),
             outputs=("stats",)),
    exercise("sac_actor_loss", "sac_walker", "compute_loss_actor", "sac_walker", lambda: [],
             SAC_LOOP, SAC_LEARN, lambda: tr("The actor descends your loss, and alpha follows "
                                            "your log pi. ", "演员沿你的损失下降，alpha 跟着你的 log π 调整。")
             + OFF_POLICY(), outputs=("actor_loss", "logp")),
    exercise("reward_to_go", "reinforce_cartpole", "reward_to_go", "reinforce_cartpole",
             lambda: [], REINFORCE_LOOP, REINFORCE_LEARN,
             lambda: tr("Every episode's G_t comes from your function: the first update that "
                        "differs is the first batch of\n  whole episodes where your G_t "
                        "differ (the pole falls in these first episodes: no time limit yet).",
                        "每个回合的 G_t 都来自你的函数：第一次不同的那次更新，就是你的 G_t 第一次"
                        "不同的那批完整回合\n  （这几个回合里杆都倒了，还没有碰到时间截断）。"),
             outputs=("G",)),
    exercise("reinforce_loss", "reinforce_cartpole", "reinforce_loss", "reinforce_cartpole",
             reinforce_cases, REINFORCE_LOOP, REINFORCE_LEARN, ON_REAL_DATA,
             outputs=("loss_pi", "loss_v", "weights"), mistakes=reinforce_mistakes,
             losses=(0, 1), gradient_mistake=reinforce_gradient_mistake),
    exercise("sarsa_update", "q_learning_cliffwalking", "sarsa_update", "q_learning_cliffwalking",
             lambda: [], TABULAR_LOOP, TABULAR_LEARN, lambda: tr(
                 "Sarsa's table is updated by your function at every step: its columns "
                 "(sarsa_*) differ first, at the first\n  episode where the table differs "
                 "(Q-learning's columns stay the script's own).",
                 "Sarsa 的表每一步都由你的函数更新：它的那几列（sarsa_*）最先不同，就在表第一次不同的"
                 "\n  那个回合（Q 学习的那几列还是脚本自己的）。")),
    exercise("q_learning_update", "q_learning_cliffwalking", "q_learning_update",
             "q_learning_cliffwalking", lambda: [], TABULAR_LOOP, TABULAR_LEARN, lambda: tr(
                 "Q-learning's table is updated by your function at every step: its columns "
                 "(q_learning_*) differ first, at the\n  first episode where the table differs "
                 "(Sarsa's columns stay the script's own).",
                 "Q 学习的表每一步都由你的函数更新：它的那几列（q_learning_*）最先不同，就在表第一次"
                 "不同的\n  那个回合（Sarsa 的那几列还是脚本自己的）。")),
)}


# Find the bug: a function that runs but trains badly, checked as its exercise is.
BUGS = {"bug_returns": "discounted_returns", "bug_gae": "gae", "bug_td_target": "td_target"}
for _bug, _of in BUGS.items():
    EXERCISES[_bug] = SimpleNamespace(**{**vars(EXERCISES[_of]), "name": _bug})


def load(name, path=None):
    """The learner's function from exercises/<name>.py (or `path`)."""
    ex = EXERCISES[name]
    path = Path(path or HERE / f"{name}.py")
    spec = importlib.util.spec_from_file_location(f"exercise_{name}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return getattr(module, ex.function)


def stage_names():
    return (tr("(a) worked cases", "第 (a) 关“手算的例子”"),
            tr("(b) the real loop", "第 (b) 关“真实的训练循环”"),
            tr("(c) learning", "第 (c) 关“学会任务”"))


def line(name, stage, verdict, why=""):
    """One line of output: the exercise, the stage, its verdict and why, punctuated as the
    language is (Chinese: full-width colons, no colon between the stage and its verdict)."""
    if LANG == "zh":
        return f"{name}：{stage}{verdict}" + (f"：{why}" if why else "")
    return f"{name}: {stage}: {verdict}" + (f": {why}" if why else "")


def error(e, first_line=False):
    """An exception raised by the learner's code: its type, then its message (Python's own
    words, in English), after the language's colon."""
    text = str(e).splitlines()[0] if first_line and str(e) else str(e)
    return f"{type(e).__name__}" + (tr(": ", "：") + text if text else "")


def check(name, fn=None, learning=True, say=print):
    """Run the stages on `fn` (default: exercises/<name>.py's); True if all pass."""
    ex, fn = EXERCISES[name], fn or load(name)
    names = stage_names()
    stages = [(names[0], worked_cases), (names[1], real_loop)]
    stages += [(names[2], learns)] if learning else []
    fail = tr("FAIL", "未通过")
    for stage, run in stages:
        start = time.time()
        try:
            note = run(ex, fn)
        except NotImplementedError:
            say(line(name, stage, fail, tr(
                f"{NOT_WRITTEN} (fill in the blank in exercises/{name}.py)",
                f"还没写（在 exercises/{name}.py 里填空）")))
            return False
        except Failed as e:
            say(line(name, stage, fail, str(e)))
            return False
        except Exception as e:  # noqa: BLE001  the learner's code raised: name it
            say(line(name, stage, fail, tr("your function raised ", "你的函数抛出了 ") + error(e)))
            return False
        seconds = time.time() - start
        say(line(name, stage, tr(f"pass ({seconds:.1f} s)", f"通过（{seconds:.1f} 秒）"),
                 note if isinstance(note, str) else ""))  # (c) returns train()'s result
    return True


def ChineseHelp(prog):
    """The scripts' --help-zh layout (help_zh.py: Chinese wrapped by columns), no defaults."""
    class Layout(help_zh.HelpFormatter):
        def _get_help_string(self, action):
            return action.help

    return Layout(prog)


def main(argv=None):
    global LANG
    argv = sys.argv[1:] if argv is None else list(argv)  # --help in the messages' language too:
    given = [b for a, b in zip(argv, argv[1:]) if a == "--lang"] + [
        a.partition("=")[2] for a in argv if a.startswith("--lang=")]
    LANG = given[-1] if given and given[-1] in ("zh", "en") else locale_lang()
    chinese = next(p for p in __doc__.split("\n\n") if p.startswith("检查练习"))
    parser = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0] + tr("", "\n\n" + chinese.replace("\n", "")),
        formatter_class=tr(argparse.HelpFormatter, ChineseHelp), add_help=False)
    parser.add_argument("-h", "--help", action="help", help=tr(
        "show this help message and exit", "show this help message and exit\n显示本帮助并退出"))
    parser.add_argument("name", nargs="?", choices=sorted(EXERCISES), help=tr(
        "the exercise", "the exercise\n练习名；不写时，列出所有练习的第 (a)、(b) 关"))
    parser.add_argument("--no-learning", action="store_true", help=tr(
        "stop after stage (b)", "stop after stage (b)\n只跑第 (a)、(b) 两关，不跑第 (c) 关“学会任务”"))
    en = "the messages' language (default: from the locale, e.g. LANG=zh_CN.UTF-8 gives zh; else en)"
    parser.add_argument("--lang", choices=("zh", "en"), default=None, help=tr(en, en + (
        "\n提示用的语言；不写时看系统语言：LANG 等以 zh 开头就用中文，否则用英文")))
    args = parser.parse_args(argv)
    LANG = args.lang or locale_lang()
    again = f" --lang {args.lang}" if args.lang else ""  # a suggested command keeps --lang
    if args.name:
        passed = check(args.name, learning=not args.no_learning)
        if passed and args.no_learning:  # say so: all-pass lines alone read as if (c) passed too
            print(line(args.name, stage_names()[2], tr("not run (--no-learning)",
                                                       "没有跑（加了 --no-learning）"),
                       tr(f"python exercises/check.py {args.name}{again} runs it",
                          f"要跑这一关，运行 python exercises/check.py {args.name}{again}")))
        sys.exit(0 if passed else 1)
    all_passed = True
    fail = tr("FAIL", "未通过")
    for name in EXERCISES:  # no name: (a) and (b) of every exercise, one line each
        lines = []
        passed = check(name, learning=False, say=lines.append)
        all_passed &= passed
        head, gap = (f"{name}：", f"{fail}：") if LANG == "zh" else (f"{name}: ", f": {fail}: ")
        stage, _, why = lines[-1].removeprefix(head).partition(gap)  # as line() wrote it
        verdict = (tr("(a) and (b) pass", "第 (a)、(b) 关都通过") if passed else
                   tr(f"FAIL at {stage}: ", f"{stage}未通过：") + why.splitlines()[0])
        if name in BUGS and not passed:  # where it fails would give the bug away
            verdict = tr("not fixed yet", "还没改好")
        print(f"{name:20} {verdict}", flush=True)
    print(tr("(stage (c), learning, runs one exercise at a time: "
             f"python exercises/check.py NAME{again})",
             f"（第 (c) 关要训练，一次只查一个练习：python exercises/check.py 练习名{again}）"))
    # exit status 0 only when every exercise passed (a) and (b): scripts and tests can rely on it
    sys.exit(0 if all_passed else 1)


if __name__ == "__main__":
    main()
