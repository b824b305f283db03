"""Unit tests of common.py: each helper against a brute-force reference."""

import dataclasses
import re
import subprocess
import sys
import textwrap

import imageio.v3 as iio
import numpy as np
import pytest
import torch

import common


# --- brute-force references: explicit sums, one env column at a time ---------


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


def test_finished_episodes_match_hand_kept_returns():
    """600 steps of 4 CartPoles with random actions: the (step, return) pairs and the solved flag
    equal per-env sums kept by hand, where the NEXT_STEP reset step belongs to no episode."""
    envs, _, threshold = common.make_vec_env("CartPole-v1", 4, seed=0)
    assert threshold == 475.0
    rng, episodes, by_hand = np.random.default_rng(0), [], []
    running, reset_step, flags = np.zeros(4), np.zeros(4, dtype=bool), set()
    for step in range(1, 601):
        _, reward, term, trunc, info = envs.step(rng.integers(0, 2, size=4))
        running += np.where(reset_step, 0.0, reward)
        for n in np.flatnonzero(term | trunc):
            by_hand.append((step, running[n]))
            running[n] = 0.0
        reset_step = term | trunc
        ended, solved = common.finished_episodes(info, step, episodes, threshold=22.0, window=5)
        episodes += ended
        last = [r for _, r in by_hand[-5:]]
        assert episodes == by_hand and solved == (len(last) == 5 and np.mean(last) >= 22.0)
        flags.add(solved)
    envs.close()
    assert len(episodes) > 50 and flags == {True, False}  # both answers were checked


@pytest.mark.parametrize("rule,good,bad", [("> 0", [1e-9, 5], [0, -1]), (">= 0", [0, 2], [-1e-9]),
                                           ("> 1", [1.5], [1, 0]), ("(0, 1]", [1, 0.5], [0, 1.01]),
                                           ("[0, 1]", [0, 1], [-0.1, 1.1]),
                                           ("> 0 or none", [None, 3], [0])])
def test_check_ranges_accepts_inside_and_names_the_flag_outside(rule, good, bad):
    words = {"> 0": "positive", "(0, 1]": "in (0, 1]", "[0, 1]": "in [0, 1]"}
    for value in good:
        common.check_ranges(dataclasses.make_dataclass("C", ["target_kl"])(value), target_kl=rule)
    for value in bad + ([] if "none" in rule else [None]):
        expected = words.get(rule.removesuffix(" or none"), rule.removesuffix(" or none"))
        with pytest.raises(ValueError, match=re.escape(f"--target-kl must be {expected}")):
            common.check_ranges(dataclasses.make_dataclass("C", ["target_kl"])(value),
                                target_kl=rule)


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


# --- config -> CLI -----------------------------------------------------------


@dataclasses.dataclass
class Demo:
    num_envs: int = 4
    """parallel envs"""
    lr: float = 1e-3
    """learning
    rate"""
    fast: bool = True
    """go fast"""
    target_kl: float | None = None
    """early stop; none = never"""
    name: str = "x"

    def __post_init__(self):
        common.check(self.num_envs > 0, f"--num-envs must be positive, got {self.num_envs}")


def test_parse_config_flags_and_defaults():
    assert common.parse_config(Demo, []) == Demo()
    cfg = common.parse_config(Demo, ["--num-envs", "8", "--lr", "3e-4", "--no-fast", "--target-kl", "0.02", "--name", "y"])
    assert cfg == Demo(num_envs=8, lr=3e-4, fast=False, target_kl=0.02, name="y")
    assert common.parse_config(Demo, ["--target-kl", "none"]).target_kl is None


@pytest.mark.parametrize("argv,needle", [(["--num-envs", "0"], "--num-envs must be positive"),
                                         (["--num-envs", "two"], "invalid int value"),
                                         (["--bogus"], "unrecognized arguments"),
                                         (["--lr", "nan"], "--lr must be a finite number, got nan"),
                                         (["--lr=-inf"], "--lr must be a finite number, got -inf"),
                                         (["--target-kl", "inf"], "--target-kl must be a finite")])
def test_parse_config_rejects_bad_values_with_exit_2(argv, needle, capsys):
    with pytest.raises(SystemExit) as e:
        common.parse_config(Demo, argv)
    assert e.value.code == 2
    err = capsys.readouterr().err
    assert needle in err and len(err.strip().splitlines()) == 1


