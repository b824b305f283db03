"""Loop exercise: tutorial 002's PPO update, with its early stop (Schulman et al. 2017, as
Spinning Up's ppo.py runs it).

From ppo_reacher.py: after each rollout, up to train_pi_iters policy steps on the whole batch,
each preceded by a look at how far pi has moved from pi_old, approx_kl = E[log pi_old - log
pi]: once it exceeds kl_stop_factor * target_kl (tutorial 002: 1.5 x 0.01), the policy stops
for this batch, before that step. Then train_v_iters value steps, whatever the policy did.
The stop keeps the new policy near the one that collected the data, where the clipped
surrogate is a good guide. The functions it calls are the script's own (compute_loss_pi,
compute_loss_v, step).

    python exercises/check.py ppo_update
The reference answer: ppo_reacher.update (ppo_reacher.py).

循环练习：教程 002 的 PPO 更新和它的早停。每收集完一批数据，在整批数据上最多做 train_pi_iters 次
策略的梯度更新；每一次更新之前先看 π 离 π_old 有多远，即 approx_kl = E[log π_old - log π]：一旦它
超过 kl_stop_factor * target_kl（教程 002 是 1.5 x 0.01），这批数据上策略就不再更新（这一步不做）。
然后做 train_v_iters 次价值网络的更新，不管策略做了几步。早停让新策略留在采集数据的策略附近，在那里
裁剪代理目标才可靠。要调用的函数都是脚本自己的（compute_loss_pi、compute_loss_v、step）。
参考答案：ppo_reacher.update。
"""

from ppo_reacher import compute_loss_pi, compute_loss_v, step  # noqa: F401


def update(policy, value_net, pi_optimizer, vf_optimizer, data, cfg):
    """One PPO update on the batch `data` (obs, act, adv, logp: log pi_old, ret).

    compute_loss_pi(policy, data, cfg.clip_ratio) -> (loss_pi, pi_info), pi_info["kl"] the
    approx_kl of pi now; compute_loss_v(value_net, data) -> the value loss; step(optimizer,
    loss, net, cfg.max_grad_norm): one optimizer step. In this order:

        for i in range(cfg.train_pi_iters):
            loss_pi and approx_kl of pi now
            if cfg.target_kl is set and approx_kl > cfg.kl_stop_factor * cfg.target_kl:
                stop here: i policy steps were taken
            one policy step on loss_pi
        cfg.train_v_iters value steps

    Returns (pi_l_old, v_l_old, the entropy before the update, stop_iter): stop_iter is the
    number of policy steps taken (cfg.train_pi_iters where nothing stopped them).

    在一批数据上做一次 PPO 更新。compute_loss_pi 给出 (loss_pi, pi_info)，pi_info["kl"] 是当前 π 的
    approx_kl；compute_loss_v 给出价值损失；step 做一步优化。顺序见上：每次策略更新之前先检查
    approx_kl 是否超过 cfg.kl_stop_factor * cfg.target_kl（target_kl 为 None 时从不早停），超过就停，
    此时已经做了 i 步；然后做 cfg.train_v_iters 步价值更新。返回 (pi_l_old, v_l_old, 更新前的熵,
    stop_iter)，stop_iter 是实际做的策略更新步数（没有早停时就是 cfg.train_pi_iters）。
    """
    pi_l_old, pi_info_old = compute_loss_pi(policy, data, cfg.clip_ratio)
    pi_l_old, v_l_old = pi_l_old.item(), compute_loss_v(value_net, data).item()
    # Your code here (你的代码写在这里): the policy's steps with the early stop, stop_iter,
    # then the value steps.
    raise NotImplementedError("not written yet")
    return pi_l_old, v_l_old, pi_info_old["ent"], stop_iter
