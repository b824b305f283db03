"""The exercises of rlhf_addition.py (exercises/bradley_terry_loss.py, answer_logp.py,
dpo_loss.py, per_token_rewards.py): typical wrong answers each fail stage (a) with their
mistake named, stage (b) tells a wrong answer from the script's own on the real loop, and
stage (c)'s bars pass the script's own functions and fail a wrong one. The blanks and the
script's own functions through (a) and (b) are tests/test_exercises.py's, which finds every
exercise."""

import sys
import textwrap

import pytest

from conftest import ROOT

sys.path.insert(0, str(ROOT / "exercises"))
import check  # noqa: E402
import checking  # noqa: E402

HEADER = """
import torch
from grpo_addition import completion_mask, token_logp
import torch.nn.functional as F
from torch.nn.functional import logsigmoid
"""


def answer(name, body):
    """The exercise's function, its signature as the blank's, `body` where the blank is."""
    signature = dict(
        bradley_terry_loss="def bradley_terry_loss(r_chosen, r_rejected):",
        per_token_rewards="def per_token_rewards(score, logp_old, logp_ref, mask, beta):",
        answer_logp="def answer_logp(model, seqs, P):",
        dpo_loss="def dpo_loss(logp_w, logp_l, ref_w, ref_l, beta):",
    )[name]
    namespace = {}
    exec(HEADER + signature + "\n" + textwrap.indent(textwrap.dedent(body), "    "), namespace)
    return namespace[check.EXERCISES[name].function]


from test_exercises import english, run  # noqa: E402,F401  (english: an autouse fixture)


REWARDS = """
    kl = (logp_old - logp_ref) * mask
    rewards = {rewards}
    last = mask.sum(1).long() - 1
    {score}
    return rewards, {kl}
"""
LAST = "rewards[torch.arange(len(score)), last] += score"


LOGP = """
    logits = model(seqs[:, :-1])[:, {first} - 1:]
    logp = torch.log_softmax(logits, -1).gather(-1, seqs[:, {first}:, None]).squeeze(-1)
    mask = completion_mask(seqs[:, P:])
    return {total}
"""


def logp_with(first="P", total="(logp * mask).sum(1)"):
    return LOGP.format(first=first, total=total)


DPO = "return -logsigmoid({}).mean()"


def rewards_with(rewards="-beta * kl", score=LAST, kl="kl", before=""):
    return textwrap.indent(before, "    ") + REWARDS.format(rewards=rewards, score=score, kl=kl)