def test_help_shows_docstrings(capsys):
    with pytest.raises(SystemExit):
        common.parse_config(Demo, ["--help"])
    out = capsys.readouterr().out
    assert "--num-envs" in out and "parallel envs" in out and "learning rate" in out


@dataclasses.dataclass
class Percent:
    share: float = 0.5
    """share of the batch, in % of it (50% = half)"""


def test_help_survives_a_percent_sign(capsys):
    with pytest.raises(SystemExit) as e:
        common.parse_config(Percent, ["--help"])
    assert e.value.code == 0
    assert "in % of it (50% = half)" in capsys.readouterr().out


# --- run folders, CSV, checkpoints, errors -----------------------------------


def test_make_run_dir_names_and_never_reuses(tmp_path):
    a = common.make_run_dir(tmp_path, "ppo_cartpole", "CartPole-v1", 3)
    b = common.make_run_dir(tmp_path, "ppo_cartpole", "CartPole-v1", 3)
    assert a != b and a.is_dir() and b.is_dir()
    assert a.name.startswith("ppo_cartpole__CartPole-v1__seed3__")


def test_make_run_dir_unwritable_is_a_user_error(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    with pytest.raises(common.UserError, match="cannot create run folder"):
        common.make_run_dir(blocker / "runs", "x", "CartPole-v1", 0)


def test_append_csv(tmp_path):
    path = tmp_path / "p.csv"
    common.append_csv(path, dict(step=1, loss=0.5))
    common.append_csv(path, dict(step=2, loss=0.25))
    assert path.read_text().splitlines() == ["step,loss", "1,0.5", "2,0.25"]


def test_checkpoint_round_trip_and_bad_files(tmp_path):
    path = tmp_path / "m.pt"
    common.save_checkpoint(dict(w=torch.arange(3.0), config=dict(a=1)), path)
    ckpt = common.load_checkpoint(path, required=("w", "config"))
    assert torch.equal(ckpt["w"], torch.arange(3.0)) and not (tmp_path / "m.pt.tmp").exists()
    with pytest.raises(common.UserError, match="lacks {'policy'}"):
        common.load_checkpoint(path, required=("policy",))
    with pytest.raises(common.UserError, match="no checkpoint"):
        common.load_checkpoint(tmp_path / "nope.pt")
    bad = tmp_path / "bad.pt"
    bad.write_bytes(b"\x00garbage" * 10)
    with pytest.raises(common.UserError, match="truncated, corrupt or not a checkpoint"):
        common.load_checkpoint(bad)
    half = tmp_path / "half.pt"  # a copy cut short: torch itself says "Invalid argument" or so
    half.write_bytes(path.read_bytes()[:100])
    with pytest.raises(common.UserError, match="truncated, corrupt or not a checkpoint"):
        common.load_checkpoint(half)
    # A pickle with Python objects in it is refused, and nothing suggests weights_only=False.
    unsafe = tmp_path / "unsafe.pt"
    torch.save(dict(w=Demo()), unsafe)
    with pytest.raises(common.UserError, match="not a checkpoint of these scripts") as e:
        common.load_checkpoint(unsafe)
    assert "weights_only" not in str(e.value)
    # A run folder stands for its model.pt; a folder without one says so.
    common.save_checkpoint(dict(w=torch.ones(1)), tmp_path / "model.pt")
    assert torch.equal(common.load_checkpoint(tmp_path)["w"], torch.ones(1))
    with pytest.raises(common.UserError, match="no checkpoint at .*empty.model.pt"):
        (tmp_path / "empty").mkdir()
        common.load_checkpoint(tmp_path / "empty")


def test_save_checkpoint_flushes_to_disk_before_the_rename(tmp_path, monkeypatch):
    calls = []
    real_fsync, real_replace = common.os.fsync, common.os.replace
    monkeypatch.setattr(common.os, "fsync", lambda fd: (calls.append("fsync"), real_fsync(fd))[1])
    monkeypatch.setattr(common.os, "replace", lambda a, b: (calls.append("replace"), real_replace(a, b))[1])
    common.save_checkpoint(dict(w=torch.ones(2)), tmp_path / "m.pt")
    assert calls == ["fsync", "replace"]


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


@pytest.mark.parametrize("body,code,stderr", [
    ("raise common.UserError('something the user can fix')", 2, "error: something the user can fix\n"),
    ("raise KeyboardInterrupt", 130, "\ninterrupted (Ctrl-C)\n"),
    # torch.save cut short by Ctrl-C; MuJoCo's import cut short by it, as gym.make reports it
    ("raise RuntimeError('unexpected pos') from KeyboardInterrupt()", 130,
     "\ninterrupted (Ctrl-C)\n"),
    ("raise RuntimeError('a bug, no Ctrl-C in it')", 1, None),  # stays a traceback
])
def test_clear_exit_prints_one_line(tmp_path, body, code, stderr):
    program = f"import common\nwith common.clear_exit():\n    {body}\n"
    p = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True, cwd=tmp_path,
                       env={"PYTHONPATH": str(__import__("pathlib").Path(common.__file__).parent), "PATH": ""})
    assert p.returncode == code
    assert p.stderr == stderr if stderr else "Traceback" in p.stderr


