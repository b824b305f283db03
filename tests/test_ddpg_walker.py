"""DDPG: its replay buffer and soft update against hand computations, a smoke run
on Walker2d-v5, reproducibility, reloading, clear errors, and learning on a cheap task."""

import csv
import io
import os
import subprocess
import sys

import imageio.v3 as iio
import numpy as np
import pytest
import torch

import common
import ddpg_walker as ddpg
import checkpoints
import report
import runlog
import mujoco_env
from common import UserError
from conftest import IN_A_PROCESS, ROOT, interrupt, run_folders, run_main, run_script


def play(path, episodes, script=ddpg):
    """What --eval PATH does: the saved actor's returns over `episodes` episodes (`script`:
    ddpg_walker, or td3_walker, whose Actor is DDPG's)."""
    cfg = script.Config(eval=str(path), eval_episodes=episodes)
    actor, env_id = checkpoints.load_model(cfg.eval, script.SCRIPT, "actor", lambda c: script.Actor(
        c["obs_dim"], c["act_dim"], c["config"]["hidden"], np.array(c["low"]), np.array(c["high"])))
    mu = [("eval_returns", "mu(s), no noise", lambda _: common.deterministic(actor, "cpu"))]
    return report.play(cfg, cfg.eval, env_id, mu)


@pytest.mark.quick
def test_replay_buffer_wraps_around_and_keeps_the_newest():
    buf = ddpg.ReplayBuffer(obs_dim=3, act_dim=2, max_size=5, device="cpu")
    for i in range(7):
        buf.add(np.full(3, i), np.full(2, -i), float(i), np.full(3, i + 0.5), terminated=False)
    assert buf.size == 5 and buf.ptr == 2
    assert sorted(buf.reward.tolist()) == [2.0, 3.0, 4.0, 5.0, 6.0]  # 0 and 1 were overwritten
    assert buf.reward[0].item() == 5.0 and buf.reward[1].item() == 6.0
    assert buf.obs[0].tolist() == [5.0] * 3 and buf.action[1].tolist() == [-6.0] * 2


@pytest.mark.quick
def test_replay_buffer_sample_shapes_and_fields():
    buf = ddpg.ReplayBuffer(obs_dim=4, act_dim=2, max_size=100, device="cpu")
    for i in range(10):
        buf.add(np.arange(4) + i, np.array([0.5, -0.5]), 1.0 + i, np.arange(4) + i + 1, terminated=(i == 9))
    obs, act, rew, next_obs, not_done = buf.sample(32)
    assert obs.shape == (32, 4) and act.shape == (32, 2) and next_obs.shape == (32, 4)
    assert rew.shape == (32,) and not_done.shape == (32,)
    # Each sampled row is one stored transition, its fields in the right place.
    i = (rew - 1).long()
    torch.testing.assert_close(obs, torch.arange(4.0) + i[:, None].float())
    torch.testing.assert_close(next_obs, obs + 1)
    assert torch.equal(not_done, (i != 9).float())
    assert (act == torch.tensor([0.5, -0.5])).all()
    # Sampling never reads beyond what was stored.
    assert set(i.tolist()) <= set(range(10))


@pytest.mark.quick
def test_truncated_is_not_terminal_in_the_buffer():
    """A time-limit truncation keeps not_done = 1 (bootstrap); only termination zeroes it."""
    buf = ddpg.ReplayBuffer(obs_dim=1, act_dim=1, max_size=4, device="cpu")
    buf.add(np.zeros(1), np.zeros(1), 1.0, np.ones(1), terminated=True)   # fell over
    buf.add(np.zeros(1), np.zeros(1), 2.0, np.ones(1), terminated=False)  # time limit or mid-episode
    assert buf.not_done[:2].tolist() == [0.0, 1.0]


@pytest.mark.quick
def test_training_loop_stores_truncation_as_not_terminal(monkeypatch, tmp_path):
    """Run the real loop on an env with a 3-step time limit: what the buffer stores as
    terminal must be the env's `terminated`, never its `truncated`."""
    real_make = common.gym.make
    flags = []  # (terminated, truncated) as the env returned them

    def make_short_env(env_id, **kw):
        env = real_make(env_id, max_episode_steps=3, **kw)
        real_step = env.step

        def step(action):
            out = real_step(action)
            flags.append((bool(out[2]), bool(out[3])))
            return out
        env.step = step
        return env

    monkeypatch.setattr(common.gym, "make", make_short_env)
    stored = []
    real_add = ddpg.ReplayBuffer.add
    monkeypatch.setattr(ddpg.ReplayBuffer, "add", lambda self, o, a, r, no, terminated: (
        stored.append(terminated), real_add(self, o, a, r, no, terminated))[1])
    ddpg.train(ddpg.Config(env_id="InvertedPendulum-v5", total_timesteps=40, start_steps=32, batch_size=32,
                           eval_every=10**6,
                           print_every=10**6, gifs=False, run_dir=str(tmp_path), cuda=False))
    assert len(stored) == 40
    assert [bool(x) for x in stored] == [term for term, _ in flags]
    assert any(trunc and not term for term, trunc in flags)  # time limits happened and were stored as not terminal


