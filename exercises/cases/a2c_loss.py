"""The checks of exercises/a2c_loss.py, A2C's actor, critic and entropy terms: its worked cases,
its named mistakes and its runs."""

from types import SimpleNamespace
import math

import torch
from torch.distributions import Categorical

from checking import tr, t, scalar, Fixed
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


def cases():
    # pi = (0.5, 0.5): log pi(a|s) = -ln 2, entropy ln 2; V = (1, 2); R = (2, 2.5). The
    # advantages given, (0.5, -1), are not R - V = (1, 0.5): an answer that recomputes A
    # from the critic gets another loss_pi (and sends the actor's gradient into V).
    model = Fixed(t([0.0, 0.0]).expand(2, 2), t(1.0, 2.0),
                  names=(tr("pi's logits", "π 的 logits"), tr("V(s)", "V(s)")))
    data = dict(obs=torch.zeros(2, 1), act=torch.tensor([0, 1]), adv=t(0.5, -1.0),
                ret=t(2.0, 2.5))
    cfg = SimpleNamespace(vf_coef=0.5, ent_coef=0.01)
    loss_pi, loss_v, entropy = math.log(2) * (0.5 - 1.0) / 2, 0.5 * (1.0 + 0.25) / 2, math.log(2)
    loss = loss_pi + 0.5 * loss_v - 0.01 * entropy
    return [(tr("A = (0.5, -1) as given (not R - V = (1, 0.5)); c1 = 0.5, c2 = 0.01",
                "A = (0.5, -1)，照给的用（不是 R - V = (1, 0.5)）；c1 = 0.5，c2 = 0.01"),
             (model, data, cfg),
             (scalar(loss), dict(loss_pi=loss_pi, loss_v=loss_v, entropy=entropy)))]


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
            (tr("the actor's sign: +mean(log pi * A) (the loss is minus it)",
                "演员项的符号反了：损失应该是 -mean(log π * A)"),
             -loss_pi + cfg.vf_coef * loss_v - cfg.ent_coef * ent)]
