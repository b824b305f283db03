"""The checks of exercises/group_advantages.py, GRPO's advantages, each completion against its
group: its worked cases, its named mistakes and its runs."""

import math

from checking import only_if, t, tr
import runs

SCRIPT = "grpo_addition"
FUNCTION = "group_advantages"
ORDER = 11  # its row in docs/exercises.md's table
CONFIG_NAMES = dict(G="group_size", scale="scale_rewards")  # the Config fields they are
OUTPUTS = ("adv",)
RUN = runs.GRPO
LOOP = runs.GRPO_LOOP
LEARN = runs.GRPO_LEARN


def loop_hint():
    return tr("Every update's advantages come from your function.", "每次更新的优势都来自你的函数。")


def cases():
    # Two groups of G = 4: (1, 0, 0, 0): mean 0.25, std 0.5 (n - 1); (1, 1, 0, 1): mean 0.75,
    # std 0.5. A flat group (1, 1, 1, 1): 0, not nan.
    r = t(1.0, 0.0, 0.0, 0.0, 1.0, 1.0, 0.0, 1.0)
    s = 0.5 + 1e-4
    return [
        (tr("G = 4, groups (1, 0, 0, 0) and (1, 1, 0, 1): means 0.25, 0.75, stds 0.5 (n - 1)",
            "G = 4，两组 (1, 0, 0, 0) 和 (1, 1, 0, 1)：均值 0.25、0.75，标准差 0.5（n - 1）"),
         (r, 4, True), t(0.75 / s, -0.25 / s, -0.25 / s, -0.25 / s,
                         0.25 / s, 0.25 / s, -0.75 / s, 0.25 / s)),
        (tr("scale = False (Dr. GRPO): r - mean of the group only",
            "scale = False（Dr. GRPO）：只减去组内均值"),
         (r, 4, False), t(0.75, -0.25, -0.25, -0.25, 0.25, 0.25, -0.75, 0.25)),
        (tr("a flat group (1, 1, 1, 1) beside (1, 0, 0, 0): 0 for the flat one, not nan",
            "全相同的一组 (1, 1, 1, 1) 和 (1, 0, 0, 0)：全相同的那组是 0，不是 nan"),
         (t(1.0, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0), 4, True),
         t(0.0, 0.0, 0.0, 0.0, 0.75 / s, -0.25 / s, -0.25 / s, -0.25 / s)),
    ]


def mistakes(rewards, G, scale):
    def adv(view=lambda r: r.view(-1, G), unbiased=True, eps=1e-4, whole=False, floor=0.0):
        r = rewards.view(1, -1) if whole else view(rewards)
        a = r - r.mean(1, keepdim=True)
        if scale:
            a = a / (r.std(1, keepdim=True, unbiased=unbiased).clamp_min(floor) + eps)
        return a.reshape(-1)
    flat = bool((rewards.view(-1, G).std(1) == 0).any())  # 0 / anything small is 0 there
    return [(tr("the std without Bessel's correction (n, not n - 1; torch's .std() is n - 1)",
                "标准差没有用贝塞尔校正（除以 n，不是 n - 1；torch 的 .std() 除以 n - 1）"),
             only_if(scale, adv(unbiased=False))),
            (tr("the mean and std over the whole batch, not each prompt's group",
                "均值和标准差是对整个批量算的，不是对每道题的那一组"), adv(whole=True)),
            (tr("the groups read down the columns (view(G, -1)): a group is G consecutive rewards",
                "分组分错了（view(G, -1)）：一组是连续的 G 个奖励"),
             (lambda r: (r - r.mean(0, keepdim=True)) / (
                 r.std(0, keepdim=True) + 1e-4 if scale else 1))(rewards.view(G, -1)).reshape(-1)),
            (tr("the std over axis 0 (r.std(0), across the groups) where each group's is over "
                "axis 1 (r.std(1)), like its mean",
                "标准差是沿第 0 维算的（r.std(0)，跨组），每组的标准差要沿第 1 维算（r.std(1)），"
                "和均值一样"),
             only_if(scale and rewards.numel() > G, (lambda r: (r - r.mean(1, keepdim=True)) / (
                 r.std(0, keepdim=True) + 1e-4))(rewards.view(-1, G)).reshape(-1))),
            (tr("the 1e-4 left out of the denominator", "分母里漏了 1e-4"),
             only_if(scale, adv(eps=0.0))),
            (tr("the 1e-4 as a floor (std.clamp_min(1e-4)) where it is added (std + 1e-4)",
                "把 1e-4 当成了下限（std.clamp_min(1e-4)），应该是加上去（std + 1e-4）"),
             only_if(scale and not flat, adv(eps=0.0, floor=1e-4))),
            (tr("1e-8 added where this project adds 1e-4 (std + 1e-4)",
                "加的是 1e-8，本项目加的是 1e-4（std + 1e-4）"),
             only_if(scale and not flat, adv(eps=1e-8))),
            (tr("scale ignored: divided by the std where scale = False asks for r - mean only",
                "忽略了 scale：scale = False 时只减均值，不除以标准差"),
             only_if(not scale, (lambda r: ((r - r.mean(1, keepdim=True)) / (
                 r.std(1, keepdim=True) + 1e-4)))(rewards.view(-1, G)).reshape(-1)))]


def group_eps_mistake(fn):
    """Which denominator `fn` uses, told apart on a group whose std (5e-6) is far below 1e-4:
    the last advantage is 7.5e-6 / (5e-6 + 1e-4) = 0.0714 right, 0.075 clamped at 1e-4, 1.497
    with 1e-8 added, 1.5 with nothing."""
    try:
        a = float(fn(t(0.0, 0.0, 0.0, 1e-5), 4, True)[3])
    except Exception:  # noqa: BLE001  the first case's message stands alone
        return None
    return (2 if abs(a - 0.075) < 1e-3 else 3 if abs(a - 1.497) < 2e-3
            else 1 if abs(a - 1.5) < 1e-3 or math.isnan(a) else None)


def narrow_mistakes(mistakes, fn):
    """Three denominators give one value in the worked cases: keep the one `fn` uses, told
    apart by group_eps_mistake (or only the first, where it cannot tell)."""
    pick = group_eps_mistake(fn)
    eps = [m for m in mistakes if "1e-" in m[0]]
    if pick is not None:
        return [m for m in mistakes if m not in eps] + [eps[pick - 1]]
    return [m for m in mistakes if m not in eps[1:]]


def named_error(e):
    """The mistake an error of the answer's shows, or ''."""
    if "must match the size" not in str(e):
        return ""
    return tr("\n  this is exactly what this mistake raises: mean/std without keepdim=True: "
              "(B/G,) cannot broadcast against (B/G, G)",
              "\n  这正是这个常见错误会引发的：\n    mean/std 没有写 keepdim=True：形状 (B/G,) "
              "不能和 (B/G, G) 广播")