@pytest.mark.quick
def test_soft_update_matches_hand_computation():
    source, target = torch.nn.Linear(3, 2), torch.nn.Linear(3, 2)
    w_s, w_t = source.weight.detach().clone(), target.weight.detach().clone()
    b_s, b_t = source.bias.detach().clone(), target.bias.detach().clone()
    ddpg.soft_update(target, source, tau=0.1)
    torch.testing.assert_close(target.weight, 0.1 * w_s + 0.9 * w_t)
    torch.testing.assert_close(target.bias, 0.1 * b_s + 0.9 * b_t)
    torch.testing.assert_close(source.weight, w_s)  # the source is untouched


@pytest.mark.quick
def test_td_target_by_hand():
    """y = r + gamma * not_done * Q'(s', mu'(s')): no future after a termination."""
    y = ddpg.td_target(torch.tensor([1.0, 1.0, -2.0]), torch.tensor([1.0, 0.0, 1.0]),
                       torch.tensor([10.0, 10.0, 4.0]), 0.9)
    assert y.tolist() == pytest.approx([1 + 0.9 * 10, 1.0, -2 + 0.9 * 4])


@pytest.mark.quick
def test_actor_loss_is_minus_q_and_its_step_raises_q():
    torch.manual_seed(0)
    actor = ddpg.Actor(3, 2, 16, np.full(2, -1.0), np.full(2, 1.0))
    critic = ddpg.Critic(3, 2, 16)
    obs = torch.randn(64, 3)
    q_before = critic(obs, actor(obs)).mean().item()
    loss = ddpg.compute_loss_actor(actor, critic, obs)
    assert loss.item() == pytest.approx(-q_before)
    opt = torch.optim.Adam(actor.parameters(), lr=1e-2)
    for _ in range(20):  # descending the loss climbs Q(s, mu(s)); the critic stays as it is
        opt.zero_grad()
        ddpg.compute_loss_actor(actor, critic, obs).backward()
        opt.step()
    assert critic(obs, actor(obs)).mean().item() > q_before + 1e-3


@pytest.mark.quick
def test_ddpg_update_by_hand_the_target_networks_give_the_td_target():
    """One update on a fixed batch: the critic's loss is the MSE to y = r + gamma * not_done *
    Q'(s', mu'(s')) with the TARGET networks (here made different from the online ones)."""
    torch.manual_seed(0)
    cfg = ddpg.Config(gamma=0.9, tau=0.5, hidden=8)
    nets = ddpg.build(3, 2, np.full(2, -1.0), np.full(2, 1.0), cfg, torch.device("cpu"))
    actor, critic, actor_target, critic_target = list(nets.values())[:4]
    with torch.no_grad():
        for p in [*actor.parameters(), *critic.parameters()]:
            p.add_(0.5 * torch.randn_like(p))  # the online networks moved away from the targets
    obs, action, next_obs = torch.randn(5, 3), torch.rand(5, 2) * 2 - 1, torch.randn(5, 3)
    reward, not_done = torch.randn(5), torch.tensor([1.0, 1.0, 0.0, 1.0, 0.0])
    with torch.no_grad():
        q = critic(obs, action)
        y = reward + 0.9 * not_done * critic_target(next_obs, actor_target(next_obs))
        y_online = reward + 0.9 * not_done * critic(next_obs, actor(next_obs))
        assert not torch.allclose(y, y_online)  # the test can tell the two apart
        targets_before = [p.clone() for p in [*actor_target.parameters(), *critic_target.parameters()]]
    critic_loss, actor_loss = ddpg.ddpg_update(*nets.values(), (obs, action, reward, next_obs, not_done), cfg)
    assert critic_loss.item() == pytest.approx(((q - y) ** 2).mean().item(), rel=1e-6)
    # the actor's loss is -Q(s, mu(s)) under the critic just updated
    assert actor_loss.item() < 0 or actor_loss.item() > 0
    # then the targets moved halfway (tau = 0.5) toward the updated networks
    after = [*actor_target.parameters(), *critic_target.parameters()]
    online = [*actor.parameters(), *critic.parameters()]
    for before, target, net in zip(targets_before, after, online):
        torch.testing.assert_close(target, 0.5 * before + 0.5 * net.detach())


