"""The bugs a reader makes in a hand-written loop, caught on train() itself.

Each test runs a short real training and records what train() hands to its update (the
batch `data`, and the networks as they were). Then it rebuilds that batch by brute force:
the recorded actions replayed in a fresh env with the same seed, returns and advantages as
explicit sums. Episodes are cut at 12 steps, so the rollouts hold time-limit truncations
as well as terminations and the vector env's autoreset steps. What this catches: the
autoreset step kept in the batch, a reset seed that is not the run's seed, obs not
advanced, value targets that are not A + V (or n-step returns), a wrong bootstrap,
log pi_old from the wrong policy, targets that still carry a gradient.
"""

import copy

import gymnasium as gym
import numpy as np
import pytest
import torch
from torch.distributions import Categorical

import actor_critic_cartpole as a2c
import ppo_cartpole as ppo
import ppo_kl_cartpole as ppo_kl
pytestmark = pytest.mark.quick  # the algorithm's pieces: pytest -m quick runs these


REAL_MAKE_VEC = gym.make_vec
CUT = 12  # max_episode_steps: a random CartPole episode often outlives it (truncated)
T, N, UPDATES = 40, 3, 3


def short_episodes(env_id, num_envs, **kw):
    return REAL_MAKE_VEC(env_id, num_envs, max_episode_steps=CUT, **kw)


def run(script, monkeypatch, tmp_path, update_name, **overrides):
    """Train `script` for UPDATES rollouts; return (cfg, rollouts as stored, one record per
    call of script.<update_name>: the networks as they were, data, which data needed grad)."""
    rollouts, calls = [], []
    real_get_batch, real_update = script.RolloutBuffer.get_batch, getattr(script, update_name)

    def get_batch(self, device):
        batch = real_get_batch(self, device)
        rollouts.append({key: x.clone() for key, x in batch.items()})
        return batch

    def update(net, *args):
        nets = [copy.deepcopy(a) for a in (net, *args) if isinstance(a, torch.nn.Module)]
        data = next(a for a in args if isinstance(a, dict))
        calls.append((nets, {k: x.detach().clone() for k, x in data.items()},
                      {k for k, x in data.items() if x.requires_grad}))
        return real_update(net, *args)

    monkeypatch.setattr(gym, "make_vec", short_episodes)
    monkeypatch.setattr(script.RolloutBuffer, "get_batch", get_batch)
    monkeypatch.setattr(script, update_name, update)
    cfg = script.Config(seed=5, num_envs=N, num_steps=T, total_timesteps=UPDATES * T * N,
                        stop_when_solved=False, gifs=False, curves=False, eval_episodes=1,
                        run_dir=str(tmp_path), print_every=10**6, **overrides)
    script.train(cfg)
    assert len(rollouts) == len(calls) == UPDATES
    return cfg, rollouts, calls


def replay(rollouts, seed, reward_scale):
    """Play the stored actions again in a fresh env reset with the run's seed: every stored
    obs must be the obs its action was chosen in, every reward and end flag what the env
    gave. Returns, per rollout, the obs each step led to, (T, N, 4): at an episode's last
    step the real final obs."""
    envs = short_episodes("CartPole-v1", N)
    obs, _ = envs.reset(seed=seed)
    led_to = []
    for r in rollouts:
        led_to.append(np.zeros((T, N, 4), dtype=np.float32))
        for t in range(T):
            np.testing.assert_array_equal(r["obs"][t].numpy(), obs, err_msg=f"obs row {t}")
            obs, reward, terminated, truncated, _ = envs.step(r["actions"][t].numpy())
            led_to[-1][t] = obs
            np.testing.assert_array_equal(r["rewards"][t].numpy(),
                                          (reward_scale * reward).astype(np.float32))
            np.testing.assert_array_equal(r["terminated"][t].numpy(), terminated)
            np.testing.assert_array_equal(r["truncated"][t].numpy(), truncated)
    envs.close()
    return led_to


def valid_rows(rollouts):
    """(T, N) per rollout: False at the step after an episode ended (the autoreset step)."""
    after_end, masks = np.zeros(N, dtype=bool), []
    for r in rollouts:
        masks.append(np.zeros((T, N), dtype=bool))
        for t in range(T):
            masks[-1][t] = ~after_end
            after_end = (r["terminated"][t] | r["truncated"][t]).numpy()
    return masks


