"""The checks of exercises/reward_to_go.py, REINFORCE's reward-to-go of one whole episode, G_T =
last_value: its worked cases, its named mistakes and its runs."""

import importlib
from types import SimpleNamespace

import numpy as np
import torch

from checking import only_if, tr, Failed, t, as_list, compare, written_default, named as named_line
import runs

SCRIPT = "reinforce_cartpole"
FUNCTION = "reward_to_go"
ORDER = 19  # its row in docs/exercises.md's table
OUTPUTS = ("G",)
RUN = runs.CARTPOLE
LOOP = runs.REINFORCE_LOOP
LEARN = runs.REINFORCE_LEARN


def loop_hint():
    return tr("Every episode's G_t comes from your function: the first update that "
              "differs is the first batch of\n  whole episodes where your G_t "
              "differ (the pole falls in these first episodes: no time limit yet).",
              "每个回合的 G_t 都来自你的函数：第一次不同的那次更新，就是你的 G_t 第一次"
              "不同的那批完整回合\n  （这几个回合里杆都倒了，还没有碰到时间截断）。")


def reward_to_go_cases():
    # (what, (rewards, gamma, last_value), G by hand); rewards as train() passes them, a tuple
    return [
        (tr("terminated after 3 steps (last_value = 0), gamma = 0.5: G_2 = 3, G_1 = 2 + 0.5 * 3, "
            "G_0 = 1 + 0.5 * 3.5", "3 步后终止（last_value = 0），gamma = 0.5：G_2 = 3，"
            "G_1 = 2 + 0.5 * 3，G_0 = 1 + 0.5 * 3.5"), ((1.0, 2.0, 3.0), 0.5, 0.0),
         (2.75, 3.5, 3.0)),
        (tr("the same rewards cut by a time limit, last_value = V(s_T) = 4: G_2 = 3 + 0.5 * 4",
            "同样的奖励，被时间截断，last_value = V(s_T) = 4：G_2 = 3 + 0.5 * 4"),
         ((1.0, 2.0, 3.0), 0.5, 4.0), (3.25, 4.5, 5.0)),
        (tr("terminated after 4 steps, gamma = 0.9: G_3 = 1, G_2 = -1 + 0.9, G_1 = 0 + 0.9 * G_2, "
            "G_0 = 2 + 0.9 * G_1", "4 步后终止，gamma = 0.9：G_3 = 1，G_2 = -1 + 0.9，"
            "G_1 = 0 + 0.9 * G_2，G_0 = 2 + 0.9 * G_1"), ((2.0, 0.0, -1.0, 1.0), 0.9, 0.0),
         (1.919, -0.09, -0.1, 1.0)),
        (tr("one step, cut by a time limit: G_0 = 5 + 0.5 * 2", "只有一步，被时间截断：G_0 = 5 + 0.5 * 2"),
         ((5.0,), 0.5, 2.0), (6.0,)),
        (tr("integer rewards (1, 1, 1), terminated, gamma = 0.5: the returns 1.75, 1.5, 1 are not "
            "integers", "整数奖励 (1, 1, 1)，终止，gamma = 0.5：回报 1.75、1.5、1 不是整数"),
         ((1, 1, 1), 0.5, 0.0), (1.75, 1.5, 1.0)),
    ]


