"""Worked cases that hold both sides of what an answer combines: a critic's error past 1
(where a Huber loss and the halved square part), Q1 below Q2 and above it (SAC's min), ratios
above 1 and below it (pi against pi_old). An answer that keeps one side only fails stage (a)
and is named."""

import sys

import pytest

from conftest import ROOT

sys.path.insert(0, str(ROOT / "exercises"))
import check  # noqa: E402
import checking  # noqa: E402
from test_exercises import compile_answer, english, sac_answer  # noqa: E402, F401


def script_with(name, line, new):
    """The script's own function of exercise `name`, its `line` replaced by `new`."""
    import inspect
    import textwrap
    ex = check.EXERCISES[name]
    source = textwrap.dedent(inspect.getsource(getattr(ex.owner(), ex.function)))
    assert line in source, line
    return source.replace(line, new)


# name: [(answer, words its stage (a) message must hold)]
ONE_SIDE = {
    "a2c_loss": [(script_with("a2c_loss", "loss_v = 0.5 * ((values - ret) ** 2).mean()",
                              "loss_v = F.smooth_l1_loss(values, ret)"),
                  "a Huber loss (smooth_l1_loss) where the halved squared error is meant")],
    "sac_actor_loss": [
        (sac_answer(critics="(lambda q1, q2: q1)"), "Q1 alone where SAC takes min(Q1, Q2)"),
        (sac_answer(critics="(lambda q1, q2: q2)"), "Q2 alone where SAC takes min(Q1, Q2)"),
        (sac_answer(critics="torch.max"), "max(Q1, Q2) where SAC takes the smaller")],
    "kl_penalty": [(script_with("kl_penalty", "ratio = torch.exp(logp - logp_old)",
                                "ratio = torch.exp(logp_old - logp)"),
                    "the ratio upside down: pi_old / pi")],
    "clipped_surrogate": [(script_with("clipped_surrogate", "ratio = torch.exp(logp - logp_old)",
                                       "ratio = torch.exp(logp_old - logp)"),
                           "the ratio upside down: pi_old / pi")],
    "grpo_loss": [(script_with("grpo_loss", "ratio = torch.exp(logp - logp_old)",
                               "ratio = torch.exp(logp_old - logp)"),
                   "the ratio upside down: pi_old / pi")],
}


@pytest.mark.quick
@pytest.mark.parametrize("name,index", [(n, i) for n in ONE_SIDE for i in range(len(ONE_SIDE[n]))])
def test_an_answer_that_keeps_one_side_fails_stage_a_and_is_named(name, index):
    source, needle = ONE_SIDE[name][index]
    with pytest.raises(checking.Failed) as failed:
        check.worked_cases(check.EXERCISES[name], compile_answer(source, name))
    assert "this is exactly what this mistake gives: " + needle in str(failed.value), \
        str(failed.value)


@pytest.mark.quick
def test_sac_cases_hold_both_orders_of_the_critics():
    """In every case, one row where Q1 < Q2 and one where Q1 > Q2."""
    cases = sys.modules["cases.sac_actor_loss"]
    q1, q2 = cases.sac_critics()
    for _, (mean, log_std, eps, scale, bias, obs, alpha) in cases.sac_cases():
        a = bias + scale * (mean + log_std.exp() * eps).tanh()
        first, second = q1(obs, a), q2(obs, a)
        assert (first < second).any() and (first > second).any()


@pytest.mark.quick
@pytest.mark.parametrize("name", ["clipped_surrogate", "kl_penalty", "grpo_loss"])
def test_the_ratios_of_the_cases_lie_above_1_and_below(name):
    """pi against pi_old: every case of an exercise that combines them has a ratio above 1 and
    one below (the ratios its script's function logs)."""
    ex = check.EXERCISES[name]
    own = getattr(ex.owner(), ex.function)
    for _, args, _ in ex.cases():
        out = own(*args)
        info = out[-1]
        ratio = info["ratio"] if "ratio" in info else None
        if ratio is None:  # kl_penalty logs no ratio: pi / pi_old of the taken actions
            policy, data, _ = args
            from torch.distributions import Categorical
            logp = Categorical(logits=policy(data["obs"])).log_prob(data["act"])
            ratio = (logp - data["logp"]).exp()
        assert (ratio > 1).any() and (ratio < 1).any(), (name, ratio)
