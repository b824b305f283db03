"""ppo_reacher.py: the Gaussian log-probability against torch and a brute-force density,
tutorial 002's early stop on a hand-made batch, the running statistics through model.pt,
--eval and --resume, the env's clip, and a seeded run that learns the arm."""

import copy
import math

import numpy as np
import pytest
import torch

import ppo_reacher as ppo
from conftest import interrupt, run_folders, run_main

SHORT = dict(num_steps=100, eval_every=200, eval_episodes=2, train_pi_iters=5, train_v_iters=5,
             print_every=100)


def flags(**overrides):
    out = []
    for name, value in overrides.items():
        flag = "--" + name.replace("_", "-")
        out += ([flag] if value is True else [flag.replace("--", "--no-", 1)] if value is False
                else [flag, str(value)])
    return out


@pytest.mark.quick
def test_gaussian_log_prob_is_torchs_and_the_density_by_brute_force():
    """Against Normal(mu, sigma).log_prob summed over dimensions, and against the density by
    hand: the product of the 1-D densities, which integrates to 1 over a fine grid and gives
    the share of samples that fall into a small box."""
    torch.manual_seed(0)
    mu, log_std = torch.randn(5, 3), torch.randn(3) * 0.5
    act = mu + torch.randn(5, 3) * 2
    expected = torch.distributions.Normal(mu, log_std.exp()).log_prob(act).sum(-1)
    assert torch.allclose(ppo.gaussian_log_prob(mu, log_std, act), expected, atol=1e-6)
    sigma = log_std.exp()
    by_hand = torch.prod(torch.exp(-(act - mu) ** 2 / (2 * sigma ** 2))
                         / (sigma * math.sqrt(2 * math.pi)), -1)
    assert torch.allclose(ppo.gaussian_log_prob(mu, log_std, act).exp(), by_hand, rtol=1e-5)
    # two dimensions on a grid: the density integrates to 1, and predicts a box's samples
    mu2, log_std2 = torch.tensor([[0.3, -0.2]]), torch.tensor([-0.5, 0.2])
    x = torch.linspace(-6, 6, 601, dtype=torch.float64)
    grid = torch.stack(torch.meshgrid(x, x, indexing="ij"), -1).reshape(-1, 2)
    dens = ppo.gaussian_log_prob(mu2.double(), log_std2.double(), grid).exp()
    assert float(dens.sum() * (x[1] - x[0]) ** 2) == pytest.approx(1.0, abs=1e-4)
    samples = torch.distributions.Normal(mu2, log_std2.exp()).sample((1_000_000,)).reshape(-1, 2)
    inside = ((samples - torch.tensor([0.4, 0.0])).abs() < 0.1).all(-1).double().mean()
    mid = torch.linspace(-0.1, 0.1, 201, dtype=torch.float64)  # the box's cells' midpoints
    mid = (mid[1:] + mid[:-1]) / 2
    cells = torch.stack(torch.meshgrid(mid + 0.4, mid, indexing="ij"), -1).reshape(-1, 2)
    box = ppo.gaussian_log_prob(mu2.double(), log_std2.double(), cells).exp().sum() * 0.001 ** 2
    assert float(box) == pytest.approx(float(inside), rel=0.04)


@pytest.mark.quick
def test_the_policy_gives_its_distribution_and_log_pi_of_the_actions():
    torch.manual_seed(0)
    policy = ppo.PolicyNetwork(4, 2, 8, log_std_init=-0.5)
    obs, act = torch.randn(3, 4), torch.randn(3, 2)
    pi, logp = policy(obs, act)
    assert torch.allclose(pi.stddev, torch.full((3, 2), math.exp(-0.5)))
    assert torch.allclose(logp, pi.log_prob(act).sum(-1), atol=1e-6) and logp.shape == (3,)


def batch(n=64, seed=0):
    torch.manual_seed(seed)
    obs, act = torch.randn(n, 3), torch.randn(n, 2)
    return dict(obs=obs, act=act, adv=torch.randn(n), ret=torch.randn(n))


def nets(lr=1e-2):
    torch.manual_seed(1)
    policy, value = ppo.PolicyNetwork(3, 2, 16, 0.0), ppo.ValueNetwork(3, 16)
    return (policy, value, torch.optim.Adam(policy.parameters(), lr=lr),
            torch.optim.Adam(value.parameters(), lr=1e-3))


