"""The exercises and their checker (exercises/check.py): every blank says "not written yet",
the scripts' own functions pass every stage, and typical wrong answers each fail at the
earliest stage that can see them, with a message that names what differs."""

import sys
import textwrap

import pytest

from conftest import ROOT

sys.path.insert(0, str(ROOT / "exercises"))
import check  # noqa: E402

HEADER = """
import torch
import torch.nn.functional as F
from torch.distributions import Categorical, kl_divergence
"""

# name: [(wrong answer, the stage that must catch it, words its message must hold)]
WRONG = {
    "discounted_returns": [
        ("""def discounted_returns(rewards, next_values, terminated, truncated, gamma):
                returns, future = torch.zeros_like(rewards), torch.zeros_like(rewards[0])
                for t in reversed(range(len(rewards))):  # no bootstrap at the cut
                    future = torch.where(terminated[t] | truncated[t], 0.0, future)
                    returns[t] = future = rewards[t] + gamma * future
                return returns""", "(a)", "bootstrap with V(s_3) = 4"),
        ("""def discounted_returns(rewards, next_values, terminated, truncated, gamma):
                returns, future = torch.zeros_like(rewards), next_values[-1]
                for t in reversed(range(len(rewards))):  # a truncation as a termination
                    future = torch.where(terminated[t] | truncated[t], 0.0, future)
                    returns[t] = future = rewards[t] + gamma * future
                return returns""", "(a)", "truncated at t = 1"),
        ("""def discounted_returns(rewards, next_values, terminated, truncated, gamma):
                returns, future = torch.zeros_like(rewards), next_values[-1]
                for t in reversed(range(len(rewards))):  # truncation checked last: it wins
                    future = torch.where(terminated[t], 0.0, future)
                    future = torch.where(truncated[t], next_values[t], future)
                    returns[t] = future = rewards[t] + gamma * future
                return returns""", "(a)", "termination wins"),
    ],
    "gae": [
        ("""def gae(rewards, values, next_values, terminated, truncated, gamma, lam):
                adv, last = torch.zeros_like(rewards), torch.zeros_like(rewards[0])
                for t in reversed(range(len(rewards))):  # a truncation as a termination
                    done = (terminated[t] | truncated[t]).float()
                    delta = rewards[t] + gamma * next_values[t] * (1 - done) - values[t]
                    last = adv[t] = delta + gamma * lam * (1 - done) * last
                return adv""", "(a)", "truncated at t = 0"),
        ("""def gae(rewards, values, next_values, terminated, truncated, gamma, lam):
                adv, last = torch.zeros_like(rewards), torch.zeros_like(rewards[0])
                for t in reversed(range(len(rewards))):  # the sum runs on past a truncation
                    nt = (~terminated[t]).float()
                    delta = rewards[t] + gamma * next_values[t] * nt - values[t]
                    last = adv[t] = delta + gamma * lam * nt * last
                return adv""", "(a)", "truncated at t = 0"),
        ("""def gae(rewards, values, next_values, terminated, truncated, gamma, lam):
                adv, last = torch.zeros_like(rewards), torch.zeros_like(rewards[0])
                for t in reversed(range(len(rewards))):  # lam forgotten
                    done = (terminated[t] | truncated[t]).float()
                    delta = rewards[t] + gamma * next_values[t] * (~terminated[t]).float() - values[t]
                    last = adv[t] = delta + gamma * (1 - done) * last
                return adv""", "(a)", "lam = 0.5"),
    ],
    "clipped_surrogate": [
        ("""def compute_loss_pi(policy, data, clip_coef):
                dist = Categorical(logits=policy(data["obs"]))
                logp = dist.log_prob(data["act"])
                ratio = torch.exp(logp - data["logp"]).detach()  # no gradient reaches pi
                adv = data["adv"]
                loss = -torch.min(ratio * adv, ratio.clamp(1 - clip_coef, 1 + clip_coef) * adv).mean()
                info = dict(approx_kl=((ratio - 1) - (logp - data["logp"])).mean().detach(),
                            clipfrac=((ratio - 1).abs() > clip_coef).float().mean(), ratio=ratio)
                return loss, dist.entropy().mean(), info""", "(b)", "the logs first differ at update 1"),
        ("""def compute_loss_pi(policy, data, clip_coef):
                dist = Categorical(logits=policy(data["obs"]))
                logp = dist.log_prob(data["act"])
                ratio = torch.exp(logp - data["logp"])
                adv = data["adv"]  # max: the optimistic bound
                loss = -torch.max(ratio * adv, ratio.clamp(1 - clip_coef, 1 + clip_coef) * adv).mean()
                return loss, dist.entropy().mean(), {}""", "(a)", "expected 0.275"),
        ("""def compute_loss_pi(policy, data, clip_coef):
                dist = Categorical(logits=policy(data["obs"]))
                logp = dist.log_prob(data["act"])
                ratio = torch.exp(logp - data["logp"])  # the product clipped, not the ratio
                loss = -(ratio * data["adv"]).clamp(1 - clip_coef, 1 + clip_coef).mean()
                return loss, dist.entropy().mean(), {}""", "(a)", "expected 0.275"),
    ],
    "kl_penalty": [
        ("""def compute_loss_pi(policy, data, beta):
                dist = Categorical(logits=policy(data["obs"]))
                ratio = torch.exp(dist.log_prob(data["act"]) - data["logp"])
                kl = kl_divergence(dist, Categorical(logits=data["logits_old"])).mean()  # reversed
                return -(ratio * data["adv"]).mean() + beta * kl, dist.entropy().mean(), dict(kl=kl.detach())
             """, "(a)", "beta = 2.0"),
        ("""def compute_loss_pi(policy, data, beta):
                dist = Categorical(logits=policy(data["obs"]))
                ratio = torch.exp(dist.log_prob(data["act"]) - data["logp"])
                kl = kl_divergence(Categorical(logits=data["logits_old"]), dist).mean().detach()
                return -(ratio * data["adv"]).mean() + beta * kl, dist.entropy().mean(), dict(kl=kl)
             """, "(b)", "the logs first differ at update"),
        ("""def compute_loss_pi(policy, data, beta):
                dist = Categorical(logits=policy(data["obs"]))
                ratio = torch.exp(dist.log_prob(data["act"]) - data["logp"])
                kl = kl_divergence(Categorical(logits=data["logits_old"]), dist).mean()
                return (ratio * data["adv"]).mean() + beta * kl, dist.entropy().mean(), dict(kl=kl.detach())
             """, "(a)", "beta = 0.0"),
    ],
    "adapt_beta": [
        ("""def adapt_beta(beta, d, cfg):  # halves where it should double
                if d < cfg.d_targ / cfg.kl_tolerance:
                    return beta * cfg.beta_factor
                if d > cfg.d_targ * cfg.kl_tolerance:
                    return beta / cfg.beta_factor
                return beta""", "(a)", "d = 0.001"),
        ("""def adapt_beta(beta, d, cfg):  # <= where the paper has <
                if d <= cfg.d_targ / cfg.kl_tolerance:
                    return beta / cfg.beta_factor
                if d > cfg.d_targ * cfg.kl_tolerance:
                    return beta * cfg.beta_factor
                return beta""", "(a)", "d = 0.00666667"),
        ("""def adapt_beta(beta, d, cfg):  # the tolerance as the factor
                if d < cfg.d_targ / cfg.kl_tolerance:
                    return beta / cfg.kl_tolerance
                if d > cfg.d_targ * cfg.kl_tolerance:
                    return beta * cfg.kl_tolerance
                return beta""", "(a)", "expected 0.5"),
    ],
    "a2c_loss": [
        ("""def a2c_loss(model, data, cfg):
                logits, values = model(data["obs"])
                dist = Categorical(logits=logits)
                adv = data["ret"] - values  # A recomputed: its gradient reaches the critic
                loss_pi = -(dist.log_prob(data["act"]) * adv).mean()
                loss_v = 0.5 * ((values - data["ret"]) ** 2).mean()
                entropy = dist.entropy().mean()
                loss = loss_pi + cfg.vf_coef * loss_v - cfg.ent_coef * entropy
                return loss, dict(loss_pi=loss_pi.item(), loss_v=loss_v.item(), entropy=entropy.item(),
                                  explained_var=0.0, values=values.detach(), ret=data["ret"])""",
         "(b)", "the logs first differ at update"),
        ("""def a2c_loss(model, data, cfg):
                logits, values = model(data["obs"])
                dist = Categorical(logits=logits)
                loss_pi = -(dist.log_prob(data["act"]) * data["adv"]).mean()
                loss_v = 0.5 * ((values - data["ret"]) ** 2).mean()
                entropy = dist.entropy().mean()  # the bonus with the wrong sign
                loss = loss_pi + cfg.vf_coef * loss_v + cfg.ent_coef * entropy
                return loss, dict(loss_pi=loss_pi.item(), loss_v=loss_v.item(), entropy=entropy.item())""",
         "(a)", "loss: first difference"),
        ("""def a2c_loss(model, data, cfg):
                logits, values = model(data["obs"])
                dist = Categorical(logits=logits)
                loss_pi = -(dist.log_prob(data["act"]) * data["adv"]).mean()
                loss_v = ((values - data["ret"]) ** 2).mean()  # the half forgotten
                entropy = dist.entropy().mean()
                loss = loss_pi + cfg.vf_coef * loss_v - cfg.ent_coef * entropy
                return loss, dict(loss_pi=loss_pi.item(), loss_v=loss_v.item(), entropy=entropy.item())""",
         "(a)", "loss: first difference"),
    ],
    "td_target": [
        ("""def td_target(reward, not_done, next_q, gamma):
                return reward + gamma * next_q  # a future after a termination""", "(a)",
         "first difference at index (1,)"),
        ("""def td_target(reward, not_done, next_q, gamma):
                return reward + gamma * (1 - not_done) * next_q""", "(a)", "first difference"),
        ("""def td_target(reward, not_done, next_q, gamma):
                return (reward + gamma * not_done * next_q).unsqueeze(-1)  # (B, 1)""", "(a)",
         "expected shape (3,), got (3, 1)"),
    ],
    "actor_loss": [
        ("""def compute_loss_actor(actor, critic, obs):
                return -critic(obs, actor(obs).detach()).mean()  # no gradient reaches mu""",
         "(b)", "the logs first differ at step"),
        ("""def compute_loss_actor(actor, critic, obs):
                return critic(obs, actor(obs)).mean()  # descends Q""", "(a)", "expected -5"),
        ("""def compute_loss_actor(actor, critic, obs):
                return -critic(obs, actor(obs)).sum()""", "(a)", "expected -5"),
    ],
    "soft_update": [
        ("""def soft_update(target, source, tau):
                with torch.no_grad():
                    for pt, p in zip(target.parameters(), source.parameters()):
                        pt.mul_(tau).add_((1 - tau) * p)  # tau on the wrong side""", "(a)",
         "expected 0.1"),
        ("""def soft_update(target, source, tau):
                target.load_state_dict(source.state_dict())  # a hard copy""", "(a)", "expected 0.1"),
        ("""def soft_update(target, source, tau):
                with torch.no_grad():
                    for pt, p in zip(target.parameters(), source.parameters()):
                        pt = tau * p + (1 - tau) * pt  # a new tensor; the target stays""", "(a)",
         "expected 0.1"),
    ],
}


