"""The checks of exercises/answer_logp.py, log pi(y|x) of whole answers summed over their own
tokens (DPO's): its worked cases, its named mistakes and its runs."""

import importlib
import math

import torch

from checking import (CheckerFault, Failed, Fixed, compare, compare_loss_gradients, same_value,
                      gradient_effect, named as named_line,
                      t, tr)
import runs


def effect_of(kind, to=""):
    """A gradient failure's line: what it is (the listed mistakes are values, not gradients)."""
    return named_line(gradient_effect(kind, to), "does")

SCRIPT = "rlhf_addition"
FUNCTION = "answer_logp"
ORDER = 25  # its row in docs/exercises.md's table
OUTPUTS = ("logp",)
RUN = runs.RLHF
LOOP = runs.RLHF_LOOP
LEARN = runs.RLHF_DPO_LEARN


def learned(result):
    runs.dpo_improves(result)


def loop_hint():
    return tr("DPO's log pi and log pi_ref come from your function: its first dpo row's loss is "
              "log 2 whatever\n  they are (pi is still pi_ref there), so its second row differs.",
              "DPO 的 log π 和 log π_ref 都来自你的函数：第一行 dpo 的 loss 不论它们是多少都是 log 2"
              "\n  （那时 π 还是 π_ref），所以是第二行 dpo 的 loss 不同。")


class PositionModel(Fixed):
    """A 'model' whose logits depend on the position only, (B, T, vocab) for ids (B, T), as a
    causal model's row t depends on tokens up to t alone; its table is what the gradient is
    checked on."""

    def __init__(self, table):
        super().__init__(table, names=(tr("the model's logits", "模型的 logits"),))

    def forward(self, idx):
        return self.outputs[0][:, :idx.shape[1]] * 1


VOCAB = "0123456789+=."  # grpo_addition.VOCAB
P = 4  # "3+5=": one-digit sums, answers of L = 3 tokens


def ids(*texts):
    return torch.tensor([[VOCAB.index(c) for c in text] for text in texts])


def by_hand(table, seqs, P, first=None, last="dot", mean=False):
    """Each row's sum (or mean) of log softmax(table[i, t - 1])[seqs[i, t]] over t from `first`
    (default P: the answer's first token) to the end of the answer (`last`: "dot" its first
    ".", "before" the token before it, "end" the last of L)."""
    out = []
    for i, row in enumerate(seqs.tolist()):
        answer = row[P:]
        n = (answer.index(VOCAB.index(".")) + 1 if VOCAB.index(".") in answer else len(answer))
        end = dict(dot=P + n, before=P + n - 1, end=len(row))[last]
        terms = []
        for pos in range(P if first is None else first, end):
            logits = table[i, pos - 1].tolist()
            norm = math.log(sum(math.exp(v) for v in logits))
            terms.append(logits[row[pos]] - norm)
        out.append(sum(terms) / (len(terms) if mean else 1))
    return t(*out)


def cases():
    # Three answers to "3+5=" and "7+6=" (P = 4, L = 3): "08." all its own, "8.." one token
    # of padding after its ".", ".13" its "." first (two of padding); the logits (seeded, fixed
    # per position) give every token a different log-probability.
    seqs = ids("3+5=08.", "3+5=8..", "7+6=.13")
    table = torch.randn(3, 7, len(VOCAB), generator=torch.Generator().manual_seed(3))
    return [(tr('answers "08.", "8.." and ".13" to "3+5=", "3+5=", "7+6=" (P = 4, L = 3)',
                '对 "3+5="、"3+5="、"7+6=" 的回答 "08."、"8.."、".13"（P = 4，L = 3）'),
             (PositionModel(table), seqs, P), by_hand(table, seqs, P))]


def mistakes(model, seqs, P):
    """(label, the value it gives) of each named mistake."""
    table = model.outputs[0].detach()
    return [(tr("the mean over the answer's tokens, where log pi(y|x) is their sum (the log "
                "of a product)", "对回答的 token 求了均值；log π(y|x) 是它们的和（乘积的对数）"),
             by_hand(table, seqs, P, mean=True)),
            (tr("the padding counted: the tokens after the answer's first \".\" are not part "
                "of it", "把填充也算进去了：回答第一个 \".\" 之后的 token 不属于回答"),
             by_hand(table, seqs, P, last="end")),
            (tr("the prompt's tokens counted too: log pi(y|x) scores the answer given the "
                "prompt, not the prompt (DPO's loss would not show it: a pair's two answers share "
                "the prompt, whose terms cancel in the gap)", "把题目的 token 也算进去了：log π(y|x) "
                "是给定题目时回答的概率，题目本身不打分（DPO 的损失看不出来：一对里的两个回答题目相同，"
                "题目那几项在分差里正好抵消）"), by_hand(table, seqs, P, first=1)),
            (tr("the answer's \".\" left out: it is the answer's last token, and counts",
                "漏了回答的 \".\"：它是回答的最后一个 token，也要算"),
             by_hand(table, seqs, P, last="before")),
            (tr("each token read at its own position, where position t - 1's logits predict "
                "token t", "每个 token 在它自己的位置读 logits；预测第 t 个 token 的是位置 t - 1 "
                "的 logits"), by_hand(torch.cat([table[:, 1:], table[:, :1]], 1), seqs, P))]


def worked_cases(fn):
    """Stage (a): the value of each case, a named mistake where it gives the answer's value,
    then the gradient of the answers' sum with respect to the logits, against the script's
    own function's (checking.check_cases takes the gradient of a loss, one number; here there
    is one per answer)."""
    own = importlib.import_module(SCRIPT).answer_logp
    for what, (model, seqs, P), expected in cases():
        for label, value in mistakes(model, seqs, P):
            if same_value(expected, value):
                raise CheckerFault(tr(
                    "this is the checker's fault, not yours: please report it.\n  ",
                    "这是检查程序的问题，不是你的：请报告它。\n  ") + (
                    f"exercises/cases/answer_logp.py: in the case \"{what}\", the listed mistake "
                    f"\"{label}\" gives the right answer: change the case so that it tells them "
                    f"apart"))
        head = (tr("case: ", "例子：") + what + tr("\n  input: ", "\n  输入：")
                + f"seqs={[''.join(VOCAB[i] for i in row) for row in seqs.tolist()]}, P={P}\n  ")
        saved = seqs.clone()
        got = fn(model, seqs, P)
        try:
            if not torch.equal(seqs, saved):
                raise Failed(tr("your function changed seqs in place", "你的函数原地改了 seqs"))
            compare("logp", got, expected)
            yours = model.outputs[0]
            if not got.requires_grad:
                compare_loss_gradients({"logits": yours}, None, effect_of)
            got.sum().backward()
            reference = PositionModel(yours.detach())
            own(reference, seqs, P).sum().backward()
            compare_loss_gradients({model.names[0]: reference.outputs[0].grad},
                                   {model.names[0]: yours.grad if yours.grad is not None
                                    else torch.zeros_like(yours)}, effect_of)
        except Failed as e:
            named = next((label for label, value in mistakes(model, seqs, P)
                          if same_value(got, value)), "")
            shown = e.plain if named else str(e)
            raise Failed(head + shown + (tr("\n  this is exactly what this mistake gives: ",
                                             "\n  你的值恰好是这个常见错误会得到的值：\n    ")
                                          + named if named else "")) from None
