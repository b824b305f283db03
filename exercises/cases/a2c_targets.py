"""The checks of exercises/a2c_targets.py, A2C's bootstrap from a rollout (V(s_{t+1}) from the
stored obs): its worked cases, its named mistakes and its runs."""

from types import SimpleNamespace

import torch

import common

from checking import tr, Failed, t, flags, compare, named as named_line
import runs

SCRIPT = "actor_critic_cartpole"
FUNCTION = "a2c_targets"
ORDER = 13  # its row in docs/exercises.md's table
OUTPUTS = ("returns", "advantages")
RUN = runs.CARTPOLE
LOOP = dict(runs.CARTPOLE_LOOP, total_timesteps=1600)
LEARN = runs.CARTPOLE_LEARN


def loop_hint():
    return tr("A2C's targets and advantages come from your function: the first update "
              "that differs is\n  where they differ on real rollouts (several envs, "
              "autoreset steps).",
              "A2C 的目标和优势来自你的函数：第一次不同的那次更新，就是它们在真实采集的"
              "\n  数据上（多个环境、自动重置步）开始不同的地方。")


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
             with_next(torch.cat([last[None], values[:-1]]))),
            (tr("values rolled (torch.roll(values, -1, 0)): the last step's V(s_{t+1}) wraps "
                "round to V(s_0), where it is V(next_obs)",
                "对 values 做了 torch.roll(values, -1, 0)：最后一步的 V(s_{t+1}) 绕回成了 V(s_0)，"
                "应该是 V(next_obs)"), with_next(torch.roll(values, -1, 0))),
            (tr("values[-1] repeated for the last step's V(s_{t+1}), where it is V(next_obs)",
                "最后一步的 V(s_{t+1}) 重复用了 values[-1]，应该是 V(next_obs)"),
             with_next(torch.cat([values[1:], values[-1:]])))]


def worked_cases(fn):
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
                raise Failed(tr("the values are right, and they carry a gradient into the "
                                "critic", "数值对，但它们带着梯度连到评论员") + named_line(tr(
                    "V computed with its graph: compute it under torch.no_grad() (the targets "
                    "are constants; A2C's actor loss would otherwise train the critic)",
                    "V 带着计算图：要在 torch.no_grad() 下计算 V（目标是常数；否则 A2C 演员的损失会去"
                    "训练评论员）"), "does"))
        except Failed as e:
            named = ""
            if lam is None and isinstance(got, tuple) and torch.is_tensor(got[0]):
                values = rollout["obs"][..., 0]
                for label, value in a2c_targets_mistakes(rollout, values, t(7.0, 8.0)):
                    if got[0].shape == value.shape and torch.allclose(got[0].detach(), value):
                        named = tr("\n  this is exactly what this mistake gives: ",
                                   "\n  你的值恰好是这个常见错误会得到的值：\n    ") + label
            shown = e.plain if named else str(e)
            raise Failed(tr("case: ", "例子：") + f"{what}\n  {shown}{named}") from None
