"""PPO-penalty's pieces of its own: the KL-penalized loss and the adaptive beta rule."""

import pytest
import torch
from torch.distributions import Categorical

import ppo_kl_cartpole as kl

pytestmark = pytest.mark.quick  # the algorithm's pieces: pytest -m quick runs these


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
                                gifs=False, curves=False, eval_episodes=1, print_every=10**6))
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


@pytest.mark.parametrize("ent_coef,vf_coef,beta", [(0.1, 0.7, 3.0), (0.0, 0.5, 0.5)])
def test_the_update_descends_the_papers_whole_loss_each_coefficient_counting(ent_coef, vf_coef,
                                                                           beta):
    """ppo_update's step follows the gradient of -(E[r A] - beta KL) + c1 L_VF - c2 S[pi]
    (eqs. 8 and 9), computed here by hand: beta, c1 and c2 (its sign) each count."""
    from test_ppo_cartpole import grads_of_the_first_step

    torch.manual_seed(0)
    policy, value_net = kl.PolicyNetwork(4, 2, 8), kl.ValueNetwork(4, 8)
    obs, act = torch.randn(40, 4), torch.randint(0, 2, (40,))
    with torch.no_grad():
        logits_old = policy(obs)
        for p in policy.parameters():  # pi moves away from pi_old: the KL is not 0
            p.add_(0.5 * torch.randn_like(p))
    data = dict(obs=obs, act=act, logp=Categorical(logits=logits_old).log_prob(act),
                adv=torch.randn(40), ret=torch.randn(40), logits_old=logits_old)
    params = [*policy.parameters(), *value_net.parameters()]
    dist = Categorical(logits=policy(obs))
    r = torch.exp(dist.log_prob(act) - data["logp"])
    kl_old_new = (torch.softmax(logits_old, -1) * (torch.log_softmax(logits_old, -1)
                                                   - torch.log_softmax(policy(obs), -1))).sum(-1)
    assert kl_old_new.mean() > 1e-3
    l_vf = 0.5 * ((value_net(obs) - data["ret"]) ** 2).mean()
    loss = (-(r * data["adv"]).mean() + beta * kl_old_new.mean() + vf_coef * l_vf
            - ent_coef * dist.entropy().mean())
    expected = torch.autograd.grad(loss, params)
    cfg = kl.Config(update_epochs=1, num_minibatches=1, norm_adv=False, max_grad_norm=0.0,
                    ent_coef=ent_coef, vf_coef=vf_coef)
    seen = grads_of_the_first_step(kl.ppo_update, params, policy, value_net, data, beta, cfg)
    for got, want in zip(seen, expected):
        torch.testing.assert_close(got, want)
