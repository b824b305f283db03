"""The checks of exercises/td_target.py, DDPG's TD target: its worked cases, its named mistakes and
its runs."""

from checking import tr, t
import runs

SCRIPT = "ddpg_walker"
FUNCTION = "td_target"
ORDER = 7  # its row in docs/exercises.md's table
OUTPUTS = ("y",)
RUN = runs.DDPG
LOOP = runs.DDPG_LOOP
LEARN = runs.DDPG_LEARN


def loop_hint():
    return tr(
        "The critic is trained toward your targets: critic_loss differs first, at the "
        "first step where your y\n  differs; actor_loss follows, through the critic.",
        "评论员朝你的目标训练：critic_loss 最先不同，就在你的 y 第一次不同的那一步；"
        "\n  actor_loss 随后也不同，因为它经过评论员。")


def cases():
    return [(tr("r = (1, 2, 3), terminated at the second, Q' = (10, 10, -4), gamma = 0.9",
                "r = (1, 2, 3)，第二个终止，Q' = (10, 10, -4)，gamma = 0.9"),
             (t(1.0, 2.0, 3.0), t(1.0, 0.0, 1.0), t(10.0, 10.0, -4.0), 0.9), t(10.0, 2.0, -0.6))]


def mistakes(reward, not_done, next_q, gamma):
    return [(tr("no not_done: a future added after a termination",
                "没有乘 not_done，终止之后还加上了未来的价值"),
             reward + gamma * next_q),
            (tr("(1 - not_done): not_done is already 1 - terminated",
                "写成了 (1 - not_done)：not_done 本身就是 1 - terminated"),
             reward + gamma * (1 - not_done) * next_q),
            (tr("gamma on the reward too, gamma * (r + not_done * Q'): r comes now, undiscounted; "
                "only the future is discounted",
                "奖励也乘了 gamma，写成了 gamma * (r + not_done * Q')：r 是现在拿到的，不打折；"
                "打折的只是未来"), gamma * (reward + not_done * next_q)),
            (tr("gamma left out", "漏了 gamma"), reward + not_done * next_q),
            (tr("(r + gamma * Q') * not_done: the reward itself zeroed at a termination; only "
                "the future is cut, r + gamma * not_done * Q'",
                "写成了 (r + gamma * Q') * not_done：终止时连奖励本身也被清零了；只该切掉未来，"
                "即 r + gamma * not_done * Q'"), (reward + gamma * next_q) * not_done)]
