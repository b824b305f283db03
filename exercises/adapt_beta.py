"""Exercise: PPO-penalty's adaptive beta (Schulman et al. 2017, section 4).

From tutorial 001 (PPO1): after each policy update, d is the mean KL(pi_old || pi); if pi
barely moved, penalize less; if it moved too far, penalize more.

    python exercises/check.py adapt_beta
The reference answer: ppo_kl_cartpole.adapt_beta (ppo_kl_cartpole.py).

练习：PPO-penalty 的自适应 beta（Schulman 等 2017 的第 4 节，对照教程 001 的 PPO1）。每次更新后，d 是平均 KL；
策略几乎没动就减小惩罚，动得太多就加大惩罚。参考答案：ppo_kl_cartpole.adapt_beta。
"""


def adapt_beta(beta, d, cfg):
    """The next update's beta, from this one's and the mean KL d:

        d < cfg.d_targ / cfg.kl_tolerance   ->  beta / cfg.beta_factor
        d > cfg.d_targ * cfg.kl_tolerance   ->  beta * cfg.beta_factor
        otherwise                           ->  beta         (the paper: 1.5 and 2)

    由这次的 beta 和平均 KL d 算出下一次更新的 beta：d < d_targ / kl_tolerance 时除以
    beta_factor；d > d_targ * kl_tolerance 时乘以 beta_factor；否则不变（论文取 1.5 和 2）。
    """
    # Your code here (你的代码写在这里)
    raise NotImplementedError("not written yet")
