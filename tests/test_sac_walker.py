"""SAC: its soft TD target, the tanh squash's log-probability correction and the temperature's
loss against hand computations and brute force, the diff from TD3 kept small, exact resume
after Ctrl-C, --eval of a saved actor and clear errors. (What the loop stores and what each
critic update is fed: tests/test_replay_loops.py.)"""

import difflib
import sys
import math

import numpy as np
import pytest
import torch

import sac_walker as sac
from conftest import ROOT, interrupt, run_folders, run_main
from test_ddpg_walker import PENDULUM, pendulum_flags, play


@pytest.mark.quick
def test_soft_td_target_subtracts_alpha_log_pi_from_the_smaller_q_by_hand():
    """y = r + gamma * not_done * (min(Q1', Q2') - alpha * log pi(a'|s')), alpha = 0.5,
    gamma = 0.9: 1 + 0.9 * (3 - 0.5 * -2) = 4.6 (Q2' the smaller, an unlikely a' adds
    entropy), 1 + 0.9 * (5 - 0.5 * 4) = 3.7 (Q1' the smaller, a likely a' costs), and no
    future after a termination: 1."""
    y = sac.td_target(torch.tensor([1.0, 1.0, 1.0]), torch.tensor([1.0, 1.0, 0.0]),
                      torch.tensor([5.0, 5.0, 5.0]), torch.tensor([3.0, 9.0, 9.0]),
                      torch.tensor([-2.0, 4.0, 4.0]), 0.5, 0.9)
    assert y.tolist() == pytest.approx([4.6, 3.7, 1.0])


def squashed_cdf(x, mean, std, low, high):
    """P(a <= x) for a = bias + scale * tanh(u), u ~ N(mean, std), one dimension: tanh is
    increasing, so a <= x exactly when u <= atanh((x - bias) / scale)."""
    scale, bias = (high - low) / 2, (high + low) / 2
    z = (math.atanh((x - bias) / scale) - mean) / std
    return 0.5 * (1 + math.erf(z / math.sqrt(2)))


@pytest.mark.quick
def test_squashed_log_prob_is_the_density_of_the_squashed_action_by_brute_force():
    """exp(log pi(a|s)) against the slope of the squashed action's distribution function,
    by central differences, in each of two dimensions of a box [-3, 1] x [0, 2] (scale 2 and
    1, bias -1 and 1), at actions from the middle to far out in tanh's tail; and log pi of
    the pair is the sum of the two. Without the correction the density is off by the factor
    scale * (1 - tanh(u)^2), from 2x to thousands of times here."""
    low, high = np.array([-3.0, 0.0]), np.array([1.0, 2.0])
    mean, std = torch.tensor([0.3, -1.0], dtype=torch.float64), torch.tensor([0.8, 1.5],
                                                                               dtype=torch.float64)
    u_dist = torch.distributions.Normal(mean, std)
    scale = torch.as_tensor((high - low) / 2)
    for u in ([0.0, 0.0], [1.0, -2.0], [-2.5, 3.0], [3.5, -4.0]):
        u = torch.tensor(u, dtype=torch.float64)
        a = torch.as_tensor((high + low) / 2) + scale * torch.tanh(u)
        per_dim = []
        for i in range(2):  # each dimension alone: its own 1-D density
            h = 1e-6 * float(1 - torch.tanh(u[i]) ** 2)  # a step well inside the box
            slope = (squashed_cdf(float(a[i]) + h, float(mean[i]), float(std[i]), low[i], high[i])
                     - squashed_cdf(float(a[i]) - h, float(mean[i]), float(std[i]), low[i],
                                    high[i])) / (2 * h)
            one = torch.distributions.Normal(mean[i:i + 1], std[i:i + 1])
            logp = sac.squashed_log_prob(one, u[i:i + 1], scale[i:i + 1]).item()
            assert math.exp(logp) == pytest.approx(slope, rel=1e-4), (u, i)
            per_dim.append(logp)
        assert sac.squashed_log_prob(u_dist, u, scale).item() == pytest.approx(sum(per_dim))


