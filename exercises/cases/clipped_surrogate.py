"""The checks of exercises/clipped_surrogate.py, PPO's ratio and clipped surrogate loss: its worked
cases, its named mistakes and its runs."""

import torch
from torch.distributions import Categorical

from checking import tr, t, scalar, Fixed, logits_names
import runs

SCRIPT = "ppo_cartpole"
FUNCTION = "compute_loss_pi"
ORDER = 3  # its row in docs/exercises.md's table
OUTPUTS = ("loss_pi", "entropy", "info")
RUN = runs.CARTPOLE
LOOP = dict(runs.CARTPOLE_LOOP, total_timesteps=1280)
LEARN = runs.PPO_LEARN


def loop_hint():
    return runs.ON_REAL_DATA()


def cut():
    return tr("no gradient reaches pi: the ratio (or log pi, or the loss) detached or computed "
              "under torch.no_grad();\n    only log pi_old is a constant, r = exp(log pi - "
              "log pi_old) must carry pi's gradient",
              "梯度传不到 π：比值（或 log π，或损失）被 detach 了，或是在 torch.no_grad() 下算的；\n"
              "    只有 log π_old 是常数，r = exp(log π - log π_old) 必须带着 π 的梯度")


def cases():
    # pi = (0.5, 0.5) everywhere; pi_old of the taken action 0.25, 0.8 or 0.45, so the ratios
    # r = 2, 0.625, 1.111 are not reciprocal pairs: exp(logp_old - logp) gives other values.
    policy = Fixed(t([0.0, 0.0]).expand(7, 2), names=logits_names())
    data = dict(obs=torch.zeros(7, 1), act=torch.tensor([0, 0, 1, 1, 0, 1, 1]),
                adv=t(1.0, -1.0, 1.0, -1.0, 2.0, -3.0, 2.0),
                logp=torch.log(t(0.25, 0.25, 0.8, 0.8, 0.45, 0.45, 0.8)))
    # eps = 0.3, not the script's 0.2, so that 0.2 written as a number shows; the band is
    # [0.7, 1.3]. min(r A, clip(r, 0.7, 1.3) A) per sample: min(2, 1.3) = 1.3; min(-2, -1.3) =
    # -2; min(0.625, 0.7) = 0.625; min(-0.625, -0.7) = -0.7; r = 10/9 inside the band: 20/9,
    # -30/9; and r = 0.625 once more, with A = 2 alone (no pair of opposite signs: min(1.25,
    # 1.4) = 1.25, where the clipped term alone gives 1.4). Ratios above 1 and below it, against
    # both signs of A. The loss is minus the mean.
    terms = [1.3, -2.0, 0.625, -0.7, 20 / 9, -30 / 9, 1.25]
    return [(tr("r = 2, 2, 0.625, 0.625, 10/9, 10/9, 0.625 against A = 1, -1, 1, -1, 2, -3, 2; "
                "eps = 0.3", "r = 2, 2, 0.625, 0.625, 10/9, 10/9, 0.625，A = 1, -1, 1, -1, 2, -3, "
                "2；eps = 0.3"), (policy, data, 0.3), (scalar(-sum(terms) / 7), None, None))]


def surrogate(policy, data, eps, inverted=False, use_max=False, clip_product=False,
              renormalized=False, upper_only=False, min_of_clipped_product=False,
              ratio_min=False, clipped_only=False, log_ratio=None):
    logp = Categorical(logits=policy(data["obs"])).log_prob(data["act"]).detach()
    r = torch.exp(data["logp"] - logp) if inverted else torch.exp(logp - data["logp"])
    if log_ratio is not None:  # the ratio written from the log-probabilities without exp
        r = logp / data["logp"] if log_ratio == "divided" else logp - data["logp"]
    a = data["adv"]
    if renormalized:
        a = (a - a.mean()) / (a.std() + 1e-8)
    if upper_only:
        return -torch.min(r * a, r.clamp(max=1 + eps) * a).mean()
    if ratio_min:
        return -(torch.min(r, r.clamp(1 - eps, 1 + eps)) * a).mean()
    if clipped_only:
        return -(r.clamp(1 - eps, 1 + eps) * a).mean()
    if min_of_clipped_product:
        return -torch.min(r * a, (r * a).clamp(1 - eps, 1 + eps)).mean()
    if clip_product:
        return -(r * a).clamp(1 - eps, 1 + eps).mean()
    return -(torch.max if use_max else torch.min)(r * a, r.clamp(1 - eps, 1 + eps) * a).mean()


def mistakes(policy, data, eps):
    right = surrogate(policy, data, eps)
    return [(tr("the ratio upside down: pi_old / pi, exp(logp_old - logp)",
                "比值倒过来了：π_old / π，即 exp(logp_old - logp)"),
             surrogate(policy, data, eps, inverted=True)),
            (tr("max where the pessimistic bound takes min", "用了 max，悲观的下界要取 min"),
             surrogate(policy, data, eps, use_max=True)),
            (tr("the ratio as logp / logp_old: log-probabilities divided, where the ratio of "
                "probabilities is exp(logp - logp_old)", "比值写成了 logp / logp_old：对数概率相除；"
                "概率之比是 exp(logp - logp_old)"),
             surrogate(policy, data, eps, log_ratio="divided")),
            (tr("the ratio as logp - logp_old without exp: that is log r, the ratio is its exp",
                "比值写成了 logp - logp_old，没有取 exp：那是 log r，比值是它的 exp"),
             surrogate(policy, data, eps, log_ratio="difference")),
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
            (tr("the min left out: the clipped term clip(r, 1 - eps, 1 + eps) A alone, where "
                "L_CLIP is min(r A, clip(r, 1 - eps, 1 + eps) A)", "漏了 min：只用了裁剪的那一项 "
                "clip(r, 1 - eps, 1 + eps) A，L_CLIP 应该是 min(r A, clip(r, 1 - eps, 1 + eps) A)"),
             surrogate(policy, data, eps, clipped_only=True)),
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