def test_the_warm_up_is_evaluated_once_then_every_eval_every(tmp_path, capsys):
    """The first line says when curve.png is redrawn, as it then happens: once in the warm-up
    only where an evaluation falls in it (the README's InvertedPendulum command: none)."""
    result = ddpg.train(small(tmp_path, env_id="InvertedPendulum-v5", total_timesteps=1500,
                              start_steps=1000, eval_every=250, eval_episodes=1, gifs=False,
                              curves=False))
    assert [e["global_step"] for e in result["evaluations"]] == [250, 1250, 1500]
    assert "once in the warm-up (step 250), then from step 1250 on" in capsys.readouterr().out
    result = ddpg.train(small(tmp_path, env_id="InvertedPendulum-v5", total_timesteps=1500,
                              start_steps=1000, eval_every=1250, eval_episodes=1, gifs=False,
                              curves=False))
    assert [e["global_step"] for e in result["evaluations"]] == [1250]
    out = capsys.readouterr().out
    assert "from step 1250 on, every 1250 steps" in out and "warm-up" not in out.split("\n")[1]


def test_eval_gif_writes_a_gif_of_a_saved_actor_without_a_display(tmp_path, capsys):
    first = ddpg.train(small(tmp_path, total_timesteps=400, start_steps=300, eval_every=400,
                             eval_episodes=1, gifs=False, curves=False))
    out = tmp_path / "walker.gif"
    p = run_main("ddpg_walker.py", "--eval", first["run_dir"] / "best.pt", "--gif", out,
                 capsys=capsys)
    assert p.returncode == 0, p.stderr
    frames = iio.imread(out)
    assert frames.ndim == 4 and frames.shape[0] >= 2 and frames[0].std() > 10
    assert f"{out}: one episode, return" in p.stdout


def test_watch_window_follows_the_agent():
    """The window (render_mode="human") ignores camera_name: --watch asks for a tracking camera
    on top of the env's own view settings."""
    import mujoco

    kw = mujoco_env.watch_camera("Walker2d-v5")["default_camera_config"]
    assert kw["type"] == mujoco.mjtCamera.mjCAMERA_TRACKING and kw["distance"] == 4.0


@pytest.mark.quick
def test_critic_takes_the_action_at_its_second_layer():
    critic = ddpg.Critic(obs_dim=17, act_dim=6, hidden=32)
    assert critic.l1.in_features == 17 and critic.l2.in_features == 32 + 6
    assert critic(torch.zeros(5, 17), torch.zeros(5, 6)).shape == (5,)


def small(tmp_path, **kw):
    return ddpg.Config(**{**dict(total_timesteps=600, start_steps=300, eval_every=300, eval_episodes=2,
                                 print_every=300, batch_size=64, hidden=64, run_dir=str(tmp_path), cuda=False), **kw})


def test_smoke_walker2d_writes_gifs_eval_csv_and_model(tmp_path, monkeypatch):
    # a few frames per GIF: rendering Walker2d off-screen on a CPU takes about 0.1 s a frame
    monkeypatch.setitem(mujoco_env.GIF, "max_frames", 4)
    result = ddpg.train(small(tmp_path))
    run = result["run_dir"]
    assert {p.name for p in run.iterdir()} == {"evaluations.csv", "episodes.csv", "model.pt", "best.pt",
                                               "best.gif", "curve.png", "inside.png", "before.gif", "after.gif",
                                               "checkpoint.pt"}
    rows = list(csv.DictReader(open(run / "evaluations.csv")))
    assert [int(r["global_step"]) for r in rows] == [300, 600]
    assert {"eval_mean", "eval_std"} <= set(rows[0])
    for gif in ("before.gif", "after.gif"):
        frames = iio.imread(run / gif)
        assert frames.ndim == 4 and frames.shape[0] >= 2
        assert frames[0].std() > 10  # a rendered scene, not a blank image
    ckpt = torch.load(run / "model.pt", weights_only=True)
    assert ckpt["global_step"] == 600 and ckpt["config"]["env_id"] == "Walker2d-v5"
    # the full checkpoint loads as plain tensors and values (weights_only), Walker2d's numpy
    # float64 rewards included
    assert torch.load(run / "checkpoint.pt", weights_only=True)["global_step"] == 600
    # --eval replays the saved actor: same returns as the last evaluation.
    returns = play(str(run / "model.pt"), 2)
    assert np.mean(returns) == pytest.approx(result["evaluations"][-1]["eval_mean"])


