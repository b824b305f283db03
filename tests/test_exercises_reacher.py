"""The exercises of ppo_reacher.py (exercises/gaussian_log_prob.py, ppo_update.py): typical wrong
answers each fail stage (a) with their mistake named, right answers written otherwise pass (a)
and (b), stage (b) tells a wrong answer from the script's own on the real loop, its loops do
what runs.py says of them, every listed mistake of the update is told from the answer where
its cases say so, and stage (c)'s bar passes the script's own function and fails a wrong one.
The blanks and the script's own functions through (a) and (b) are tests/test_exercises.py's,
which finds every exercise."""

import sys
import textwrap

import pytest

from conftest import ROOT

sys.path.insert(0, str(ROOT / "exercises"))
import check  # noqa: E402
import checking  # noqa: E402
import runs  # noqa: E402
from cases import ppo_update as update_cases  # noqa: E402

HEADER = """
import math
import torch
from torch.distributions import Independent, MultivariateNormal, Normal
from ppo_reacher import compute_loss_pi, compute_loss_v, step
"""

SIGNATURE = dict(
    gaussian_log_prob="def gaussian_log_prob(mu, log_std, act):",
    ppo_update="def update(policy, value_net, pi_optimizer, vf_optimizer, data, cfg):")


def answer(name, body):
    """The exercise's function, its signature as the blank's, `body` where the blank is."""
    namespace = {}
    exec(HEADER + SIGNATURE[name] + "\n" + textwrap.indent(textwrap.dedent(body), "    "),
         namespace)
    return namespace[check.EXERCISES[name].function]


from test_exercises import english, run  # noqa: E402,F401  (english: an autouse fixture)


C = "0.5 * math.log(2 * math.pi)"


def logp(square="-0.5 * z ** 2", sigma="log_std.exp()", log_sigma="- log_std", const=f"- {C}",
         reduce=".sum(-1)"):
    """gaussian_log_prob's body, the script's but for the part named."""
    return f"""
        z = (act - mu) / {sigma}
        return ({square} {log_sigma} {const}){reduce}"""


def update_body(check="before", limit="cfg.kl_stop_factor * cfg.target_kl", kl='pi_info["kl"]',
                stop="i", leave="break", values="after"):
    """ppo_update's body, the script's lines but for the part named."""
    policy_step = "step(pi_optimizer, loss_pi, policy, cfg.max_grad_norm)"
    value_steps = """for j in range(cfg.train_v_iters):
            step(vf_optimizer, compute_loss_v(value_net, data), value_net, cfg.max_grad_norm)"""
    test = f"cfg.target_kl is not None and {kl} > {limit}"
    if check == "before":
        loop = f"""
        if {test}:
            stop_iter = {stop}
            {leave}
        {policy_step}"""
    else:  # the step first, then the check
        loop = f"""
        {policy_step}
        if {test}:
            stop_iter = {stop}
            {leave}"""
    inside = ("\n        " + value_steps.replace("\n    ", "\n            ")
              if values == "inside" else "")
    after = "\n    " + value_steps if values == "after" else ""
    return f"""
    pi_l_old, pi_info_old = compute_loss_pi(policy, data, cfg.clip_ratio)
    pi_l_old, v_l_old = pi_l_old.item(), compute_loss_v(value_net, data).item()
    stop_iter = cfg.train_pi_iters
    for i in range(cfg.train_pi_iters):
        loss_pi, pi_info = compute_loss_pi(policy, data, cfg.clip_ratio){loop}{inside}{after}
    return pi_l_old, v_l_old, pi_info_old["ent"], stop_iter"""


RETURN = 'return pi_l_old, v_l_old, pi_info_old["ent"], stop_iter'

