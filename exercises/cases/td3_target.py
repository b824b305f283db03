"""The checks of exercises/td3_target.py, TD3's clipped double-Q target with target policy
smoothing: its worked cases, its named mistakes and its runs."""

from types import SimpleNamespace

import torch

from checking import tr, Failed, t, compare
import runs

SCRIPT = "td3_walker"
FUNCTION = "update_critics"
ORDER = 10  # its row in docs/exercises.md's table
OUTPUTS = ("critic_loss",)
RUN = runs.TD3
LOOP = runs.TD3_LOOP
LEARN = runs.TD3_LEARN


def loop_hint():
    return tr("Both critics are trained toward your target; the noise comes "
              "from torch's generator in\n  the script's order "
              "(torch.randn_like(action), one draw per update). ",
              "两个评论员都朝你的目标训练；噪声来自 torch 的随机数生成器，"
              "顺序和脚本一样\n  （torch.randn_like(action)，每次更新抽一次）。") + runs.OFF_POLICY()


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


def worked_cases(fn):
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
            raise Failed(tr("case: ", "例子：") + f"{what}\n  {e.plain if named else e}" + (tr(
                "\n  this is exactly what this mistake gives: ",
                "\n  你的值恰好是这个常见错误会得到的值：\n    ") + named[0] if named else "")) from None