def test_a_short_run_writes_its_files_and_replays_its_last_evaluation(tmp_path):
    """600 steps on the cheap MuJoCo task, every file written, --eval giving back the last
    evaluation (the quick layer's DDPG run is test_every_script.py's smoke run); three
    evaluations after the warm-up's, so that inside.png draws lines, not points."""
    result = ddpg.train(small(tmp_path, env_id="InvertedPendulum-v5", total_timesteps=600,
                              start_steps=200, eval_every=150, eval_episodes=1))
    run = result["run_dir"]
    assert {p.name for p in run.iterdir()} == {"evaluations.csv", "episodes.csv", "model.pt", "best.pt",
                                               "best.gif", "curve.png", "inside.png", "before.gif", "after.gif",
                                               "checkpoint.pt"}
    assert [e["global_step"] for e in result["evaluations"]] == [150, 300, 450, 600]
    from test_cartpole_scripts import assert_curve_drawn
    assert_curve_drawn(run / "inside.png")
    row = list(csv.DictReader(open(run / "evaluations.csv")))[-1]
    assert int(row["q_states"]) > 0 and float(row["discounted_return"]) > 0
    assert play(run / "model.pt", 1) == [result["evaluations"][-1]["eval_mean"]]


@pytest.mark.parametrize("env_id", ["Hopper-v5", "HalfCheetah-v5", "InvertedPendulum-v5"])
def test_other_mujoco_tasks_run(tmp_path, env_id):
    result = ddpg.train(small(tmp_path, env_id=env_id, total_timesteps=300, start_steps=200, eval_every=300,
                              eval_episodes=1, gifs=False))
    assert result["global_step"] == 300 and len(result["evaluations"]) == 1
    ckpt = torch.load(result["run_dir"] / "model.pt", weights_only=True)
    assert ckpt["config"]["env_id"] == env_id


def test_best_pt_holds_the_best_evaluation(tmp_path):
    result = ddpg.train(small(tmp_path, env_id="InvertedPendulum-v5", total_timesteps=2000,
                              start_steps=500, eval_every=250, eval_episodes=2, gifs=False,
                              curves=False, actor_lr=1e-3, critic_lr=1e-3))
    rows = list(csv.DictReader(open(result["run_dir"] / "evaluations.csv")))
    means = [float(r["eval_mean"]) for r in rows]
    assert len(set(means)) > 1  # the evaluations differ, so "the best" means something
    best = play(str(result["run_dir"] / "best.pt"), 2)
    assert np.mean(best) == pytest.approx(max(means), rel=1e-5)
    step = torch.load(result["run_dir"] / "best.pt", weights_only=True)["global_step"]
    assert step == int(rows[int(np.argmax(means))]["global_step"])


def test_curve_is_redrawn_at_every_evaluation(tmp_path, monkeypatch):
    from test_cartpole_scripts import assert_curve_drawn

    seen = []
    real_draw = report.plots.draw

    def draw(run_dir, name, *args, **kw):
        path = real_draw(run_dir, name, *args, **kw)
        if name == "curve.png":
            seen.append(path.read_bytes())
        return path
    monkeypatch.setattr(report.plots, "draw", draw)
    result = ddpg.train(small(tmp_path, env_id="InvertedPendulum-v5", total_timesteps=1200,
                              start_steps=300, eval_every=300, eval_episodes=1, gifs=False))
    assert len(seen) == 4 and len(set(seen)) == 4  # one new picture per evaluation
    assert_curve_drawn(result["run_dir"] / "curve.png")


def test_the_camera_follows_the_walker():
    """Moved 6 m forward, the walker is still in the picture of the GIFs' camera; gymnasium's
    default free camera shows empty floor there."""
    import gymnasium as gym
    import mujoco

    def walker_pixels(**make_kw):
        env = gym.make("Walker2d-v5", render_mode="rgb_array", **make_kw)
        env.reset(seed=0)
        counts = []
        for dx in (0.0, 6.0):
            data = env.unwrapped.data
            data.qpos[0] += dx  # the torso's x position
            mujoco.mj_forward(env.unwrapped.model, data)
            frame = env.render().astype(int)
            counts.append(int(((frame[..., 0] - frame[..., 1]) > 40).sum()))  # the walker's colours
        env.close()
        return counts

    start, moved = walker_pixels(camera_name=mujoco_env.GIF["camera_name"])
    assert start > 500 and moved > 0.5 * start
    assert walker_pixels()[1] < 50  # the default camera lost it: the test can tell


# --- exact continuation: a stopped, killed or interrupted run, resumed, is the unbroken run ---

PENDULUM = dict(env_id="InvertedPendulum-v5", total_timesteps=2400, start_steps=600, eval_every=300,
                eval_episodes=2, checkpoint_every=800, print_every=100, batch_size=64, hidden=64,
                gifs=False, curves=False, cuda=False)