def compile_answer(source, name):
    namespace = {}
    exec(HEADER + textwrap.dedent(source), namespace)
    return namespace[check.EXERCISES[name].function]


def run(name, fn, learning=False):
    lines = []
    passed = check.check(name, fn=fn, learning=learning, say=lines.append)
    return passed, lines


BLANKS = [name for name in check.EXERCISES if name not in check.BUGS]


@pytest.mark.quick
@pytest.mark.parametrize("name", BLANKS)
def test_each_blank_says_not_written_yet(name):
    passed, lines = run(name, None)
    assert not passed and lines == [f"{name}: (a) worked cases: FAIL: not written yet (fill in "
                                    f"the blank in exercises/{name}.py)"]


@pytest.mark.parametrize("name", BLANKS)
def test_the_scripts_own_function_passes_the_cases_and_the_loop(name):
    ex = check.EXERCISES[name]
    passed, lines = run(name, getattr(ex.owner(), ex.function))
    assert passed, lines


@pytest.mark.parametrize("name,index", [(name, i) for name in WRONG for i in range(3)])
def test_a_wrong_answer_fails_at_the_earliest_stage_that_sees_it(name, index):
    source, stage, needle = WRONG[name][index]
    passed, lines = run(name, compile_answer(source, name))
    assert not passed and lines[-1].startswith(f"{name}: {stage}"), lines
    assert needle in lines[-1], lines[-1]


