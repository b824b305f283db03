"""The two tabular TD updates' checks, shared by cases/sarsa_update.py and
cases/q_learning_update.py: a small Q table, the worked steps and the named mistakes."""

import importlib

import numpy as np

from checking import tr, Failed, named as named_line


def tabular_table():
    """Q of three states, four actions. In s' = 1 the best action is 1 (-1.5), the next action
    taken is 2 (an exploring step, -20) and the action just taken, 0, is worth -3: a target
    that values s' any other way than the right one gives another number. Row 2 holds the
    table's largest value (2), for the case where s' = s (a step into a wall)."""
    return np.array([[-2.0, -4.0, 0.5, -1.0], [-3.0, -1.5, -20.0, -6.0], [2.0, -5.0, -8.0, -7.0]])


def tabular_cases(sarsa):
    """(what, (s, a, r, s_next, a_next, terminated, alpha, gamma)); r and the states as the env
    gives them (ints), terminated a Python bool."""
    row = tr("Q(s', .) = (-3, -1.5, -20, -6): the best action 1 (-1.5), ",
             "Q(s', .) = (-3, -1.5, -20, -6)：最好的动作是 1（-1.5），")
    nxt = tr("the next action a' = 2 (an exploring step, -20); ",
             "下一个动作 a' = 2（探索的一步，-20）；") if sarsa else ""
    return [
        (tr("s = 0, a = 0 (Q = -2), r = -1, s' = 1, not terminated; ", "s = 0，a = 0（Q = -2），"
            "r = -1，s' = 1，没有终止；") + row + nxt
         + tr("alpha = 0.25, gamma = 0.9", "alpha = 0.25，gamma = 0.9"),
         (0, 0, -1, 1, 2, False, 0.25, 0.9)),
        (tr("the same step, terminated (the goal): the target is r alone, whatever Q(s', .)",
            "同样的一步，但终止了（到达终点）：目标只有 r，不管 Q(s', .) 是多少"),
         (0, 0, -1, 1, 2, True, 0.25, 0.9)),
        (tr("a step into a wall, s' = s = 2, a = 3 (Q = -7)", "撞墙的一步，s' = s = 2，a = 3（Q = -7）")
         + (tr(", a' = 3 again", "，a' 还是 3") if sarsa else "")
         + tr(": Q(s', .) = (2, -5, -8, -7); alpha = 0.5, gamma = 1",
              "：Q(s', .) = (2, -5, -8, -7)；alpha = 0.5，gamma = 1"),
         (2, 3, -1, 2, 3, False, 0.5, 1.0)),
    ]


def tabular_by_hand(Q, s, a, r, s_next, a_next, terminated, alpha, gamma, sarsa, value=None,
               not_done=None, discount=None, step=None, sign=1.0):
    """(Q[s, a] after the update, the TD error) in plain Python, and the mistakes' versions:
    value, the value of s' used; not_done, the factor that cuts it; discount, gamma's place;
    step, alpha's; sign, delta's."""
    q = Q[s, a]
    value = (Q[s_next, a_next] if sarsa else Q[s_next].max()) if value is None else value
    not_done = (0.0 if terminated else 1.0) if not_done is None else not_done
    target = r + (gamma if discount is None else discount) * not_done * value
    delta = sign * (target - q)
    return q + (alpha if step is None else step) * delta, delta