def sums_by_hand(r, v, v_next, gamma, lam):
    """GAE advantages as the explicit sum A_t = sum_k (gamma lam)^k delta_{t+k} over the
    rest of the episode inside the rollout, delta_k = r_k + gamma V(s'_k) [not terminated]
    - V(s_k), with s'_k the obs step k led to; and the n-step returns
    G_t = sum_k gamma^k r_{t+k} + gamma^(j-t+1) V(s'_j) [j not terminated], j the episode's
    last step in the rollout. Both (T, N), float64."""
    rew, term = r["rewards"].double().numpy(), r["terminated"].numpy()
    done = term | r["truncated"].numpy()
    adv, ret = np.zeros((T, N)), np.zeros((T, N))
    for t in range(T):
        for n in range(N):
            k = t
            while True:
                delta = rew[k, n] + gamma * v_next[k, n] * (not term[k, n]) - v[k, n]
                adv[t, n] += (gamma * lam) ** (k - t) * delta
                ret[t, n] += gamma ** (k - t) * rew[k, n]
                if done[k, n] or k == T - 1:
                    ret[t, n] += gamma ** (k - t + 1) * v_next[k, n] * (not term[k, n])
                    break
                k += 1
    return adv, ret


def check_rows(data, r, keep):
    """data holds the stored obs and actions of the valid rows, in (t, n) order, and no more."""
    assert keep.sum() < T * N  # the rollout has autoreset rows to drop
    assert len(data["obs"]) == keep.sum(), "the autoreset steps must be dropped from the batch"
    np.testing.assert_array_equal(data["obs"].numpy(), r["obs"].numpy()[keep])
    np.testing.assert_array_equal(data["act"].numpy(), r["actions"].numpy()[keep])


@pytest.mark.parametrize("script", [ppo, ppo_kl], ids=["ppo_cartpole", "ppo_kl_cartpole"])
def test_ppo_train_hands_the_update_the_batch_brute_force_gives(script, monkeypatch, tmp_path):
    """obs, act, logp = log pi_old(a|s), adv = GAE, ret = A + V: the valid rows only."""
    cfg, rollouts, calls = run(script, monkeypatch, tmp_path, "ppo_update")
    led_to = replay(rollouts, cfg.seed, cfg.reward_scale)
    kinds = set()
    for r, keep, s_next, ((policy, value_net), data, with_grad) in zip(
            rollouts, valid_rows(rollouts), led_to, calls):
        assert not with_grad, f"{with_grad} still carry a gradient into the update"
        check_rows(data, r, keep)
        with torch.no_grad():
            logits = policy(r["obs"])
            v, v_next = value_net(r["obs"]).double().numpy(), value_net(
                torch.as_tensor(s_next)).double().numpy()
        logp = Categorical(logits=logits).log_prob(r["actions"])
        adv, _ = sums_by_hand(r, v, v_next, cfg.gamma, cfg.lam)
        np.testing.assert_allclose(data["logp"].numpy(), logp.numpy()[keep], atol=1e-6)
        np.testing.assert_allclose(data["adv"].numpy(), adv[keep], rtol=1e-4, atol=1e-5)
        np.testing.assert_allclose(data["ret"].numpy(), (adv + v)[keep], rtol=1e-4, atol=1e-5)
        if "logits_old" in data:  # PPO-penalty's pi_old in full
            np.testing.assert_allclose(torch.log_softmax(data["logits_old"], -1).numpy(),
                                       torch.log_softmax(logits, -1).numpy()[keep], atol=1e-6)
        kinds |= {name for name in ("terminated", "truncated") if r[name].any()}
    assert kinds == {"terminated", "truncated"}  # both kinds of episode end were checked


def test_a2c_train_hands_the_update_n_step_returns(monkeypatch, tmp_path):
    """A2C's default (lam none): ret = the n-step return, adv = ret - V."""
    cfg, rollouts, calls = run(a2c, monkeypatch, tmp_path, "a2c_loss", norm_adv=False)
    assert cfg.lam is None
    led_to = replay(rollouts, cfg.seed, 1 - cfg.gamma)  # the default reward scale
    kinds = set()
    for r, keep, s_next, ((model,), data, with_grad) in zip(
            rollouts, valid_rows(rollouts), led_to, calls):
        assert not with_grad, f"{with_grad} still carry a gradient into the update"
        check_rows(data, r, keep)
        kinds |= {name for name in ("terminated", "truncated") if r[name].any()}
        with torch.no_grad():
            v = model(r["obs"])[1].double().numpy()
            v_next = model(torch.as_tensor(s_next))[1].double().numpy()
        _, ret = sums_by_hand(r, v, v_next, cfg.gamma, lam=1.0)
        np.testing.assert_allclose(data["ret"].numpy(), ret[keep], rtol=1e-4, atol=1e-5)
        np.testing.assert_allclose(data["adv"].numpy(), (ret - v)[keep], rtol=1e-4, atol=1e-5)
    assert kinds == {"terminated", "truncated"}