# name: [(the wrong answer's body, words its stage (a) message must hold)]
WRONG = {
    "bradley_terry_loss": [
        ("return -logsigmoid(r_rejected - r_chosen).mean()", "chosen and rejected swapped"),
        ("return logsigmoid(r_chosen - r_rejected).mean()", "the sign: log sigmoid(gap)"),
        ("return -torch.sigmoid(r_chosen - r_rejected).mean()", "sigmoid without the log"),
        ("return -logsigmoid(r_chosen - r_rejected).sum()", "summed over the pairs"),
        ("return torch.relu(1 - (r_chosen - r_rejected)).mean()", "a margin (hinge) loss"),
        ("return F.margin_ranking_loss(r_chosen, r_rejected, torch.ones_like(r_chosen), "
         "margin=1.0)", "a margin (hinge) loss"),
        ("return -(logsigmoid(r_chosen) + logsigmoid(-r_rejected)).mean()",
         "each answer classified on its own"),
        ("return -logsigmoid(r_chosen.detach() - r_rejected).mean()",
         "no gradient reaches r_chosen"),
        ("return -logsigmoid(r_chosen - r_rejected).mean().detach()", "gradient cut"),
        ("return -logsigmoid(r_chosen - r_rejected)", "expected shape (), got (3,)"),
    ],
    "per_token_rewards": [
        (rewards_with(score="rewards = rewards + score[:, None] * mask"),
         "the score on every token of the answer"),
        (rewards_with(score="rewards[:, -1] += score"), "the score on the last of the L positions"),
        (rewards_with(score="rewards[:, 0] += score"), "the score on the first token"),
        (rewards_with(rewards="beta * kl"), "the penalty's sign: + beta * kl"),
        (rewards_with(before="logp_old, logp_ref = logp_ref, logp_old"),
         "the KL the other way round"),
        (rewards_with(rewards="torch.zeros_like(kl)",
                      score="rewards[torch.arange(len(score)), last] += score - beta * kl.sum(1)"),
         "the KL summed into the last token only"),
        (rewards_with().replace("(logp_old - logp_ref) * mask", "logp_old - logp_ref"),
         "the mask not applied: the padding after the answer's"),
        (rewards_with(rewards="-kl"), "beta left out"),
        (rewards_with(kl="logp_old - logp_ref"), "kl returned without the mask"),
        (REWARDS.format(rewards="-beta * kl", score=LAST, kl="kl").replace(
            "(logp_old - logp_ref)", "logp_old.sub_(logp_ref)"),
         "changed one of its inputs in place"),
    ],
    "answer_logp": [
        (logp_with(total="(logp * mask).sum(1) / mask.sum(1)"),
         "the mean over the answer's tokens, where log pi(y|x) is their sum"),
        (logp_with(total="(logp * mask).mean(1)"), "logp: first difference"),
        (logp_with(total="logp.sum(1)"), "the padding counted"),
        (logp_with(first="1", total="logp[:, :P - 1].sum(1) + (logp[:, P - 1:] * mask).sum(1)"),
         "the prompt's tokens counted too"),
        (logp_with(total="(logp * mask * (seqs[:, P:] != 12).float()).sum(1)"),
         "the answer's \".\" left out"),
        ("""
            logits = model(seqs)[:, P:]
            logp = torch.log_softmax(logits, -1).gather(-1, seqs[:, P:, None]).squeeze(-1)
            return (logp * completion_mask(seqs[:, P:])).sum(1)""",
         "each token read at its own position"),
        ("""
            with torch.no_grad():
                return (token_logp(model, seqs, P) * completion_mask(seqs[:, P:])).sum(1)""",
         "gradient cut"),
        ("return (token_logp(model, seqs, P).detach() * completion_mask(seqs[:, P:])).sum(1)",
         "gradient cut"),
        ("""
            logits = model(seqs[:, :-1])[:, P - 1:]
            picked = logits.gather(-1, seqs[:, P:, None]).squeeze(-1)
            logp = picked - torch.logsumexp(logits.detach(), -1)  # the normalizer detached
            return (logp * completion_mask(seqs[:, P:])).sum(1)""", "wrong gradient"),
        ("return (token_logp(model, seqs, P) * completion_mask(seqs[:, P:])).sum(1, keepdim=True)",
         "expected shape (3,), got (3, 1)"),
    ],
    "dpo_loss": [
        (DPO.format("beta * ((logp_l - ref_l) - (logp_w - ref_w))"), "chosen and rejected swapped"),
        (DPO.format("beta * ((ref_w - logp_w) - (ref_l - logp_l))"), "chosen and rejected swapped"),
        (DPO.format("beta * (logp_w - logp_l)"), "the reference left out"),
        ("return -beta * logsigmoid((logp_w - ref_w) - (logp_l - ref_l)).mean()", "beta outside"),
        (DPO.format("beta * (logp_w - ref_w) - (logp_l - ref_l)"),
         "beta on the chosen answer's term only"),
        (DPO.format("(logp_w - ref_w) - (logp_l - ref_l)"), "beta left out"),
        (DPO.format("0.1 * ((logp_w - ref_w) - (logp_l - ref_l))"),
         "0.1, the script's default, written as a number where beta is meant"),
        ("return logsigmoid(beta * ((logp_w - ref_w) - (logp_l - ref_l))).mean()",
         "the sign: log sigmoid(...)"),
        ("return -torch.sigmoid(beta * ((logp_w - ref_w) - (logp_l - ref_l))).mean()",
         "sigmoid without the log"),
        ("return -logsigmoid(beta * ((logp_w - ref_w) - (logp_l - ref_l))).sum()",
         "summed over the pairs"),
        (DPO.format("beta * ((logp_w - ref_w).exp() - (logp_l - ref_l).exp())"),
         "ratios of probabilities"),
        (DPO.format("beta * ((logp_w.detach() - ref_w) - (logp_l - ref_l))"),
         "no gradient reaches logp_w"),
    ],
}


