"""The pictures and logs a user looks at: curve.png, TensorBoard scalars, runs compared."""

import subprocess
import sys

import imageio.v3 as iio
import pytest

import ppo_cartpole as ppo
from conftest import ROOT, run_script
from test_cartpole_scripts import assert_curve_drawn


def quick_run(tmp_path, seed, **kw):
    return ppo.train(ppo.Config(seed=seed, total_timesteps=1024, stop_when_solved=False, gifs=False,
                                eval_episodes=1, run_dir=str(tmp_path), print_every=10**6, **kw))


def test_tensorboard_scalars_use_cleanrl_tags(tmp_path):
    pytest.importorskip("tensorboard")
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    run = quick_run(tmp_path, 0, tensorboard=True)["run_dir"]
    events = EventAccumulator(str(run))
    events.Reload()
    tags = set(events.Tags()["scalars"])
    assert {"charts/episodic_return", "charts/learning_rate", "charts/SPS", "losses/policy_loss",
            "losses/value_loss", "losses/entropy", "losses/approx_kl", "losses/clipfrac"} <= tags
    # The same numbers as the CSV: one point per finished episode, at its env step.
    returns = events.Scalars("charts/episodic_return")
    episodes = (run / "episodes.csv").read_text().splitlines()[1:]
    assert [(e.step, e.value) for e in returns] == [
        (int(step), float(ret)) for step, ret in (line.split(",") for line in episodes)]


def test_tensorboard_missing_is_one_clear_line(tmp_path):
    code = ("import sys; sys.modules['tensorboard'] = None\n"  # as if it were not installed
            "import ppo_cartpole; ppo_cartpole.main(['--tensorboard', '--run-dir', sys.argv[1]])")
    p = subprocess.run([sys.executable, "-c", code, str(tmp_path)], capture_output=True, text=True,
                       cwd=ROOT, timeout=120)
    assert p.returncode == 2, p.stderr
    assert "pip install tensorboard" in p.stderr and len(p.stderr.strip().splitlines()) == 1
    assert not list(tmp_path.iterdir())


def test_compare_overlays_three_runs_into_one_png(tmp_path):
    runs = [quick_run(tmp_path / "runs", seed, curves=False)["run_dir"] for seed in range(3)]
    out = tmp_path / "compare.png"
    p = run_script("plots.py", *runs, "--out", out)
    assert p.returncode == 0, p.stderr
    assert_curve_drawn(out)
    assert [f.name for f in tmp_path.iterdir() if f.suffix == ".png"] == ["compare.png"]


def test_compare_rejects_a_folder_that_is_not_a_run(tmp_path):
    p = run_script("plots.py", tmp_path)
    assert p.returncode == 2 and "is not a run folder" in p.stderr and "Traceback" not in p.stderr


def test_curve_is_not_drawn_blank_for_a_ppo_kl_run(tmp_path):
    import ppo_kl_cartpole as kl

    run = kl.train(kl.Config(total_timesteps=1024, stop_when_solved=False, gifs=False, eval_episodes=1,
                             run_dir=str(tmp_path), print_every=10**6))["run_dir"]
    assert_curve_drawn(run / "curve.png")
    assert iio.imread(run / "curve.png").shape[-1] in (3, 4)


def test_curve_of_a_run_in_which_no_episode_finished(tmp_path):
    """One short rollout of Acrobot (its episodes run to 500 steps): no episodes.csv, a curve."""
    run = ppo.train(ppo.Config(env_id="Acrobot-v1", total_timesteps=256, gifs=False,
                               eval_episodes=1, run_dir=str(tmp_path), print_every=10**6))["run_dir"]
    assert not (run / "episodes.csv").exists() and (run / "curve.png").exists()
