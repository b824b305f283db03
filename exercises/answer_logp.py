"""Exercise: log pi(y | x) of whole answers, as DPO needs them: the sum of the log-probabilities
of the answer's own tokens, the prompt's and the padding's left out (Rafailov et al. 2023,
section 4: pi(y|x) is the product over the answer's tokens).

From docs/ppo_to_rlhf.md: a row of `seqs` is a prompt of P tokens ("47+38=") and an answer of
L tokens drawn after it; the answer ends at its first ".", and the tokens after that are
padding. The model's logits at position t predict token t + 1, so token t's log-probability is
read from position t - 1 (grpo_addition.token_logp does that for positions P..: the prompt's
own tokens are never scored). The answer's log pi is the sum of its tokens' up to and
including its ".": grpo_addition.completion_mask marks them.

    python exercises/check.py answer_logp
The reference answer: rlhf_addition.answer_logp (rlhf_addition.py).

练习：整个回答的 log π(y | x)，DPO 要用它：回答自己每个 token 的对数概率之和，题目的 token 和填充都
不算（Rafailov 等 2023 的第 4 节：π(y|x) 是回答各个 token 的概率之积）。seqs 的每一行是 P 个 token 的
题目（"47+38="）加上在它后面采样出的 L 个 token 的回答；回答在第一个 "." 结束，之后的 token 是填充。
模型在位置 t 的 logits 预测第 t + 1 个 token，所以第 t 个 token 的对数概率要从位置 t - 1 读
（grpo_addition.token_logp 对位置 P 以后的 token 就是这样做的：题目自己的 token 从不打分）。回答的
log π 是它到第一个 "."（含）为止各个 token 的对数概率之和：grpo_addition.completion_mask 标出它们。
参考答案：rlhf_addition.answer_logp。
"""

import torch

from grpo_addition import completion_mask, token_logp


def answer_logp(model, seqs, P):
    """log pi(y|x) of each row of seqs (B, P + L) (token ids: the prompt's P, then the
    answer's L), (B,): model(ids) maps (B, T) ids to (B, T, vocab) logits of the next token.

        log pi(y|x) = sum over the answer's tokens t (up to its first ".") of
                      log softmax(model(seqs)[:, t - 1])[seqs[:, t]]

    E.g. an answer "8.." (L = 3) counts its first two tokens, "8" and "."; "08." all three.

    seqs (B, P + L) 每一行（token 编号：先是题目的 P 个，再是回答的 L 个）的 log π(y|x)，(B,)：
    model(ids) 把 (B, T) 的编号变成 (B, T, vocab)、预测下一个 token 的 logits。公式见上：对回答的
    token t（到第一个 "." 为止）求 log softmax(model(seqs)[:, t - 1])[seqs[:, t]] 的和。例如回答
    "8.."（L = 3）算前两个 token，"8" 和 "."；"08." 三个都算。
    """
    # Your code here (你的代码写在这里)
    raise NotImplementedError("not written yet")
