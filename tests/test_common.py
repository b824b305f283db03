"""Unit tests of common.py: returns and GAE against brute-force sums, evaluation, GIFs, envs."""

import imageio.v3 as iio
import numpy as np
import pytest
import torch

import common


# --- brute-force references: explicit sums, one env column at a time ---------

pytestmark = pytest.mark.quick  # the algorithm's pieces: pytest -m quick runs these


def episode_end(terminated, truncated, t):
    """Index of the step that ends the episode containing t (or T-1 if the rollout ends first)."""
    T = len(terminated)
    k = t
    while k < T - 1 and not (terminated[k] or truncated[k]):
        k += 1
    return k


def brute_returns(r, nv, term, trunc, gamma):
    """G_t = sum_{k=t}^{end} gamma^(k-t) r_k  (+ gamma^(end-t+1) V(s_end+1) unless terminated)."""
    T, N = r.shape
    out = np.zeros((T, N))
    for n in range(N):
        for t in range(T):
            end = episode_end(term[:, n], trunc[:, n], t)
            g = sum(gamma ** (k - t) * r[k, n] for k in range(t, end + 1))
            if not term[end, n]:
                g += gamma ** (end - t + 1) * nv[end, n]
            out[t, n] = g
    return out


def brute_gae(r, v, nv, term, trunc, gamma, lam):
    """A_t = sum_{k=t}^{end} (gamma*lam)^(k-t) delta_k, delta_k = r_k + gamma*V(s_k+1)*(1-term_k) - V(s_k)."""
    T, N = r.shape
    out = np.zeros((T, N))
    for n in range(N):
        for t in range(T):
            end = episode_end(term[:, n], trunc[:, n], t)
            out[t, n] = sum((gamma * lam) ** (k - t) * (r[k, n] + gamma * nv[k, n] * (1 - term[k, n]) - v[k, n])
                            for k in range(t, end + 1))
    return out


def rollout(T=12, N=4, seed=0):
    """Random (T, N) rollout where env 1 is truncated mid-rollout, env 2 terminated,
    env 3 truncated and terminated at once (termination wins), env 0 runs through."""
    g = np.random.default_rng(seed)
    r, v, nv = g.normal(size=(3, T, N))
    term = np.zeros((T, N), dtype=bool)
    trunc = np.zeros((T, N), dtype=bool)
    trunc[4, 1] = True
    term[6, 2] = True
    term[2, 3] = trunc[2, 3] = True
    trunc[8, 3] = True
    return r, v, nv, term, trunc


def as_t(*arrays):
    return [torch.as_tensor(a) for a in arrays]


@pytest.mark.parametrize("gamma", [0.0, 0.5, 0.99, 1.0])
def test_discounted_returns_matches_explicit_sum(gamma):
    r, v, nv, term, trunc = rollout()
    got = common.discounted_returns(*as_t(r, nv, term, trunc), gamma)
    np.testing.assert_allclose(got.numpy(), brute_returns(r, nv, term, trunc, gamma), rtol=1e-10, atol=1e-10)


@pytest.mark.parametrize("gamma,lam", [(0.99, 0.95), (0.98, 0.8), (0.9, 0.0), (0.9, 1.0), (1.0, 1.0)])
def test_gae_matches_explicit_sum(gamma, lam):
    r, v, nv, term, trunc = rollout()
    got = common.gae(*as_t(r, v, nv, term, trunc), gamma, lam)
    np.testing.assert_allclose(got.numpy(), brute_gae(r, v, nv, term, trunc, gamma, lam), rtol=1e-10, atol=1e-10)


def test_truncation_bootstraps_and_termination_does_not():
    """The rule itself, on a 1-step rollout: only the flags differ."""
    r, v, nv = torch.tensor([[1.0]]), torch.tensor([[0.0]]), torch.tensor([[10.0]])
    yes, no = torch.tensor([[True]]), torch.tensor([[False]])
    assert common.discounted_returns(r, nv, no, yes, 0.9).item() == pytest.approx(1 + 0.9 * 10)  # truncated
    assert common.discounted_returns(r, nv, yes, no, 0.9).item() == pytest.approx(1.0)  # terminated
    assert common.discounted_returns(r, nv, yes, yes, 0.9).item() == pytest.approx(1.0)  # both: terminated wins
    assert common.gae(r, v, nv, no, yes, 0.9, 0.95).item() == pytest.approx(1 + 0.9 * 10)
    assert common.gae(r, v, nv, yes, no, 0.9, 0.95).item() == pytest.approx(1.0)


