"""REINFORCE's own pieces: the reward-to-go by hand, the loss's gradient against its exact
expectation on a two-action bandit (with and without a baseline), the gradient-variance
measurement by hand, and the training loop's episodes (the autoreset step, the bootstrap at
a time-limit truncation only)."""

import doctest

import gymnasium as gym
import numpy as np
import pytest
import torch
import torch.nn as nn

import reinforce_cartpole as rf

pytestmark = pytest.mark.quick  # the algorithm's pieces: pytest -m quick runs these


def test_reward_to_go_by_hand():
    # G_2 = 3; G_1 = 2 + 0.5 * 3 = 3.5; G_0 = 1 + 0.5 * 3.5 = 2.75
    np.testing.assert_allclose(rf.reward_to_go([1.0, 2.0, 3.0], 0.5), [2.75, 3.5, 3.0])
    # cut by a time limit: the tail is V(s_T) = 10; G_1 = 3 + 0.5 * 10 = 8, G_0 = 2 + 0.5 * 8
    np.testing.assert_allclose(rf.reward_to_go([2.0, 3.0], 0.5, last_value=10.0), [6.0, 8.0])
    np.testing.assert_allclose(rf.reward_to_go([1.0, 1.0], 1.0), [2.0, 1.0])  # no discount
    assert doctest.testmod(rf).failed == 0  # the docstring's worked examples


class Bandit(nn.Module):
    """pi over two actions from two free logits, whatever the obs; a constant "V"."""

    def __init__(self, logits, value=0.0):
        super().__init__()
        self.logits = nn.Parameter(torch.tensor(logits))
        self.value = value

    def forward(self, obs):
        return self.logits.expand(len(obs), 2)


@pytest.mark.parametrize("baseline", [False, True])
def test_the_loss_gradient_is_the_policy_gradient_in_expectation(baseline):
    """A one-step bandit, rewards r = (1, 3): J = sum_a pi(a) r(a) and dJ/dlogit_a =
    pi(a) (r(a) - J). The loss's gradient on a batch of one action a, averaged over a with
    weights pi(a) (the exact expectation, every action enumerated), is -dJ: with any
    constant baseline b = 2.5 as well (it changes the variance, not the expectation)."""
    rewards = torch.tensor([1.0, 3.0])
    policy = Bandit([0.3, -0.2])
    value_net = lambda obs: torch.full((len(obs),), 2.5)  # noqa: E731
    pi = torch.softmax(policy.logits.detach(), 0)
    J = (pi * rewards).sum()
    expected = torch.zeros(2)
    for a in (0, 1):
        data = dict(obs=torch.zeros(1, 4), act=torch.tensor([a]), ret=rewards[a:a + 1])
        loss_pi, _, weights = rf.reinforce_loss(policy, value_net, data, baseline)
        assert weights.item() == pytest.approx(rewards[a].item() - 2.5 * baseline)
        (grad,) = torch.autograd.grad(loss_pi, policy.logits)
        expected += pi[a] * grad
    torch.testing.assert_close(expected, -(pi * (rewards - J)))


def test_the_baseline_does_not_learn_from_the_policys_loss_and_fits_G():
    """V appears in pi's weights as a constant: loss_pi gives V's parameters no gradient;
    loss_v = 0.5 * mean((V - G)^2), by hand."""
    torch.manual_seed(0)
    policy, value_net = rf.PolicyNetwork(4, 2, 8), rf.ValueNetwork(4, 8)
    data = dict(obs=torch.randn(3, 4), act=torch.tensor([0, 1, 1]),
                ret=torch.tensor([1.0, 2.0, 3.0]))
    loss_pi, loss_v, weights = rf.reinforce_loss(policy, value_net, data, baseline=True)
    grads = torch.autograd.grad(loss_pi, list(value_net.parameters()), allow_unused=True)
    assert all(g is None or not g.any() for g in grads)
    with torch.no_grad():
        V = value_net(data["obs"])
    assert loss_v.item() == pytest.approx(0.5 * ((V - data["ret"]) ** 2).mean().item())
    torch.testing.assert_close(weights, data["ret"] - V)
    logp = torch.log_softmax(policy(data["obs"]), -1)[torch.arange(3), data["act"]]
    assert loss_pi.item() == pytest.approx(-(logp * weights).mean().item(), rel=1e-6)