def tabular_mistakes(Q, s, a, r, s_next, a_next, terminated, alpha, gamma, sarsa):
    """(label, (Q[s, a] after, the TD error returned)) of each known mistake."""
    case = (Q, s, a, r, s_next, a_next, terminated, alpha, gamma, sarsa)
    q_new, delta = tabular_by_hand(*case)
    target = delta + Q[s, a]
    if sarsa:
        values = [
            (tr("max_a' Q(s', a') where Sarsa takes the next action a' (that is Q-learning's "
                "target: Sarsa values s' by the action it will\n    really take there, "
                "exploration included)", "用了 max_a' Q(s', a')，Sarsa 要的是下一个动作 a'（那是 "
                "Q 学习的目标：Sarsa 按它在 s' 真的要做的动作估值，\n    探索的动作也算）"),
             Q[s_next].max()),
            (tr("Q(s', a), the action just taken, where Sarsa takes the next action a_next",
                "用了 Q(s', a)，即刚做过的那个动作，Sarsa 要的是下一个动作 a_next"), Q[s_next, a])]
    else:
        values = [
            (tr("Q(s', a), the action just taken valued at s', where Q-learning takes the best "
                "action there, max_a' Q(s', a')\n    (Q-learning has no next action: whatever "
                "the agent does next, the target takes the max)",
                "用了 Q(s', a)，即把刚做过的动作放到 s' 去估值；Q 学习要的是那里最好的动作 "
                "max_a' Q(s', a')\n    （Q 学习没有“下一个动作”：不管智能体接下来做什么，目标都取最大值）"),
             Q[s_next, a]),
            (tr("the mean over the actions of s', where Q-learning takes the max",
                "对 s' 的各个动作取了平均，Q 学习要取最大值"), Q[s_next].mean()),
            (tr("argmax (an action's index) where the max (its value) belongs: Q[s_next].max()",
                "用了 argmax（动作的编号），应该用 max（它的价值）：Q[s_next].max()"),
             float(np.argmax(Q[s_next]))),
            (tr("the max at s, not at s' (Q[s].max())", "在 s 处取的最大值，应该在 s' 处（写成了 Q[s].max()）"),
             Q[s].max()),
            (tr("the max over the whole table (Q.max()), not over s_next's row",
                "对整张表取了最大值（Q.max()），应该只在 s_next 这一行取"), Q.max())]
    found = [(label, tabular_by_hand(*case, value=v)) for label, v in values]
    found += [
        (tr("a bootstrap at a termination: after the goal there is no s' to value, the target "
            "is r alone ((1 - terminated))", "终止处还在自举：到达终点之后没有 s' 可估值，目标只有 r"
            "（要乘 (1 - terminated)）"), tabular_by_hand(*case, not_done=1.0)),
        (tr("~terminated on a Python bool: ~False is -1 and ~True is -2, not 1 and 0: use "
            "(1 - terminated) or (not terminated)", "对 Python 的布尔值用了 ~terminated：~False 是 "
            "-1，~True 是 -2，不是 1 和 0：要用 (1 - terminated) 或 (not terminated)"),
         tabular_by_hand(*case, not_done=-2.0 if terminated else -1.0)),
        (tr("gamma left out: r + Q(s', .) where the target is r + gamma * Q(s', .)",
            "漏了 gamma：写成了 r + Q(s', .)，目标是 r + gamma * Q(s', .)"),
         tabular_by_hand(*case, discount=1.0)),
        (tr("alpha left out: Q[s, a] = target, a full replacement, where Q moves a step alpha "
            "toward it (Q[s, a] += alpha * delta)", "漏了 alpha：Q[s, a] = 目标，整个换掉了；应该朝目标"
            "走 alpha 那么大的一步（Q[s, a] += alpha * delta）"), tabular_by_hand(*case, step=1.0)),
        (tr("the TD error's sign: delta = Q[s, a] - target, so Q moves away from the target "
            "(delta = target - Q[s, a])", "TD 误差的符号反了：写成了 delta = Q[s, a] - 目标，Q 就"
            "离目标越来越远（delta = 目标 - Q[s, a]）"), tabular_by_hand(*case, sign=-1.0)),
        (tr("the TD error returned with its sign flipped (Q[s, a] - target); the update itself "
            "is right", "返回的 TD 误差符号反了（Q[s, a] - 目标）；更新本身是对的"),
         (q_new, -delta)),
        (tr("the TD error computed after the update (target - the new Q[s, a], which is "
            "(1 - alpha) * delta): compute delta first,\n    then move Q[s, a]",
            "TD 误差是在更新之后算的（目标 - 新的 Q[s, a]，即 (1 - alpha) * delta）：先算 delta，"
            "\n    再更新 Q[s, a]"), (q_new, target - q_new)),
        (tr("the step alpha * delta returned where the TD error delta belongs",
            "返回的是这一步的大小 alpha * delta，应该返回 TD 误差 delta"), (q_new, alpha * delta))]
    config = importlib.import_module("q_learning_cliffwalking").Config()
    for name, given, default in (("alpha", alpha, config.alpha), ("gamma", gamma, config.gamma)):
        for number in sorted({default, 0.5, 0.1} if name == "alpha" else {default, 0.99, 0.9}):
            if number != given:
                found.append((written_as_number(name, number, default), tabular_by_hand(
                    *case, **{"step" if name == "alpha" else "discount": number})))
    return found


