"""A2C's own pieces: the n-step targets of a real vector-env rollout."""

import gymnasium as gym
import numpy as np
import torch

import actor_critic_cartpole as a2c


def test_targets_are_n_step_returns_across_truncation_and_autoreset():
    """With lam = 1, a2c_targets' critic targets are the n-step returns written out by hand:
    rewards summed to the episode's end (a termination adds nothing, a time-limit truncation
    adds V of the real final obs) or to the rollout's end (adds V of the obs after it); the
    vector env's reset steps are dropped."""
    cfg = a2c.Config(gamma=0.9, lam=1.0, norm_adv=False)
    torch.manual_seed(0)
    model = a2c.ActorCritic(4, 2, 16)
    T, N = 30, 2
    envs = gym.make_vec("CartPole-v1", num_envs=N, max_episode_steps=12)  # truncations inside the rollout
    obs, _ = envs.reset(seed=0)
    buffer = a2c.RolloutBuffer(T, N, 4, "cpu")
    autoreset = np.zeros(N, dtype=bool)
    for t in range(T):
        # env 0 always pushes right and falls (terminated); env 1 alternates and is truncated at 12 steps.
        action = np.array([1, t % 2])
        next_obs, reward, term, trunc, _ = envs.step(action)
        buffer.store(t, torch.as_tensor(obs, dtype=torch.float32), torch.as_tensor(action), reward, term, trunc,
                     valid=~autoreset)
        autoreset, obs = term | trunc, next_obs
    envs.close()
    next_obs = torch.as_tensor(obs, dtype=torch.float32)
    assert buffer.terminated.any() and buffer.truncated.any() and not buffer.valid.all()

    _, _, adv, returns = a2c.a2c_targets(model, buffer, next_obs, cfg)

    with torch.no_grad():
        V = lambda o: float(model(o)[1])  # noqa: E731
        expected = []
        for t in range(T):  # rows in the order buffer[valid] gives them: t-major, then env
            for n in range(N):
                if not buffer.valid[t, n]:
                    continue
                g, k = 0.0, t
                while True:
                    g += cfg.gamma ** (k - t) * float(buffer.rewards[k, n])
                    if buffer.terminated[k, n]:
                        break
                    if buffer.truncated[k, n]:  # the next row holds the episode's real final obs
                        g += cfg.gamma ** (k - t + 1) * V(buffer.obs[k + 1, n] if k + 1 < T else next_obs[n])
                        break
                    if k == T - 1:
                        g += cfg.gamma ** (k - t + 1) * V(next_obs[n])
                        break
                    k += 1
                expected.append(g)
        values = model(buffer.obs[buffer.valid])[1]
    np.testing.assert_allclose(returns.numpy(), expected, rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(adv.numpy(), returns.numpy() - values.numpy(), rtol=1e-5, atol=1e-6)

