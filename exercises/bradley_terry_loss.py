"""Exercise: the reward model's loss, Bradley-Terry on preference pairs (Ouyang et al. 2022,
eq. 1; Christiano et al. 2017, section 2.2.3).

From docs/ppo_to_rlhf.md: the judge prefers y_w to y_l for the same prompt x; the reward
model says how likely that is through the gap of its two scores, P(y_w preferred) =
sigmoid(r(x, y_w) - r(x, y_l)), and is trained to make the judge's choices likely. Only the
gap is learned: r is free up to a constant per prompt.

    python exercises/check.py bradley_terry_loss
The reference answer: rlhf_addition.bradley_terry_loss (rlhf_addition.py).

练习：奖励模型的损失，偏好对上的 Bradley-Terry 损失（Ouyang 等 2022 的式 1；Christiano 等 2017
的第 2.2.3 节）。评审在同一个题目的两个回答里更喜欢 y_w 而不是 y_l；奖励模型用两个打分的差给出这件事
的概率，P(y_w 被选中) = sigmoid(r(x, y_w) - r(x, y_l))，训练目标是让评审的选择变得可能。只有分差是
学到的：对每个题目，r 可以整体加一个常数。参考答案：rlhf_addition.bradley_terry_loss。
"""

import torch


def bradley_terry_loss(r_chosen, r_rejected):
    """The loss, a number, of B pairs: r_chosen is (B,), the reward model's score r(x, y_w) of
    each pair's chosen answer, r_rejected (B,) its r(x, y_l) of the rejected one.

        loss = -mean over the pairs of log sigmoid(r(x, y_w) - r(x, y_l))

    torch.nn.functional.logsigmoid computes log sigmoid without overflow. E.g. gaps +1 and
    -2: (0.3133 + 2.1269) / 2 = 1.2201; no gap: log 2 = 0.6931.

    B 个偏好对的损失（一个数）：r_chosen 是 (B,)，每一对里被选中的回答的打分 r(x, y_w)；r_rejected
    是 (B,)，被拒绝的回答的 r(x, y_l)。loss = -（对所有偏好对取均值）log sigmoid(r(x, y_w) -
    r(x, y_l))。torch.nn.functional.logsigmoid 算 log sigmoid 不会溢出。例如分差 +1 和 -2：
    (0.3133 + 2.1269) / 2 = 1.2201；分差为 0：log 2 = 0.6931。
    """
    # Your code here (你的代码写在这里)
    raise NotImplementedError("not written yet")
