"""PPO-clip's own pieces: the clipped surrogate, the update's minibatches and early stop,
and the learning-rate schedule."""

import csv

import pytest
import torch
from torch.distributions import Categorical

import ppo_cartpole as ppo

pytestmark = pytest.mark.quick  # the algorithm's pieces: pytest -m quick runs these


class FixedPolicy(torch.nn.Module):
    """pi(.|s) from one free logit vector per state: the ratio is set by hand."""

    def __init__(self, logits):
        super().__init__()
        self.logits = torch.nn.Parameter(logits.clone())

    def forward(self, obs):
        return self.logits


@pytest.mark.parametrize("adv,ratio,grad_is_zero", [
    (+1.0, 1.5, True),   # A > 0 and r > 1 + eps: clipped, no push to raise pi(a|s) further
    (+1.0, 1.1, False),  # A > 0 inside the range: the gradient raises pi(a|s)
    (+1.0, 0.5, False),  # A > 0 and r < 1 - eps: min() keeps the unclipped term, still pushed
    (-1.0, 0.5, True),   # A < 0 and r < 1 - eps: clipped, no push to lower pi(a|s) further
    (-1.0, 0.9, False),
    (-1.0, 1.5, False),  # A < 0 and r > 1 + eps: the unclipped term, pulled back
])
def test_clipped_surrogate_gradient_is_zero_only_on_the_clipped_side(adv, ratio, grad_is_zero):
    """L_CLIP = min(r A, clip(r, 1 - eps, 1 + eps) A) (eq. 7): flat where the clip binds."""
    policy = FixedPolicy(torch.log(torch.tensor([[0.4, 0.6]])))
    act = torch.tensor([1])
    logp_old = torch.log(torch.tensor([0.6 / ratio]))  # so that r = pi / pi_old = ratio
    data = dict(obs=None, act=act, adv=torch.tensor([adv]), logp=logp_old)
    loss, _, info = ppo.compute_loss_pi(policy, data, 0.2)
    r = ratio
    assert loss.item() == pytest.approx(-min(r * adv, min(max(r, 0.8), 1.2) * adv), rel=1e-5)
    assert info["clipfrac"].item() == (1.0 if abs(r - 1) > 0.2 else 0.0)
    loss.backward()
    grad = policy.logits.grad.abs().sum().item()
    assert (grad == 0) if grad_is_zero else (grad > 1e-3)
    if not grad_is_zero:  # descending the loss moves pi(a|s) the way A says
        assert (policy.logits.grad[0, 1] < 0) == (adv > 0)


def test_approx_kl_is_zero_at_pi_old_and_positive_after():
    torch.manual_seed(0)
    policy = ppo.PolicyNetwork(4, 2, 16)
    obs, act, adv = torch.randn(64, 4), torch.randint(0, 2, (64,)), torch.randn(64)
    with torch.no_grad():
        logp_old = Categorical(logits=policy(obs)).log_prob(act)
    data = dict(obs=obs, act=act, adv=adv, logp=logp_old)
    _, _, info = ppo.compute_loss_pi(policy, data, 0.2)
    assert info["approx_kl"].item() == pytest.approx(0.0, abs=1e-7)
    with torch.no_grad():
        for p in policy.parameters():
            p.add_(0.3 * torch.randn_like(p))
    _, _, info = ppo.compute_loss_pi(policy, data, 0.2)
    assert info["approx_kl"].item() > 1e-4


def batch(B=30, seed=0):
    torch.manual_seed(seed)
    policy, value_net = ppo.PolicyNetwork(4, 2, 8), ppo.ValueNetwork(4, 8)
    obs, act = torch.randn(B, 4), torch.randint(0, 2, (B,))
    with torch.no_grad():
        logp = Categorical(logits=policy(obs)).log_prob(act)
    return policy, value_net, dict(obs=obs, act=act, logp=logp, adv=torch.randn(B),
                                   ret=torch.randn(B))


