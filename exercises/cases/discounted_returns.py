"""The checks of exercises/discounted_returns.py, the reward-to-go, bootstrapped where the rollout
is cut (A2C's n-step targets): its worked cases, its named mistakes and its runs."""

import torch

from checking import flags, only_if, t, tr
import runs

SCRIPT = "actor_critic_cartpole"
FUNCTION = "discounted_returns"
OWNER = "common"  # where the reference answer lives
ORDER = 1  # its row in docs/exercises.md's table
OUTPUTS = ("returns",)
RUN = runs.CARTPOLE
LOOP = dict(runs.CARTPOLE_LOOP, total_timesteps=1600)
LEARN = runs.CARTPOLE_LEARN


def loop_hint():
    return tr("A2C's critic targets R_t come from your returns: the first update "
              "that differs is\n  where your returns differ on real rollouts "
              "(several envs, autoreset steps).",
              "A2C 评论员的目标 R_t 来自你的回报：第一次不同的那次更新，就是你的回报在"
              "\n  真实采集的数据上（多个环境、自动重置步）开始不同的地方。")


def cases():
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


def returns_with(r, nv, term, trunc, gamma, cut=True, trunc_boots=True, term_wins=True,
                 term_resets=True, shift=0, late=False):
    out, future = torch.zeros_like(r), (nv[-1] if cut else torch.zeros_like(r[0]))
    zero = torch.zeros_like(r[0])
    for t in reversed(range(len(r))):
        boot = (nv[t - shift] if trunc_boots else zero)
        ended = term[t] if term_resets else torch.zeros_like(term[t])
        if late:  # the flag of step t + 1 read at t
            ended = term[t + 1] if t + 1 < len(r) else torch.zeros_like(term[t])
        if term_wins:
            future = torch.where(ended, zero, torch.where(trunc[t], boot, future))
        else:
            future = torch.where(trunc[t], boot, torch.where(ended, zero, future))
        out[t] = future = r[t] + gamma * future
    return out


def mistakes(r, nv, term, trunc, gamma):
    cut, both = (trunc & ~term).any(), (trunc & term).any()  # what the case has
    return [(tr("no bootstrap at the rollout's end (after step T - 1 the future is V(s_T), not 0)",
                "这批数据的末尾没有自举（第 T - 1 步之后的未来是 V(s_T)，不是 0）"),
             returns_with(r, nv, term, trunc, gamma, cut=False)),
            (tr("a time-limit truncation treated as a termination (no bootstrap there)",
                "把时间截断当成了终止（那里没有自举）"),
             only_if(cut, returns_with(r, nv, term, trunc, gamma, trunc_boots=False))),
            (tr("truncation ignored: the sum runs on past a truncation into the next episode "
                "(there the future is V(final obs) = next_values[t])",
                "忽略了时间截断：累加越过了时间截断，进入了下一个回合（那里的未来是 "
                "V(最后的观测) = next_values[t]）"),
             only_if(cut, returns_with(r, nv, term, torch.zeros_like(trunc), gamma))),
            (tr("truncation wins where both flags are set (termination must win)",
                "两个标志都在时按时间截断算了（应该按终止算）"),
             only_if(both, returns_with(r, nv, term, trunc, gamma, term_wins=False))),
            (tr("at a truncation, the value of the step before, next_values[t - 1], where "
                "V(final obs) is next_values[t]", "时间截断处用了前一步的 next_values[t - 1]，"
                "V(最后的观测) 是 next_values[t]"),
             only_if(cut, returns_with(r, nv, term, trunc, gamma, shift=1))),
            (tr("the future is not reset where an episode terminated (the next episode's "
                "rewards leak in)", "回合终止处没有把未来清零（下一个回合的奖励漏了进来）"),
             only_if(term[:-1].any(), returns_with(r, nv, term, trunc, gamma,
                                                   term_resets=False))),
            (tr("terminated[t + 1] read at step t, where step t's own flag belongs: the future "
                "is cut a step off (the terminal step's return runs into the next episode)",
                "在第 t 步读了 terminated[t + 1]，应该读第 t 步自己的标志：未来在错的一步被清零"
                "（终止那一步的回报跑进了下一个回合）"),
             only_if(term.any(), returns_with(r, nv, term, trunc, gamma, late=True)))]