def pendulum_flags(**kw):
    cfg = {**PENDULUM, **kw}
    flags = []
    for name, value in cfg.items():
        flag = "--" + name.replace("_", "-")
        flags += [flag] if value is True else [f"--no-{flag[2:]}"] if value is False else [flag, value]
    return flags


def assert_same_state(a, b, where="checkpoint"):
    """Two saved states equal in every field, recursively: tensors bit for bit, numbers and
    lists exactly."""
    assert type(a) is type(b), where
    if isinstance(a, dict):
        assert a.keys() == b.keys(), where
        for key in a:
            assert_same_state(a[key], b[key], f"{where}[{key!r}]")
    elif isinstance(a, (list, tuple)):
        assert len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b)):
            assert_same_state(x, y, f"{where}[{i}]")
    elif torch.is_tensor(a):
        assert a.dtype == b.dtype and torch.equal(a, b), where
    else:
        assert a == b or a != a and b != b, where  # nan == nan here


def assert_same_run(a, b):
    """Same logs byte for byte, and the same checkpoint in every field of every object it
    holds (networks, optimizers, replay buffer, env, random generators, logs), but the
    run's clock."""
    for name in ("evaluations.csv", "episodes.csv"):
        assert (a / name).read_bytes() == (b / name).read_bytes(), name
    ca, cb = (torch.load(d / "checkpoint.pt", weights_only=True) for d in (a, b))
    for ckpt in (ca, cb):
        ckpt["log"].pop("elapsed")
        ckpt["config"].pop("resume")  # the resumed run names its folder
        ckpt["config"].pop("run_dir")
        files = ckpt["log"]["files"]  # its copies of model.pt, best.pt (and pictures, GIFs)
        for name in [name for name in files if name.endswith(".pt")]:
            files[name] = torch.load(io.BytesIO(files[name].numpy().tobytes()),
                                     weights_only=True)
            files[name]["config"].pop("resume")  # these too, as their run named them
            files[name]["config"].pop("run_dir")
    assert_same_state(ca, cb)


@pytest.fixture(scope="module")
def unbroken(tmp_path_factory):
    """The reference: one run that never stopped."""
    return ddpg.train(ddpg.Config(**PENDULUM, run_dir=str(tmp_path_factory.mktemp("unbroken"))))


def test_resume_after_a_kill_rolls_back_to_the_checkpoint_and_is_the_unbroken_run(unbroken, tmp_path):
    """kill -9 after the step-800 checkpoint, once later rows are written: --resume drops those
    rows, continues from step 800 and ends exactly as the run that never stopped."""
    proc = subprocess.Popen([sys.executable, str(ROOT / "ddpg_walker.py"), *map(str, pendulum_flags()),
                             "--run-dir", str(tmp_path)], stdout=subprocess.PIPE, text=True, cwd=ROOT,
                            env=dict(os.environ, PYTHONUNBUFFERED="1"))
    seen = []
    for line in proc.stdout:  # wait for the checkpoint, then for rows that come after it
        seen.append(line)
        if line.startswith("evaluation at step 1200"):
            break
    proc.kill()  # SIGKILL: no handler runs, nothing is saved
    proc.wait()
    assert any(line.startswith("checkpoint at step 800") for line in seen), seen
    (run,) = run_folders(tmp_path)
    steps = [int(r["global_step"]) for r in csv.DictReader(open(run / "evaluations.csv"))]
    assert steps[-1] >= 1200  # rows after the checkpoint were written before the kill
    (run / "checkpoint.pt.tmp").write_bytes(b"half a checkpoint")  # as a kill mid-write leaves it
    result = ddpg.train(ddpg.Config(resume=str(run)))  # its saved settings, not the defaults
    assert result["global_step"] == PENDULUM["total_timesteps"]
    assert not list(run.glob("*.tmp"))
    assert_same_run(unbroken["run_dir"], run)


def test_ctrl_c_saves_a_checkpoint_at_the_step_it_stopped_and_resume_is_the_unbroken_run(unbroken, tmp_path):
    code, out, err = interrupt("ddpg_walker.py", *pendulum_flags(), "--run-dir", tmp_path,
                               after="step     1100")
    assert code == 130, err
    assert err.strip() == "", err  # the one line saying where everything is goes to stdout
    (run,) = run_folders(tmp_path)
    stopped = torch.load(run / "checkpoint.pt", weights_only=True)["global_step"]
    assert 1100 <= stopped < 2400 and stopped % 800  # where Ctrl-C came, not a periodic checkpoint
    assert f"interrupted at step {stopped}" in out and f"--resume {run}" in out
    assert out.splitlines()[-1].startswith(f"interrupted at step {stopped};")  # the one line:
    assert f"checkpoint at step {stopped}:" not in out  # no second about the checkpoint
    result = ddpg.train(ddpg.Config(resume=str(run), run_dir=str(tmp_path)))
    assert result["global_step"] == 2400
    assert_same_run(unbroken["run_dir"], run)


