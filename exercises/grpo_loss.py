"""Exercise: GRPO's loss, per token, with the k3 KL estimate and the completion mask (Shao et
al. 2024, eq. 3 and eq. 4).

From docs/ppo_to_grpo.md: PPO's clipped ratio, now per token of each sampled completion, with
the completion's advantage A_i for every one of its tokens; a KL penalty toward the frozen
supervised model pi_ref, estimated per token by k3; the tokens after a completion's first "."
are padding, masked out. The lines after the blank are the script's own.

    python exercises/check.py grpo_loss
The reference answer: grpo_addition.grpo_loss (grpo_addition.py).

练习：GRPO 的损失，逐个 token 计算，用 k3 估计 KL，并用掩码去掉填充（Shao 等 2024，式 3、
式 4）。每个 token 用 PPO 的裁剪比值，优势是它所在回答的 A_i；KL 惩罚把策略拉向冻结的监督模型
pi_ref，每个 token 用 k3 估计；回答里第一个 "." 之后的 token 是填充，要用掩码去掉。空白后面的
代码和脚本里的一样。参考答案：grpo_addition.grpo_loss。
"""

import torch


def grpo_loss(logp, logp_old, logp_ref, adv, mask, cfg):
    """(loss, info) for B completions of L tokens: logp, logp_old, logp_ref are (B, L), the
    log-probabilities of each sampled token under pi (being trained), pi_old (that sampled
    it) and pi_ref (frozen); adv is (B,); mask (B, L) is 1 for a completion's own tokens.

        r_t   = exp(logp - logp_old)
        S_t   = min(r_t A_i, clip(r_t, 1 - eps, 1 + eps) A_i)           (eps = cfg.clip_coef)
        D_t   = pi_ref / pi - log(pi_ref / pi) - 1                      (k3, eq. 4)
        L_t   = (S_t - cfg.beta * D_t) * mask
        loss  = -mean over completions of (sum over t of L_t) / length_i

    length_i is completion i's number of tokens (mask.sum(1)) if cfg.length_norm, else L for
    every completion (Dr. GRPO). Name the per-token k3 `kl` and the ratio `ratio`: the lines
    after the blank log them.

    对 B 个各有 L 个 token 的回答返回 (loss, info)：logp、logp_old、logp_ref 都是 (B, L)，是每个
    采样出的 token 在 pi（正在训练）、pi_old（采样它的模型）和 pi_ref（冻结）下的对数概率；adv 是
    (B,)；mask 是 (B, L)，回答自己的 token 处为 1。公式见上，D_t 就是 k3。cfg.length_norm 为真时，
    length_i 是回答 i 的 token 数（mask.sum(1)），否则每个回答都用 L（Dr. GRPO）。逐 token 的 k3 要
    命名为 kl，比值命名为 ratio，空白后面的代码要记录它们。
    """
    # Your code here (你的代码写在这里): ratio, the clipped surrogate, kl (k3), then loss.
    raise NotImplementedError("not written yet")
    with torch.no_grad():  # what the log shows (the script's own lines)
        n = mask.sum()
        info = dict(kl=((kl * mask).sum() / n).item(),
                    clipfrac=((((ratio - 1).abs() > cfg.clip_coef).float() * mask).sum()
                              / n).item(),
                    ratio=ratio[mask > 0].detach())
    return loss, info
