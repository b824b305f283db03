"""The checks of exercises/per_token_rewards.py, the per-token reward of RLHF's PPO stage (the
KL penalty on every answer token, the reward model's score on the last): its worked cases, its
named mistakes and its runs."""

import torch

from checking import t, tr
import runs

SCRIPT = "rlhf_addition"
FUNCTION = "per_token_rewards"
ORDER = 24  # its row in docs/exercises.md's table
OUTPUTS = ("rewards", "kl")
RUN = runs.RLHF
LOOP = runs.RLHF_LOOP
LEARN = runs.RLHF_PPO_LEARN


def learned(result):
    runs.ppo_improves(result)


def loop_hint():
    return tr("PPO's advantages come from your rewards and its logged kl from your kl: the "
              "first PPO update's\n  loss differs where the score is misplaced; from the second "
              "on (pi no longer pi_ref), where the\n  KL term is.",
              "PPO 的优势来自你的奖励，记录的 kl 来自你的 kl：打分放错了地方，第一次 PPO 更新的 "
              "loss 就不同；\n  KL 项错了，从第二次更新起才不同（那时 π 已经不是 π_ref）。")


def by_hand(score, logp_old, logp_ref, mask, beta, score_at="last", kl_sign=1.0, masked=True,
            kl_at_end=False, score_everywhere=False):
    """(rewards, kl) token by token in plain Python (and the named mistakes' versions)."""
    B, L = mask.shape
    rewards, kl = [[0.0] * L for _ in range(B)], [[0.0] * L for _ in range(B)]
    for i in range(B):
        n = int(mask[i].sum())
        for j in range(L):
            m = 1.0 if not masked else float(mask[i, j])
            kl[i][j] = kl_sign * float(logp_old[i, j] - logp_ref[i, j]) * m
            if not kl_at_end:
                rewards[i][j] = -beta * kl[i][j]
            if score_everywhere and mask[i, j] > 0:
                rewards[i][j] += float(score[i])
        if kl_at_end:
            rewards[i][n - 1] = -beta * sum(kl[i])
        if not score_everywhere:
            rewards[i][dict(last=n - 1, end=L - 1, first=0)[score_at]] += float(score[i])
    return t(*rewards), t(*kl)


def cases():
    # Three answers of L = 4 tokens: 2 of their own then padding, all 4, and 1. The padding's
    # log ratios are not 0 (a KL left unmasked shows), and no two tokens' are alike.
    logp_old = t([-0.2, -1.0, -0.5, -2.0], [-0.1, -0.3, -1.2, -0.4], [-0.6, -0.1, -3.0, -0.7])
    logp_ref = t([-0.7, -0.8, -1.5, -0.5], [-0.4, -0.3, -0.2, -1.4], [-0.1, -0.9, -0.6, -0.2])
    mask = t([1.0, 1.0, 0.0, 0.0], [1.0, 1.0, 1.0, 1.0], [1.0, 0.0, 0.0, 0.0])
    score = t(1.5, -0.5, 2.0)
    return [(tr(f"3 answers of 2, 4 and 1 tokens (L = 4), scores (1.5, -0.5, 2), beta = {beta}",
                f"3 个回答，分别有 2、4、1 个 token（L = 4），打分 (1.5, -0.5, 2)，β = {beta}"),
             (score, logp_old, logp_ref, mask, beta),
             by_hand(score, logp_old, logp_ref, mask, beta)) for beta in (0.5, 0.05)]


def mistakes(score, logp_old, logp_ref, mask, beta):
    args = (score, logp_old, logp_ref, mask, beta)
    right_rewards, right_kl = by_hand(*args)
    return [(tr("the score on every token of the answer, where it is paid once, at its last",
                "每个 token 上都加了打分；打分只在回答的最后一个 token 上付一次"),
             by_hand(*args, score_everywhere=True)),
            (tr("the score on the last of the L positions, where the answer's own last token "
                "(its \".\", mask.sum(1) - 1) is meant", "打分加在了 L 个位置的最后一个上；应该加在"
                "回答自己的最后一个 token 上（它的 \".\"，mask.sum(1) - 1）"),
             by_hand(*args, score_at="end")),
            (tr("the score on the first token, where it belongs on the answer's last",
                "打分加在了第一个 token 上；应该加在回答的最后一个 token 上"),
             by_hand(*args, score_at="first")),
            (tr("the penalty's sign: + beta * kl, which pays the policy for moving away from "
                "pi_ref", "惩罚的符号反了：+ β * kl 等于奖励策略离开 π_ref"),
             (by_hand(*args, kl_sign=-1.0)[0], right_kl)),
            (tr("the KL the other way round: log pi_ref - log pi_old, where the penalty is "
                "log pi_old / pi_ref", "KL 的方向反了：写成了 log π_ref - log π_old，惩罚项是 "
                "log π_old / π_ref"), by_hand(*args, kl_sign=-1.0)),
            (tr("the KL summed into the last token only, where each token pays its own "
                "(the sum over the answer is the same, GAE's credit is not)",
                "把 KL 加总后只放在最后一个 token 上；应该每个 token 各付各的（整个回答的和一样，"
                "GAE 分给各个 token 的功劳不一样）"), by_hand(*args, kl_at_end=True)),
            (tr("the mask not applied: the padding after the answer's \".\" pays a KL",
                "没有乘掩码：回答的 \".\" 之后的填充也付了 KL"), by_hand(*args, masked=False)),
            (tr("beta left out: -kl where the penalty is -beta * kl", "漏了 β：写成了 -kl，"
                "惩罚是 -β * kl"), by_hand(score, logp_old, logp_ref, mask, 1.0)),
            (tr("kl returned without the mask (the rewards right): the padding's log ratios "
                "logged as KL", "返回的 kl 没有乘掩码（奖励是对的）：填充处的对数比值被记成了 KL"),
             (right_rewards, by_hand(*args, masked=False)[1]))]
