"""PPO-penalty's pieces of its own: the KL-penalized loss and the adaptive beta rule."""

import pytest
import torch
from torch.distributions import Categorical, kl_divergence

import ppo_kl_cartpole as kl


@pytest.mark.parametrize("d,expected", [
    (0.001, 0.5),    # d < d_targ / 1.5: pi barely moved, halve beta
    (0.0066, 0.5),   # just under 0.01 / 1.5
    (0.0067, 1.0),   # inside the band: hold
    (0.01, 1.0),
    (0.015, 1.0),    # the upper edge itself holds
    (0.0151, 2.0),   # d > d_targ * 1.5: pi moved too far, double beta
    (0.5, 2.0),
])
def test_beta_rule_halves_holds_doubles(d, expected):
    cfg = kl.Config(d_targ=0.01, kl_tolerance=1.5, beta_factor=2.0)
    assert kl.adapt_beta(1.0, d, cfg) == expected


def test_beta_rule_uses_the_named_fields():
    cfg = kl.Config(d_targ=0.02, kl_tolerance=2.0, beta_factor=3.0)
    assert kl.adapt_beta(0.9, 0.0099, cfg) == pytest.approx(0.3)
    assert kl.adapt_beta(0.9, 0.041, cfg) == pytest.approx(2.7)
    assert kl.adapt_beta(0.9, 0.02, cfg) == 0.9


def test_loss_penalizes_moving_away_from_pi_old():
    """At pi = pi_old the KL term is 0; moved away, it costs beta * KL on top of -E[r*A]."""
    torch.manual_seed(1)
    policy = kl.PolicyNetwork(4, 2, 16)
    obs, act, adv = torch.randn(32, 4), torch.randint(0, 2, (32,)), torch.randn(32)
    with torch.no_grad():
        logits_old = policy(obs)
    logp_old = Categorical(logits=logits_old).log_prob(act)
    data = dict(obs=obs, act=act, adv=adv, logp=logp_old, logits_old=logits_old)
    loss0, _, info = kl.compute_loss_pi(policy, data, beta=5.0)
    assert loss0.item() == pytest.approx(-adv.mean().item(), abs=1e-6)  # r = 1, KL = 0
    assert info["kl"].item() == pytest.approx(0.0, abs=1e-7)
    with torch.no_grad():
        for p in policy.parameters():
            p.add_(0.5 * torch.randn_like(p))
    loss_b0, _, _ = kl.compute_loss_pi(policy, data, beta=0.0)
    loss_b5, _, info = kl.compute_loss_pi(policy, data, beta=5.0)
    # KL(pi_old || pi) by hand: sum_a pi_old(a|s) (log pi_old(a|s) - log pi(a|s)), averaged.
    lp_old, lp = torch.log_softmax(logits_old, -1), torch.log_softmax(policy(obs), -1)
    d = (lp_old.exp() * (lp_old - lp)).sum(-1).mean()
    assert d > 0 and info["kl"].item() == pytest.approx(d.item(), rel=1e-5)
    assert (loss_b5 - loss_b0).item() == pytest.approx(5.0 * d.item(), rel=1e-5)


def test_beta_and_kl_are_logged(tmp_path):
    result = kl.train(kl.Config(run_dir=str(tmp_path), total_timesteps=3000, stop_when_solved=False,
                                gifs=False, eval_episodes=1, print_every=10**6))
    import csv

    rows = list(csv.DictReader(open(result["run_dir"] / "progress.csv")))
    assert {"beta", "kl"} <= set(rows[0])
    betas = [float(r["beta"]) for r in rows]
    assert betas[0] == 1.0
    # Every change follows the rule: by the factor 2, in the direction the KL asked for.
    for prev, cur, row in zip(betas, betas[1:], rows):
        d = float(row["kl"])
        expected = prev / 2 if d < 0.01 / 1.5 else prev * 2 if d > 0.015 else prev
        assert cur == pytest.approx(expected, rel=1e-4)
