"""The checks of exercises/a2c_loss.py, A2C's actor, critic and entropy terms: its worked cases,
its named mistakes and its runs."""

from types import SimpleNamespace
import math

import torch
import torch.nn.functional as F
from torch.distributions import Categorical

from checking import only_if, tr, t, scalar, Fixed
import runs

SCRIPT = "actor_critic_cartpole"
FUNCTION = "a2c_loss"
ORDER = 6  # its row in docs/exercises.md's table
OUTPUTS = ("loss", "stats")
RUN = runs.CARTPOLE
LOOP = dict(runs.CARTPOLE_LOOP, total_timesteps=1600)
LEARN = runs.CARTPOLE_LEARN


def loop_hint():
    return runs.ON_REAL_DATA()


def a2c_case(v, ret, vf_coef, ent_coef):
    """pi = (0.5, 0.5): log pi(a|s) = -ln 2, entropy ln 2; A = (0.5, -1) as given."""
    model = Fixed(t([0.0, 0.0]).expand(2, 2), t(*v),
                  names=(tr("pi's logits", "π 的 logits"), tr("V(s)", "V(s)")))
    data = dict(obs=torch.zeros(2, 1), act=torch.tensor([0, 1]), adv=t(0.5, -1.0), ret=t(*ret))
    loss_pi, entropy = math.log(2) * (0.5 - 1.0) / 2, math.log(2)
    loss_v = 0.5 * sum((a - b) ** 2 for a, b in zip(v, ret)) / 2
    loss = loss_pi + vf_coef * loss_v - ent_coef * entropy
    return ((model, data, SimpleNamespace(vf_coef=vf_coef, ent_coef=ent_coef)),
            (scalar(loss), dict(loss_pi=loss_pi, loss_v=loss_v, entropy=entropy)))


def cases():
    # The advantages given, (0.5, -1), are not R - V: an answer that recomputes A from the
    # critic gets another loss_pi (and sends the actor's gradient into V). The coefficients
    # are not the script's (1.0 and 0.01), so that a default written as a number shows. The
    # second case's first error, V - R = -2.5, is past 1, where a Huber loss (smooth_l1_loss)
    # is no longer the halved square: 2.0 against 3.125.
    return [(tr("V = (1, 2), R = (2, 2.5); A = (0.5, -1) as given (not R - V = (1, 0.5)); "
                "vf_coef = 0.25, ent_coef = 0.1",
                "V = (1, 2)，R = (2, 2.5)；A = (0.5, -1)，照给的用（不是 R - V = (1, 0.5)）；"
                "vf_coef = 0.25，ent_coef = 0.1"), *a2c_case((1.0, 2.0), (2.0, 2.5), 0.25, 0.1)),
            (tr("V = (1, 2), R = (3.5, 2.5): an error of 2.5, past 1; vf_coef = 2, "
                "ent_coef = 0.05", "V = (1, 2)，R = (3.5, 2.5)：误差 2.5，大于 1；vf_coef = 2，"
                "ent_coef = 0.05"), *a2c_case((1.0, 2.0), (3.5, 2.5), 2.0, 0.05))]


def mistakes(model, data, cfg):
    logits, values = (x.detach() for x in model(data["obs"]))
    dist = Categorical(logits=logits)
    logp, ent = dist.log_prob(data["act"]), dist.entropy().mean()
    loss_pi, loss_v = -(logp * data["adv"]).mean(), 0.5 * ((values - data["ret"]) ** 2).mean()
    return [(tr("A recomputed as R - V from the critic, where data[\"adv\"] is given (a constant)",
                "用评论员重新算了 A = R - V，应该直接用给的 data[\"adv\"]（常数）"),
             -(logp * (data["ret"] - values)).mean() + cfg.vf_coef * loss_v - cfg.ent_coef * ent),
            (tr("the entropy bonus with the wrong sign (+ ent_coef * H; the bonus is subtracted "
                "from the loss)", "熵正则项的符号反了（损失里应该减去 ent_coef * H）"),
             loss_pi + cfg.vf_coef * loss_v + cfg.ent_coef * ent),
            (tr("the critic's loss not halved (0.5 * mean((V - R)^2))",
                "评论员的损失没有乘 0.5（应该是 0.5 * mean((V - R)^2)）"),
             loss_pi + cfg.vf_coef * 2 * loss_v - cfg.ent_coef * ent),
            (tr("a Huber loss (smooth_l1_loss) where the halved squared error is meant: past an "
                "error of 1 it grows as |V - R| - 0.5,\n    not as (V - R)^2 / 2 (the script's "
                "critic fits R with 0.5 * mean((V - R)^2))",
                "用了 Huber 损失（smooth_l1_loss），应该是平方误差的一半：误差大于 1 以后，它按 "
                "|V - R| - 0.5 增长，\n    不是 (V - R)^2 / 2（脚本的评论员用 0.5 * mean((V - R)^2) "
                "拟合 R）"),
             only_if(bool(((values - data["ret"]).abs() > 1).any()),  # else Huber is the same
                     loss_pi + cfg.vf_coef * F.smooth_l1_loss(values, data["ret"])
                     - cfg.ent_coef * ent)),
            (tr("loss_pi summed over the batch (.sum()) where it is the mean (.mean()): its "
                "weight against the critic's and the entropy's grows with the batch",
                "loss_pi 对批量求了和（.sum()），应该求均值（.mean()）：它相对评论员项和熵项的"
                "分量会随批量变大"),
             -(logp * data["adv"]).sum() + cfg.vf_coef * loss_v - cfg.ent_coef * ent),
            (tr("the entropy summed over the batch (.sum()) where it is the mean (.mean())",
                "熵对批量求了和（.sum()），应该求均值（.mean()）"),
             loss_pi + cfg.vf_coef * loss_v - cfg.ent_coef * dist.entropy().sum()),
            (tr("the actor's sign: +mean(log pi * A) (the loss is minus it)",
                "演员项的符号反了：损失应该是 -mean(log π * A)"),
             -loss_pi + cfg.vf_coef * loss_v - cfg.ent_coef * ent)]
