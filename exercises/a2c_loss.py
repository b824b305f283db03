"""Exercise: A2C's loss (Mnih et al. 2016, Algorithm S3 and section 4).

From tutorial 004: the actor ascends log pi(a|s) * A (A a constant: the critic's estimate
only weighs the step), the critic fits its targets R, and an entropy bonus keeps exploring.

    python exercises/check.py a2c_loss
The reference answer: actor_critic_cartpole.a2c_loss (actor_critic_cartpole.py).

练习：A2C 的损失（Mnih 等 2016 的算法 S3 和第 4 节，对照教程 004）。演员提高
log pi(a|s) * A（A 是常数），评论员拟合目标 R，熵正则项鼓励探索。参考答案：
actor_critic_cartpole.a2c_loss。
"""

from torch.distributions import Categorical


def a2c_loss(model, data, cfg):
    """(loss, stats) on a batch: model(obs) gives (logits, V); data["obs"], ["act"], ["adv"]
    (the advantages A_t, already computed) and ["ret"] (the critic's targets R_t).

        loss_pi = -mean(log pi(a_t|s_t) * A_t)
        loss_v  = 0.5 * mean((V(s_t) - R_t)^2)
        entropy = mean of H(pi(.|s_t))
        loss    = loss_pi + cfg.vf_coef * loss_v - cfg.ent_coef * entropy

    stats: loss_pi, loss_v and entropy as numbers (.item()), as the script logs them.

    在一批数据上返回 (loss, stats)：model(obs) 给出 (logits, V)；data["obs"]、["act"]、["adv"]
    （优势 A_t，已经算好）和 ["ret"]（评论员的目标 R_t）。四行公式见上；stats 里的 loss_pi、loss_v
    和 entropy 都是数（.item()），和脚本记的一样。
    """
    obs, act, adv, ret = data["obs"], data["act"], data["adv"], data["ret"]
    logits, values = model(obs)
    dist = Categorical(logits=logits)  # pi(.|s)
    # Your code here (你的代码写在这里)
    raise NotImplementedError("not written yet")
    explained = 1 - (ret - values).var() / ret.var().clamp_min(1e-8)  # the script's own lines
    return loss, dict(loss_pi=loss_pi.item(), loss_v=loss_v.item(), entropy=entropy.item(),
                      explained_var=explained.item(), values=values.detach(), ret=ret)
