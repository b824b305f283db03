"""Exercise: GRPO's advantages, each completion against its own group (Shao et al. 2024,
section 4.1.2, outcome supervision).

From docs/ppo_to_grpo.md: GRPO has no critic. For each prompt it samples a group of G
completions and scores them; a completion's advantage is how much better its reward is than
its group's mean, in units of the group's spread.

    python exercises/check.py group_advantages
The reference answer: grpo_addition.group_advantages (grpo_addition.py).

练习：GRPO 的优势，每个回答只和自己那一组比（Shao 等 2024 的第 4.1.2 节，结果监督）。
GRPO 没有评论员：每道题采样一组 G 个回答并打分，一个回答的优势是它的奖励比组内均值高多少，
再除以组内的标准差。参考答案：grpo_addition.group_advantages。
"""

import torch


def group_advantages(rewards, G, scale):
    """The advantages A_i, shaped like `rewards` (B * G,): the rewards come prompt by prompt,
    G consecutive ones per prompt (repeat_interleave), so rewards.view(-1, G) has one group
    per row.

        A_i = (r_i - mean of its group) / (std of its group + 1e-4)    scale=True
        A_i =  r_i - mean of its group                                 scale=False (Dr. GRPO)

    std is torch's .std() (with Bessel's correction, n - 1); the 1e-4 keeps a group whose
    rewards are all equal at 0 (not nan). E.g. G = 8, two right (1) and six wrong (0): +1.62
    for the two, -0.54 for the others.

    优势 A_i，形状和 rewards 一样，是 (B * G,)。奖励按题目依次排列，每道题连续 G 个
    （repeat_interleave），所以 rewards.view(-1, G) 每行是一组。scale=True 时
    A_i = (r_i - 组内均值) / (组内标准差 + 1e-4)；scale=False（Dr. GRPO）时只减组内均值。标准差用
    torch 的 .std()（除以 n - 1）；加 1e-4，是为了组内奖励全都相同时结果为 0 而不是 nan。例如 G = 8，
    两个答对（1）、六个答错（0）：答对的两个是 +1.62，其余是 -0.54。
    """
    # Your code here (你的代码写在这里)
    raise NotImplementedError("not written yet")
