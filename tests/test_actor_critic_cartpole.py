"""A2C's own pieces: the n-step targets of a real vector-env rollout, and the loss."""

import math

import gymnasium as gym
import numpy as np
import pytest
import torch

import actor_critic_cartpole as a2c

pytestmark = pytest.mark.quick  # the algorithm's pieces: pytest -m quick runs these


def test_targets_are_n_step_returns_across_truncation_and_autoreset():
    """a2c_targets' critic targets are the n-step returns written out by hand: rewards
    summed to the episode's end (a termination adds nothing, a time-limit truncation adds V
    of the real final obs) or to the rollout's end (adds V of the obs after it)."""
    cfg = a2c.Config(gamma=0.9, norm_adv=False)
    assert cfg.lam is None  # the textbook default: n-step returns, no GAE
    torch.manual_seed(0)
    model = a2c.ActorCritic(4, 2, 16)
    T, N = 30, 2
    envs = gym.make_vec("CartPole-v1", num_envs=N, max_episode_steps=12)  # truncations inside
    obs, _ = envs.reset(seed=0)
    buffer = a2c.RolloutBuffer(T, N, 4)
    autoreset = np.zeros(N, dtype=bool)
    for t in range(T):
        # env 0 always pushes right and falls (terminated); env 1 alternates and is truncated.
        action = np.array([1, t % 2])
        next_obs, reward, term, trunc, _ = envs.step(action)
        buffer.store(t, obs, action, reward, term, trunc, valid=~autoreset)
        autoreset, obs = term | trunc, next_obs
    envs.close()
    rollout = buffer.get_batch("cpu")
    assert buffer.terminated.any() and buffer.truncated.any() and not buffer.valid.all()

    returns, adv = a2c.a2c_targets(model, rollout, obs, cfg)

    with torch.no_grad():
        V = lambda o: float(model(torch.as_tensor(o, dtype=torch.float32))[1])  # noqa: E731
        expected = np.zeros((T, N))
        for t in range(T):
            for n in range(N):
                g, k = 0.0, t
                while True:
                    g += cfg.gamma ** (k - t) * float(buffer.rewards[k, n])
                    if buffer.terminated[k, n]:
                        break
                    if buffer.truncated[k, n]:  # the next row holds the episode's real final obs
                        g += cfg.gamma ** (k - t + 1) * V(buffer.obs[k + 1, n] if k + 1 < T else obs[n])
                        break
                    if k == T - 1:
                        g += cfg.gamma ** (k - t + 1) * V(obs[n])
                        break
                    k += 1
                expected[t, n] = g
        values = model(rollout["obs"])[1]
    valid = buffer.valid  # the autoreset rows are dropped by the loop; their targets do not matter
    np.testing.assert_allclose(returns.numpy()[valid], expected[valid], rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(adv.numpy(), (returns - values).numpy(), rtol=1e-5, atol=1e-6)


def test_a2c_loss_by_hand():
    """Two transitions with pi = (0.25, 0.75) and V = (1, 2): each term of the loss by hand."""
    logits = torch.log(torch.tensor([[0.25, 0.75], [0.25, 0.75]])).requires_grad_()
    values = torch.tensor([1.0, 2.0], requires_grad=True)
    model = lambda obs: (logits, values)  # noqa: E731  (a stand-in with known outputs)
    act, adv, ret = torch.tensor([1, 0]), torch.tensor([2.0, -1.0]), torch.tensor([1.5, 1.0])
    cfg = a2c.Config(vf_coef=0.5, ent_coef=0.01)
    loss, stats = a2c.a2c_loss(model, dict(obs=None, act=act, adv=adv, ret=ret), cfg)
    loss_pi = -(math.log(0.75) * 2.0 + math.log(0.25) * -1.0) / 2  # -mean(log pi(a|s) * A)
    loss_v = 0.5 * ((1.0 - 1.5) ** 2 + (2.0 - 1.0) ** 2) / 2  # 0.5 * mean((V - R)^2)
    entropy = -(0.25 * math.log(0.25) + 0.75 * math.log(0.75))
    assert stats["loss_pi"] == pytest.approx(loss_pi, rel=1e-6)
    assert stats["loss_v"] == pytest.approx(loss_v, rel=1e-6)
    assert stats["entropy"] == pytest.approx(entropy, rel=1e-6)
    assert loss.item() == pytest.approx(loss_pi + 0.5 * loss_v - 0.01 * entropy, rel=1e-6)
    # inside.png's fit of V: 1 - Var(R - V) / Var(R), by hand: 1 - 1.125 / 0.125
    assert stats["explained_var"] == pytest.approx(1 - 1.125 / 0.125, rel=1e-6)
    assert stats["values"].tolist() == [1.0, 2.0] and stats["ret"].tolist() == [1.5, 1.0]
    # Descending the loss raises log pi of the action with A > 0 and moves V toward R.
    loss.backward()
    assert logits.grad[0, 1] < 0 and values.grad[0] < 0 and values.grad[1] > 0


def test_default_reward_scale_is_never_zero(monkeypatch, tmp_path):
    """reward_scale none means 1 - gamma, which is 0 at gamma = 1: then it means 1."""
    seen = []
    real_store = a2c.RolloutBuffer.store
    monkeypatch.setattr(a2c.RolloutBuffer, "store", lambda self, t, o, a, r, *rest, **kw: (
        seen.append(np.asarray(r).copy()), real_store(self, t, o, a, r, *rest, **kw))[1])
    for gamma, scale in ((1.0, 1.0), (0.98, 0.02)):
        seen.clear()
        a2c.train(a2c.Config(gamma=gamma, total_timesteps=512, gifs=False, curves=False,
                             eval_episodes=1, run_dir=str(tmp_path), print_every=10**6))
        rewards = np.concatenate(seen)
        assert set(np.unique(rewards)) <= {0.0, np.float32(scale)} and rewards.max() > 0
