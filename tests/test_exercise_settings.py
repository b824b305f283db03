"""The exercises' worked cases hand the function settings other than the script's defaults,
so that an answer which writes a default as a number (0.2 for clip_coef) fails stage (a), and
is named for it."""

import sys

import pytest

from conftest import ROOT

sys.path.insert(0, str(ROOT / "exercises"))
import check  # noqa: E402
import checking  # noqa: E402
from test_exercises import HEADER, compile_answer, english, run  # noqa: E402, F401

EXERCISES = [name for name in check.EXERCISES if name not in check.BUGS]


def case_settings(name):
    """{field: [its value in each call]} of the settings stage (a) hands the function, the
    script's own answering (each cfg's fields as the script's function reads them)."""
    ex = check.EXERCISES[name]
    own = getattr(ex.owner(), ex.function)
    seen = {}

    def answer(*args):
        out, settings = checking.read_settings(ex, args, own)
        for s in settings:
            seen.setdefault(s.field, (s.default, []))[1].append(s.value)
        return out

    check.worked_cases(ex, answer)
    return seen


@pytest.mark.quick
@pytest.mark.parametrize("name", EXERCISES)
def test_no_setting_of_the_worked_cases_is_only_the_scripts_default(name):
    """Every hyperparameter a worked case hands the function (a field of its cfg that the
    script's own function reads, or an argument named as a Config field) takes, in some case,
    a value other than the script's Config default."""
    for field, (default, values) in case_settings(name).items():
        assert any(v != default for v in values), \
            f"{name}: every worked case has {field} = {default!r}, the script's default"


def test_a_case_at_the_defaults_only_fails_the_settings_test(monkeypatch):
    """The test above catches a case that hands the function the defaults alone (planted:
    clipped_surrogate's eps back at 0.2)."""
    ex = check.EXERCISES["clipped_surrogate"]
    cases, own = ex.cases, getattr(ex.owner(), ex.function)
    monkeypatch.setattr(ex, "cases", lambda: [
        (what, (*args[:2], 0.2), (own(*args[:2], 0.2)[0].detach(), None, None))
        for what, args, _ in cases()])
    with pytest.raises(AssertionError, match="clip_coef = 0.2, the script's default"):
        test_no_setting_of_the_worked_cases_is_only_the_scripts_default("clipped_surrogate")