# name: [(wrong answer's body, words the stage (a) message must hold)]
WRONG = {
    "gaussian_log_prob": [
        (logp(reduce=".mean(-1)"), "the mean over the action's dimensions"),
        (logp(sigma="log_std"), "log_std used as sigma"),
        (logp(square="-(act - mu) ** 2 / (2 * log_std.exp())"),
         "divided by 2 sigma, not by 2 sigma^2"),
        (logp(log_sigma=""), "the log sigma term left out"),
        (logp(const=""), "PPO's ratio would not change"),
        (logp(square="0.5 * z ** 2"), "the sign of the square term"),
        (logp(log_sigma="+ log_std"), "the sign of log sigma"),
        (logp(reduce=".sum(-1).neg()"), "-log pi (a negative log-likelihood)"),
        (logp(reduce=""), "expected shape (2,), got (2, 2)"),
        (logp(reduce=""), "no sum over the action's dimensions"),
    ],
    "ppo_update": [
        (update_body(check="after"), "the check after the policy step"),
        (update_body(limit="cfg.target_kl"), "the factor left out"),
        (update_body(leave=RETURN), "the value steps stopped with the policy"),
        (update_body(values="inside"), "the value steps inside the policy loop"),
        (update_body(kl='pi_info_old["kl"]'), "approx_kl from the info before the update"),
        (update_body(kl='-pi_info["kl"]'), "the KL estimator reversed"),
        (update_body(stop="i + 1"), "stop_iter returned as i + 1"),
        (update_body(leave="continue"), "continue where break belongs"),
        (update_body(limit="1.5 * cfg.target_kl"), "1.5, the script's default, written as a "
                                                    "number where cfg.kl_stop_factor is meant"),
        (update_body(limit="cfg.kl_stop_factor * 0.01"), "0.01, the script's default, written "
                                                         "as a number where cfg.target_kl"),
        (update_body().replace("range(cfg.train_v_iters)", "range(80)"),
         "80, the script's default, written as a number where cfg.train_v_iters"),
        (update_body().replace("loss_pi, policy, cfg.max_grad_norm", "loss_pi, policy, 0.0"),
         "the policy network after the update: log_std differs"),
        (update_body().replace("range(cfg.train_v_iters)", "range(cfg.train_pi_iters)"),
         "the value loop counted with train_pi_iters"),
        ("""
        pi_l_old, pi_info_old = compute_loss_pi(policy, data, cfg.clip_ratio)
        pi_l_old, v_l_old = pi_l_old.item(), compute_loss_v(value_net, data).item()
        stop_iter = cfg.train_pi_iters
        for i in range(cfg.train_pi_iters):  # one value step with each policy step
            loss_pi, pi_info = compute_loss_pi(policy, data, cfg.clip_ratio)
            if cfg.target_kl is not None and pi_info["kl"] > cfg.kl_stop_factor * cfg.target_kl:
                stop_iter = i
                break
            step(pi_optimizer, loss_pi, policy, cfg.max_grad_norm)
            step(vf_optimizer, compute_loss_v(value_net, data), value_net, cfg.max_grad_norm)
        return pi_l_old, v_l_old, pi_info_old["ent"], stop_iter""",
         "one value step after each policy step, inside the policy loop"),
    ],
}


@pytest.mark.parametrize("name,index", [(n, i) for n in WRONG for i in range(len(WRONG[n]))])
def test_a_wrong_answer_fails_stage_a_and_its_mistake_is_named(name, index):
    body, needle = WRONG[name][index]
    passed, lines = run(name, answer(name, body))
    assert not passed and lines[-1].startswith(f"{name}: (a)"), lines
    assert needle in lines[-1], lines[-1]


RIGHT = {  # right answers written otherwise than the script: (a) and (b) pass
    "gaussian_log_prob": [
        "return Normal(mu, log_std.exp()).log_prob(act).sum(-1)",
        "return Independent(Normal(mu, log_std.exp()), 1).log_prob(act)",
        "return MultivariateNormal(mu, torch.diag(log_std.exp() ** 2)).log_prob(act)",
        f"return (-(act - mu) ** 2 / (2 * torch.exp(2 * log_std)) - log_std - {C}).sum(-1)",
        """
        sigma = log_std.exp()  # the density itself, then its log
        density = torch.exp(-(act - mu) ** 2 / (2 * sigma ** 2)) / (sigma * math.sqrt(2 * math.pi))
        return torch.log(torch.prod(density, -1))""",
    ],
    "ppo_update": [
        update_body().replace(" > ", " >= "),  # equal only by chance: the same here
        # continue, with stop_iter the steps counted: no more steps, and stop_iter is right
        """
        pi_l_old, pi_info_old = compute_loss_pi(policy, data, cfg.clip_ratio)
        pi_l_old, v_l_old = pi_l_old.item(), compute_loss_v(value_net, data).item()
        stop_iter = 0
        for i in range(cfg.train_pi_iters):
            loss_pi, pi_info = compute_loss_pi(policy, data, cfg.clip_ratio)
            if cfg.target_kl is not None and pi_info["kl"] > cfg.kl_stop_factor * cfg.target_kl:
                continue
            step(pi_optimizer, loss_pi, policy, cfg.max_grad_norm)
            stop_iter += 1
        for i in range(cfg.train_v_iters):
            step(vf_optimizer, compute_loss_v(value_net, data), value_net, cfg.max_grad_norm)
        return pi_l_old, v_l_old, pi_info_old["ent"], stop_iter""",
    ],
}


