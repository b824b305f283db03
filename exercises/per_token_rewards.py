"""Exercise: the per-token reward of RLHF's PPO stage: the KL penalty on every token of the
answer, the reward model's score on its last one (Ziegler et al. 2019, eq. 2; Stiennon et al.
2020, section 3.4).

From docs/ppo_to_rlhf.md: an episode is one answer, an action one token. The reward model
scores the whole answer once, r(x, y), paid at its last token (its first "."); every token
also pays -beta * (log pi_old - log pi_ref), so that the sum over the answer is
R(x, y) = r(x, y) - beta * log(pi_old(y|x) / pi_ref(y|x)): the policy is held near the
supervised model pi_ref. GAE then runs over the tokens, as over CartPole's steps.

    python exercises/check.py per_token_rewards
The reference answer: rlhf_addition.per_token_rewards (rlhf_addition.py).

练习：RLHF 中 PPO 阶段每个 token 的奖励：回答的每个 token 上都有 KL 惩罚，最后一个 token 上再加
奖励模型的打分（Ziegler 等 2019 的式 2；Stiennon 等 2020 的第 3.4 节）。一个回合就是一个回答，一个
动作就是一个 token。奖励模型给整个回答打一次分 r(x, y)，记在它的最后一个 token（第一个 "."）上；
每个 token 还要付 -β * (log π_old - log π_ref)，所以整个回答的奖励之和是
R(x, y) = r(x, y) - β * log(π_old(y|x) / π_ref(y|x))：策略被拉在监督模型 π_ref 附近。之后 GAE 在
token 上计算，和 CartPole 的时间步一样。参考答案：rlhf_addition.per_token_rewards。
"""

import torch


def per_token_rewards(score, logp_old, logp_ref, mask, beta):
    """(rewards, kl), both (B, L), for B sampled answers of L tokens: score (B,) is r(x, y) of
    each answer; logp_old and logp_ref (B, L) are the log-probabilities of its sampled tokens
    under pi_old (the policy that sampled them) and pi_ref (the frozen supervised model); mask
    (B, L) is 1 for the answer's own tokens, up to and including its first ".", 0 for the
    padding after it (answers end at different tokens).

        kl_t      = (logp_old_t - logp_ref_t) * mask_t     (log pi_old / pi_ref, k1)
        rewards_t = -beta * kl_t, plus score on the answer's last token (mask.sum(1) - 1)

    Padding gets 0 in both. E.g. beta 0.1, log ratios 0.5 then 0, score 2: rewards -0.05, 2.
    Do not change the inputs in place.

    对 B 个各有 L 个 token 的采样回答返回 (rewards, kl)，都是 (B, L)：score (B,) 是每个回答的
    r(x, y)；logp_old 和 logp_ref (B, L) 是采样出的 token 在 π_old（采样它们的策略）和 π_ref（冻结的
    监督模型）下的对数概率；mask (B, L) 在回答自己的 token 上为 1（到第一个 "." 为止，含 "."），之后的
    填充为 0（回答在不同的 token 结束）。kl_t = (logp_old_t - logp_ref_t) * mask_t；
    rewards_t = -β * kl_t，回答的最后一个 token（mask.sum(1) - 1）上再加 score。填充处两者都是 0。
    例如 β = 0.1，对数比值依次是 0.5、0，score 为 2：奖励是 -0.05、2。不要原地修改输入。
    """
    # Your code here (你的代码写在这里)
    raise NotImplementedError("not written yet")