def reward_to_go_mistakes(rewards, gamma, last_value):
    """(label, G as the mistake computes it) for each known mistake."""
    r, T = list(rewards), len(rewards)

    def back(step, start):  # G = step(r_t, G) from G_T = start, t = T - 1 down to 0
        out, G = [0.0] * T, start
        for i in reversed(range(T)):
            out[i] = G = step(r[i], G)
        return out
    right = back(lambda x, G: x + gamma * G, last_value)
    forward, G = [], 0.0
    for x in r:
        G = x + gamma * G
        forward.append(G)
    return [
        (tr("the whole episode's return G_0 for every step: each action is weighted by rewards "
            "that came before it too\n    (the reward-to-go G_t starts at t: an action cannot "
            "change what came before it)", "每一步都用了整个回合的回报 G_0：每个动作也被它之前的"
            "奖励加了权\n    （回报 G_t 从 t 开始算：动作改变不了它之前的奖励）"), [right[0]] * T),
        (tr("the sum run forward, G_t = r_t + gamma * G_{t-1}: the rewards before t counted, those "
            "after it left out;\n    go backwards, from t = T - 1 down to 0",
            "累加的方向反了，写成了 G_t = r_t + gamma * G_{t-1}：算进了 t 之前的奖励，漏了 t 之后的；"
            "\n    要从 t = T - 1 往回算到 0"), forward),
        (tr("a running sum from the episode's start, sum_{k <= t} gamma^k r_k: the rewards before "
            "t counted, those after it left out", "从回合开始累加，即 sum_{k <= t} gamma^k r_k："
            "算进了 t 之前的奖励，漏了 t 之后的"),
         [sum(gamma ** k * r[k] for k in range(i + 1)) for i in range(T)]),
        (tr("gamma^k counted from the episode's start, sum_{k >= t} gamma^k r_k: r_k's discount "
            "is gamma^(k - t),\n    by how far after t it came (G_t = r_t + gamma * G_{t+1} gives "
            "it)", "gamma 的指数从回合开始数，即 sum_{k >= t} gamma^k r_k：r_k 的折扣是 "
            "gamma^(k - t)，\n    按它离 t 多远算（G_t = r_t + gamma * G_{t+1} 自然就是这样）"),
         [sum(gamma ** k * r[k] for k in range(i, T)) + gamma ** T * last_value
          for i in range(T)]),
        (tr("the reward itself discounted, G_t = gamma * (r_t + G_{t+1}): r_t comes at t, "
            "undiscounted; only the future is, r_t + gamma * G_{t+1}",
            "奖励本身也打了折，写成了 G_t = gamma * (r_t + G_{t+1})：r_t 就在 t 时刻拿到，"
            "不打折；打折的只是未来，即 r_t + gamma * G_{t+1}"),
         back(lambda x, G: gamma * (x + G), last_value)),
        (tr("gamma left out: G_t = r_t + G_{t+1}", "漏了 gamma：写成了 G_t = r_t + G_{t+1}"),
         back(lambda x, G: x + G, last_value)),
        (tr("last_value ignored: the sum starts from 0, where a time limit cut the episode and "
            "G_T = last_value = V(s_T)\n    (the episode did not end: its tail is the critic's "
            "guess)", "忽略了 last_value：从 0 开始累加，可回合是被时间截断的，G_T = last_value = "
            "V(s_T)\n    （回合没有真正结束：剩下的部分用 V 估计）"),
         back(lambda x, G: x + gamma * G, 0.0)),
        (tr("last_value not discounted: G_{T-1} = r_{T-1} + last_value, where last_value is "
            "G_T, one step later:\n    r_{T-1} + gamma * last_value",
            "last_value 没有打折：写成了 G_{T-1} = r_{T-1} + last_value；last_value 是晚一步的 "
            "G_T，\n    应该是 r_{T-1} + gamma * last_value"),
         [g + gamma ** (T - 1 - i) * last_value
          for i, g in enumerate(back(lambda x, G: x + gamma * G, 0.0))]),
        (tr("last_value added, undiscounted, to the last step's G only: it is G_T, and reaches "
            "every G_t, discounted by gamma^(T - t)",
            "只在最后一步的 G 上加了 last_value，还没有打折：它是 G_T，每个 G_t 都要算上它，"
            "折扣是 gamma^(T - t)"),
         only_if(last_value != 0, [g + (last_value if i == T - 1 else 0.0)
                                   for i, g in enumerate(back(lambda x, G: x + gamma * G, 0.0))])),
        (tr("G started at gamma * last_value, so last_value is discounted twice: G_T = "
            "last_value, and the step G_{T-1} = r_{T-1} + gamma * G_T discounts it once",
            "G 从 gamma * last_value 开始，last_value 就打了两次折：G_T = last_value，"
            "G_{T-1} = r_{T-1} + gamma * G_T 已经给它打了一次折"),
         only_if(last_value != 0, back(lambda x, G: x + gamma * G, gamma * last_value))),
        (tr("G_t stored before r_t is added (returns[t] = G, then G = r_t + gamma * G): each step "
            "holds G_{t+1}, the return of the step after it",
            "先存 G 再加上 r_t（returns[t] = G，然后 G = r_t + gamma * G）：每一步存的都是 "
            "G_{t+1}，即后一步的回报"), right[1:] + [last_value]),
        (tr("the returns in reverse order: appended in the backward loop and not turned round "
            "(returns[T - 1 - t] holds G_t)", "回报的顺序反了：在往回的循环里 append，最后没有"
            "倒过来（returns[T - 1 - t] 里放的是 G_t）"), right[::-1])] + [
        (written_default([SimpleNamespace(where="gamma", default=default)]),
         back(lambda x, G: x + default * G, last_value))
        for default in [importlib.import_module(SCRIPT).Config.gamma] if default != gamma]


def worked_cases(fn):
    for what, (rewards, gamma, last_value), expected in reward_to_go_cases():
        got = fn(rewards, gamma, last_value)
        values = as_list(got)
        inputs = (tr("\n  input: ", "\n  输入：")
                  + f"rewards={rewards}, gamma={gamma}, last_value={last_value}")
        try:
            if values is not None and (not isinstance(got, np.ndarray) or got.dtype.kind != "f"):
                raise Failed(tr(f"expected a numpy array of floats (np.zeros(len(rewards)), as "
                                f"the script's own makes), got {type(got).__name__}"
                                + (f" of {got.dtype}" if isinstance(got, np.ndarray) else ""),
                                f"应该返回浮点数的 numpy 数组（像脚本自己那样用 np.zeros(len(rewards))），"
                                f"得到的是 {type(got).__name__}"
                                + (f"，类型是 {got.dtype}" if isinstance(got, np.ndarray) else ""))
                             + (named_line(tr("an integer array: it truncates every G_t stored in it "
                                         "(np.zeros_like of integer rewards is one)",
                                         "整数数组：存进去的每个 G_t 都被截断成整数（对整数奖励用 "
                                         "np.zeros_like 就得到这样的数组）"), "does")
                                if isinstance(got, np.ndarray) else ""))
            if values is None or np.ndim(values) != 1:
                raise Failed(tr(f"expected an array of {len(rewards)} numbers (one G_t per step), "
                                f"got {type(got).__name__} {got!r}",
                                f"应该返回 {len(rewards)} 个数的数组（每一步一个 G_t），得到的是 "
                                f"{type(got).__name__} {got!r}"))
            compare("G", torch.tensor(values, dtype=torch.float64), t(*expected))
        except Failed as e:
            named = [label for label, value in reward_to_go_mistakes(rewards, gamma, last_value)
                     if values is not None and np.shape(values) == np.shape(value)
                     and np.allclose(values, value, atol=1e-5)
                     and not np.allclose(value, expected, atol=1e-5)]  # a wrong value only
            shown = e.plain if named else str(e)
            raise Failed(tr("case: ", "例子：") + what + inputs + f"\n  {shown}" + (tr(
                "\n  this is exactly what this mistake gives: ",
                "\n  你的值恰好是这个常见错误会得到的值：\n    ") + named[0] if named else "")) from None
