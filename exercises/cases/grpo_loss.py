"""The checks of exercises/grpo_loss.py, GRPO's per-token loss (a token is a character here), the
KL estimated by k3 (a per-token estimate, never negative), the padding masked out: its worked
cases, its named mistakes and its runs."""

from types import SimpleNamespace
import math

import torch

from checking import only_if, scalar, t, tr
import runs

SCRIPT = "grpo_addition"
FUNCTION = "grpo_loss"
ORDER = 12  # its row in docs/exercises.md's table
OUTPUTS = ("loss", "info")
RUN = runs.GRPO
LOOP = runs.GRPO_LOOP
LEARN = runs.GRPO_LEARN


def loop_hint():
    return runs.ON_REAL_DATA()


def grpo_by_hand(logp, logp_old, logp_ref, adv, mask, cfg, kl_reversed=False, no_mask=False,
                 token_mean=False, kl_sign=1.0, no_clip=False, ratio_one=False,
                 kl_unmasked=False, always_norm=False, k1=False, all_mean=False,
                 inverted=False, use_max=False, ratio_to_ref=False):
    """The loss element by element, in plain Python (and the named mistakes' versions)."""
    eps, per_completion, total, tokens = cfg.clip_coef, [], 0.0, 0.0
    for i in range(len(adv)):
        row = 0.0
        for j in range(logp.shape[1]):
            old = logp_ref if ratio_to_ref else logp_old
            r = 1.0 if ratio_one else math.exp(float(logp[i, j] - old[i, j]) * (
                -1 if inverted else 1))
            a = float(adv[i])
            pick = max if use_max else min
            s = r * a if no_clip else pick(r * a, min(max(r, 1 - eps), 1 + eps) * a)
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


def cases():
    # Two completions of 3 tokens, the first with 2 of its own (its third is padding). Ratios
    # 1.5, 0.9, 1.1 / 0.7, 1.05, 1.3 against A = 1.5, -0.5: above 1 and below it, 1.5 clipped
    # to 1.25 and 0.7 to 0.75 by eps = 0.25 (not the script's 0.2, so that 0.2 written as a
    # number shows); pi_ref / pi of 2, 0.5, 0.76, ...
    # (the padding token's pi_ref / pi is not 1: its KL term, and its gradient, are not 0, so
    # a KL left unmasked shows)
    logp_old = torch.log(t([0.4, 0.5, 0.6], [0.5, 0.4, 0.3]))
    logp = (torch.log(t([0.6, 0.45, 0.66], [0.35, 0.42, 0.39]))).requires_grad_()
    logp_ref = torch.log(t([0.3, 0.9, 0.5], [0.7, 0.21, 0.5]))
    adv, mask = t(1.5, -0.5), t([1.0, 1.0, 0.0], [1.0, 1.0, 1.0])
    cases = []
    for norm in (True, False):
        cfg = SimpleNamespace(clip_coef=0.25, beta=0.1, length_norm=norm)
        args = (logp, logp_old, logp_ref, adv, mask, cfg)
        cases.append((tr(f"2 completions of 3 tokens, the first's third masked; eps = 0.25, "
                         f"beta = 0.1, length_norm = {norm}",
                         f"2 个回答各 3 个 token，第一个的第三个被掩掉；eps = 0.25，β = 0.1，"
                         f"length_norm = {norm}"), args,
                      (grpo_by_hand(*(a.detach() if torch.is_tensor(a) else a for a in args)),
                       None)))
    return cases


def mistakes(logp, logp_old, logp_ref, adv, mask, cfg):
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
                "也算进去了：应该先在每个回答自己的 token 上平均"), only_if(
                cfg.length_norm, grpo_by_hand(*args, cfg, all_mean=True))),
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
            (tr("max where the pessimistic bound takes min", "用了 max，悲观的下界要取 min"),
             grpo_by_hand(*args, cfg, use_max=True)),
            (tr("the ratio against pi_ref, exp(logp - logp_ref), where the clipped ratio is "
                "against pi_old (pi_ref is for the KL only)", "比值的分母用了 π_ref，即 "
                "exp(logp - logp_ref)；裁剪的比值分母是 π_old（π_ref 只用在 KL 里）"),
             grpo_by_hand(*args, cfg, ratio_to_ref=True)),
            (tr("the ratio upside down: pi_old / pi, exp(logp_old - logp)",
                "比值倒过来了：π_old / π，即 exp(logp_old - logp)"),
             grpo_by_hand(*args, cfg, inverted=True)),
            (tr("the ratio against logp itself (always 1): pi_old is logp_old",
                "比值的分母用了 logp 自己（比值总是 1）：π_old 是 logp_old"),
             grpo_by_hand(*args, cfg, ratio_one=True)),
            (tr("the sign: the objective returned, where the loss is its negative",
                "符号反了：返回的是目标函数，损失应该取负"), -grpo_by_hand(*args, cfg))]