@pytest.mark.parametrize("preset,expected", [({}, ("dummy", "egl")),
                                             ({"MUJOCO_GL": "osmesa"}, ("dummy", "osmesa"))])
def test_headless_defaults_without_a_display_keep_user_choices(preset, expected):
    import os

    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY", "SDL_VIDEODRIVER", "MUJOCO_GL")}
    env.update(preset, PYTHONPATH=os.path.dirname(common.__file__))
    code = "import os, common; print(os.environ['SDL_VIDEODRIVER'], os.environ['MUJOCO_GL'])"
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
    assert p.returncode == 0, p.stderr
    assert tuple(p.stdout.split()) == expected


def test_env_errors_names_a_missing_egl_library():
    """Headless, MUJOCO_GL=egl (common's default there) on a machine without libEGL: importing
    MuJoCo fails inside PyOpenGL with this AttributeError (seen on a GPU server)."""
    with pytest.raises(common.UserError, match="Walker2d-v5: MuJoCo cannot render without the EGL"):
        with common.env_errors("Walker2d-v5"):
            raise AttributeError("'NoneType' object has no attribute 'eglQueryString'")
    with pytest.raises(AttributeError, match="no attribute 'step'"):  # any other: a bug, shown
        with common.env_errors("Walker2d-v5"):
            raise AttributeError("'NoneType' object has no attribute 'step'")


def test_env_errors_knows_a_ctrl_c_from_a_missing_package():
    """A Ctrl-C while gym.make imports MuJoCo arrives as DependencyNotInstalled, from
    ImportError("initialization failed"), from the KeyboardInterrupt: it is a Ctrl-C."""
    import gymnasium as gym

    def cut_short():
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as ctrl_c:
            try:
                raise ImportError("initialization failed") from ctrl_c
            except ImportError as e:
                raise gym.error.DependencyNotInstalled("MuJoCo is not installed") from e

    with pytest.raises(KeyboardInterrupt):
        with common.env_errors("Walker2d-v5"):
            cut_short()
    with pytest.raises(common.UserError, match="needs a package that is not installed"):
        with common.env_errors("Walker2d-v5"):
            raise gym.error.DependencyNotInstalled("MuJoCo is not installed")


@pytest.fixture
def ctrl_c_raises():
    """SIGINT raises KeyboardInterrupt in this process, as in a terminal (a background job
    would ignore it)."""
    import signal

    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, before)


def test_ctrl_c_during_save_checkpoint_waits_for_the_whole_file(tmp_path, monkeypatch,
                                                                ctrl_c_raises):
    import signal

    real_save = torch.save

    def save(obj, f):  # Ctrl-C as torch.save starts
        signal.raise_signal(signal.SIGINT)
        real_save(obj, f)

    monkeypatch.setattr(common.torch, "save", save)
    with pytest.raises(KeyboardInterrupt):  # it still arrives, once the file is whole
        common.save_checkpoint(dict(w=torch.arange(5.0)), tmp_path / "m.pt")
    monkeypatch.undo()
    assert torch.equal(common.load_checkpoint(tmp_path / "m.pt")["w"], torch.arange(5.0))
    assert [p.name for p in tmp_path.iterdir()] == ["m.pt"]