@pytest.mark.parametrize("name,index", [(n, i) for n in RIGHT for i in range(len(RIGHT[n]))])
def test_a_right_answer_written_otherwise_passes_a_and_b(name, index):
    """Another float order (torch's Normal, the density itself) moves log pi in its last bits:
    the one-update loop of gaussian_log_prob passes it, with a note at most."""
    passed, lines = run(name, answer(name, RIGHT[name][index]))
    assert passed, lines


def test_stage_b_tells_a_cut_gradient_from_the_scripts_own():
    """mu detached inside log pi: the values of (a) are right, and mu(s) never learns."""
    body = logp(sigma="log_std.exp()").replace("(act - mu)", "(act - mu.detach())")
    passed, lines = run("gaussian_log_prob", answer("gaussian_log_prob", body))
    assert not passed and lines[-1].startswith("gaussian_log_prob: (b)"), lines
    assert "evaluation at step 1000" in lines[-1], lines[-1]


def test_the_update_loop_stops_early_in_some_updates_and_not_in_others(tmp_path):
    """runs.REACHER_LOOP: the early stop cuts the first two updates (seed 0: 4 and 7 policy
    steps of 10) and none of the rest, so that (b) sees both; the columns (b) leaves out are
    not among its rows."""
    rows = check.loop_logs(check.EXERCISES["ppo_update"], None, tmp_path)
    steps = [int(float(r["pi_steps"])) for r in rows[1:]]
    assert min(steps) < runs.REACHER_LOOP["train_pi_iters"] == max(steps), steps
    assert not set(runs.NOISY) & set(rows[1]) and "pi_steps" in rows[1]


def test_every_listed_mistake_of_the_update_is_told_where_its_cases_say():
    """Each listed mistake differs from the script's own update in the cases MISTAKES gives it;
    and a case on which one gives the right answer is refused (planted: the factor left out
    listed for the batch already past the limit, where both stop at once)."""
    own = update_cases.script().update
    with update_cases.one_thread():
        for what, args, kind in update_cases.cases():
            update_cases.mistake_outcomes(what, args, kind, update_cases.outcome(own, args))
        what, args, kind = update_cases.cases()[1]
        label, how, _ = update_cases.MISTAKES[1]
        planted = [(label, how, (kind,))]
        saved, update_cases.MISTAKES = update_cases.MISTAKES, planted
        try:
            with pytest.raises(checking.CheckerFault, match="the factor left out"):
                update_cases.mistake_outcomes(what, args, kind, update_cases.outcome(own, args))
        finally:
            update_cases.MISTAKES = saved


@pytest.mark.slow
def test_the_scripts_own_log_pi_reaches_and_a_negated_one_does_not():
    """Stage (c): tests/test_ppo_reacher.py's run (60,000 steps, seed 0), the bar -10: the
    script's own ends near -8.1; log pi negated turns every ratio upside down, and the arm
    does not learn to reach."""
    ex = check.EXERCISES["gaussian_log_prob"]
    result = check.learns(ex, getattr(ex.owner(), ex.function))
    assert result["evaluations"][-1]["eval_mean"] > runs.REACH_BAR
    with pytest.raises(check.Failed, match="not above -10"):
        check.learns(ex, answer("gaussian_log_prob", logp(reduce=".sum(-1).neg()")))