@pytest.mark.quick
def test_squashed_log_prob_stays_finite_far_in_the_tail_in_float32():
    """At u = 12, 1 - tanh(u)^2 rounds to 0 in float32; the stable form gives the same number
    as float64 does: log pi is finite, and the gradient through it too."""
    u = torch.tensor([12.0, -15.0], requires_grad=True)
    dist = torch.distributions.Normal(torch.zeros(2), torch.ones(2))
    logp = sac.squashed_log_prob(dist, u, torch.ones(2))
    exact = sac.squashed_log_prob(torch.distributions.Normal(torch.zeros(2, dtype=torch.float64),
                                                             torch.ones(2, dtype=torch.float64)),
                                  u.detach().double(), torch.ones(2, dtype=torch.float64))
    assert torch.isfinite(logp) and logp.item() == pytest.approx(exact.item(), rel=1e-5)
    logp.backward()
    assert torch.isfinite(u.grad).all()


@pytest.mark.quick
def test_actor_samples_stay_in_the_box_and_its_mean_action_is_tanh_of_the_mean():
    torch.manual_seed(0)
    actor = sac.Actor(3, 2, 16, np.array([-3.0, 0.0]), np.array([1.0, 2.0]))
    obs = torch.randn(500, 3) * 10  # far from where the weights were made: saturated actions
    a, logp = actor.sample(obs)
    assert a.shape == (500, 2) and logp.shape == (500,)
    assert (a[:, 0] >= -3).all() and (a[:, 0] <= 1).all() and (a[:, 1] >= 0).all()
    with torch.no_grad():
        expected = torch.tensor([-1.0, 1.0]) + torch.tensor([2.0, 1.0]) * torch.tanh(
            actor.distribution(obs).mean)
    assert torch.equal(actor(obs), expected)  # evaluation: no sampling


@pytest.mark.quick
def test_actor_loss_is_alpha_log_pi_minus_the_smaller_q_and_its_gradient_passes_the_sample():
    """J_pi = mean(alpha log pi(a|s) - min(Q1, Q2)) for the sample the actor draws (recomputed
    from the same random numbers), and the actor's weights get a gradient through a itself
    (reparameterisation): with alpha = 0 the loss is -min Q alone, and still moves them."""
    torch.manual_seed(0)
    cfg = sac.Config(env_id="InvertedPendulum-v5", hidden=16)
    nets = sac.build(3, 2, np.full(2, -1.0), np.full(2, 1.0), cfg, "cpu")
    obs = torch.randn(64, 3)
    state = torch.get_rng_state()
    loss, logp = sac.compute_loss_actor(nets["actor"], nets["critic"], nets["critic2"], obs, 0.3)
    torch.set_rng_state(state)
    with torch.no_grad():
        a, logp_again = nets["actor"].sample(obs)
        q = torch.minimum(nets["critic"](obs, a), nets["critic2"](obs, a))
        assert not torch.equal(q, nets["critic"](obs, a))  # the min matters here
    assert torch.equal(logp.detach(), logp_again)
    assert loss.item() == pytest.approx((0.3 * logp_again - q).mean().item(), rel=1e-6)
    loss, _ = sac.compute_loss_actor(nets["actor"], nets["critic"], nets["critic2"], obs, 0.0)
    loss.backward()
    assert nets["actor"].mean.weight.grad.abs().sum() > 0


@pytest.mark.quick
def test_temperature_loss_by_hand_and_alpha_moves_toward_the_target_entropy():
    """J(alpha) = mean(-alpha (log pi + H_target)): alpha = 0.5, log pi = [1, -3], H_target =
    -2 gives -0.5 * mean([-1, -5]) = 1.5. Its gradient in log alpha is alpha times the same
    mean, 1.5; one descent step lowers alpha (the entropy, 1, is above its target, -2).
    Below the target (log pi = [4, 2]: entropy -3), alpha rises."""
    temperature = sac.Temperature(0.5)
    temperature.log_alpha.requires_grad_(True)
    loss = sac.compute_loss_alpha(temperature, torch.tensor([1.0, -3.0]), -2.0)
    assert loss.item() == pytest.approx(1.5)
    loss.backward()
    assert temperature.log_alpha.grad.item() == pytest.approx(1.5)
    for logp, direction in (([1.0, -3.0], -1), ([4.0, 2.0], 1)):
        temperature = sac.Temperature()  # learned, from alpha = 1
        opt = torch.optim.Adam(temperature.parameters(), lr=0.1)
        opt.zero_grad()
        sac.compute_loss_alpha(temperature, torch.tensor(logp), -2.0).backward()
        opt.step()
        assert np.sign(temperature().item() - 1.0) == direction