def test_save_checkpoint_that_cannot_write_is_a_user_error_and_leaves_no_tmp(tmp_path,
                                                                             monkeypatch):
    def full(fd):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(common.os, "fsync", full)
    with pytest.raises(common.UserError, match="cannot write .*m.pt: No space left on device"):
        common.save_checkpoint(dict(w=torch.ones(2)), tmp_path / "m.pt")
    assert list(tmp_path.iterdir()) == []


def test_load_checkpoint_refuses_another_scripts_model(tmp_path):
    common.save_checkpoint(dict(script="ppo_cartpole", w=torch.ones(1)), tmp_path / "a.pt")
    common.save_checkpoint(dict(w=torch.ones(1)), tmp_path / "old.pt")
    assert common.load_checkpoint(tmp_path / "a.pt", ("w",), script="ppo_cartpole")["w"] == 1
    with pytest.raises(common.UserError, match="not a model of ppo_kl_cartpole.py: it is a model "
                                               "of ppo_cartpole.py"):
        common.load_checkpoint(tmp_path / "a.pt", ("w",), script="ppo_kl_cartpole")
    with pytest.raises(common.UserError, match="older version .* train it again"):
        common.load_checkpoint(tmp_path / "old.pt", ("w",), script="ppo_cartpole")


def test_stop_if_diverged(tmp_path):
    net, run = torch.nn.Linear(2, 1), tmp_path / "run"
    run.mkdir()
    common.stop_if_diverged(5, dict(loss=0.5, kl=torch.tensor(0.1)), [net], run, obs=[[1., 2.]])
    assert run.exists()  # all finite: nothing happens
    with pytest.raises(common.UserError, match=r"at step 7: nan or inf in loss_v; likely cause: "
                                               r"too high a learning rate .*run was removed"):
        common.stop_if_diverged(7, dict(loss_pi=0.1, loss_v=float("inf")), [net], run)
    assert not run.exists()
    with torch.no_grad():
        net.weight[0, 0] = 1e38  # finite weights, an output of inf
    with pytest.raises(common.UserError, match="nan or inf in Linear's weights or output"):
        common.stop_if_diverged(7, {}, [net], obs=[[10., 0.]])
    with torch.no_grad():
        net.bias[0] = float("nan")
    with pytest.raises(common.UserError, match="nan or inf in Linear's weights or output"):
        common.stop_if_diverged(7, {}, [net])


@dataclasses.dataclass
class Device:
    cuda: bool = False
    """train on the GPU"""
    lr: float = 1e-3

    def __post_init__(self):
        common.check(self.lr > 0, f"--lr must be positive, got {self.lr}")


@dataclasses.dataclass
class GpuFirst:
    cuda: bool = True
    """train on the GPU if there is one"""


def test_cuda_asked_for_without_a_gpu_says_so_in_one_line(monkeypatch, capsys):
    monkeypatch.setattr(common.torch.cuda, "is_available", lambda: False)
    assert common.parse_config(Device, ["--cuda"]).cuda
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "torch sees no GPU" in err and "running on the CPU" in err
    with pytest.raises(SystemExit):  # bad input: its one error line, and no warning beside it
        common.parse_config(Device, ["--cuda", "--lr", "0"])
    assert capsys.readouterr().err.count("\n") == 1
    common.parse_config(Device, [])  # not asked for: nothing to say
    common.parse_config(GpuFirst, [])  # the GPU when there is one (DDPG's default): no warning
    common.parse_config(GpuFirst, ["--cuda"])
    assert capsys.readouterr().err == ""
    monkeypatch.setattr(common.torch.cuda, "is_available", lambda: True)
    common.parse_config(Device, ["--cuda"])
    assert capsys.readouterr().err == ""


def test_load_weights_mismatch_is_a_user_error():
    small, big = torch.nn.Linear(3, 2), torch.nn.Linear(5, 2)
    common.load_weights(small, torch.nn.Linear(3, 2).state_dict(), "ok.pt")
    with pytest.raises(common.UserError, match="other.pt does not fit this script's Linear"):
        common.load_weights(small, big.state_dict(), "other.pt")