@pytest.mark.parametrize("name,index", [(n, i) for n in WRONG for i in range(len(WRONG[n]))])
def test_a_wrong_answer_fails_stage_a_and_its_mistake_is_named(name, index):
    body, words = WRONG[name][index]
    passed, lines = run(name, answer(name, body))
    assert not passed and lines[-1].startswith(f"{name}: (a) worked cases: FAIL"), lines
    assert words in lines[-1], lines[-1]


# name: a wrong answer that stage (b)'s loop tells from the script's own (with the first stage
# that logs the difference)
LOOP_WRONG = {
    "bradley_terry_loss": ("return -logsigmoid(r_rejected - r_chosen).mean()", "rm"),
    "per_token_rewards": (rewards_with().replace("(logp_old - logp_ref) * mask",
                                                 "logp_old - logp_ref"), "ppo"),
    "answer_logp": (logp_with(total="logp.sum(1)"), "dpo"),
    "dpo_loss": (DPO.format("beta * (logp_w - logp_l)"), "dpo"),
}


@pytest.mark.parametrize("name", LOOP_WRONG)
def test_stage_b_tells_a_wrong_answer_from_the_scripts_own(name):
    """The loop has padded answers (a "." before the last token) and PPO updates after the
    first (whose KL is 0): a mistake of the mask, the KL or the loss shows in its logs, at the
    stage that uses the function."""
    body, phase = LOOP_WRONG[name]
    with pytest.raises(check.Failed, match="the logs first differ at step") as failed:
        check.real_loop(check.EXERCISES[name], answer(name, body))
    step = int(str(failed.value).split("the logs first differ at step ")[1].split(",")[0])
    reference = check.REFERENCE[(check.EXERCISES[name].script,
                                 tuple(sorted(check.EXERCISES[name].loop.items())))]
    assert reference[step - 1]["phase"] == phase, (step, reference[step - 1])


@pytest.mark.slow
@pytest.mark.parametrize("name", ["bradley_terry_loss", "per_token_rewards", "dpo_loss"])
def test_the_scripts_own_functions_learn(name):
    """Stage (c) with the script's own functions: the reward model ranks held-out pairs
    (one-digit sums), PPO on the judge's score and DPO on pairs without flips each raise the
    held-out true score after 500 supervised steps (answer_logp's run is dpo_loss's)."""
    ex = check.EXERCISES[name]
    result = check.learns(ex, getattr(ex.owner(), ex.function))  # raises check.Failed if not
    if name == "bradley_terry_loss":
        assert result["rm_accuracy"] > 0.8
    else:
        stage = "PPO" if name == "per_token_rewards" else "DPO"
        assert result["held"][stage][1] > result["held"]["supervised"][1] + 0.02  # accuracy too


@pytest.mark.slow
@pytest.mark.parametrize("name", ["bradley_terry_loss", "dpo_loss"])
def test_chosen_and_rejected_swapped_fails_stage_c(name):
    """The bars tell learning from its opposite: with the pairs' two answers swapped, the
    reward model ranks the held-out pairs backwards (0.165 on seed 0) and DPO moves the
    policy toward the rejected answers (held-out true score 0.751 -> 0.690)."""
    body = WRONG[name][0][0]
    with pytest.raises(check.Failed, match="under 0.7 |a gain under 0.01"):
        check.learns(check.EXERCISES[name], answer(name, body))


def test_answer_logp_refuses_a_case_on_which_a_listed_mistake_is_right(monkeypatch):
    """answer_logp runs its own worked cases (one gradient per answer): like every exercise's,
    they stop with a line for the maintainer where a listed mistake gives the right answer."""
    from cases import answer_logp as cases

    ex = check.EXERCISES["answer_logp"]
    right = cases.cases()[0][2]
    monkeypatch.setattr(cases, "mistakes", lambda *args: [("planted", right)])
    with pytest.raises(checking.CheckerFault, match='"planted" gives the right answer'):
        check.worked_cases(ex, getattr(ex.owner(), ex.function))