@pytest.mark.quick
def test_a_fixed_alpha_stays_and_a_learned_one_moves(tmp_path, capsys):
    """--alpha 0.2 fixes alpha through training; by default alpha starts at 1 and moves. The
    progress line shows it (the last line: alpha as the run ended)."""
    small = dict(env_id="InvertedPendulum-v5", total_timesteps=200, start_steps=100,
                 eval_every=200, eval_episodes=1, batch_size=32, hidden=16, print_every=200,
                 gifs=False, curves=False)
    for alpha in (0.2, None):
        run = sac.train(sac.Config(**small, alpha=alpha, run_dir=str(tmp_path)))["run_dir"]
        log_alpha = torch.load(run / "checkpoint.pt", weights_only=True)["temperature"]["log_alpha"]
        line = next(s for s in capsys.readouterr().out.splitlines() if s.startswith("step "))
        assert f"alpha {log_alpha.exp().item():8.3f}" in line and "critic_loss" in line, line
        if alpha is None:
            assert 0.5 < log_alpha.exp().item() < 1.0  # 100 steps of Adam 3e-4 lower it from 1
        else:
            assert log_alpha.exp().item() == pytest.approx(0.2)


@pytest.mark.quick
def test_the_diff_from_td3_is_what_sac_changes_and_little_else():
    """`diff td3_walker.py sac_walker.py`: at most ~140 lines of TD3's out and ~200 in (the
    squashed Gaussian, the temperature, the docstrings that explain them)."""
    td3_lines = (ROOT / "td3_walker.py").read_text().splitlines()
    sac_lines = (ROOT / "sac_walker.py").read_text().splitlines()
    diff = list(difflib.unified_diff(td3_lines, sac_lines, lineterm="", n=0))
    removed = [d for d in diff if d.startswith("-") and not d.startswith("---")]
    added = [d for d in diff if d.startswith("+") and not d.startswith("+++")]
    assert len(removed) <= 140 and len(added) <= 200, (len(removed), len(added))
    # 419 before its inside.png's panels said on their y labels what they measure (2 lines)
    assert len(sac_lines) <= 421, f"sac_walker.py has {len(sac_lines)} lines, over its 421"


def test_ctrl_c_then_resume_is_the_unbroken_run(tmp_path):
    """Ctrl-C mid-run writes a checkpoint; --resume ends exactly as the run that never
    stopped: the same logs byte for byte, every network, the temperature and every optimizer
    bit for bit."""
    short = dict(total_timesteps=1600)  # the checkpoint at step 800, Ctrl-C after step 1100
    unbroken = sac.train(sac.Config(**{**PENDULUM, **short},
                                    run_dir=str(tmp_path / "unbroken")))["run_dir"]
    code, out, err = interrupt("sac_walker.py", *pendulum_flags(**short), "--run-dir",
                               tmp_path / "cut", after="step     1100")
    assert code == 130, err
    (run,) = run_folders(tmp_path / "cut")
    stopped = torch.load(run / "checkpoint.pt", weights_only=True)["global_step"]
    assert 1100 <= stopped < 1600 and f"--resume {run}" in out
    assert out.splitlines()[-1].startswith(f"interrupted at step {stopped};")
    sac.train(sac.Config(resume=str(run)))
    for name in ("evaluations.csv", "episodes.csv"):
        assert (run / name).read_bytes() == (unbroken / name).read_bytes(), name
    a, b = (torch.load(d / "checkpoint.pt", weights_only=True) for d in (unbroken, run))
    for key in ("actor", "critic", "critic2", "critic_target", "critic2_target", "temperature"):
        assert all(torch.equal(b[key][k], v) for k, v in a[key].items()), key
    for key in ("actor_opt", "critic_opt", "alpha_opt"):
        for i, state in a[key]["state"].items():
            assert all(torch.equal(b[key]["state"][i][k], v) for k, v in state.items()), key


