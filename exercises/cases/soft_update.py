"""The checks of exercises/soft_update.py, the soft target update: its worked cases, its named
mistakes and its runs."""

import importlib
from types import SimpleNamespace

import torch

from checking import tr, Failed, written_default
import runs

SCRIPT = "ddpg_walker"
FUNCTION = "soft_update"
ORDER = 9  # its row in docs/exercises.md's table
RUN = runs.DDPG
LOOP = runs.DDPG_LOOP
LEARN = runs.DDPG_LEARN


def loop_hint():
    return tr(
        "The target networks moved by your function; the critic's loss differs first "
        "because its target,\n  Q'(s', mu'(s')), uses those networks.",
        "目标网络是由你的函数移动的；评论员的损失最先不同，是因为它的目标 Q'(s', mu'(s'))"
        "\n  用的就是这两个目标网络。")


def worked_cases(fn):
    target, source = torch.nn.Linear(2, 1), torch.nn.Linear(2, 1)
    with torch.no_grad():
        for p, q in zip(target.parameters(), source.parameters()):
            p.fill_(0.0)
            q.fill_(1.0)
    before = [id(p) for p in target.parameters()]
    seen = []  # the target's numbers after each of the two updates
    for expected in (0.1, 0.19):
        try:
            fn(target, source, 0.1)
        except Exception:  # noqa: BLE001  after a wrong first update, the first is told
            if not seen or seen[0] == [0.1] * 3:
                raise
            break
        seen.append([round(float(x), 6) for p in target.parameters()
                     for x in p.detach().flatten()])
    # what each mistake gives after the first and the second update: named only where both
    # agree (a single number is shared: tau left off the source gives 1.0, as a hard copy does)
    known = {(0.9, 0.99): tr("tau and 1 - tau swapped (the target jumps most of the way)",
                             "tau 和 1 - tau 放反了（目标网络一下子移动了大部分距离）"),
             (0.0, 0.0): tr("the target did not move: assign in place (p_target.mul_/add_ or "
                            "copy_), and move the target, not the source\n    (p_target = ... "
                            "only rebinds a name; the network keeps its old tensor)",
                            "目标网络没有动：要原地赋值（p_target.mul_/add_ 或 copy_），并且动的是"
                            "目标网络，不是当前网络\n    （p_target = ... 只是让这个名字指向新张量，"
                            "网络里还是原来的那个）"),
             (1.0, 1.0): tr("a hard copy: tau = 1 (the target becomes the network at once)",
                            "硬拷贝：相当于 tau = 1（目标网络一下子变成了当前网络）"),
             (0.09, 0.171): tr(
                 "the two steps in the wrong order: add_(tau * theta) then mul_(1 - "
                 "tau) scales theta too;\n    mul_(1 - tau) first, then add_(tau * "
                 "theta)", "两步的顺序反了：先 add_(tau * theta) 再 mul_(1 - tau)，"
                 "把 theta 也缩小了；\n    应该先 mul_(1 - tau)，再 add_(tau * theta)"),
             (1.0, 1.9): tr("tau left off the network's term: theta' = (1 - tau) * theta' + "
                            "theta, where it is tau * theta",
                            "当前网络那一项漏了 tau：写成了 theta' = (1 - tau) * theta' + theta，"
                            "应该是 tau * theta")}
    tau = importlib.import_module(SCRIPT).Config.tau  # the script's, written as a number
    known[(tau, round(tau + (1 - tau) * tau, 6))] = written_default(
        [SimpleNamespace(where="tau", default=tau)])
    for expected, got in zip((0.1, 0.19), seen):
        if got != [expected] * 3:
            label = next((label for pair, label in known.items()
                          if seen == [[v] * 3 for v in pair]), None)
            raise Failed(tr(
                f"case: theta' = 0, theta = 1, tau = 0.1: two soft updates in a row, 0.1 after "
                f"the first, 0.19 after the second\n  target's weights and bias after soft_update: "
                f"expected {expected} each (theta' = tau * theta + (1 - tau) * theta'), got {got}",
                f"例子：theta' = 0，theta = 1，tau = 0.1：连续软更新两次，第一次后应为 0.1，第二次后应为 "
                f"0.19\n  软更新后目标网络的权重和偏置：应该都是 {expected}（theta' = tau * theta + "
                f"(1 - tau) * theta'），得到的是 {got}") + (tr(
                    "\n  this is exactly what this mistake gives: ",
                    "\n  你的值恰好是这个常见错误会得到的值：\n    ") + label if label else ""))
    if [id(p) for p in target.parameters()] != before:
        raise Failed(tr("the target's parameters were replaced, not updated in place",
                        "目标网络的参数被换成了新的张量，而不是原地更新"))
    if [float(x) for p in source.parameters() for x in p.detach().flatten()] != [1.0] * 3:
        raise Failed(tr("soft_update changed the source network; only the target moves",
                        "soft_update 改了当前网络；应该只动目标网络"))
