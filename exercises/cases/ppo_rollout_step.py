"""The checks of exercises/ppo_rollout_step.py, PPO's rollout step (the flags as the env gave them,
the reset step masked, obs advanced): its worked cases, its named mistakes and its runs."""

import importlib

import numpy as np

from checking import tr, Failed, as_list
import runs

SCRIPT = "ppo_cartpole"
FUNCTION = "store_and_advance"
ORDER = 16  # its row in docs/exercises.md's table
OUTPUTS = ("obs", "autoreset")
RUN = runs.CARTPOLE
LOOP = dict(runs.CARTPOLE_LOOP, total_timesteps=1280)
LEARN = runs.PPO_LEARN


def loop_hint():
    return tr("Every rollout is stored by your function, and every action is chosen in "
              "the obs it returned: the\n  first update that differs is where they "
              "differ on real steps (8 envs, autoreset steps).",
              "每批 rollout 都由你的函数存下，每个动作都在它返回的观测上选：第一次不同的"
              "更新，\n  就是它们在真实的步上（8 个环境、自动重置步）开始不同的地方。")


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


def worked_cases(fn):
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
