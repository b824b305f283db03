"""The checks of exercises/gae.py, generalized advantage estimation: its worked cases, its named
mistakes and its runs."""

import torch

from checking import flags, only_if, t, tr
import runs

SCRIPT = "ppo_cartpole"
FUNCTION = "gae"
OWNER = "common"  # where the reference answer lives
ORDER = 2  # its row in docs/exercises.md's table
OUTPUTS = ("advantages",)
RUN = runs.CARTPOLE
LOOP = dict(runs.CARTPOLE_LOOP, total_timesteps=1280)
LEARN = runs.PPO_LEARN


def loop_hint():
    return tr("PPO's advantages and value targets come from your GAE: the first "
              "update that\n  differs is where your GAE differs on real rollouts.",
              "PPO 的优势和价值目标来自你的 GAE：第一次不同的那次更新，就是你的 GAE 在"
              "\n  真实采集的数据上开始不同的地方。")


def cases():
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
        (tr("3 steps, env 0 terminated at t = 1: A_1 = delta_1 = 0 (A_2 is the next episode's), "
            "A_0 = delta_0 + 0.5 * A_1 = 1; env 1 on: A = 1.75, 1.5, 1",
            "3 步，环境 0 在 t = 1 处终止：A_1 = delta_1 = 0（A_2 属于下一个回合），"
            "A_0 = delta_0 + 0.5 * A_1 = 1；环境 1 一直没结束：A = 1.75、1.5、1"),
         (t([1.0, 1.0], [1.0, 1.0], [1.0, 1.0]), t([1.0, 1.0], [1.0, 1.0], [1.0, 1.0]),
          t([2.0, 2.0], [2.0, 2.0], [2.0, 2.0]), flags([False, False], [True, False],
                                                      [False, False]),
          flags([False, False], [False, False], [False, False]), 0.5, 1.0),
         t([1.0, 1.75], [0.0, 1.5], [1.0, 1.0])),
    ]


def gae_with(r, v, nv, term, trunc, gamma, lam, trunc_boots=True, cut_at_trunc=True,
             term_wins=True, next_v=True, term_resets=True, shifted=False, swapped=False):
    adv, last = torch.zeros_like(r), torch.zeros_like(r[0])
    if shifted:  # values[t + 1] read as V(s_{t+1}), next_values only at the end
        nv = torch.cat([v[1:], nv[-1:]])
    for t in reversed(range(len(r))):
        boots = ~term[t] if term_wins else (~term[t] | trunc[t])
        boots = boots & ~trunc[t] if not trunc_boots else boots
        keep = ~(term[t] | trunc[t]) if cut_at_trunc else ~term[t]
        keep = keep if term_resets else torch.ones_like(keep)
        discount = lam if swapped else gamma
        delta = r[t] + discount * (nv[t] if next_v else v[t]) * boots.float() - v[t]
        last = adv[t] = delta + (gamma if swapped else gamma * lam) * keep.float() * last
    return adv


def mistakes(r, v, nv, term, trunc, gamma, lam):
    cut, both = (trunc & ~term).any(), (trunc & term).any()  # what the case has
    carried = (~(term | trunc))[:-1].any()  # some A_{t+1} is added in
    right = gae_with(r, v, nv, term, trunc, gamma, lam)
    swapped = gae_with(r, v, nv, term, trunc, gamma, lam, swapped=True)
    return [(tr("the value targets A_t + V(s_t) returned, where gae returns the advantages A_t "
                "(the loop adds V(s_t) itself, for the targets)", "返回的是价值目标 A_t + V(s_t)，"
                "gae 返回的是优势 A_t（循环自己再加上 V(s_t) 得到目标）"),
             only_if(bool((v != 0).any()), right + v)),
            (tr("gamma and lambda swapped: lambda in delta (r + lambda * V(s') - V(s)) and gamma "
                "alone in the sum; delta discounts by gamma, the sum by gamma * lambda",
                "gamma 和 lambda 弄反了：delta 里用了 lambda（r + lambda * V(s') - V(s)），累加时只乘"
                "了 gamma；delta 用 gamma 打折，累加用 gamma * lambda"),
             only_if(not torch.allclose(swapped, right), swapped)),
            (tr("a time-limit truncation treated as a termination in delta (no bootstrap there)",
                "在 delta 里把时间截断当成了终止（那里没有自举）"),
             only_if(cut, gae_with(r, v, nv, term, trunc, gamma, lam, trunc_boots=False))),
            (tr("the sum runs on past a truncation (what follows belongs to the next episode)",
                "累加越过了时间截断（后面属于下一个回合）"),
             only_if(cut, gae_with(r, v, nv, term, trunc, gamma, lam, cut_at_trunc=False))),
            (tr("truncation wins where both flags are set: delta bootstraps at a termination",
                "两个标志都在时按时间截断算了：终止处的 delta 还在自举"),
             only_if(both, gae_with(r, v, nv, term, trunc, gamma, lam, term_wins=False))),
            (tr("lam left out of the sum (gamma * A_{t+1}, not gamma * lam * A_{t+1})",
                "累加时漏了 lam（写成了 gamma * A_{t+1}，应该是 gamma * lam * A_{t+1}）"),
             only_if(carried and lam != 1, gae_with(r, v, nv, term, trunc, gamma, 1.0))),
            (tr("gamma * lam left out of the sum (A_t = delta_t + A_{t+1}: tutorial 000's bug)",
                "累加时整个漏了 gamma * lam（写成了 A_t = delta_t + A_{t+1}：这正是教程 000 的错误，"
                "见 README.zh-CN.md 路线一第 3 步）"),
             only_if(carried, gae_with(r, v, nv, term, trunc, gamma, 1.0 / gamma))),
            (tr("V(s_t) where V(s_{t+1}) belongs in delta (values[t], not next_values[t])",
                "delta 里用了 V(s_t)，应该是 V(s_{t+1})（用了 values[t]，不是 next_values[t]）"),
             gae_with(r, v, nv, term, trunc, gamma, lam, next_v=False)),
            (tr("the sum is not cut where an episode ended", "回合结束处没有切断累加"),
             only_if(term[:-1].any(), gae_with(r, v, nv, term, trunc, gamma, lam,
                                               term_resets=False))),
            (tr("values[t + 1] where next_values[t] belongs: use next_values; they coincide "
                "with values[t + 1] in this project's\n    loops (NEXT_STEP autoreset stores the "
                "final obs at t + 1), not under every autoreset convention\n    (e.g. where the "
                "final obs is kept apart and the obs at t + 1 is the next episode's first)",
                "用了 values[t + 1]，应该是 next_values[t]：要用 next_values。在本项目的循环里"
                "两者相同\n    （NEXT_STEP 自动重置在 t + 1 处存的是最后的观测），但不是每种自动重置方式"
                "都这样\n    （例如最后的观测另外存放，t + 1 处是下一个回合的第一个观测）"),
             only_if(not torch.equal(nv[:-1], v[1:]),
                     gae_with(r, v, nv, term, trunc, gamma, lam, shifted=True)))]