@pytest.mark.parametrize("B,minibatches", [(30, 4), (7, 4), (256, 4), (250, 8)])
def test_update_takes_exactly_epochs_times_minibatches_steps(B, minibatches):
    policy, value_net, data = batch(B)
    opt = torch.optim.Adam([*policy.parameters(), *value_net.parameters()], lr=1e-3)
    cfg = ppo.Config(update_epochs=3, num_minibatches=minibatches)
    ppo.ppo_update(policy, value_net, opt, data, cfg)
    assert opt.state_dict()["state"][0]["step"].item() == 3 * minibatches


def test_early_stop_halts_the_policy_and_keeps_training_v():
    """Tutorial 002: once approx_kl > 1.5 * target_kl, no more policy steps; V goes on."""
    policy, value_net, data = batch(64)
    opt = torch.optim.Adam([*policy.parameters(), *value_net.parameters()], lr=0.05)
    cfg = ppo.Config(update_epochs=10, num_minibatches=4, target_kl=1e-6)  # stops at once
    stats = ppo.ppo_update(policy, value_net, opt, data, cfg)
    state = opt.state_dict()["state"]
    n_policy = len(list(policy.parameters()))
    steps = [state[i]["step"].item() for i in sorted(state)]
    # The first minibatch sees pi = pi_old (KL 0) and steps; after that the policy is frozen.
    assert steps[:n_policy] == [1] * n_policy and stats["policy_stopped"] == 1
    assert steps[n_policy:] == [40] * (len(steps) - n_policy)  # V: 10 epochs x 4 minibatches


def test_early_stop_checks_the_whole_batch_and_sticks(monkeypatch):
    """Tutorial 002 checks approx_kl on the whole batch before each policy step; once it has
    stopped the policy, a KL that dips again (here: a scripted one) does not restart it."""
    policy, value_net, data = batch(64)
    opt = torch.optim.Adam([*policy.parameters(), *value_net.parameters()], lr=1e-3)
    seen, kls = [], iter([0.0, 0.001, 1.0] + [0.0] * 100)  # above 1.5 x 0.01 once, then low

    def approx_kl(policy, batch, cfg):
        seen.append(len(batch["obs"]))
        return next(kls)

    monkeypatch.setattr(ppo, "approx_kl", approx_kl)
    cfg = ppo.Config(update_epochs=10, num_minibatches=4, target_kl=0.01)
    stats = ppo.ppo_update(policy, value_net, opt, data, cfg)
    state = opt.state_dict()["state"]
    n_policy = len(list(policy.parameters()))
    assert [state[i]["step"].item() for i in range(n_policy)] == [2] * n_policy  # 2 steps, no more
    assert stats["policy_stopped"] == 1
    # Checked before the 1st, 2nd and 3rd policy steps, each time on all 64 rows, and no more
    # (the log's KL after the update comes from compute_loss_pi on the whole batch).
    assert seen == [64] * 3


def test_logged_approx_kl_is_pi_after_the_update_against_pi_old_on_the_whole_batch():
    policy, value_net, data = batch(64)
    opt = torch.optim.Adam([*policy.parameters(), *value_net.parameters()], lr=0.01)
    stats = ppo.ppo_update(policy, value_net, opt, data, ppo.Config(update_epochs=4))
    with torch.no_grad():
        log_r = Categorical(logits=policy(data["obs"])).log_prob(data["act"]) - data["logp"]
    assert stats["approx_kl"] == pytest.approx(((log_r.exp() - 1) - log_r).mean().item(), rel=1e-5)
    assert stats["approx_kl"] > 1e-4


def test_the_update_measures_the_ratio_against_pi_old():
    """After a few steps pi has moved: ratios leave the clip range (a loop that recomputed
    logp_old from the moving policy would see r = 1 throughout and never clip)."""
    policy, value_net, data = batch(256)
    opt = torch.optim.Adam([*policy.parameters(), *value_net.parameters()], lr=0.05)
    stats = ppo.ppo_update(policy, value_net, opt, data, ppo.Config(update_epochs=10))
    assert stats["clipfrac"] > 0.05


