"""DDPG's and TD3's loops, checked on train() itself: every transition the replay buffer holds
against the env's own record of what happened, and what each update is fed (its minibatch
and its TD target) against a brute-force computation from those transitions.

The env is InvertedPendulum-v5 cut at 15 steps: random actions tip the pole over (terminated)
and the actor keeps it up long enough for the cut (truncated), so both kinds of episode end
are stored. What this catches: s' stored as s (or s as s'), a truncation stored as terminal,
the reset obs not taken after an episode ends, a field of one transition stored with another,
a minibatch that is not stored transitions, a TD target from the online networks or without
the termination mask, TD3's max for its min, unclipped smoothing noise, an actor or target
that moves at every critic step, SAC's target without its entropy term or from a target
actor.
"""

import copy

import numpy as np
import pytest
import torch

import common
import ddpg_walker as ddpg
import sac_walker as sac
import td3_walker as td3

pytestmark = pytest.mark.quick
CUT, TOTAL, START = 15, 160, 64


def record_training(script, monkeypatch, tmp_path, update_name, **overrides):
    """Train `script` for TOTAL steps; return (cfg, the env's record, the replay buffer, one
    record per call of script.<update_name>: the networks and the RNG state as they were
    before it, its minibatch, and what it returned)."""
    real_make, made, record = common.gym.make, [], []

    def make_recorded(env_id, **kw):  # the first env made is the training env
        env = real_make(env_id, max_episode_steps=CUT, **kw)
        if made:
            return env
        made.append(env)
        real_reset, real_step = env.reset, env.step
        last = {}

        def reset(**kw):
            last["obs"], info = real_reset(**kw)
            return last["obs"], info

        def step(action):
            out = real_step(action)
            record.append(dict(obs=last["obs"], action=np.array(action), reward=out[1],
                               next_obs=out[0], terminated=out[2], truncated=out[3]))
            last["obs"] = out[0]
            return out
        env.reset, env.step = reset, step
        return env

    buffers, calls = [], []

    class Buffer(script.ReplayBuffer):
        def __init__(self, *args, **kw):
            super().__init__(*args, **kw)
            buffers.append(self)

    real_update = getattr(script, update_name)

    def update(*args):
        nets = args[0] if isinstance(args[0], dict) else dict(zip(
            ("actor", "critic", "actor_target", "critic_target"), args[:4]))
        batch = next(a for a in args if isinstance(a, tuple))
        before = {k: copy.deepcopy(v) for k, v in nets.items() if isinstance(v, torch.nn.Module)}
        rng = torch.get_rng_state()
        out = real_update(*args)
        calls.append(dict(nets=before, rng=rng, batch=[x.clone() for x in batch], out=out))
        return out

    monkeypatch.setattr(common.gym, "make", make_recorded)
    monkeypatch.setattr(script, "ReplayBuffer", Buffer)
    monkeypatch.setattr(script, update_name, update)
    cfg = script.Config(env_id="InvertedPendulum-v5", total_timesteps=TOTAL, start_steps=START,
                        batch_size=32, hidden=32, eval_every=10**6, print_every=10**6,
                        gifs=False, curves=False, run_dir=str(tmp_path), **overrides)
    script.train(cfg)
    assert len(buffers) == 1
    return cfg, record, buffers[0], calls


@pytest.mark.parametrize("script", [ddpg, td3, sac], ids=["ddpg_walker", "td3_walker",
                                                           "sac_walker"])
def test_every_stored_transition_is_what_the_env_returned(script, monkeypatch, tmp_path):
    update = "ddpg_update" if script is ddpg else "update_critics"
    _, record, buffer, _ = record_training(script, monkeypatch, tmp_path, update)
    assert len(record) == TOTAL and buffer.size == TOTAL
    ends = {"terminated": 0, "truncated": 0}
    for i, step in enumerate(record):
        for field, value in (("obs", step["obs"]), ("action", step["action"]),
                             ("next_obs", step["next_obs"])):
            np.testing.assert_allclose(getattr(buffer, field)[i].numpy(), value, rtol=1e-6,
                                       atol=1e-6, err_msg=f"transition {i}: {field}")
        assert buffer.reward[i].item() == pytest.approx(step["reward"], rel=1e-6), i
        # 1 - terminated: a time-limit truncation is stored as not terminal (it bootstraps)
        assert buffer.not_done[i].item() == (0.0 if step["terminated"] else 1.0), i
        ends["terminated"] += bool(step["terminated"])
        ends["truncated"] += bool(step["truncated"] and not step["terminated"])
        if i + 1 < TOTAL and (step["terminated"] or step["truncated"]):
            assert not np.array_equal(record[i + 1]["obs"], step["next_obs"]), (
                f"after the episode ended at transition {i}, the next one must start from a "
                "reset obs")
        elif i + 1 < TOTAL:
            np.testing.assert_array_equal(record[i + 1]["obs"], step["next_obs"])
    assert ends["terminated"] and ends["truncated"], ends  # both kinds were checked


def stored_index(buffer, obs, action, size):
    """The index of the stored transition (among the first `size`) with this obs and action."""
    hit = ((buffer.obs[:size] == obs).all(1) & (buffer.action[:size] == action).all(1)).nonzero()
    assert len(hit) >= 1, "a minibatch row that is no stored transition"
    return int(hit[0])


def check_minibatch(buffer, batch, size):
    """Every row of `batch` is one stored transition (of the first `size`), all its fields."""
    obs, action, reward, next_obs, not_done = batch
    for row in range(len(obs)):
        i = stored_index(buffer, obs[row], action[row], size)
        assert reward[row] == buffer.reward[i] and not_done[row] == buffer.not_done[i]
        assert torch.equal(next_obs[row], buffer.next_obs[i])