def test_gae_with_lambda_one_is_return_minus_value():
    r, v, nv, term, trunc = rollout(seed=3)
    # The sum of TD errors telescopes only when V(s_{t+1}) is the next row's V inside an episode.
    inside = ~(term | trunc)[:-1]
    nv[:-1][inside] = v[1:][inside]
    adv = common.gae(*as_t(r, v, nv, term, trunc), 0.97, 1.0)
    ret = common.discounted_returns(*as_t(r, nv, term, trunc), 0.97)
    np.testing.assert_allclose(adv.numpy(), (ret - torch.as_tensor(v)).numpy(), atol=1e-10)


def test_truncation_in_a_real_vector_env_rollout():
    """A CartPole vector env with a 5-step time limit: the truncation lands mid-rollout,
    the NEXT_STEP reset step follows it, and the final obs is the next buffer row."""
    import gymnasium as gym

    envs = gym.make_vec("CartPole-v1", num_envs=2, max_episode_steps=5)
    obs, _ = envs.reset(seed=0)
    rows, rewards, terms, truncs = [obs], [], [], []
    for _ in range(8):
        obs, rew, term, trunc, _ = envs.step(np.zeros(2, dtype=np.int64) + np.array([0, 1]))
        rows.append(obs), rewards.append(rew), terms.append(term), truncs.append(trunc)
    envs.close()
    trunc, term = np.array(truncs), np.array(terms)
    assert trunc[4].all() and not term[:5].any()  # 5 steps, then the time limit
    # The row after the truncated step is the final obs of the old episode (not a fresh start)...
    assert np.abs(rows[5]).max() > 0.05
    # ...and the row after that is a new episode (reset obs lie in [-0.05, 0.05]).
    assert np.abs(rows[6]).max() <= 0.05
    r = np.array(rewards, dtype=np.float64)
    assert r[5].sum() == 0  # the reset step pays nothing
    v = np.linspace(1, 2, 9)[:, None].repeat(2, 1)  # any value function will do
    values, next_values = v[:-1], v[1:]  # V(s_{t+1}) = value of the next stored row
    got = common.gae(*as_t(r, values, next_values, term, trunc), 0.99, 0.95)
    np.testing.assert_allclose(got.numpy(), brute_gae(r, values, next_values, term, trunc, 0.99, 0.95), atol=1e-10)
    # The truncated step's advantage uses V(final obs) = next_values[4] = v[5], not 0.
    assert got[4, 0].item() == pytest.approx(1 + 0.99 * v[5, 0] - v[4, 0])


# --- evaluation and GIFs -----------------------------------------------------


def test_evaluate_is_deterministic_and_counts_rewards():
    left = common.evaluate("CartPole-v1", lambda obs: 0, episodes=3, seed=7)
    assert left == common.evaluate("CartPole-v1", lambda obs: 0, episodes=3, seed=7)
    assert all(5 <= r <= 15 for r in left)  # always pushing left fails fast
    # A simple controller (push toward the pole's lean) does far better.
    lean = common.evaluate("CartPole-v1", lambda obs: int(obs[2] + obs[3] > 0), episodes=3, seed=7)
    assert min(lean) > 3 * max(left)


def test_record_gif_writes_frames_showing_the_cart(tmp_path):
    path = tmp_path / "x.gif"
    ret = common.record_gif("CartPole-v1", lambda obs: 0, path, seed=0, every=2, scale=2)
    frames = iio.imread(path)  # (frames, H, W, 3)
    # One frame per 2 steps, plus the first and the last; the GIF writer may merge identical neighbours.
    assert frames.ndim == 4 and 3 <= frames.shape[0] <= 1 + int(ret) // 2 + 1
    assert frames.shape[1:3] == (200, 300)
    first = frames[0]
    assert (first < 60).all(axis=-1).sum() > 200  # the black cart is drawn
    assert (first > 240).all(axis=-1).mean() > 0.5  # on a white background
    assert list(tmp_path.iterdir()) == [path]  # no temporary file left behind


