"""The checks of exercises/ddpg_store_step.py, DDPG's store-and-advance step (terminated, not
terminated or truncated; s and s' apart; a new episode after one ends): its worked cases, its
named mistakes and its runs."""

import importlib

import numpy as np

from checking import tr, Failed, as_list
import runs

SCRIPT = "ddpg_walker"
FUNCTION = "store_and_advance"
ORDER = 15  # its row in docs/exercises.md's table
RUN = runs.DDPG
LOOP = runs.DDPG_LOOP
LEARN = runs.DDPG_LEARN


def loop_hint():
    return tr("Every minibatch is sampled from what your function stored, and every "
              "action is chosen in the obs\n  it returned: the first step that differs "
              "is where they first differ.",
              "每个小批量都是从你的函数存下的数据里抽的，每个动作都在它返回的观测上选："
              "\n  第一个不同的步就是它们开始不同的地方。")


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


def worked_cases(fn):
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
