"""TD3: each of its three fixes against a hand computation, the diff from DDPG kept small,
exact resume after Ctrl-C, clear errors, and learning on a cheap task. (What the loop
stores and what each update is fed: tests/test_replay_loops.py.)"""

import difflib

import numpy as np
import pytest
import torch

import td3_walker as td3
from conftest import ROOT, interrupt, run_folders, run_main
from test_ddpg_walker import PENDULUM, pendulum_flags, play


@pytest.mark.quick
def test_clipped_double_q_target_takes_the_smaller_estimate_by_hand():
    """y = r + gamma * not_done * min(Q1', Q2'): 1 + 0.5 * 3 = 2.5 (Q2' the smaller), then
    1 + 0.5 * 5 = 3.5 (Q1' the smaller), and no future after a termination: 1."""
    y = td3.td_target(torch.tensor([1.0, 1.0, 1.0]), torch.tensor([1.0, 1.0, 0.0]),
                      torch.tensor([5.0, 5.0, 5.0]), torch.tensor([3.0, 9.0, 9.0]), 0.5)
    assert y.tolist() == [2.5, 3.5, 1.0]


@pytest.mark.quick
def test_target_action_noise_is_clipped_then_the_action_kept_in_its_box():
    """With std 1e6 every noise draw is clipped: mu'(s') moves by exactly noise_clip times
    the half-width (here 0.5 * 3 = 1.5), and the sum is clamped to [-3, 3]."""
    cfg = td3.Config(env_id="InvertedPendulum-v5", hidden=8, target_noise=1e6, noise_clip=0.5)
    low, high = np.array([-3.0, -3.0]), np.array([3.0, 3.0])
    torch.manual_seed(0)  # an actor whose mu'(s') is well inside [-1.5, 1.5]
    nets = td3.build(3, 2, low, high, cfg, "cpu")
    seen = []

    class Spy(torch.nn.Module):
        def __init__(self, net):
            super().__init__()
            self.net = net

        def forward(self, obs, action):
            seen.append(action.clone())
            return self.net(obs, action)

    nets["critic_target"] = Spy(nets["critic_target"])
    next_obs = torch.zeros(64, 3)
    with torch.no_grad():
        mu = nets["actor_target"](next_obs)
    batch = (torch.zeros(64, 3), torch.zeros(64, 2), torch.ones(64), next_obs, torch.ones(64))
    half = torch.tensor([3.0, 3.0])
    td3.update_critics(nets, batch, half, -half, half, cfg)
    assert mu.abs().max() < 1.5
    assert torch.allclose((seen[0] - mu).abs(), torch.tensor(1.5))
    mu_far = torch.full((64, 2), 2.5)  # near the bound: the smoothed action is clamped at 3
    assert ((mu_far + 1.5).clamp(-3, 3) == 3).all()


@pytest.mark.quick
def test_the_diff_from_ddpg_is_the_three_fixes_and_little_else():
    """`diff ddpg_walker.py td3_walker.py`: at most ~90 changed lines a side."""
    ddpg_lines = (ROOT / "ddpg_walker.py").read_text().splitlines()
    td3_lines = (ROOT / "td3_walker.py").read_text().splitlines()
    diff = list(difflib.unified_diff(ddpg_lines, td3_lines, lineterm="", n=0))
    removed = [d for d in diff if d.startswith("-") and not d.startswith("---")]
    added = [d for d in diff if d.startswith("+") and not d.startswith("+++")]
    assert len(removed) <= 90 and len(added) <= 90, (len(removed), len(added))
    for name, lines, budget in (("td3_walker", td3_lines, 400), ("ddpg_walker", ddpg_lines, 350)):
        assert len(lines) <= budget, f"{name}.py has {len(lines)} lines, over its {budget}"


def test_ctrl_c_then_resume_is_the_unbroken_run(tmp_path):
    """Ctrl-C mid-run writes a checkpoint; --resume ends exactly as the run that never
    stopped: the same logs byte for byte, every network and optimizer bit for bit."""
    short = dict(total_timesteps=1600)  # the checkpoint at step 800, Ctrl-C after step 1100
    unbroken = td3.train(td3.Config(**{**PENDULUM, **short},
                                    run_dir=str(tmp_path / "unbroken")))["run_dir"]
    code, out, err = interrupt("td3_walker.py", *pendulum_flags(**short), "--run-dir",
                               tmp_path / "cut", after="step     1100")
    assert code == 130, err
    (run,) = run_folders(tmp_path / "cut")
    stopped = torch.load(run / "checkpoint.pt", weights_only=True)["global_step"]
    assert 1100 <= stopped < 1600 and f"--resume {run}" in out
    assert out.splitlines()[-1].startswith(f"interrupted at step {stopped};")  # one last line,
    assert f"checkpoint at step {stopped}:" not in out  # not a second one about the checkpoint
    td3.train(td3.Config(resume=str(run)))
    for name in ("evaluations.csv", "episodes.csv"):
        assert (run / name).read_bytes() == (unbroken / name).read_bytes(), name
    a, b = (torch.load(d / "checkpoint.pt", weights_only=True) for d in (unbroken, run))
    nets = ("actor", "critic", "critic2", "actor_target", "critic_target", "critic2_target")
    for key in nets:
        assert all(torch.equal(b[key][k], v) for k, v in a[key].items()), key
    for key in ("actor_opt", "critic_opt"):
        for i, state in a[key]["state"].items():
            assert all(torch.equal(b[key]["state"][i][k], v) for k, v in state.items()), key


