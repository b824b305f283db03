"""The checks of exercises/sac_actor_loss.py, SAC's actor loss with the tanh log-probability
correction: its worked cases, its named mistakes and its runs."""

import importlib
import math

import torch
import torch.nn.functional as F

from checking import tr, Failed, t, scalar, compare, rounded
import runs

SCRIPT = "sac_walker"
FUNCTION = "compute_loss_actor"
ORDER = 18  # its row in docs/exercises.md's table
OUTPUTS = ("actor_loss", "logp")
RUN = runs.SAC
LOOP = runs.SAC_LOOP
LEARN = runs.SAC_LEARN


def loop_hint():
    return tr("The actor descends your loss, and alpha follows your log pi. ",
              "演员沿你的损失下降，alpha 跟着你的 log π 调整。") + runs.OFF_POLICY()


class FixedNoise(torch.distributions.Normal):
    """A Normal whose draws use a given eps: u = mean + sigma * eps (rsample); sample() is the
    same number without the gradient, as torch's."""

    draws = 0  # how many times a case's noise was drawn: 0 means the answer drew its own

    def __init__(self, loc, scale, eps):
        super().__init__(loc, scale)
        self.eps = eps

    def rsample(self, sample_shape=torch.Size()):
        FixedNoise.draws += 1
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
    """obs (B, 2); Q1(s, a) = s_0 + sum(a), Q2(s, a) = s_1 + 2 sum(a): in every case Q1 is the
    smaller in the first row (sum(a) > -1 there) and Q2 in the second (sum(a) < 5), so that an
    answer taking one critic alone, or the larger, shows; alpha = 0.5."""
    mean, log_std, eps = t(*mean), t(*log_std), t(*eps)
    low, high = t(*low), t(*high)
    obs = t([0.0, 1.0], [5.0, 0.0])
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
    q1, q2 = critic(obs, at), critic2(obs, at)
    q = dict(min=torch.min, max=torch.max, q1=lambda a, b: a, q2=lambda a, b: b)[critics](q1, q2)
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
        (tr("Q1 alone where SAC takes min(Q1, Q2): the smaller of the two critics is what "
            "curbs the overestimation", "只用了 Q1，SAC 取 min(Q1, Q2)：正是取两个评论员中较小的"
            "那个，才压住了高估"), dict(critics="q1")),
        (tr("Q2 alone where SAC takes min(Q1, Q2): the smaller of the two critics is what "
            "curbs the overestimation", "只用了 Q2，SAC 取 min(Q1, Q2)：正是取两个评论员中较小的"
            "那个，才压住了高估"), dict(critics="q2")),
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


def worked_cases(fn):
    own = importlib.import_module("sac_walker").compute_loss_actor
    critic, critic2 = sac_critics()
    for what, (mean, log_std, eps, scale, bias, obs, alpha) in sac_cases():
        def actor(case=(mean, log_std, eps, scale, bias)):
            return SacActor(*case)
        yours, FixedNoise.draws = actor(), 0
        out = fn(yours, critic, critic2, obs, alpha)
        own_noise = FixedNoise.draws == 0  # the distribution's rsample() never called
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
            drew = tr("\n  your answer drew its own noise: the cases fix eps through the "
                      "distribution's rsample() (u = mean + sigma * eps), as the exercise asks; "
                      "call it", "\n  你的答案自己抽了噪声：这些例子通过分布的 rsample() 固定 eps"
                      "（u = mean + sigma * eps），练习要求的正是调用它") if own_noise else ""
            shown = e.plain if named or drew else str(e)
            raise Failed(tr("case: ", "例子：") + what + inputs + f"\n  {shown}" + (tr(
                "\n  this is exactly what this mistake gives: ", "\n  这正是这个错误会得到的值：")
                + named if named else drew)) from None
