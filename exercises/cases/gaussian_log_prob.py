"""The checks of exercises/gaussian_log_prob.py, log pi(a|s) of a diagonal Gaussian policy: its
worked cases, its named mistakes and its runs."""

import math

import torch

from checking import tr, t
import runs

SCRIPT = "ppo_reacher"
FUNCTION = "gaussian_log_prob"
ORDER = 27  # its row in docs/exercises.md's table
OUTPUTS = ("log pi(a|s)",)
RUN = runs.REACHER
LOOP = runs.REACHER_LOGP_LOOP
LEARN = runs.REACHER_LEARN


def loop_hint():
    return tr("log pi gives both pi_old (batch_of) and pi (compute_loss_pi): the ratio, "
              "approx_kl and the early stop follow it. ",
              "log π 同时给出 π_old（batch_of）和 π（compute_loss_pi）：比值、approx_kl 和早停都"
              "跟着它。") + runs.ON_REAL_DATA()


def by_hand(mu, log_std, act):
    """The formula of the docstring in float64, one term at a time."""
    mu, log_std, act = (x.double() for x in (mu, log_std, act))
    sigma = torch.exp(log_std)
    per_dim = -(act - mu) ** 2 / (2 * sigma ** 2) - log_std - 0.5 * math.log(2 * math.pi)
    return per_dim.sum(-1).float()


def cases():
    # sigma = (2, 0.25), mu and a chosen so that (a - mu) / sigma = (1, -2) and (-0.5, 0.5):
    # row 0: (-0.5 - log 2 - 0.918939) + (-2 + log 4 - 0.918939) = -2.112086 - 1.532645
    #        = -3.644731;
    # row 1: (-0.125 - log 2 - 0.918939) + (-0.125 + log 4 - 0.918939) = -1.737086 + 0.342355
    #        = -1.394731 (a density above 1 in the narrow dimension: its log is positive).
    # The log sigma terms do not cancel (log 2 + log 0.25 != 0), nor do the squares.
    mu, log_std = t([0.5, -1.0], [1.0, 2.0]), t(math.log(2.0), math.log(0.25))
    act = t([2.5, -1.5], [0.0, 2.125])
    # Three dimensions, three states, sigma below 1 and above it, each mean apart
    mu3, log_std3 = t([0.2, -0.4, 1.0], [0.0, 0.3, -0.5], [1.5, -1.0, 0.1]), t(-0.5, 0.3, -1.2)
    act3 = t([0.9, 0.6, 1.1], [-0.6, -1.2, -0.2], [1.0, 0.5, 0.4])
    return [(tr("sigma = (2, 0.25): (a - mu) / sigma = (1, -2) and (-0.5, 0.5); two states, "
                "two dimensions",
                "sigma = (2, 0.25)：(a - mu) / sigma = (1, -2) 和 (-0.5, 0.5)；两个状态，两维"),
             (mu, log_std, act), t(-3.644731, -1.394731)),
            (tr("three states, three dimensions, sigma = exp(-0.5, 0.3, -1.2)",
                "三个状态，三维，sigma = exp(-0.5, 0.3, -1.2)"),
             (mu3, log_std3, act3), by_hand(mu3, log_std3, act3))]


def variant(mu, log_std, act, reduce="sum", sigma=None, square=True, log_sigma=1.0,
            constant=1.0, quadratic_sign=-1.0):
    """log pi as a known mistake computes it (`constant`: how many halves of log(2 pi))."""
    s = log_std.exp() if sigma is None else sigma(log_std)
    quadratic = quadratic_sign * (act - mu) ** 2 / (2 * (s ** 2 if square else s))
    per_dim = quadratic - log_sigma * log_std - constant * 0.5 * math.log(2 * math.pi)
    return dict(sum=lambda x: x.sum(-1), mean=lambda x: x.mean(-1), none=lambda x: x,
                batch=lambda x: x.sum(0))[reduce](
        per_dim)


def mistakes(mu, log_std, act):
    right = variant(mu, log_std, act)
    return [
        (tr("the mean over the action's dimensions, where the density of a vector of "
            "independent dimensions is their product: its log the sum",
            "对动作的各维求了平均；各维独立时向量的密度是各维密度之积，取对数是求和"),
         variant(mu, log_std, act, reduce="mean")),
        (tr("log_std used as sigma ((a - mu) / log_std): sigma = log_std.exp()",
            "把 log_std 当成了 sigma（(a - mu) / log_std）：sigma = log_std.exp()"),
         variant(mu, log_std, act, sigma=lambda x: x)),
        (tr("(a - mu)^2 divided by 2 sigma, not by 2 sigma^2 (the square of sigma forgotten)",
            "(a - mu)^2 除以了 2 sigma，应该除以 2 sigma^2（忘了 sigma 的平方）"),
         variant(mu, log_std, act, square=False)),
        (tr("the log sigma term left out: the density's 1 / sigma (a wider Gaussian is lower "
            "everywhere)", "漏了 log sigma 这一项：密度里的 1 / sigma（越宽的高斯处处越低）"),
         variant(mu, log_std, act, log_sigma=0.0)),
        (tr("the constant log(2 pi) / 2 left out of each dimension: PPO's ratio would not change "
            "(it cancels in log pi - log pi_old),\n    but the value is not log pi (the density "
            "would not integrate to 1)",
            "每一维都漏了常数 log(2π)/2：PPO 的比值不会变（它在 log π - log π_old 里消掉了），"
            "\n    但这个值不是 log π（这样的密度积分不为 1）"),
         variant(mu, log_std, act, constant=0.0)),
        (tr("log(2 pi) where each dimension's constant is log(2 pi) / 2 (the 1 / sqrt(2 pi) "
            "of the density)", "每一维的常数写成了 log(2π)，应该是 log(2π)/2（密度里的 "
            "1 / sqrt(2π)）"), variant(mu, log_std, act, constant=2.0)),
        (tr("the sign of the square term: +(a - mu)^2 / (2 sigma^2), where the density falls "
            "away from the mean", "平方项的符号反了：写成了 +(a - mu)^2 / (2 sigma^2)，密度离均值越远"
            "越低"), variant(mu, log_std, act, quadratic_sign=1.0)),
        (tr("the sign of log sigma: + log sigma, where the density's 1 / sigma gives - log sigma",
            "log sigma 的符号反了：密度里的 1 / sigma 给出的是 - log sigma"),
         variant(mu, log_std, act, log_sigma=-1.0)),
        (tr("the sign of the whole: -log pi (a negative log-likelihood) returned",
            "整体的符号反了：返回的是 -log π（负对数似然）"), -right),
        (tr("no sum over the action's dimensions: each dimension's log density apart, (B, "
            "act_dim); log pi(a|s) is their sum, .sum(-1), (B,)",
            "没有对动作的各维求和：得到的是每一维各自的对数密度，形状 (B, act_dim)；log π(a|s) "
            "是它们的和，.sum(-1)，形状 (B,)"), variant(mu, log_std, act, reduce="none")),
        (tr("summed over the batch (.sum(0), axis 0) where the sum is over the action's "
            "dimensions (.sum(-1)): one number per dimension, not per action",
            "对批量求了和（.sum(0)，第 0 维），应该对动作的各维求和（.sum(-1)）：得到的是每一维一个数，"
            "不是每个动作一个"), variant(mu, log_std, act, reduce="batch"))]