def test_learning_rate_anneals_linearly_to_zero(tmp_path):
    cfg = ppo.Config(total_timesteps=256 * 5, stop_when_solved=False, gifs=False, curves=False,
                     eval_episodes=1, run_dir=str(tmp_path), print_every=10**6)
    rows = list(csv.DictReader(open(ppo.train(cfg)["run_dir"] / "progress.csv")))
    # lr_k = lr * (1 - (k - 1) / K) for updates k = 1..K: 4e-3, 3.2e-3, ..., 0.8e-3
    assert [float(r["lr"]) for r in rows] == pytest.approx([4e-3 * (1 - k / 5) for k in range(5)])
    cfg.anneal_lr = False
    rows = list(csv.DictReader(open(ppo.train(cfg)["run_dir"] / "progress.csv")))
    assert {float(r["lr"]) for r in rows} == {4e-3}


def test_each_update_logs_clipfrac_and_the_zero_gradient_share_on_the_same_ratios(
        monkeypatch, tmp_path):
    """After each update: clipfrac_after and zero_grad_frac are counted on the very ratios
    of the whole batch after the update, and the zero-gradient share is never above it."""
    seen = []
    real = ppo.common.ratio_stats
    monkeypatch.setattr(ppo.common, "ratio_stats",
                        lambda ratio, *a: (seen.append(ratio.clone()), real(ratio, *a))[1])
    cfg = ppo.Config(total_timesteps=256 * 8, stop_when_solved=False, gifs=False, curves=False,
                     eval_episodes=1, run_dir=str(tmp_path), print_every=10**6)
    rows = list(csv.DictReader(open(ppo.train(cfg)["run_dir"] / "progress.csv")))
    assert len(rows) == len(seen) == 8
    for row, ratio in zip(rows, seen):
        outside = ((ratio - 1).abs() > cfg.clip_coef).double().mean().item()
        assert float(row["clipfrac_after"]) == pytest.approx(outside, abs=1e-6)
        assert float(row["zero_grad_frac"]) <= float(row["clipfrac_after"])
    assert list(rows[0])[-1] == "clipfrac_after"  # a new column goes at the end of the log


def grads_of_the_first_step(update, params, *args):
    """The gradient the update's first optimizer step uses (the step itself moves nothing)."""
    opt, seen = torch.optim.SGD(params, lr=0.0), []
    real_step = opt.step

    def step(*a, **kw):
        seen.append([p.grad.clone() for p in params])
        return real_step(*a, **kw)
    opt.step = step
    update(*args[:2], opt, *args[2:])
    return seen[0]


@pytest.mark.parametrize("ent_coef,vf_coef", [(0.1, 0.7), (0.0, 0.5)])
def test_the_update_descends_the_papers_whole_loss_each_coefficient_counting(ent_coef, vf_coef):
    """ppo_update's step follows the gradient of -L_CLIP + c1 L_VF - c2 S[pi] (eq. 9), computed
    here by hand: the entropy bonus (c2 > 0, its sign) and c1 each count."""
    policy, value_net, data = batch(B=40)
    with torch.no_grad():  # pi moves away from pi_old: some ratios leave the clip range
        for p in policy.parameters():
            p.add_(0.5 * torch.randn_like(p))
    params = [*policy.parameters(), *value_net.parameters()]
    dist = Categorical(logits=policy(data["obs"]))
    r, adv = torch.exp(dist.log_prob(data["act"]) - data["logp"]), data["adv"]
    assert 0 < ((r - 1).abs() > 0.2).float().mean() < 1
    l_clip = torch.min(r * adv, torch.clamp(r, 0.8, 1.2) * adv).mean()
    l_vf = 0.5 * ((value_net(data["obs"]) - data["ret"]) ** 2).mean()
    loss = -l_clip + vf_coef * l_vf - ent_coef * dist.entropy().mean()
    expected = torch.autograd.grad(loss, params)
    cfg = ppo.Config(update_epochs=1, num_minibatches=1, norm_adv=False, max_grad_norm=0.0,
                     ent_coef=ent_coef, vf_coef=vf_coef)
    seen = grads_of_the_first_step(ppo.ppo_update, params, policy, value_net, data, cfg)
    for got, want in zip(seen, expected):
        torch.testing.assert_close(got, want)
