"""Behaviour of each CartPole script: it learns, it is reproducible, it saves and
reloads what it learned, and bad input ends in one clear line with exit code 2."""

import csv
import importlib
import imageio.v3 as iio
import numpy as np
import pytest
import torch

from conftest import ROOT, interrupt, run_script

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


def test_smoke_run_writes_gifs_model_and_csv(script, tmp_path):
    result = script.train(small(script, tmp_path, total_timesteps=2048, stop_when_solved=False, eval_episodes=2))
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
    assert {"global_step", "episodes", "return_mean20"} <= set(log[0])


@pytest.mark.slow
def test_learns_cartpole_with_a_fixed_seed(script, tmp_path):
    """The defaults solve CartPole well inside a 60k-step budget (median steps over seeds 0-9: README)."""
    result = script.train(small(script, tmp_path, seed=1, total_timesteps=60_000, gifs=False, eval_episodes=5))
    assert result["solved"], f"not solved in {result['global_step']} steps"
    assert np.mean(result["episode_returns"][-20:]) >= 475
    assert np.mean(result["eval_returns"]) >= 450  # and the greedy policy holds the pole too
    # It learned: the first episodes were short.
    assert np.mean(result["episode_returns"][:20]) < 100


def test_same_seed_same_progress_csv(script, tmp_path):
    runs = [script.train(small(script, tmp_path / str(i), seed=3, total_timesteps=4096, stop_when_solved=False,
                               gifs=False, eval_episodes=1)) for i in range(2)]
    a, b = [(r["run_dir"] / "progress.csv").read_text() for r in runs]
    assert a == b and len(a.splitlines()) > 3
    other = script.train(small(script, tmp_path / "x", seed=4, total_timesteps=4096, stop_when_solved=False,
                               gifs=False, eval_episodes=1))
    assert (other["run_dir"] / "progress.csv").read_text() != a  # the seed matters


def test_eval_reloads_the_saved_model(script, tmp_path):
    result = script.train(small(script, tmp_path, total_timesteps=6000, stop_when_solved=False, gifs=False,
                                eval_episodes=4))
    model = result["run_dir"] / "model.pt"
    assert script.play(small(script, tmp_path, eval=str(model), eval_episodes=4)) == result["eval_returns"]
    p = run_script(f"{script.__name__}.py", "--eval", model, "--eval-episodes", 4)
    assert p.returncode == 0, p.stderr
    assert f"returns {[round(r) for r in result['eval_returns']]}" in p.stdout


@pytest.mark.parametrize("args,needle", [
    (["--num-envs", "0"], "--num-envs must be positive"),
    (["--total-timesteps", "-5"], "--total-timesteps must be positive"),
    (["--num-envs", "2", "--num-steps", "4", "--num-minibatches", "9"], "--num-minibatches (9) exceeds the batch size (8)"),
    (["--learning-rate", "abc"], "invalid float value"),
    (["--env-id", "NoSuchEnv-v0"], "unknown environment"),
    (["--env-id", "Pendulum-v1"], "needs Discrete actions"),
    (["--run-dir", "{file}/runs"], "cannot create run folder"),
    (["--eval", "{tmp}/missing.pt"], "no checkpoint"),
    (["--eval", "{file}"], "cannot read checkpoint"),
    (["--watch"], "no display"),
])
def test_bad_input_is_one_line_and_exit_2(script, tmp_path, args, needle):
    blocker = tmp_path / "not_a_folder.pt"
    blocker.write_bytes(b"this is not a checkpoint")
    args = [a.format(file=blocker, tmp=tmp_path) for a in args]
    if "--run-dir" not in args:
        args += ["--run-dir", str(tmp_path)]
    p = run_script(f"{script.__name__}.py", *args, timeout=120)
    assert p.returncode == 2, (p.stdout, p.stderr)
    assert "Traceback" not in p.stderr
    assert needle in p.stderr and len(p.stderr.strip().splitlines()) == 1, p.stderr


def test_ctrl_c_saves_model_and_log(script, tmp_path):
    code, out, err = interrupt(f"{script.__name__}.py", "--run-dir", tmp_path, "--no-stop-when-solved",
                               "--total-timesteps", 10_000_000, "--print-every", 1, after="step")
    assert code == 130, err
    assert "Traceback" not in err and "interrupted" in out
    (run,) = tmp_path.iterdir()
    ckpt = torch.load(run / "model.pt", weights_only=True)
    assert ckpt["global_step"] > 0
    assert len(rows(run / "progress.csv")) >= 1
