"""The checks of exercises/actor_loss.py, DDPG's actor loss (the deterministic policy gradient):
its worked cases, its named mistakes and its runs."""

from checking import tr, t, scalar, Fixed
import runs

SCRIPT = "ddpg_walker"
FUNCTION = "compute_loss_actor"
ORDER = 8  # its row in docs/exercises.md's table
OUTPUTS = ("actor_loss",)
RUN = runs.DDPG
LOOP = runs.DDPG_LOOP
LEARN = runs.DDPG_LEARN


def loop_hint():
    return tr(
        "The actor descends your loss: actor_loss differs at the first step where its "
        "value differs; where only\n  its gradient differs, critic_loss differs "
        "first, a step later: its target Q'(s', mu'(s')) uses the\n  actor's target "
        "network, which follows the actor.",
        "演员沿你的损失下降：损失的数值不同时，actor_loss 在第一个不同的步就不同；只有梯度"
        "不同时，\n  critic_loss 会晚一步先不同：它的目标 Q'(s', mu'(s')) 用到目标演员，"
        "而目标演员跟着演员走。")


def cut():
    return tr("the action computed without a gradient: torch.no_grad() or "
              ".detach() around actor(obs) cuts the actor off\n    (Q(s, mu(s)) "
              "must reach mu(s): only the critic's parameters stay out of the step)",
              "动作是在不带梯度的情况下算的：actor(obs) 外面的 torch.no_grad() 或 "
              ".detach() 把演员切断了\n    （Q(s, mu(s)) 的梯度要传到 mu(s)；"
              "不更新的只是评论员的参数）")


def cases():
    actor = Fixed(t([2.0], [4.0]), names=(tr("mu(s)", "mu(s)"),))  # mu(s) for the two states
    critic = lambda obs, action: (obs * action).sum(-1)  # noqa: E731  Q(s, a) = s . a
    return [(tr("mu(s) = (2, 4) at s = (1, 2), Q(s, a) = s * a: Q(s, mu(s)) = (2, 8)",
                "s = (1, 2) 处 mu(s) = (2, 4)，Q(s, a) = s * a：Q(s, mu(s)) = (2, 8)"),
             (actor, critic, t([1.0], [2.0])), scalar(-5.0))]


def mistakes(actor, critic, obs):
    q = critic(obs, actor(obs).detach())
    return [(tr("+Q: the actor must ascend Q, so its loss is -Q", "+Q：演员要提高 Q，所以损失是 -Q"),
             q.mean()),
            (tr("a sum over the batch where the mean belongs", "对批量求了和，应该求均值"), -q.sum())]