def test_resume_extends_a_finished_run_and_refuses_other_learning_settings(unbroken, tmp_path,
                                                                           monkeypatch):
    """A run resumed by a script that has since declared another column is refused at once,
    in one line (its rows could not share one evaluations.csv)."""
    import shutil

    run = tmp_path / "run"
    shutil.copytree(unbroken["run_dir"], run)
    with pytest.raises(UserError, match="already ran 2400 steps"):
        ddpg.train(ddpg.Config(resume=str(run)))
    with pytest.raises(UserError, match="--actor-lr 0.001 differs from the saved 0.0003"):
        ddpg.train(ddpg.Config(resume=str(run), total_timesteps=2700, actor_lr=1e-3))
    with monkeypatch.context() as m:
        m.setattr(ddpg, "LOGGED", {**ddpg.LOGGED, "added_later": (None, "a new column")})
        with pytest.raises(UserError, match="this ddpg_walker.py logs .*'added_later'.*: resume "
                                            "it with the version that began it"):
            ddpg.train(ddpg.Config(resume=str(run), total_timesteps=2700))
    result = ddpg.train(ddpg.Config(resume=str(run), total_timesteps=2700))
    assert [e["global_step"] for e in result["evaluations"]][-2:] == [2400, 2700]
    ckpt = torch.load(run / "checkpoint.pt", weights_only=True)
    assert ckpt["global_step"] == 2700 and ckpt["config"]["hidden"] == 64  # the saved settings


def assert_files_agree_with_the_logs(run, scratch):
    """curve.png and inside.png are what the run's logs draw; best.pt is the actor of the
    best evaluation in evaluations.csv (the first of equals), and best.gif that actor's
    episode, as the run records it."""
    import shutil
    import types

    rows = list(csv.DictReader(open(run / "evaluations.csv")))
    means = [float(r["eval_mean"]) for r in rows]
    best = torch.load(run / "best.pt", weights_only=True)
    assert best["global_step"] == int(rows[int(np.argmax(means))]["global_step"]), (
        best["global_step"], rows)
    copy = scratch / run.name  # the pictures' title is the folder's name
    copy.mkdir(parents=True)
    for name in ("evaluations.csv", "episodes.csv"):
        shutil.copy(run / name, copy)
    log = types.SimpleNamespace(dir=copy, labels=runlog.EvaluationLog(
        ddpg.SCRIPT, ddpg.Config(resume=str(copy)), "cpu", ddpg.LOGGED, 0, 1).labels,
        learning_starts=PENDULUM["start_steps"])  # the warm-up the pictures shade
    report.draw_pictures(log, ddpg.PICTURES, report.plots.evaluation_returns())
    for name in ("curve.png", "inside.png"):
        assert (run / name).read_bytes() == (copy / name).read_bytes(), name
    actor = ddpg.Actor(best["obs_dim"], best["act_dim"], best["config"]["hidden"],
                       np.array(best["low"]), np.array(best["high"]))
    actor.load_state_dict(best["actor"])
    common.record_gif(best["config"]["env_id"], common.deterministic(actor, "cpu"),
                      copy / "best.gif", best["config"]["eval_seed"], **mujoco_env.GIF)
    assert (run / "best.gif").read_bytes() == (copy / "best.gif").read_bytes()


def test_resume_after_a_kill_puts_back_the_pictures_and_best_files_of_its_checkpoint(tmp_path):
    """kill -9 after evaluations past the step-1600 checkpoint drew curve.png and wrote a new
    best: --resume puts back the pictures, best.pt and best.gif as they were at the
    checkpoint (a Ctrl-C right after the resume leaves no future drawn), and they agree with
    evaluations.csv again when the run ends."""
    flags = pendulum_flags(gifs=True, curves=True)
    proc = subprocess.Popen([sys.executable, str(ROOT / "ddpg_walker.py"), *map(str, flags),
                             "--run-dir", str(tmp_path / "runs")], stdout=subprocess.PIPE,
                            text=True, cwd=ROOT, env=dict(os.environ, PYTHONUNBUFFERED="1"))
    for line in proc.stdout:  # step 2200: the evaluation at 2100 has written its files
        if line.startswith("step     2200"):
            break
    proc.kill()  # SIGKILL: no handler runs, nothing is saved
    proc.wait()
    (run,) = run_folders(tmp_path / "runs")
    saved = torch.load(run / "checkpoint.pt", weights_only=True)["global_step"]
    future = torch.load(run / "best.pt", weights_only=True)["global_step"]
    assert saved == 1600 and future > saved  # what this test is about: a best past it
    code, out, err = interrupt("ddpg_walker.py", "--resume", run, after="resumed")
    assert code == 130, (out, err)
    assert torch.load(run / "best.pt", weights_only=True)["global_step"] <= saved
    assert torch.load(run / "model.pt", weights_only=True)["global_step"] <= 1700
    assert_files_agree_with_the_logs(run, tmp_path / "at_the_checkpoint")
    ddpg.train(ddpg.Config(resume=str(run)))
    assert_files_agree_with_the_logs(run, tmp_path / "at_the_end")
    assert torch.load(run / "best.pt", weights_only=True)["global_step"] == future