# name: [(an answer that writes a default as a number, words its stage (a) message must hold)]
DEFAULTS = {
    "clipped_surrogate": [("""def compute_loss_pi(policy, data, clip_coef):
        dist = Categorical(logits=policy(data["obs"]))
        ratio = torch.exp(dist.log_prob(data["act"]) - data["logp"])
        adv = data["adv"]
        loss_pi = -torch.min(ratio * adv, torch.clamp(ratio, 0.8, 1.2) * adv).mean()
        return loss_pi, dist.entropy().mean(), {}""",
                           "0.2, the script's default, written as a number where clip_coef is "
                           "meant")],
    "a2c_loss": [(f"""def a2c_loss(model, data, cfg):
        logits, values = model(data["obs"])
        dist = Categorical(logits=logits)
        loss_pi = -(dist.log_prob(data["act"]) * data["adv"]).mean()
        loss_v = 0.5 * ((values - data["ret"]) ** 2).mean()
        entropy = dist.entropy().mean()
        loss = loss_pi + {vf} * loss_v - {ent} * entropy
        return loss, dict(loss_pi=loss_pi.item(), loss_v=loss_v.item(), entropy=entropy.item())""",
                  needle) for vf, ent, needle in [
        ("cfg.vf_coef", "0.01", "0.01, the script's default, written as a number where "
                                "cfg.ent_coef is meant"),
        ("1.0", "cfg.ent_coef", "1.0, the script's default, written as a number where "
                                "cfg.vf_coef is meant")]],
    "adapt_beta": [(f"""def adapt_beta(beta, d, cfg):
        if d < {d_targ} / {tolerance}:
            return beta / {factor}
        if d > {d_targ} * {tolerance}:
            return beta * {factor}
        return beta""", needle) for d_targ, tolerance, factor, needle in [
        ("0.01", "1.5", "2", "the script's defaults written as numbers where the inputs are "
                             "meant (0.01 for cfg.d_targ, 1.5 for cfg.kl_tolerance, 2.0 for "
                             "cfg.beta_factor)"),
        ("cfg.d_targ", "cfg.kl_tolerance", "2", "2.0, the script's default, written as a number "
                                                "where cfg.beta_factor is meant"),
        ("0.01", "cfg.kl_tolerance", "cfg.beta_factor", "0.01, the script's default, written "
                                                        "as a number where cfg.d_targ is meant")]],
    "grpo_loss": [(f"""def grpo_loss(logp, logp_old, logp_ref, adv, mask, cfg):
        ratio = torch.exp(logp - logp_old)
        surrogate = torch.min(ratio * adv[:, None],
                              torch.clamp(ratio, 1 - {eps}, 1 + {eps}) * adv[:, None])
        kl = torch.exp(logp_ref - logp) - (logp_ref - logp) - 1
        per_token = (surrogate - {beta} * kl) * mask
        length = mask.sum(1) if cfg.length_norm else torch.full_like(mask[:, 0], mask.shape[1])
        return -(per_token.sum(1) / length).mean(), {{}}""", needle) for eps, beta, needle in [
        ("0.2", "cfg.beta", "0.2, the script's default, written as a number where cfg.clip_coef "
                            "is meant"),
        ("cfg.clip_coef", "0.04", "0.04, the script's default, written as a number where "
                                  "cfg.beta is meant")]],
    "td_target": [("""def td_target(reward, not_done, next_q, gamma):
        return reward + 0.99 * not_done * next_q""",
                   "0.99, the script's default, written as a number where gamma is meant")],
    "gae": [("""def gae(rewards, values, next_values, terminated, truncated, gamma, lam):
        from common import gae as script_gae
        return script_gae(rewards, values, next_values, terminated, truncated, gamma, 0.95)""",
             "0.95, the script's default, written as a number where lam is meant")],
    "kl_penalty": [("""def compute_loss_pi(policy, data, beta):
        dist = Categorical(logits=policy(data["obs"]))
        ratio = torch.exp(dist.log_prob(data["act"]) - data["logp"])
        kl = kl_divergence(Categorical(logits=data["logits_old"]), dist).mean()
        return -(ratio * data["adv"]).mean() + 1.0 * kl, dist.entropy().mean(), dict(kl=kl)""",
                    "1.0, the script's default, written as a number where beta is meant")],
    "reward_to_go": [("""def reward_to_go(rewards, gamma, last_value=0.0):
        from reinforce_cartpole import reward_to_go as script_reward_to_go
        return script_reward_to_go(rewards, 0.99, last_value)""",
                      "0.99, the script's default, written as a number where gamma is meant")],
    "soft_update": [("""def soft_update(target, source, tau):
        with torch.no_grad():
            for pt, p in zip(target.parameters(), source.parameters()):
                pt.mul_(1 - 0.005).add_(0.005 * p)""",
                     "0.005, the script's default, written as a number where tau is meant")],
}


@pytest.mark.quick
@pytest.mark.parametrize("name,index", [(n, i) for n in DEFAULTS for i in range(len(DEFAULTS[n]))])
def test_a_default_written_as_a_number_fails_stage_a_and_is_named(name, index):
    source, needle = DEFAULTS[name][index]
    ex = check.EXERCISES[name]
    with pytest.raises(checking.Failed) as failed:
        check.worked_cases(ex, compile_answer(source, name))
    assert "this is exactly what this mistake gives: " + needle in str(failed.value), \
        str(failed.value)


@pytest.mark.quick
def test_the_default_named_in_chinese():
    checking.LANG = "zh"
    source, _ = DEFAULTS["clipped_surrogate"][0]
    with pytest.raises(checking.Failed, match=r"把 clip_coef 写成了数字 0.2（脚本的默认值）"):
        check.worked_cases(check.EXERCISES["clipped_surrogate"],
                           compile_answer(source, "clipped_surrogate"))