@pytest.mark.parametrize("args,needle", [
    (["--policy-delay", "0"], "--policy-delay must be positive"),
    (["--target-noise", "-1"], "--target-noise must be >= 0"),
    (["--env-id", "CartPole-v1"], "is not a MuJoCo env"),
])
def test_bad_input_is_one_line_and_exit_2(tmp_path, args, needle, capsys):
    p = run_main("td3_walker.py", *args, "--run-dir", tmp_path, capsys=capsys)
    assert p.returncode == 2, (p.stdout, p.stderr)
    assert needle in p.stderr and len(p.stderr.strip().splitlines()) == 1
    assert not list(tmp_path.iterdir())


# TD3's learning run on InvertedPendulum (seed 2, 25,000 steps) is in tests/test_exercises.py:
# stage (c) of the td3_target exercise, with the script's own update.


def test_help_shows_the_three_fixes(capsys):
    p = run_main("td3_walker.py", "--help", capsys=capsys)
    assert p.returncode == 0, p.stderr
    assert all(flag in p.stdout for flag in ("--policy-delay", "--target-noise", "--noise-clip"))


def test_the_shipped_td3_walker_walks():
    """docs/td3_walker2d.pt, the best actor of TD3's 1M-step Walker2d runs (the README's TD3
    --eval command replays it), still loads as a TD3 model and walks: one episode, >= 1000."""
    (ret,) = play(ROOT / "docs" / "td3_walker2d.pt", 1, script=td3)
    assert ret >= 1000, ret


@pytest.mark.quick
def test_the_actor_step_climbs_q1_and_its_loss_is_minus_q1():
    """TD3's actor loss is -mean Q1(s, mu(s)) (not +Q1, not Q2), and the actor steps that
    update_actor_and_targets takes raise Q1(s, mu(s)) on the batch's states while the
    critics stay as they are."""
    torch.manual_seed(0)
    cfg = td3.Config(env_id="InvertedPendulum-v5", hidden=16, actor_lr=1e-2)
    nets = td3.build(3, 2, np.full(2, -1.0), np.full(2, 1.0), cfg, "cpu")
    obs = torch.randn(64, 3)
    with torch.no_grad():
        q1_before = nets["critic"](obs, nets["actor"](obs)).mean().item()
        q2_before = nets["critic2"](obs, nets["actor"](obs)).mean().item()
    assert q1_before != pytest.approx(q2_before, abs=1e-3)  # which critic matters here
    loss = td3.compute_loss_actor(nets["actor"], nets["critic"], obs)
    assert loss.item() == pytest.approx(-q1_before, rel=1e-6)
    critics = [p.detach().clone() for p in [*nets["critic"].parameters(),
                                             *nets["critic2"].parameters()]]
    losses = [td3.update_actor_and_targets(nets, obs, cfg).item() for _ in range(10)]
    assert losses[0] == pytest.approx(-q1_before, rel=1e-6)
    with torch.no_grad():
        q1_after = nets["critic"](obs, nets["actor"](obs)).mean().item()
    assert q1_after > q1_before + 1e-3, (q1_before, q1_after)
    assert all(torch.equal(a, b) for a, b in zip(critics, [*nets["critic"].parameters(),
                                                            *nets["critic2"].parameters()]))


@pytest.mark.quick
def test_the_actions_played_while_learning_are_mu_plus_gaussian_noise(monkeypatch, tmp_path):
    """After the warm-up, train() plays mu(s) plus N(0, expl_noise * half-width) noise, one
    draw a step: with the actor held still (no actor step in this short run) the played
    action minus mu(s) over the 96 learning steps has a mean near 0 and a std near
    0.1 * 3 = 0.3 (InvertedPendulum's actions lie in [-3, 3]), and is never 0. No noise, or
    noise not scaled to the action box, fails."""
    from test_replay_loops import START, TOTAL, record_training

    _, record, _, calls = record_training(td3, monkeypatch, tmp_path, "update_critics",
                                          policy_delay=10**6)
    actor = calls[0]["nets"]["actor"]  # the actor as it was (and stays) through learning
    assert all(torch.equal(p, q) for p, q in zip(actor.parameters(),
                                                 calls[-1]["nets"]["actor"].parameters()))
    learning = record[START:]
    assert len(learning) == TOTAL - START
    with torch.no_grad():
        mu = actor(torch.as_tensor(np.array([s["obs"] for s in learning]), dtype=torch.float32))
    noise = np.array([s["action"] for s in learning]).reshape(mu.shape) - mu.numpy()
    assert (np.abs(mu.numpy()) < 2).all()  # far from the box's edge: no clipping
    assert (noise != 0).all()
    assert abs(noise.mean()) < 0.1 and 0.2 < noise.std() < 0.42, (noise.mean(), noise.std())
