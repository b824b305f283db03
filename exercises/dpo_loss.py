"""Exercise: DPO's loss (Rafailov et al. 2023, eq. 7): Bradley-Terry with beta log(pi / pi_ref)
of the whole answer as the reward.

From docs/ppo_to_rlhf.md: DPO trains the policy on the preference pairs directly, with no
reward model and no sampling. Its reward of an answer is implicit: beta times how much more
likely the policy makes the answer than the frozen supervised model pi_ref does. The loss is
the reward model's loss with that reward in the place of r. The log-probabilities come summed
over each answer's own tokens (answer_logp, exercise 25).

    python exercises/check.py dpo_loss
The reference answer: rlhf_addition.dpo_loss (rlhf_addition.py).

练习：DPO 的损失（Rafailov 等 2023 的式 7）：把整个回答的 β log(π / π_ref) 当作奖励的
Bradley-Terry 损失。DPO 不要奖励模型，也不采样，直接在偏好对上训练策略。它给回答的奖励是隐式奖励：
β 乘以策略让这个回答比冻结的监督模型 π_ref 更可能多少。损失就是奖励模型的损失，只是 r 换成了这个
奖励。对数概率已经在每个回答自己的 token 上求了和（answer_logp，练习 25）。
参考答案：rlhf_addition.dpo_loss。
"""

import torch


def dpo_loss(logp_w, logp_l, ref_w, ref_l, beta):
    """The loss, a number, of B pairs: logp_w (B,) is log pi(y_w|x) of each pair's chosen
    answer under the policy being trained, logp_l (B,) log pi(y_l|x) of its rejected one;
    ref_w and ref_l (B,) the same under pi_ref (constants); beta is DPO's beta (cfg.dpo_beta).

        loss = -mean over the pairs of log sigmoid(beta * ((logp_w - ref_w) - (logp_l - ref_l)))

    E.g. log pi / pi_ref = +1 for the chosen answer, -1 for the rejected one, beta 0.5:
    -log sigmoid(1) = 0.3133; pi = pi_ref: log 2 = 0.6931, whatever beta.

    B 个偏好对的损失（一个数）：logp_w (B,) 是每一对里被选中的回答在正在训练的策略下的
    log π(y_w|x)，logp_l (B,) 是被拒绝的回答的 log π(y_l|x)；ref_w、ref_l (B,) 是它们在 π_ref 下的
    对数概率（常数）；beta 是 DPO 的 β（cfg.dpo_beta）。公式见上。例如被选中的回答 log π / π_ref = +1，
    被拒绝的 -1，β = 0.5：-log sigmoid(1) = 0.3133；π = π_ref 时不论 β 是多少都是 log 2 = 0.6931。
    """
    # Your code here (你的代码写在这里)
    raise NotImplementedError("not written yet")