def test_gradient_spread_by_hand():
    """pi = (0.5, 0.5): d log pi(a) / d logits = e_a - pi. Episode 0 plays a = 0 with weight
    w0 = 2 (g_0 = -2 (0.5, -0.5)), episode 1 plays a = 1 with w1 = 4 (g_1 = -4 (-0.5, 0.5)):
    g_0 = (-1, 1), g_1 = (2, -2), their mean (0.5, -0.5), each 1.5 * sqrt(2) away: 4.5."""
    data = dict(obs=torch.zeros(2, 4), act=torch.tensor([0, 1]), episode=torch.tensor([0, 1]))
    spread = rf.gradient_spread(Bandit([0.0, 0.0]), data, dict(w=torch.tensor([2.0, 4.0]),
                                                               same=torch.tensor([1.0, -1.0])))
    assert spread["w"] == pytest.approx(4.5)
    assert spread["same"] == pytest.approx(0.0)  # both episodes estimate (-0.5, 0.5)


def test_the_loop_plays_whole_episodes_and_bootstraps_only_at_a_time_limit(monkeypatch,
                                                                            tmp_path):
    """train() itself, on CartPole cut at 12 steps: each episode's rewards reach
    reward_to_go whole (as long as the episode), its tail V(s_T) only where the time limit
    cut it, 0 where the pole fell; the batch's first obs of an episode is a reset state (the
    autoreset step is not stored as a step of the next episode)."""
    gym.register("CartPole12-v1", entry_point="gymnasium.envs.classic_control:CartPoleEnv",
                 max_episode_steps=12, reward_threshold=475.0)
    calls, batches = [], []
    real_rtg, real_loss = rf.reward_to_go, rf.reinforce_loss
    monkeypatch.setattr(rf, "reward_to_go", lambda rewards, gamma, last_value=0.0: (
        calls.append((len(rewards), last_value)), real_rtg(rewards, gamma, last_value))[1])
    monkeypatch.setattr(rf, "reinforce_loss", lambda policy, value_net, data, baseline: (
        batches.append({k: v.clone() for k, v in data.items()}),
        real_loss(policy, value_net, data, baseline))[1])
    try:
        result = rf.train(rf.Config(env_id="CartPole12-v1", total_timesteps=600, gifs=False,
                                    curves=False, eval_episodes=1, run_dir=str(tmp_path),
                                    print_every=10**6))
    finally:
        gym.registry.pop("CartPole12-v1")
    lengths = [n for n, _ in calls]
    assert sum(lengths) == result["global_step"] and len(calls) == len(result["episode_returns"])
    assert lengths == [round(r) for r in result["episode_returns"]]  # one reward per step
    cut = [v for n, v in calls if n == 12]
    assert all(v == 0.0 for n, v in calls if n < 12) and any(v != 0.0 for v in cut)
    assert any(n < 12 for n in lengths)  # both ways of ending were seen
    for data in batches:
        firsts = torch.cat([torch.tensor([True]), data["episode"][1:] != data["episode"][:-1]])
        assert (data["obs"][firsts].abs() <= 0.05).all()  # CartPole resets within +-0.05
        assert len(data["episode"].unique()) == rf.Config().episodes_per_update


@pytest.mark.slow
def test_reinforce_solves_cartpole_with_its_defaults(tmp_path):
    result = rf.train(rf.Config(run_dir=str(tmp_path), gifs=False, curves=False,
                                print_every=10**6))
    assert result["solved"] and np.mean(result["eval_returns"]) >= 475, result["solved_step"]


@pytest.mark.parametrize("script", ["reinforce_cartpole.py", "q_learning_cliffwalking.py"])
@pytest.mark.parametrize("flag", ["--seed", "--eval-seed"])
def test_a_negative_seed_is_refused_in_one_line(script, flag, tmp_path, capsys):
    """gymnasium refuses a negative seed with a traceback (or, through the env check, as an
    'unknown environment'); the flags say so first, in one line, before any folder is made."""
    from conftest import run_main

    p = run_main(script, flag, "-1", "--run-dir", tmp_path, capsys=capsys)
    assert p.returncode == 2 and f"{flag} must be >= 0" in p.stderr, p.stderr
    assert len(p.stderr.strip().splitlines()) == 1 and not any(tmp_path.iterdir())