@pytest.mark.quick
def test_the_early_stop_stops_before_the_step_at_which_kl_passes_1_5_target_kl():
    """Replayed by hand: each policy step's approx_kl before it; update() stops at the first
    i whose kl exceeds 1.5 x target_kl, having taken i steps, and V still takes all of its."""
    cfg = ppo.Config(train_pi_iters=40, train_v_iters=7, target_kl=0.01)
    policy, value, pi_opt, vf_opt = nets(lr=3e-3)
    data = batch()
    with torch.no_grad():
        data["logp"] = policy(data["obs"], data["act"])[1]
    kls, replay, opt = [], copy.deepcopy(policy), None
    opt = torch.optim.Adam(replay.parameters(), lr=3e-3)
    for i in range(cfg.train_pi_iters):
        loss, info = ppo.compute_loss_pi(replay, data, cfg.clip_ratio)
        kls.append(info["kl"])
        if info["kl"] > 1.5 * cfg.target_kl:
            break
        opt.zero_grad()
        loss.backward()
        opt.step()
    first = next(i for i, kl in enumerate(kls) if kl > 0.015)
    assert 1 < first < cfg.train_pi_iters  # the hand-made batch stops in the middle
    v_before = copy.deepcopy(value.state_dict())
    _, _, _, stop_iter = ppo.update(policy, value, pi_opt, vf_opt, data, cfg)
    assert stop_iter == first
    assert all(torch.equal(a, b) for a, b in zip(policy.state_dict().values(),
                                                  replay.state_dict().values()))
    assert vf_opt.state[next(iter(value.parameters()))]["step"] == cfg.train_v_iters
    assert not torch.equal(v_before["v_net.0.weight"], value.state_dict()["v_net.0.weight"])


@pytest.mark.quick
def test_a_batch_already_past_the_limit_takes_no_policy_step_and_v_still_learns():
    cfg = ppo.Config(train_pi_iters=10, train_v_iters=3, target_kl=0.01)
    policy, value, pi_opt, vf_opt = nets()
    data = batch()
    with torch.no_grad():
        data["logp"] = policy(data["obs"], data["act"])[1] + 1.0  # approx_kl = 1 at once
    before = copy.deepcopy(policy.state_dict())
    *_, stop_iter = ppo.update(policy, value, pi_opt, vf_opt, data, cfg)
    assert stop_iter == 0 and all(torch.equal(before[k], v) for k, v in policy.state_dict().items())
    assert vf_opt.state[next(iter(value.parameters()))]["step"] == 3
    cfg = ppo.Config(train_pi_iters=10, train_v_iters=3, target_kl=None)  # none: never stops
    assert ppo.update(policy, value, pi_opt, vf_opt, data, cfg)[3] == 10


@pytest.mark.quick
def test_the_clipped_surrogate_and_the_value_loss_by_hand():
    """One sample per case: r = e^(logp - logp_old); the loss is -min(rA, clip(r)A)."""
    policy, value, _, _ = nets()
    data = batch(n=2)
    with torch.no_grad():
        logp = policy(data["obs"], data["act"])[1]
    data["logp"] = logp - torch.tensor([math.log(1.5), math.log(0.5)])  # r = 1.5 and 0.5
    data["adv"] = torch.tensor([2.0, 2.0])
    loss, info = ppo.compute_loss_pi(policy, data, clip_ratio=0.2)
    assert float(loss.detach()) == pytest.approx(-(1.2 * 2 + 0.5 * 2) / 2, abs=1e-5)
    kl = -(math.log(1.5) + math.log(0.5)) / 2  # E[log pi_old - log pi] = E[-log r]
    assert info["cf"] == 1.0 and info["kl"] == pytest.approx(kl, abs=1e-5)
    with torch.no_grad():
        v = value(data["obs"])
    assert float(ppo.compute_loss_v(value, data).detach()) == pytest.approx(
        float(((v - data["ret"]) ** 2).mean()), abs=1e-6)


@pytest.mark.quick
def test_running_norm_is_the_mean_and_variance_of_all_it_has_seen():
    torch.manual_seed(0)
    norm, seen = ppo.common.RunningNorm(3), torch.randn(50, 3) * 4 + 2
    for part in seen.split([7, 20, 23]):
        norm.update(part)
    assert torch.allclose(norm.mean, seen.double().mean(0), atol=1e-5)
    assert torch.allclose(norm.var, seen.double().var(0, unbiased=False), rtol=1e-4)
    x = torch.tensor([[100.0, 2.0, 2.0]])
    assert float(norm(x)[0, 0]) == 10.0  # clipped to +-10
    assert torch.equal(ppo.common.RunningNorm(3, active=False)(x), x)  # off: as it is


def test_the_env_gets_the_action_clipped_and_the_buffer_keeps_it_as_drawn(monkeypatch, tmp_path):
    """log pi of the sample, not of the clipped action: the ratio is of the density that drew
    it; the env gets it inside its box."""
    played, kept = [], []
    step, store = ppo.common.gym.vector.SyncVectorEnv.step, ppo.RolloutBuffer.store

    def spy_step(self, action):
        played.append(np.array(action))
        return step(self, action)

    def spy_store(self, t, obs, action, *args, **kw):
        kept.append(np.array(action))
        return store(self, t, obs, action, *args, **kw)

    monkeypatch.setattr(ppo.common.gym.vector.SyncVectorEnv, "step", spy_step)
    monkeypatch.setattr(ppo.RolloutBuffer, "store", spy_store)
    ppo.train(ppo.Config(**{**SHORT, "print_every": 10**6}, total_timesteps=200,
                         log_std_init=1.0, gifs=False, curves=False, run_dir=str(tmp_path)))
    played, kept = np.concatenate(played), np.concatenate(kept)
    assert np.abs(kept).max() > 1.5 and np.abs(played).max() <= 1.0  # Reacher's box: [-1, 1]
    assert np.array_equal(played, np.clip(kept, -1, 1))