def test_a2c_with_gae_targets_are_a_plus_v(monkeypatch, tmp_path):
    cfg, rollouts, calls = run(a2c, monkeypatch, tmp_path, "a2c_loss", norm_adv=False, lam=0.9)
    led_to = replay(rollouts, cfg.seed, 1 - cfg.gamma)
    for r, keep, s_next, ((model,), data, _) in zip(rollouts, valid_rows(rollouts), led_to, calls):
        with torch.no_grad():
            v = model(r["obs"])[1].double().numpy()
            v_next = model(torch.as_tensor(s_next))[1].double().numpy()
        adv, _ = sums_by_hand(r, v, v_next, cfg.gamma, cfg.lam)
        np.testing.assert_allclose(data["adv"].numpy(), adv[keep], rtol=1e-4, atol=1e-5)
        np.testing.assert_allclose(data["ret"].numpy(), (adv + v)[keep], rtol=1e-4, atol=1e-5)


def rows_of(minibatch, data):
    """The row of `data` each row of `minibatch` is (matched by its obs, unique in CartPole)."""
    where = {tuple(row): i for i, row in enumerate(data["obs"].tolist())}
    assert len(where) == len(data["obs"])
    return np.array([where[tuple(row)] for row in minibatch["obs"].tolist()])


@pytest.mark.parametrize("script", [ppo, ppo_kl], ids=["ppo_cartpole", "ppo_kl_cartpole"])
def test_ppo_loss_sees_each_epoch_partitioned_with_advantages_normalized_per_minibatch(
        script, monkeypatch, tmp_path):
    """What compute_loss_pi is fed: each epoch's minibatches hold every row of the batch once,
    each row as the batch has it, and the advantages centred and scaled within the minibatch:
    (A - mean) / (std + 1e-8), over that minibatch's rows."""
    seen = []
    real = script.compute_loss_pi
    monkeypatch.setattr(script, "compute_loss_pi", lambda policy, mb, *rest: (
        seen.append({k: x.detach().clone() for k, x in mb.items()}), real(policy, mb, *rest))[1])
    cfg, _, calls = run(script, monkeypatch, tmp_path, "ppo_update")
    per_update = cfg.update_epochs * cfg.num_minibatches
    for _, data, _ in calls:
        n = len(data["obs"])
        minibatches = seen[:per_update]
        del seen[:per_update]
        while seen and len(seen[0]["obs"]) == n:  # the whole batch, after the update (stats)
            seen.pop(0)
        for epoch in range(cfg.update_epochs):
            epoch_rows = []
            for mb in minibatches[epoch * cfg.num_minibatches:(epoch + 1) * cfg.num_minibatches]:
                rows = rows_of(mb, data)
                epoch_rows += rows.tolist()
                for key in ("act", "logp", "ret"):
                    assert torch.equal(mb[key], data[key][rows]), key
                raw = data["adv"][rows]
                expected = (raw - raw.mean()) / (raw.std(unbiased=False) + 1e-8)
                torch.testing.assert_close(mb["adv"], expected, rtol=1e-5, atol=1e-6)
            assert sorted(epoch_rows) == list(range(n)), f"epoch {epoch} is no partition"
    assert not seen


def test_a2c_loss_sees_the_advantages_normalized_over_the_batch(monkeypatch, tmp_path):
    """A2C's default (norm_adv): the loss gets (A - mean) / (std + 1e-8) of the n-step
    advantages over the whole batch, and the targets unchanged."""
    cfg, rollouts, calls = run(a2c, monkeypatch, tmp_path, "a2c_loss")
    assert cfg.norm_adv
    led_to = replay(rollouts, cfg.seed, 1 - cfg.gamma)
    for r, keep, s_next, ((model,), data, _) in zip(rollouts, valid_rows(rollouts), led_to, calls):
        with torch.no_grad():
            v = model(r["obs"])[1].double().numpy()
            v_next = model(torch.as_tensor(s_next))[1].double().numpy()
        _, ret = sums_by_hand(r, v, v_next, cfg.gamma, lam=1.0)
        adv = (ret - v)[keep]
        np.testing.assert_allclose(data["ret"].numpy(), ret[keep], rtol=1e-4, atol=1e-5)
        np.testing.assert_allclose(data["adv"].numpy(), (adv - adv.mean()) / (adv.std() + 1e-8),
                                   rtol=1e-4, atol=1e-4)