def test_record_gif_keeps_the_one_pixel_track_when_halved(tmp_path):
    """CartPole draws its track as a 1-pixel black line; halving by dropping rows can lose it.
    Averaging 2 x 2 blocks keeps it as a grey line across the frame."""
    full = tmp_path / "full.gif"
    common.record_gif("CartPole-v1", lambda obs: 0, full, seed=0, max_frames=1)
    track_row = int(np.argmax((iio.imread(full)[0] < 60).all(axis=-1).sum(axis=1) > 250))
    assert track_row % 2 == 1  # an odd row: dropping every other row would lose it
    half = tmp_path / "half.gif"
    common.record_gif("CartPole-v1", lambda obs: 0, half, seed=0, max_frames=1, scale=2)
    row = iio.imread(half)[0][track_row // 2]
    assert (row < 200).all(axis=-1).mean() > 0.8  # still a line across the frame


def test_record_gif_returns_the_whole_episode_even_when_frames_are_capped(tmp_path):
    lean = lambda obs: int(obs[2] + obs[3] > 0)  # noqa: E731  (balances for hundreds of steps)
    whole = common.evaluate("CartPole-v1", lean, episodes=1, seed=0)[0]
    assert whole > 100
    assert common.record_gif("CartPole-v1", lean, tmp_path / "x.gif", seed=0, max_frames=10) == whole
    assert iio.imread(tmp_path / "x.gif").shape[0] <= 10


def test_env_errors_are_user_errors():
    with pytest.raises(common.UserError, match="unknown environment"):
        common.evaluate("NoSuchEnv-v0", lambda obs: 0, 1, 0)
    with pytest.raises(common.UserError, match="unknown environment"):
        common.make_vec_env("NoSuchEnv-v0", 2, 0)
    with pytest.raises(common.UserError, match="Discrete"):
        common.make_vec_env("Pendulum-v1", 2, 0)
    import gymnasium as gym

    gym.register("CartPoleNoThreshold-v0", "gymnasium.envs.classic_control:CartPoleEnv")
    with pytest.raises(common.UserError, match="has no reward_threshold; pass --solved-return"):
        common.make_vec_env("CartPoleNoThreshold-v0", 2, 0)
    assert common.make_vec_env("CartPoleNoThreshold-v0", 2, 0, solved_return=50)[2] == 50
    envs, obs, solved = common.make_vec_env("CartPole-v1", 2, 0)
    assert solved == 475 and obs.shape == (2, 4)
    assert common.make_vec_env("CartPole-v1", 2, 0, solved_return=100)[2] == 100


def test_make_continuous_env_refuses_discrete_actions_and_other_simulators():
    with pytest.raises(common.UserError, match="needs continuous \\(Box\\) actions"):
        common.make_continuous_env("CartPole-v1")
    with pytest.raises(common.UserError, match="is not a MuJoCo env"):
        common.make_continuous_env("Pendulum-v1")
    env = common.make_continuous_env("InvertedPendulum-v5")
    assert env.action_space.shape == (1,)
    env.close()



# --- inside the algorithms ---------------------------------------------------------------


def test_ratio_stats_match_numpy_and_the_gradient_itself():
    """The quantiles are numpy's on the same ratios; the share of samples with no policy
    gradient is the share whose term of L_CLIP has a zero gradient, found by autograd."""
    torch.manual_seed(0)
    logp = torch.randn(500, requires_grad=True)
    ratio = torch.exp(logp - logp.detach() + 0.3 * torch.randn(500))  # r, its gradient via logp
    adv = torch.randn(500) + 0.3
    stats = common.ratio_stats(ratio.detach(), adv, 0.2, normalize=True)
    r = ratio.detach().numpy()
    for key, q in common.QUANTILES.items():
        assert stats[key] == pytest.approx(np.quantile(r, q), rel=1e-5)
    assert stats["ratio_min"] == pytest.approx(r.min()) and stats["ratio_max"] == pytest.approx(r.max())
    a = adv - adv.mean()  # the update's normalized advantages have this sign
    terms = torch.min(ratio * a, torch.clamp(ratio, 0.8, 1.2) * a)  # each sample's L_CLIP term
    (grad,) = torch.autograd.grad(terms.sum(), logp)  # d term_i / d log pi(a_i|s_i)
    assert stats["zero_grad_frac"] == pytest.approx((grad == 0).float().mean().item())
    clipfrac = ((ratio.detach() - 1).abs() > 0.2).float().mean().item()
    assert stats["clipfrac_after"] == pytest.approx(clipfrac)  # on the very same ratios
    assert 0 < stats["zero_grad_frac"] < clipfrac  # the clip binds on one side only


def test_clipfrac_after_and_zero_grad_frac_by_hand():
    """r = 1.5, 1.5, 0.5, 0.5, 1.0 with A = +, -, +, -, +: four ratios outside [0.8, 1.2]
    (clipfrac 0.8), of which two on the side their advantage favours (zero gradient 0.4)."""
    r, a = torch.tensor([1.5, 1.5, 0.5, 0.5, 1.0]), torch.tensor([1., -1., 1., -1., 1.])
    stats = common.ratio_stats(r, a, 0.2, normalize=False)
    assert (stats["clipfrac_after"], stats["zero_grad_frac"]) == (0.8, 0.4)


def test_q_against_return_is_the_critic_on_those_states_and_an_explicit_sum():
    """Discounted returns from each state by explicit sums; Q by the critic on those states;
    a time-limited episode's last `horizon` states left out, a terminated one's all kept."""
    rng = np.random.default_rng(0)
    cut = dict(obs=rng.normal(size=(8, 3)), rewards=rng.normal(size=8), terminated=False)
    ended = dict(obs=rng.normal(size=(5, 3)), rewards=rng.normal(size=5), terminated=True)
    actor = torch.nn.Linear(3, 2)
    critic = lambda obs, action: obs.sum(-1) * 2 + action.sum(-1)  # noqa: E731
    q, g, n = common.q_against_return([cut, ended], actor, critic, 0.9, "cpu", horizon=3)
    states = np.concatenate([cut["obs"][:5], ended["obs"]])
    returns = [sum(0.9 ** k * ep["rewards"][t + k] for k in range(len(ep["rewards"]) - t))
               for ep, keep in ((cut, 5), (ended, 5)) for t in range(keep)]
    with torch.no_grad():
        x = torch.as_tensor(states, dtype=torch.float32)
        want_q = critic(x, actor(x)).mean().item()
    assert n == 10 and g == pytest.approx(np.mean(returns)) and q == pytest.approx(want_q, rel=1e-5)


@pytest.mark.parametrize("gamma", [0.99, 0.995])
def test_q_against_return_bounds_the_unseen_tail_as_documented(gamma):
    """An episode cut by the time limit after 3000 steps of reward 1 (the largest): from a
    state that counts, the true return 1/(1 - gamma) exceeds the one summed to the cut by at
    most 0.66 (the docstring's bound); the states closer to the cut than tail_horizon are
    left out; gamma = 1 keeps no state of a cut episode, and all of a terminated one."""
    steps = 3000
    cut = dict(obs=np.zeros((steps, 1)), rewards=np.ones(steps), terminated=False)
    actor, critic = torch.nn.Linear(1, 1), lambda obs, action: obs.sum(-1)  # noqa: E731
    _, g, n = common.q_against_return([cut], actor, critic, gamma, "cpu")
    assert n == steps - common.tail_horizon(gamma)
    true, h = 1 / (1 - gamma), common.tail_horizon(gamma)
    last_kept = (1 - gamma ** (steps - (n - 1))) / (1 - gamma)  # summed from state n-1 to the cut
    assert true - last_kept <= 0.66 < gamma ** (h - 1) / (1 - gamma)  # h - 1 steps: not enough
    assert 0 <= true - g <= 0.66  # the mean over the kept states is no further off
    assert common.q_against_return([cut], actor, critic, 1.0, "cpu")[2] == 0
    ended = dict(cut, terminated=True)
    assert common.q_against_return([ended], actor, critic, 1.0, "cpu")[1:] == (
        pytest.approx(np.mean(np.arange(steps, 0, -1))), steps)


def test_evaluate_hands_back_each_episodes_states_and_rewards():
    seen = []
    returns = common.evaluate("CartPole-v1", lambda obs: 0, episodes=2, seed=3, trajectories=seen)
    assert len(seen) == 2
    for episode, total in zip(seen, returns):
        assert episode["rewards"].sum() == total and len(episode["obs"]) == len(episode["rewards"])
        assert episode["terminated"]  # always pushing left: the pole falls


def test_pi_actions_greedy_plays_the_most_probable_action_and_otherwise_draws_from_pi():
    """greedy=True: argmax of the logits on every one of 200 observations (here the
    observation is the logits); without it, actions drawn with pi's probabilities (1/5, 3/5,
    1/5 here, within 0.03 over 3000 draws), the same draws again from the same seed."""
    logits = np.random.default_rng(0).normal(size=(200, 3)) * 0.3  # close: a draw often differs
    greedy = common.pi_actions(lambda x: x, "cpu", seed=0, greedy=True)
    assert [greedy(row) for row in logits] == list(logits.argmax(1))
    row = np.log([1.0, 3.0, 1.0])
    drawn = common.pi_actions(lambda x: x, "cpu", seed=1)
    actions = [drawn(row) for _ in range(3000)]
    assert np.bincount(actions, minlength=3) / 3000 == pytest.approx([0.2, 0.6, 0.2], abs=0.03)
    again = common.pi_actions(lambda x: x, "cpu", seed=1)
    assert [again(row) for _ in range(3000)] == actions