@pytest.mark.parametrize("extra", [dict(), dict(update="minibatch", num_minibatches=4)],
                         ids=["full_batch", "minibatch"])
def test_ctrl_c_then_resume_is_the_unbroken_run_with_its_statistics(tmp_path, extra):
    """Both normalisations on: Ctrl-C writes a checkpoint at a whole update; --resume ends as
    the run that never stopped, the same logs byte for byte, the same weights, optimizers and
    running statistics; --eval of its model.pt replays the last evaluation (the statistics
    travel in model.pt); --eval of checkpoint.pt says it is for --resume."""
    run = dict(SHORT, total_timesteps=1200, norm_reward=True, checkpoint_every=400,
               gifs=False, **extra)
    unbroken = ppo.train(ppo.Config(**run, run_dir=str(tmp_path / "unbroken")))
    code, out, err = interrupt("ppo_reacher.py", *flags(**run), "--run-dir", tmp_path / "cut",
                               after="step      600")
    assert code == 130, err
    (cut,) = run_folders(tmp_path / "cut")
    stopped = torch.load(cut / "checkpoint.pt", weights_only=True)["global_step"]
    assert 600 <= stopped < 1200 and f"its checkpoint is at step {stopped}" in out
    ppo.train(ppo.Config(resume=str(cut)))
    for name in ("evaluations.csv", "episodes.csv"):
        assert (cut / name).read_bytes() == (unbroken["run_dir"] / name).read_bytes(), name
    a, b = (torch.load(d / "checkpoint.pt", weights_only=True) for d in (unbroken["run_dir"], cut))
    for key in ("policy", "value", "obs_norm", "return_norm"):
        assert all(torch.equal(b[key][k], v) for k, v in a[key].items()), key
    assert a["obs_norm"]["count"] > 1000 and a["return_norm"]["var"] != 1
    model = torch.load(cut / "model.pt", weights_only=True)["actor"]
    assert torch.equal(model["obs_norm.mean"], a["obs_norm"]["mean"])
    cfg = ppo.Config(eval=str(cut / "model.pt"), eval_episodes=2)
    actor, _ = ppo.checkpoints.load_model(cfg.eval, ppo.SCRIPT, "actor", lambda c: ppo.MeanActor(
        ppo.common.RunningNorm(c["obs_dim"]), ppo.PolicyNetwork(c["obs_dim"], c["act_dim"], 64, 0.0),
        np.array(c["low"]), np.array(c["high"])))
    returns = ppo.common.evaluate("Reacher-v5", ppo.common.deterministic(actor, "cpu"), 2, 10_000)
    assert np.mean(returns) == pytest.approx(unbroken["evaluations"][-1]["eval_mean"], abs=1e-4)
    with pytest.raises(ppo.common.UserError, match="is the run's checkpoint, for --resume"):
        ppo.checkpoints.load_model(cut / "checkpoint.pt", ppo.SCRIPT, "actor", None)  # not --eval


@pytest.mark.parametrize("args,needle", [
    (["--update", "epochs"], "--update is full_batch or minibatch"),
    (["--num-envs", "3"], "must divide --print-every"),
    (["--env-id", "CartPole-v1"], "is not a MuJoCo env"),
    (["--target-kl", "0"], "--target-kl must be positive or none"),
])
def test_bad_input_is_one_line_and_exit_2(tmp_path, args, needle, capsys):
    p = run_main("ppo_reacher.py", *args, "--run-dir", tmp_path, capsys=capsys)
    assert p.returncode == 2 and needle in p.stderr, (p.stdout, p.stderr)
    assert len(p.stderr.strip().splitlines()) == 1 and not list(tmp_path.iterdir())


@pytest.mark.slow
def test_learns_to_reach_with_a_fixed_seed(tmp_path):
    """Seed 0, rollouts of 1000 steps, 60,000 steps: the untrained mean action scores -13.8
    (mu is near 0: the arm barely moves, the fingertip stays ~0.2 from the target); after
    60,000 steps -8.1, the fingertip ~0.1 away (at the defaults, 1M steps: docs/results.md)."""
    result = ppo.train(ppo.Config(total_timesteps=60_000, num_steps=1000, eval_every=20_000,
                                  gifs=False, curves=False, print_every=10**6,
                                  run_dir=str(tmp_path)))
    first, last = result["evaluations"][0], result["evaluations"][-1]
    assert first["global_step"] == 0 and first["eval_mean"] < -12, first
    assert last["global_step"] == 60_000, last
    assert last["eval_mean"] > -10 and last["distance"] < first["distance"] - 0.05, last