def test_ddpg_update_is_fed_stored_transitions_and_fits_the_td_target(monkeypatch, tmp_path):
    cfg, _, buffer, calls = record_training(ddpg, monkeypatch, tmp_path, "ddpg_update")
    assert len(calls) == TOTAL - START  # one update per env step after the warm-up
    for k, call in enumerate(calls):
        check_minibatch(buffer, call["batch"], START + k + 1)
        obs, action, reward, next_obs, not_done = call["batch"]
        nets = call["nets"]
        with torch.no_grad():  # y = r + gamma (1 - terminated) Q'(s', mu'(s')), targets' nets
            y = reward + cfg.gamma * not_done * nets["critic_target"](
                next_obs, nets["actor_target"](next_obs))
            expected = ((nets["critic"](obs, action) - y) ** 2).mean()
        assert call["out"][0].item() == pytest.approx(expected.item(), rel=1e-5), k


def test_td3_critics_fit_the_clipped_double_q_target_of_smoothed_actions(monkeypatch, tmp_path):
    cfg, _, buffer, calls = record_training(td3, monkeypatch, tmp_path, "update_critics",
                                            target_noise=2.0, noise_clip=0.3)
    assert len(calls) == TOTAL - START
    half = 3.0  # InvertedPendulum's actions lie in [-3, 3]
    for k, call in enumerate(calls):
        check_minibatch(buffer, call["batch"], START + k + 1)
        obs, action, reward, next_obs, not_done = call["batch"]
        nets = call["nets"]
        torch.set_rng_state(call["rng"])  # the very noise the update drew
        eps = torch.randn_like(action) * cfg.target_noise
        assert (eps.abs() > cfg.noise_clip).any()  # the clip matters in this case
        with torch.no_grad():
            mu = nets["actor_target"](next_obs)
            a = (mu + half * eps.clamp(-cfg.noise_clip, cfg.noise_clip)).clamp(-half, half)
            q1, q2 = nets["critic_target"](next_obs, a), nets["critic2_target"](next_obs, a)
            y = reward + cfg.gamma * not_done * torch.minimum(q1, q2)
            expected = (((nets["critic"](obs, action) - y) ** 2).mean()
                        + ((nets["critic2"](obs, action) - y) ** 2).mean())
        assert call["out"].item() == pytest.approx(expected.item(), rel=1e-5), k


def test_td3_actor_and_targets_move_only_every_policy_delay_steps(monkeypatch, tmp_path):
    """Between two critic updates the targets stay put unless the actor step came between;
    the actor steps at every policy_delay-th env step of learning."""
    events = []
    real = td3.update_actor_and_targets
    monkeypatch.setattr(td3, "update_actor_and_targets",
                        lambda *a: (events.append("actor"), real(*a))[1])
    _, _, _, calls = record_training(td3, monkeypatch, tmp_path, "update_critics",
                                     policy_delay=3)
    # update_critics' calls are recorded after they ran; the actor's step follows in the loop
    steps = range(START + 1, TOTAL + 1)
    assert events.count("actor") == sum(step % 3 == 0 for step in steps)
    for k in range(1, len(calls)):
        for name in ("actor", "actor_target", "critic_target", "critic2_target"):
            moved = any(not torch.equal(p, q) for p, q in zip(
                calls[k - 1]["nets"][name].parameters(), calls[k]["nets"][name].parameters()))
            assert moved == ((START + k) % 3 == 0), f"{name} before step {START + k + 1}"


def test_sac_critics_fit_the_soft_target_of_the_current_policys_samples(monkeypatch, tmp_path):
    """y = r + gamma (1 - terminated) (min(Q1', Q2')(s', a') - alpha log pi(a'|s')), a' drawn
    from the current actor with the very random numbers the update drew, log pi from torch's
    own tanh and affine transforms of the Gaussian (not the script's formula), alpha the
    temperature before the update; with alpha fixed at 0.5 the entropy term is large here."""
    from torch.distributions import AffineTransform, Normal, TanhTransform
    from torch.distributions import TransformedDistribution

    cfg, _, buffer, calls = record_training(sac, monkeypatch, tmp_path, "update_critics",
                                            alpha=0.5)
    assert len(calls) == TOTAL - START
    for k, call in enumerate(calls):
        check_minibatch(buffer, call["batch"], START + k + 1)
        obs, action, reward, next_obs, not_done = call["batch"]
        nets = call["nets"]
        torch.set_rng_state(call["rng"])  # the very samples the update drew
        with torch.no_grad():
            base = nets["actor"].distribution(next_obs)
            pi = TransformedDistribution(Normal(base.mean, base.stddev), [
                TanhTransform(cache_size=1), AffineTransform(0.0, 3.0, cache_size=1)])
            a = pi.rsample()  # InvertedPendulum's actions lie in [-3, 3]
            logp = pi.log_prob(a).sum(-1)
            q1, q2 = nets["critic_target"](next_obs, a), nets["critic2_target"](next_obs, a)
            alpha = nets["temperature"]()
            assert alpha.item() == pytest.approx(0.5)
            y = reward + cfg.gamma * not_done * (torch.minimum(q1, q2) - alpha * logp)
            expected = (((nets["critic"](obs, action) - y) ** 2).mean()
                        + ((nets["critic2"](obs, action) - y) ** 2).mean())
        assert call["out"].item() == pytest.approx(expected.item(), rel=1e-5), k