def test_eval_replays_the_saved_actor_and_inside_png_has_the_entropy(tmp_path, capsys):
    """--eval of model.pt plays tanh(mean) without sampling: the last evaluation's returns;
    evaluations.csv has SAC's entropy, its target and alpha, which inside.png draws (three
    evaluations after the warm-up's: lines, not points)."""
    import csv

    from test_cartpole_scripts import assert_curve_drawn

    result = sac.train(sac.Config(env_id="InvertedPendulum-v5", total_timesteps=800,
                                  start_steps=200, eval_every=200, eval_episodes=2,
                                  batch_size=64, hidden=32, print_every=10**6, gifs=False,
                                  run_dir=str(tmp_path)))
    run = result["run_dir"]
    assert np.mean(play(run / "model.pt", 2, script=sac)) == pytest.approx(
        result["evaluations"][-1]["eval_mean"])  # the same episodes (eval seed) and actor
    row = list(csv.DictReader(open(run / "evaluations.csv")))[-1]
    assert float(row["target_entropy"]) == -1 and 0 < float(row["alpha"]) < 1
    assert np.isfinite(float(row["entropy"]))
    assert_curve_drawn(run / "inside.png")
    p = run_main("sac_walker.py", "--eval", run / "model.pt", "--eval-episodes", 2,
                 capsys=capsys)
    assert p.returncode == 0 and "mean" in p.stdout, p.stderr


@pytest.mark.parametrize("args,needle", [
    (["--alpha", "0"], "--alpha must be positive or none"),
    (["--alpha-lr", "-1"], "--alpha-lr must be positive"),
    (["--env-id", "CartPole-v1"], "is not a MuJoCo env"),
])
def test_bad_input_is_one_line_and_exit_2(tmp_path, args, needle, capsys):
    p = run_main("sac_walker.py", *args, "--run-dir", tmp_path, capsys=capsys)
    assert p.returncode == 2, (p.stdout, p.stderr)
    assert needle in p.stderr and len(p.stderr.strip().splitlines()) == 1
    assert not list(tmp_path.iterdir())


@pytest.mark.slow
def test_learns_inverted_pendulum_with_a_fixed_seed():
    """The README's DDPG-in-minutes settings (hidden 128, batch 128) with step sizes 3e-3
    (alpha's too) and SAC's own tau, seed 1, 15,000 steps: its evaluations were 62 to 85
    until step 10,000, then 1000 (the maximum) at 12,500 and 15,000. This is the
    sac_actor_loss exercise's stage (c) with the script's own function, the very run a
    learner's right answer must repeat (exercises/check.py: SAC_LEARN)."""
    sys.path.insert(0, str(ROOT / "exercises"))
    import check
    ex = check.EXERCISES["sac_actor_loss"]
    evaluations = check.learns(ex, getattr(ex.owner(), ex.function))["evaluations"]
    assert evaluations[0]["eval_mean"] < 200  # the pole falls
    assert [e["eval_mean"] for e in evaluations[-check.HOLD:]] == [1000] * check.HOLD


def test_help_shows_the_temperature(capsys):
    p = run_main("sac_walker.py", "--help", capsys=capsys)
    assert p.returncode == 0, p.stderr
    assert all(flag in p.stdout for flag in ("--alpha", "--alpha-lr", "--target-entropy"))


@pytest.mark.quick
def test_each_target_critic_follows_its_own_critic(monkeypatch, tmp_path):
    """Each target critic starts as a copy of its own critic; from one critic update to the next,
    on train() itself, it moves tau of the way toward that critic as the last update left it
    (the actor step between them leaves the critics alone): critic_target toward Q1,
    critic2_target toward Q2. tau = 0.5 here, so a target that follows the other critic (the
    two start from different weights), stays put or moves the wrong fraction is far off."""
    from test_replay_loops import record_training

    _, _, _, calls = record_training(sac, monkeypatch, tmp_path, "update_critics", tau=0.5)
    assert len(calls) > 50
    for target, own in (("critic_target", "critic"), ("critic2_target", "critic2")):
        assert all(torch.equal(t, q) for t, q in zip(calls[0]["nets"][target].parameters(),
                                                      calls[0]["nets"][own].parameters()))
    for k in range(1, len(calls)):
        before, now = calls[k - 1]["nets"], calls[k]["nets"]
        for target, own in (("critic_target", "critic"), ("critic2_target", "critic2")):
            for t0, t1, q in zip(before[target].parameters(), now[target].parameters(),
                                 now[own].parameters()):
                assert torch.allclose(t1, 0.5 * t0 + 0.5 * q, atol=1e-6), (k, target)