def test_same_seed_same_evaluations(tmp_path):
    a, b = [ddpg.train(small(tmp_path / str(i), gifs=False, seed=5)) for i in range(2)]
    assert (a["run_dir"] / "evaluations.csv").read_text() == (b["run_dir"] / "evaluations.csv").read_text()


@pytest.mark.parametrize("args,needle", [
    (["--env-id", "CartPole-v1"], "is not a MuJoCo env"),
    (["--env-id", "NoSuchEnv-v0"], "unknown environment"),
    (["--tau", "0"], "--tau must be in (0, 1]"),
    (["--start-steps", "0"], "--start-steps must be at least --batch-size"),
    (["--total-timesteps", "100", "--start-steps", "25000"], "must exceed --start-steps"),
    (["--buffer-size", "10000000000", "--total-timesteps", "100000000000"],
     "not enough memory"),
    (["--eval", "{tmp}"], "no checkpoint at"),
    (["--eval", "{tmp}/missing.pt"], "no checkpoint"),
    (["--resume", "{tmp}"], "no checkpoint at"),
    (["--resume", "{tmp}", "--eval", "{file}"], "pass one"),
    (["--gif", "{tmp}/x.gif"], "it needs --eval"),
    (["--env-id", "Pendulum-v1"], "is not a MuJoCo env"),
])
def test_bad_input_is_one_line_and_exit_2(tmp_path, args, needle, capsys):
    bad = tmp_path / "bad.pt"
    bad.write_bytes(b"not a checkpoint")
    args = [a.format(tmp=tmp_path, file=bad) for a in args]
    if "--total-timesteps" not in args:  # small budgets, so that a valid run would be short
        args += ["--total-timesteps", "300"] + ([] if "--start-steps" in args else ["--start-steps", "256"])
    if needle in IN_A_PROCESS:  # as a user runs it
        p = run_script("ddpg_walker.py", *args, "--run-dir", tmp_path, timeout=120)
    else:  # in this process (conftest.run_main)
        p = run_main("ddpg_walker.py", *args, "--run-dir", tmp_path, capsys=capsys)
    assert p.returncode == 2, (p.stdout, p.stderr)
    assert needle in p.stderr and len(p.stderr.strip().splitlines()) == 1 and "Traceback" not in p.stderr
    assert sorted(tmp_path.iterdir()) == [bad]  # no run folder left behind


def test_eval_of_a_checkpoint_says_it_is_for_resume_and_gif_needs_a_gif_name(tmp_path, capsys):
    """--eval RUN/checkpoint.pt names what the file is for; --gif OUT.png is refused, not
    written as a GIF under a .png name. Each: one line, exit 2, nothing written."""
    run = ddpg.train(small(tmp_path, env_id="InvertedPendulum-v5", total_timesteps=300,
                           start_steps=200, eval_every=300, eval_episodes=1,
                           gifs=False))["run_dir"]
    capsys.readouterr()
    p = run_main("ddpg_walker.py", "--eval", run / "checkpoint.pt", capsys=capsys)
    assert p.returncode == 2 and len(p.stderr.strip().splitlines()) == 1, p.stderr
    assert f"for --resume {run}" in p.stderr
    p = run_main("ddpg_walker.py", "--eval", run / "model.pt", "--gif", tmp_path / "out.png",
                 capsys=capsys)
    assert p.returncode == 2 and "ends in .gif" in p.stderr, p.stderr
    assert not (tmp_path / "out.png").exists()


def test_missing_mujoco_is_one_clear_line(tmp_path):
    code = ("import sys; sys.modules['mujoco'] = None\n"  # as if MuJoCo were not installed
            "import ddpg_walker; ddpg_walker.main(['--run-dir', sys.argv[1]])")
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    p = subprocess.run([sys.executable, "-c", code, str(tmp_path)], capture_output=True, text=True, env=env,
                       timeout=120)
    assert p.returncode == 2, p.stderr
    assert "needs a package that is not installed" in p.stderr and "Traceback" not in p.stderr


