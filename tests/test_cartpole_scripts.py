"""Behaviour of each CartPole script: it learns, it is reproducible, it saves and
reloads what it learned, and bad input ends in one clear line with exit code 2."""

import csv
import importlib
import signal
import imageio.v3 as iio
import numpy as np
import pytest
import torch

import checkpoints
import report

from conftest import IN_A_PROCESS, ROOT, ctrl_c_default, interrupt, run_folders, run_main, run_script

SCRIPTS = [name for name in ("ppo_cartpole", "ppo_kl_cartpole", "actor_critic_cartpole")
           if (ROOT / f"{name}.py").exists()]


@pytest.fixture(params=SCRIPTS)
def script(request):
    return importlib.import_module(request.param)


def small(module, tmp_path, **overrides):
    """A Config for a quick run into tmp_path."""
    return module.Config(**{**dict(run_dir=str(tmp_path), print_every=10**6), **overrides})


def rows(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def test_smoke_run_writes_gifs_model_csv_and_curve(script, tmp_path):
    """The CartPole runs' files in detail (the quick layer's smoke run of every script,
    tests/test_every_script.py, checks that each is written and drawn)."""
    result = script.train(small(script, tmp_path, total_timesteps=2048, stop_when_solved=False,
                                eval_episodes=2))
    run = result["run_dir"]
    assert run.parent == tmp_path and run.name.startswith(f"{script.__name__}__CartPole-v1__seed0__")
    assert result["global_step"] >= 1024 and len(result["eval_returns"]) == 2
    for gif in ("before.gif", "after.gif"):
        frames = iio.imread(run / gif)
        assert frames.ndim == 4 and frames.shape[0] >= 2 and frames.shape[-1] == 3
        assert (frames[0] < 60).all(axis=-1).sum() > 200  # the cart is drawn
    ckpt = torch.load(run / "model.pt", weights_only=True)
    assert ckpt["config"]["env_id"] == "CartPole-v1" and ckpt["global_step"] == result["global_step"]
    log = rows(run / "progress.csv")
    assert len(log) >= 2 and int(log[-1]["global_step"]) == result["global_step"]
    assert {"global_step", "episodes", "recent_return", "loss_pi", "loss_v", "entropy"} <= set(log[0])
    episodes = rows(run / "episodes.csv")
    assert len(episodes) == len(result["episode_returns"]) == int(log[-1]["episodes"])
    assert [float(e["return"]) for e in episodes] == result["episode_returns"]
    assert_curve_drawn(run / "curve.png")
    assert_curve_drawn(run / "inside.png")


def assert_curve_drawn(path):
    """A valid PNG whose plot area is not blank: the curve's coloured pixels are there."""
    image = iio.imread(path)
    assert image.ndim == 3 and image.shape[0] > 200 and image.shape[1] > 300
    rgb = image[..., :3].astype(int)
    colored = (rgb.max(-1) - rgb.min(-1)) > 60  # not white, grey or black: a plotted line
    # a line's share of the pixels falls as the dpi rises (96: DDPG's one-panel inside.png of
    # a 600-step run, 0.0028); a plot with its lines left out keeps its legend's, about 0.0002
    assert colored.mean() > 0.0015, colored.mean()


def test_the_last_progress_row_is_where_training_ended(script, tmp_path):
    """Stopped at the solve, the log's last row shows the solving state, not the update before."""
    result = script.train(small(script, tmp_path, solved_return=30, gifs=False, eval_episodes=1))
    assert result["solved"]
    last = rows(result["run_dir"] / "progress.csv")[-1]
    assert int(last["global_step"]) == result["solved_step"] == result["global_step"]
    assert float(last["recent_return"]) >= 30 and last["loss_pi"] == "nan"  # no update on it


def test_max_grad_norm_zero_means_no_clipping(script, tmp_path):
    """0 turns clipping off; it must not freeze the networks (every gradient times 0)."""
    result = script.train(small(script, tmp_path, max_grad_norm=0.0, total_timesteps=1024,
                                stop_when_solved=False, gifs=False, curves=False, eval_episodes=1))
    fresh = script.train(small(script, tmp_path / "b", total_timesteps=1024, stop_when_solved=False,
                               gifs=False, curves=False, eval_episodes=1, learning_rate=1e-12))  # ~ init
    a = torch.load(result["run_dir"] / "model.pt", weights_only=True)
    b = torch.load(fresh["run_dir"] / "model.pt", weights_only=True)
    key = "policy" if "policy" in a else "model"
    moved = [(a[key][k] - b[key][k]).abs().max().item() for k in a[key]]
    assert max(moved) > 1e-3  # trained weights differ from the barely-trained ones


def test_eval_reloads_the_saved_model(script, tmp_path, capsys):
    result = script.train(small(script, tmp_path, total_timesteps=2048, stop_when_solved=False,
                                gifs=False, curves=False, eval_episodes=4))
    model = result["run_dir"] / "model.pt"
    cfg = small(script, tmp_path, eval=str(model), eval_episodes=4)
    cls, key = (script.ActorCritic, "model") if hasattr(script, "ActorCritic") else (script.PolicyNetwork, "policy")
    net, env_id = checkpoints.load_model(cfg.eval, script.SCRIPT, key, lambda c: cls(
        c["obs_dim"], c["n_actions"], c["config"]["hidden"]))
    logits_of = net if key == "policy" else (lambda x: net(x)[0])
    play = report.sampled_and_greedy(logits_of, "cpu")
    assert report.play(cfg, cfg.eval, env_id, play) == result["eval_returns"]
    # The run folder stands for its model.pt.
    capsys.readouterr()
    p = run_main(f"{script.__name__}.py", "--eval", result["run_dir"], "--eval-episodes", 4,
                 capsys=capsys)
    assert p.returncode == 0, p.stderr
    assert f"returns {[round(r) for r in result['eval_returns']]}" in p.stdout


def test_eval_gif_draws_the_saved_model_as_after_gif_without_a_display(script, tmp_path, capsys):
    """--eval RUN --gif OUT: one episode of the saved policy, headless, drawn exactly as the
    run's after.gif was (same policy, same draws, same env seed)."""
    import imageio.v3 as iio

    result = script.train(small(script, tmp_path / "run", total_timesteps=2048,
                                stop_when_solved=False, curves=False, eval_episodes=1))
    out = tmp_path / "cartpole.gif"
    capsys.readouterr()
    p = run_main(f"{script.__name__}.py", "--eval", result["run_dir"], "--gif", out, capsys=capsys)
    assert p.returncode == 0, p.stderr
    assert f"{out}: one episode, return" in p.stdout
    assert np.array_equal(iio.imread(out), iio.imread(result["run_dir"] / "after.gif"))


# Ctrl-C after training and during --eval, and the real command's --help: the path is
# report's, the same for the three (report.finish_updates, report.play), so one script's real
# process stands for all (each script's own Ctrl-C: tests/test_every_script.py).
ONE = ["ppo_cartpole"]


@pytest.mark.parametrize("script", ONE, indirect=True)
def test_help_of_the_real_script(script):
    p = run_script(f"{script.__name__}.py", "--help", timeout=120)
    assert p.returncode == 0, p.stderr
    assert "--learning-rate" in p.stdout and "--eval" in p.stdout and "Traceback" not in p.stderr


def test_train_works_from_a_notebook(script, tmp_path, monkeypatch):
    """train(Config(...)) from Python: no sys.argv parsing, no exit."""
    monkeypatch.setattr("sys.argv", ["jupyter-kernel", "--f=/tmp/kernel.json"])
    result = script.train(script.Config(run_dir=str(tmp_path), gifs=False, curves=False,
                                        total_timesteps=1024, stop_when_solved=False,
                                        eval_episodes=1, print_every=10**6))
    assert result["global_step"] >= 1024 - 8 and not result["interrupted"]


BAD = [
    (["--num-envs", "0"], "--num-envs must be positive"),
    (["--total-timesteps", "-5"], "--total-timesteps must be positive"),
    (["--total-timesteps", "100"], "is less than one rollout"),
    (["--num-envs", "1000", "--num-steps", "100000000", "--total-timesteps", "10000000000000"],
     "not enough memory"),
    (["--learning-rate", "abc"], "invalid float value"),
    (["--gif", "out.gif"], "it needs --eval"),
    (["--env-id", "NoSuchEnv-v0"], "unknown environment"),
    (["--env-id", "Pendulum-v1"], "needs Discrete actions"),
    (["--run-dir", "{file}/runs"], "cannot create run folder"),
    (["--eval", "{tmp}/missing.pt"], "no checkpoint"),
    (["--eval", "{file}"], "truncated, corrupt or not a checkpoint"),
    (["--eval", "{tmp}"], "no checkpoint at"),
    (["--watch"], "no display"),
]


# Those that need a process of their own (IN_A_PROCESS: a new interpreter each, seconds) are
# the tools' (cli's memory check, common's env errors): one script's real command for them.
@pytest.mark.parametrize("script,args,needle", [
    (name, args, needle) for name in SCRIPTS for args, needle in BAD
    if needle not in IN_A_PROCESS or name in ONE], indirect=["script"])
def test_bad_input_is_one_line_and_exit_2(script, tmp_path, args, needle, capsys):
    blocker = tmp_path / "not_a_folder.pt"
    blocker.write_bytes(b"this is not a checkpoint")
    args = [a.format(file=blocker, tmp=tmp_path) for a in args]
    if "--run-dir" not in args:
        args += ["--run-dir", str(tmp_path)]
    before = set(tmp_path.iterdir())
    if needle in IN_A_PROCESS:  # the real command, warnings on stderr included (conftest)
        p = run_script(f"{script.__name__}.py", *args, timeout=120)
    else:
        p = run_main(f"{script.__name__}.py", *args, capsys=capsys)
    assert p.returncode == 2, (p.stdout, p.stderr)
    assert "Traceback" not in p.stderr
    assert needle in p.stderr and len(p.stderr.strip().splitlines()) == 1, p.stderr
    assert set(tmp_path.iterdir()) == before  # no run folder left behind


# Ctrl-C, and SIGTERM (kill PID), which does what Ctrl-C does: (signal, exit code, its line)
SIGNALS = [pytest.param((signal.SIGINT, 130, "interrupted (Ctrl-C)"), id="ctrl_c"),
           pytest.param((signal.SIGTERM, 143, "interrupted (SIGTERM)"), id="sigterm")]


@pytest.mark.parametrize("sent", SIGNALS)
@pytest.mark.parametrize("script", ONE, indirect=True)
def test_ctrl_c_while_gifs_are_written(script, tmp_path, sent):
    """After training: exit 130 (SIGTERM: 143), the model and logs kept, no half-written file,
    and one last line that says where the run folder and its model.pt are."""
    how, exit_code, _ = sent
    code, out, err = interrupt(f"{script.__name__}.py", "--run-dir", tmp_path, "--solved-return", 30,
                               after="greedy evaluation", signal=how)
    assert code == exit_code, (out, err)
    assert err.strip() == "", err
    (run,) = run_folders(tmp_path)
    last = out.strip().splitlines()[-1]
    assert last.startswith("interrupted") and str(run) in last and "model.pt" in last, out
    assert torch.load(run / "model.pt", weights_only=True)["global_step"] > 0
    assert rows(run / "progress.csv") and rows(run / "episodes.csv")
    assert not list(run.glob("*.tmp*"))


@pytest.mark.parametrize("sent", SIGNALS)
@pytest.mark.parametrize("script", ONE, indirect=True)
def test_ctrl_c_during_eval(script, tmp_path, sent):
    how, exit_code, line = sent
    result = script.train(small(script, tmp_path, total_timesteps=1024, stop_when_solved=False,
                                gifs=False, curves=False, eval_episodes=1))
    code, out, err = interrupt(f"{script.__name__}.py", "--eval", result["run_dir"],
                               "--eval-episodes", 100_000, after="playing", signal=how)
    assert code == exit_code, (out, err)
    assert "Traceback" not in err and err.strip().splitlines() == [line], err


@pytest.mark.parametrize("sent", SIGNALS)
def test_ctrl_c_during_watch(tmp_path, sent):
    """--watch with a display: each return printed as it ends, then Ctrl-C ends it in one line.
    SDL's dummy driver stands in for the screen (a DISPLAY is set, so the script allows --watch)."""
    import os
    import subprocess
    import sys

    import ppo_cartpole

    run = ppo_cartpole.train(small(ppo_cartpole, tmp_path, total_timesteps=256, stop_when_solved=False,
                                   gifs=False, curves=False, eval_episodes=1))["run_dir"]
    env = dict(os.environ, DISPLAY=":99", SDL_VIDEODRIVER="dummy", PYTHONUNBUFFERED="1")
    proc = subprocess.Popen([sys.executable, str(ROOT / "ppo_cartpole.py"), "--eval", str(run), "--watch",
                             "--eval-episodes", "100000"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, env=env, cwd=ROOT, preexec_fn=ctrl_c_default)
    seen = []
    for line in proc.stdout:
        seen.append(line)
        if line.startswith("episode 2/"):
            break
    how, exit_code, line = sent
    proc.send_signal(how)
    out, err = proc.communicate(timeout=60)
    assert "Ctrl-C stops" in "".join(seen) and seen[-1].startswith("episode 2/100000: return")
    assert proc.returncode == exit_code, err
    assert "Traceback" not in err and err.strip().splitlines() == [line], err


@pytest.mark.quick
def test_a_run_that_stops_short_of_its_budget_says_why(tmp_path, capsys):
    """--total-timesteps 2000 trains 1792 steps (7 whole rollouts of 8 x 32): the line says so."""
    import ppo_cartpole
    result = ppo_cartpole.train(small(ppo_cartpole, tmp_path, total_timesteps=2000,
                                      stop_when_solved=False, gifs=False, curves=False,
                                      eval_episodes=1))
    assert result["global_step"] == 1792
    assert ("trained 1792 steps (whole rollouts only: the last 208 steps of --total-timesteps "
            "2000 make no whole one)") in capsys.readouterr().out