@pytest.mark.quick
@pytest.mark.parametrize("bug", check.BUGS)
def test_each_planted_bug_fails_and_the_table_does_not_give_it_away(bug, capsys):
    passed, lines = run(bug, check.load(bug))
    assert not passed and "FAIL" in lines[-1]
    check.main([])
    (row,) = [line for line in capsys.readouterr().out.splitlines() if line.startswith(bug)]
    assert row.split() == [bug, "not", "fixed", "yet"]


def test_four_exercises_have_a_wrong_answer_only_the_loop_catches():
    assert len({name for name, answers in WRONG.items()
                if any(stage != "(a)" for _, stage, _ in answers)}) >= 4


@pytest.mark.slow
@pytest.mark.parametrize("name", ["gae", "kl_penalty", "a2c_loss", "td_target"])
def test_the_scripts_own_functions_learn(name):
    """Stage (c) with the scripts' own functions: one exercise per script (the others of the
    same script run the very same training)."""
    ex = check.EXERCISES[name]
    result = check.learns(ex, getattr(ex.owner(), ex.function))
    if ex.script == "ddpg_walker":  # from falling within ~100 steps to balancing all 1000
        assert result["evaluations"][0]["eval_mean"] < 200  # (seeds 0-4 reach 1000: docs/experiments.md)
        assert result["evaluations"][-1]["eval_mean"] >= 900, result["evaluations"]


def test_the_checker_from_the_command_line(tmp_path):
    from conftest import run_script

    p = run_script("exercises/check.py", "td_target", timeout=120)
    assert p.returncode == 1 and "not written yet" in p.stdout, p.stdout + p.stderr
    p = run_script("exercises/check.py", "nope", timeout=120)
    assert p.returncode == 2 and "invalid choice" in p.stderr