# DDPG's learning run on InvertedPendulum (the README's settings, seed 0) is in
# tests/test_exercises.py: stage (c) of its exercises, with the script's own functions.


def test_help_shows_the_exploration_noise(capsys):
    p = run_main("ddpg_walker.py", "--help", capsys=capsys)
    assert p.returncode == 0, p.stderr
    assert "--threads" in p.stdout and "--expl-noise" in p.stdout


def test_ctrl_c_during_eval(tmp_path):
    first = ddpg.train(small(tmp_path, env_id="InvertedPendulum-v5", total_timesteps=300,
                             start_steps=200, eval_every=300, eval_episodes=1, gifs=False))
    code, out, err = interrupt("ddpg_walker.py", "--eval", first["run_dir"] / "best.pt",
                               "--eval-episodes", 100_000, after="playing")
    assert code == 130, (out, err)
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1 and "interrupted" in err


def test_the_shipped_walker_walks():
    """docs/ddpg_walker2d.pt, the best actor of the 1M-step Walker2d runs (the README's first
    DDPG command replays it), still loads and walks: one episode without noise, >= 1000."""
    (ret,) = play(str(ROOT / "docs" / "ddpg_walker2d.pt"), 1)
    assert ret >= 1000, ret


def test_steps_per_second_leave_out_the_evaluations_and_resume_keeps_the_clock(
        tmp_path, monkeypatch, capsys):
    """On a fake clock where every step costs the same and an evaluation costs 1000 s: every
    progress line's steps/s is the same (the line after an evaluation does not count it), and
    --resume goes on with the run's clock, not from 0."""
    import time as real_time

    class Clock:  # 0.01 s a call, plus what an evaluation costs
        now = 1000.0

        def time(self):
            Clock.now += 0.01
            return Clock.now

        def __getattr__(self, name):
            return getattr(real_time, name)

    monkeypatch.setattr(runlog, "time", Clock())
    real_evaluate = common.evaluate

    def slow_evaluate(*args, **kw):
        Clock.now += 1000.0
        return real_evaluate(*args, **kw)

    monkeypatch.setattr(common, "evaluate", slow_evaluate)
    cfg = small(tmp_path, env_id="InvertedPendulum-v5", total_timesteps=1200, start_steps=300,
                eval_every=400, print_every=100, eval_episodes=1, gifs=False, curves=False,
                checkpoint_every=600)
    ddpg.train(cfg)
    lines = [line.split() for line in capsys.readouterr().out.splitlines()
             if line.startswith("step") and "steps/s" in line]
    rates = [float(words[2]) for words in lines]
    assert len(rates) >= 8 and max(rates) - min(rates) <= 0.1 * max(rates), rates
    run = run_folders(tmp_path)[0]
    ckpt = torch.load(run / "checkpoint.pt", weights_only=True)
    assert ckpt["log"]["elapsed"] > 2000  # two evaluations of 1000 s on the run's clock
    ddpg.train(ddpg.Config(resume=str(run), total_timesteps=1300))
    last = [line for line in capsys.readouterr().out.splitlines() if line.startswith("step")][-1]
    *hours, minutes, _ = last.split()[-1].split(":")  # the run's clock: [h:]mm:ss
    assert int(hours[0] if hours else 0) * 60 + int(minutes) >= 33  # 2000 s on: not from 0


def test_model_pt_is_the_actor_training_ended_with(tmp_path):
    """400 steps, evaluations at 150 and 300: model.pt holds step 400's actor (not the last
    evaluation's), and says so; --eval plays that actor."""
    result = ddpg.train(small(tmp_path, env_id="InvertedPendulum-v5", total_timesteps=400,
                              start_steps=150, eval_every=150, eval_episodes=1, gifs=False,
                              curves=False))
    ckpt = torch.load(result["run_dir"] / "model.pt", weights_only=True)
    assert ckpt["global_step"] == result["global_step"] == 400
    best = torch.load(result["run_dir"] / "best.pt", weights_only=True)
    assert best["global_step"] in (150, 300)
    assert any(not torch.equal(ckpt["actor"][k], best["actor"][k]) for k in ckpt["actor"])


def test_resume_of_another_scripts_run_names_that_script(tmp_path, capsys):
    import ppo_cartpole
    run = ppo_cartpole.train(ppo_cartpole.Config(run_dir=str(tmp_path), total_timesteps=512,
                                                 stop_when_solved=False, gifs=False,
                                                 curves=False, eval_episodes=1))["run_dir"]
    p = run_main("ddpg_walker.py", "--resume", run, capsys=capsys)
    assert p.returncode == 2 and "is not a model of ddpg_walker.py: it is a model of " \
        "ppo_cartpole.py" in p.stderr, p.stderr