def written_as_number(name, number, default):
    """The label of `name` (alpha, gamma) written as the number `number`."""
    if number == default:
        return tr(f"{number!r}, the script's default, written as a number where {name} is "
                  f"meant: any other setting would be ignored",
                  f"把 {name} 写成了数字 {number!r}（脚本的默认值）：换成别的设置就不起作用了")
    return tr(f"{number!r} written as a number where {name} is meant (the script's default is "
              f"{default!r}): any other setting would be ignored",
              f"把 {name} 写成了数字 {number!r}（脚本的默认值是 {default!r}）：换成别的设置就不起作用了")


def check_td_control(fn, sarsa):
    for what, (s, a, r, s_next, a_next, terminated, alpha, gamma) in tabular_cases(sarsa):
        Q = tabular_table()
        before = Q.copy()
        args = (s, a, r, s_next) + ((a_next,) if sarsa else ()) + (terminated, alpha, gamma)
        got = fn(Q, *args)
        case = (before, s, a, r, s_next, a_next, terminated, alpha, gamma, sarsa)
        q_new, delta = tabular_by_hand(*case)
        try:
            td = float(got)
        except (TypeError, ValueError):
            td = None
        changed = [(int(i), int(j)) for i, j in zip(*np.nonzero(Q != before))]
        named = []
        try:
            if not isinstance(Q, np.ndarray) or Q.shape != before.shape:
                raise Failed(tr("the table Q was replaced: update its entry in place",
                                "Q 表被换掉了：要原地更新它的那一项"))
            others = [ij for ij in changed if ij != (s, a)]
            if others and any(i == s_next for i, _ in others):
                named = [tr("the entry of s' updated (Q[s_next, ...]) where Q[s, a] belongs: the "
                            "update moves the pair just left, (s, a)",
                            "更新的是 s' 的那一项（Q[s_next, ...]），应该是 Q[s, a]：要更新的是"
                            "刚离开的那一对 (s, a)")]
            if others and not named and sorted(others + [(s, a)]) == [
                    (s, j) for j in range(before.shape[1])]:
                named = [tr("the whole row Q[s] moved (Q[s] += alpha * delta) where only the "
                            "pair just taken, Q[s, a], does",
                            "整行 Q[s] 都动了（Q[s] += alpha * delta），只该更新刚做过的那一对 Q[s, a]")]
            if others:
                raise Failed(tr(f"entries other than Q[s, a] = Q[{s}, {a}] changed: {others} "
                                f"(only Q[s, a] moves)", f"除了 Q[s, a] = Q[{s}, {a}] 之外，"
                                f"还有别的项变了：{others}（只有 Q[s, a] 会变）"))
            if not changed and abs(q_new - before[s, a]) > 1e-9:
                raise Failed(tr("Q did not change", "Q 没有变") + named_line(tr(
                    "the update written into another table (Q = ..., Q.copy()), not the "
                    "caller's: update it in place (Q[s, a] += ...)",
                    "更新写进了另一张表（Q = ...、Q.copy()），不是调用者手里的那张：要原地更新"
                    "（Q[s, a] += ...）"), "does"))
            if abs(Q[s, a] - q_new) > 1e-6:
                same_q = [(label, d) for label, (q, d) in tabular_mistakes(*case)
                          if abs(Q[s, a] - q) < 1e-6]
                named = [label for label, d in same_q if td is None or abs(td - d) < 1e-6] or [
                    label for label, _ in same_q]
                raise Failed(tr(f"Q[{s}, {a}] after the update: expected {q_new:.6g}, got "
                                f"{Q[s, a]:.6g}", f"更新之后的 Q[{s}, {a}]：应该是 {q_new:.6g}，"
                                f"得到的是 {Q[s, a]:.6g}"))
            if td is None or abs(td - delta) > 1e-6:
                named = [label for label, (q, d) in tabular_mistakes(*case)
                         if td is not None and abs(q - q_new) < 1e-9 and abs(td - d) < 1e-6]
                shown = f"{td:.6g}" if td is not None else repr(got)
                raise Failed(tr(f"the TD error returned: expected {delta:.6g}, got {shown}",
                                f"返回的 TD 误差：应该是 {delta:.6g}，得到的是 {shown}") + (tr(
                    " (nothing returned: return delta, the TD error, as a float)",
                    "（没有返回值：要返回 TD 误差 delta，一个浮点数）") if got is None else ""))
        except Failed as e:
            raise Failed(tr("case: ", "例子：") + what + f"\n  {e.plain if named else e}" + (tr(
                "\n  this is exactly what this mistake gives: ",
                "\n  你的值恰好是这个常见错误会得到的值：\n    ") + named[0] if named else "")) from None
