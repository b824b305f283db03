"""Exercise: PPO's clipped surrogate loss (Schulman et al. 2017, eq. 7).

From tutorial 001 (PPO2's clip) and tutorial 002 (compute_loss_pi): the ratio
r_t = pi(a|s) / pi_old(a|s) reweights pi_old's samples; min(r A, clip(r, 1 - eps, 1 + eps) A)
stops rewarding a sample once its ratio has left the band on its advantage's side. The loss
is minus its mean. The lines around the blank are the script's own.

    python exercises/check.py clipped_surrogate
The reference answer: ppo_cartpole.compute_loss_pi (ppo_cartpole.py).

练习：PPO 的裁剪代理目标函数（Schulman 等 2017 的式 7）。对照教程 001 的 PPO2 和教程 002 的
compute_loss_pi。比值 r_t = pi(a|s) / pi_old(a|s) 给 pi_old 采到的样本重新加权；
min(r A, clip(r, 1 - eps, 1 + eps) A) 的作用是：一个样本的比值朝它的优势希望的方向越出区间以后，
就不再奖励它。损失是它的均值取负。空白前后的代码和脚本里的一样。参考答案：ppo_cartpole.compute_loss_pi。
"""

import torch
from torch.distributions import Categorical


def compute_loss_pi(policy, data, clip_coef):
    """(loss_pi, entropy, info) on a batch: data["obs"], ["act"], ["adv"] and ["logp"], the
    log pi_old(a|s) of the taken actions, each with one row per sample.

        r_t    = exp(log pi(a_t|s_t) - log pi_old(a_t|s_t))
        L_CLIP = mean over t of min(r_t * A_t, clip(r_t, 1 - eps, 1 + eps) * A_t)
        loss_pi = -L_CLIP     (eps = clip_coef)

    在一批数据上返回 (loss_pi, entropy, info)：data["obs"]、["act"]、["adv"] 和 ["logp"]（所选动作
    的 log pi_old(a|s)），每个样本一行。公式见上：r_t 是比值，L_CLIP 是裁剪代理目标函数在这批数据上的均值，
    loss_pi = -L_CLIP（eps 就是 clip_coef）。
    """
    obs, act, adv, logp_old = data["obs"], data["act"], data["adv"], data["logp"]
    dist = Categorical(logits=policy(obs))  # pi(.|s)
    logp = dist.log_prob(act)  # log pi(a|s) of the taken actions, (B,)
    # Your code here (你的代码写在这里): the ratio, then loss_pi.
    raise NotImplementedError("not written yet")
    with torch.no_grad():  # what the log shows: how far pi moved (the script's own lines)
        info = dict(approx_kl=((ratio - 1) - (logp - logp_old)).mean(),
                    clipfrac=((ratio - 1).abs() > clip_coef).float().mean(), ratio=ratio.detach())
    return loss_pi, dist.entropy().mean(), info
