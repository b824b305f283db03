"""Unit tests of the tools the scripts call (cli.py, runlog.py, checkpoints.py, report.py and
the last part of common.py): flags, run folders, CSV rows, checkpoints, one-line errors,
Ctrl-C and SIGTERM, the divergence check and the run's episode bookkeeping."""

import copy
import csv
import dataclasses
import errno
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import torch

import checkpoints
import cli
import common
import runlog
import cartpole_env
from common import UserError
from conftest import run_main, run_script


def a_run(tmp_path, threshold, logged=None, **flags):
    cfg = dataclasses.make_dataclass("Cfg", [("env_id", str, "CartPole-v1"), ("seed", int, 0),
                                      ("num_envs", int, 4), ("num_steps", int, 8),
                                      ("total_timesteps", int, 1000)],
                                     bases=(cli.SolvedFlags,))(
        **{"run_dir": str(tmp_path), "stop_when_solved": False, **flags})
    return runlog.UpdateLog("test", cfg, logged or {})


@pytest.mark.quick
def test_the_runs_episodes_and_solved_step_match_hand_kept_returns(tmp_path):
    """600 steps of 4 CartPoles with random actions: the (step, return) pairs the run keeps,
    and the step it calls solved, equal per-env sums kept by hand, where the NEXT_STEP reset
    step belongs to no episode."""
    envs, _, threshold = common.make_vec_env("CartPole-v1", 4, seed=0)
    assert threshold == 475.0
    run = a_run(tmp_path, threshold=22.0)
    rng, by_hand, first_solved = np.random.default_rng(0), [], None
    running, reset_step = np.zeros(4), np.zeros(4, dtype=bool)
    for step in range(1, 601):
        _, reward, term, trunc, info = envs.step(rng.integers(0, 2, size=4))
        running += np.where(reset_step, 0.0, reward)
        ended = []
        for n in np.flatnonzero(term | trunc):
            by_hand.append((step, running[n]))
            ended.append(running[n])
            running[n] = 0.0
        reset_step = term | trunc
        assert run.episodes_ended(info, step) == ended
        last = [r for _, r in by_hand[-20:]]
        assert run.solved(22.0) == (len(last) == 20 and np.mean(last) >= 22.0)
        if first_solved is None and len(last) == 20 and np.mean(last) >= 22.0:
            first_solved = step
        assert run.episodes == by_hand and run.solved_step == first_solved
    envs.close()
    assert len(by_hand) > 50 and first_solved is not None and first_solved > 20


@pytest.mark.quick
def test_the_runs_progress_rows_and_the_last_row_at_a_stop(tmp_path):
    """update() writes the step, episodes, mean of the last 20, the extra columns, then the
    stats; a stop writes one more row with the stats as nan and the rest as they are now."""
    logged = {k: (None, k) for k in ("running_reward", "lr", "loss_pi", "loss_v")}
    run = a_run(tmp_path, threshold=10.0, logged=logged, stop_when_solved=True)
    run.episodes = [(i, 12.0) for i in range(20)]
    run.global_step = 64
    run.update(dict(loss_pi=0.5, loss_v=0.25), running_reward=3.0, lr=0.001)
    run.global_step = 70
    assert run.solved(10.0)
    run.stopped_row(running_reward=4.0, lr=0.5)
    rows = list(csv.DictReader(open(run.dir / "progress.csv")))
    assert rows == [dict(global_step="64", episodes="20", recent_return="12", running_reward="3",
                         lr="0.001", loss_pi="0.5", loss_v="0.25"),
                    dict(global_step="70", episodes="20", recent_return="12", running_reward="4",
                         lr="0.5", loss_pi="nan", loss_v="nan")]
    assert run.solved_step == 70


@pytest.mark.parametrize("rule,good,bad", [("> 0", [1e-9, 5], [0, -1]), (">= 0", [0, 2], [-1e-9]),
                                           ("> 1", [1.5], [1, 0]), ("(0, 1]", [1, 0.5], [0, 1.01]),
                                           ("[0, 1]", [0, 1], [-0.1, 1.1]),
                                           ("> 0 or none", [None, 3], [0])])
@pytest.mark.quick
def test_check_ranges_accepts_inside_and_names_the_flag_outside(rule, good, bad):
    words = {"> 0": "positive", "(0, 1]": "in (0, 1]", "[0, 1]": "in [0, 1]"}
    for value in good:
        cli.check_ranges(dataclasses.make_dataclass("C", ["target_kl"])(value), target_kl=rule)
    for value in bad + ([] if "none" in rule else [None]):
        expected = words.get(rule.removesuffix(" or none"), rule.removesuffix(" or none"))
        with pytest.raises(ValueError, match=re.escape(f"--target-kl must be {expected}")):
            cli.check_ranges(dataclasses.make_dataclass("C", ["target_kl"])(value),
                                target_kl=rule)


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
        cli.check(self.num_envs > 0, f"--num-envs must be positive, got {self.num_envs}")


@pytest.mark.quick
def test_parse_config_flags_and_defaults():
    assert cli.parse_config(Demo, []) == Demo()
    cfg = cli.parse_config(Demo, ["--num-envs", "8", "--lr", "3e-4", "--no-fast", "--target-kl", "0.02", "--name", "y"])
    assert cfg == Demo(num_envs=8, lr=3e-4, fast=False, target_kl=0.02, name="y")
    assert cli.parse_config(Demo, ["--target-kl", "none"]).target_kl is None


@pytest.mark.parametrize("argv,needle", [(["--num-envs", "0"], "--num-envs must be positive"),
                                         (["--num-envs", "two"], "invalid int value"),
                                         (["--bogus"], "unrecognized arguments"),
                                         (["--lr", "nan"], "--lr must be a finite number, got nan"),
                                         (["--lr=-inf"], "--lr must be a finite number, got -inf"),
                                         (["--target-kl", "inf"], "--target-kl must be a finite")])
@pytest.mark.quick
def test_parse_config_rejects_bad_values_with_exit_2(argv, needle, capsys):
    with pytest.raises(SystemExit) as e:
        cli.parse_config(Demo, argv)
    assert e.value.code == 2
    err = capsys.readouterr().err
    assert needle in err and len(err.strip().splitlines()) == 1


@pytest.mark.quick
def test_help_shows_docstrings(capsys):
    with pytest.raises(SystemExit):
        cli.parse_config(Demo, ["--help"])
    out = capsys.readouterr().out
    assert "--num-envs" in out and "parallel envs" in out and "learning rate" in out


@dataclasses.dataclass
class Percent:
    share: float = 0.5
    """share of the batch, in % of it (50% = half)"""


@pytest.mark.quick
def test_help_survives_a_percent_sign(capsys):
    with pytest.raises(SystemExit) as e:
        cli.parse_config(Percent, ["--help"])
    assert e.value.code == 0
    assert "in % of it (50% = half)" in capsys.readouterr().out


# --- run folders, CSV, checkpoints, errors -----------------------------------


@pytest.mark.quick
def test_make_run_dir_names_and_never_reuses(tmp_path):
    a = runlog.make_run_dir(tmp_path, "ppo_cartpole", "CartPole-v1", 3)
    b = runlog.make_run_dir(tmp_path, "ppo_cartpole", "CartPole-v1", 3)
    assert a != b and a.is_dir() and b.is_dir()
    assert a.name.startswith("ppo_cartpole__CartPole-v1__seed3__")


@pytest.mark.quick
def test_make_run_dir_unwritable_is_a_user_error(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    with pytest.raises(UserError, match="cannot create run folder"):
        runlog.make_run_dir(blocker / "runs", "x", "CartPole-v1", 0)


@pytest.mark.quick
def test_append_csv(tmp_path):
    path = tmp_path / "p.csv"
    runlog.append_csv(path, dict(step=1, loss=0.5))
    runlog.append_csv(path, dict(step=2, loss=0.25))
    assert path.read_text().splitlines() == ["step,loss", "1,0.5", "2,0.25"]


@pytest.mark.quick
def test_checkpoint_round_trip_and_bad_files(tmp_path):
    path = tmp_path / "m.pt"
    checkpoints.save_checkpoint(dict(w=torch.arange(3.0), config=dict(a=1)), path)
    ckpt = checkpoints.load_checkpoint(path, required=("w", "config"))
    assert torch.equal(ckpt["w"], torch.arange(3.0)) and not (tmp_path / "m.pt.tmp").exists()
    with pytest.raises(UserError, match="lacks {'policy'}"):
        checkpoints.load_checkpoint(path, required=("policy",))
    with pytest.raises(UserError, match="no checkpoint"):
        checkpoints.load_checkpoint(tmp_path / "nope.pt")
    bad = tmp_path / "bad.pt"
    bad.write_bytes(b"\x00garbage" * 10)
    with pytest.raises(UserError, match="truncated, corrupt or not a checkpoint"):
        checkpoints.load_checkpoint(bad)
    half = tmp_path / "half.pt"  # a copy cut short: torch itself says "Invalid argument" or so
    half.write_bytes(path.read_bytes()[:100])
    with pytest.raises(UserError, match="truncated, corrupt or not a checkpoint"):
        checkpoints.load_checkpoint(half)
    # A pickle with Python objects in it is refused, and nothing suggests weights_only=False.
    unsafe = tmp_path / "unsafe.pt"
    torch.save(dict(w=Demo()), unsafe)
    with pytest.raises(UserError, match="holds a test_tools.Demo object, which is not loaded") as e:
        checkpoints.load_checkpoint(unsafe)
    assert "weights_only" not in str(e.value)
    numpy_number = tmp_path / "numpy.pt"  # a column logged as np.float64, say
    torch.save(dict(evaluations=[dict(eval_length=np.float64(74.3))]), numpy_number)
    with pytest.raises(UserError, match=r"holds a numpy\S* object.*save float\(x\)"):
        checkpoints.load_checkpoint(numpy_number)
    # A run folder stands for its model.pt; a folder without one says so.
    checkpoints.save_checkpoint(dict(w=torch.ones(1)), tmp_path / "model.pt")
    assert torch.equal(checkpoints.load_checkpoint(tmp_path)["w"], torch.ones(1))
    with pytest.raises(UserError, match="no checkpoint at .*empty.model.pt"):
        (tmp_path / "empty").mkdir()
        checkpoints.load_checkpoint(tmp_path / "empty")


@pytest.mark.quick
def test_save_checkpoint_is_on_disk_whole_before_it_takes_its_name(tmp_path, monkeypatch):
    """When the file is flushed to disk, it is complete and not yet at its name: a crash then
    leaves the previous checkpoint, never a half one."""
    seen, real_fsync = [], os.fsync

    def fsync(fd):
        real_fsync(fd)
        seen.append((os.path.exists(tmp_path / "m.pt"), os.fstat(fd).st_size))

    monkeypatch.setattr(checkpoints.os, "fsync", fsync)
    checkpoints.save_checkpoint(dict(w=torch.ones(2)), tmp_path / "m.pt")
    assert seen == [(False, (tmp_path / "m.pt").stat().st_size)]


@pytest.mark.parametrize("body,code,stderr", [
    ("raise common.UserError('something the user can fix')", 2, "error: something the user can fix\n"),
    ("raise KeyboardInterrupt", 130, "\ninterrupted (Ctrl-C)\n"),
    # torch.save cut short by Ctrl-C; MuJoCo's import cut short by it, as gym.make reports it
    ("raise RuntimeError('unexpected pos') from KeyboardInterrupt()", 130,
     "\ninterrupted (Ctrl-C)\n"),
    # `kill PID`: SIGTERM does what Ctrl-C does, and says which came
    ("import signal; signal.raise_signal(signal.SIGTERM)", 143, "\ninterrupted (SIGTERM)\n"),
    ("raise RuntimeError('a bug, no Ctrl-C in it')", 1, None),  # stays a traceback
])
def test_clear_exit_prints_one_line(tmp_path, body, code, stderr):
    program = f"import cli, common\nwith cli.clear_exit():\n    {body}\n"
    p = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True, cwd=tmp_path,
                       env={"PYTHONPATH": str(__import__("pathlib").Path(cli.__file__).parent), "PATH": ""})
    assert p.returncode == code
    assert p.stderr == stderr if stderr else "Traceback" in p.stderr


@pytest.mark.parametrize("preset,expected", [({}, ("dummy", "egl")),
                                             ({"MUJOCO_GL": "osmesa"}, ("dummy", "osmesa"))])
def test_headless_defaults_without_a_display_keep_user_choices(preset, expected):
    import os

    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY", "SDL_VIDEODRIVER", "MUJOCO_GL")}
    env.update(preset, PYTHONPATH=os.path.dirname(common.__file__))
    code = ("import os, common; common.headless_defaults(); "
            "print(os.environ['SDL_VIDEODRIVER'], os.environ['MUJOCO_GL'])")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
    assert p.returncode == 0, p.stderr
    assert tuple(p.stdout.split()) == expected


@pytest.mark.quick
def test_env_errors_names_a_missing_egl_library():
    """Headless, MUJOCO_GL=egl (common's default there) on a machine without libEGL: importing
    MuJoCo fails inside PyOpenGL with this AttributeError (seen on a GPU server)."""
    with pytest.raises(UserError, match="Walker2d-v5: MuJoCo cannot render without the EGL"):
        with common.env_errors("Walker2d-v5"):
            raise AttributeError("'NoneType' object has no attribute 'eglQueryString'")
    with pytest.raises(AttributeError, match="no attribute 'step'"):  # any other: a bug, shown
        with common.env_errors("Walker2d-v5"):
            raise AttributeError("'NoneType' object has no attribute 'step'")


@pytest.mark.quick
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
    with pytest.raises(UserError, match="needs a package that is not installed"):
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


@pytest.mark.quick
@pytest.mark.parametrize("sent", ["SIGINT", "SIGTERM"])
def test_ctrl_c_during_save_checkpoint_waits_for_the_whole_file(tmp_path, monkeypatch,
                                                                ctrl_c_raises, sent):
    """Ctrl-C, or SIGTERM as main() receives it (common.sigterm_as_ctrl_c)."""
    import signal

    real_save = torch.save

    def save(obj, f):  # the signal as torch.save starts
        signal.raise_signal(getattr(signal, sent))
        real_save(obj, f)

    monkeypatch.setattr(checkpoints.torch, "save", save)
    with common.sigterm_as_ctrl_c(), pytest.raises(KeyboardInterrupt):  # it still arrives,
        checkpoints.save_checkpoint(dict(w=torch.arange(5.0)), tmp_path / "m.pt")  # once whole
    monkeypatch.undo()
    assert torch.equal(checkpoints.load_checkpoint(tmp_path / "m.pt")["w"], torch.arange(5.0))
    assert [p.name for p in tmp_path.iterdir()] == ["m.pt"]
    assert common.stopped_by() == {"SIGINT": ("Ctrl-C", 130), "SIGTERM": ("SIGTERM", 143)}[sent]


@pytest.mark.quick
def test_sigterm_stops_a_training_loop_at_a_whole_step_as_ctrl_c_does(ctrl_c_raises):
    """Under sigterm_as_ctrl_c, a first SIGTERM only marks the loop to stop (CtrlC.pressed),
    a second ends it at once; after the block SIGTERM's handler is what it was."""
    import signal

    before = signal.getsignal(signal.SIGTERM)
    steps = []
    with common.sigterm_as_ctrl_c():
        with checkpoints.CtrlC() as ctrl_c:
            for step in range(5):
                steps.append(step)
                if step == 1:
                    signal.raise_signal(signal.SIGTERM)  # the step goes on to its end
                    steps.append("whole")
                if ctrl_c.pressed:
                    break
        assert steps == [0, 1, "whole"] and ctrl_c.pressed
        with checkpoints.CtrlC() as ctrl_c:
            signal.raise_signal(signal.SIGTERM)
            signal.raise_signal(signal.SIGTERM)  # the second: at once
            steps.append("not reached")
        assert steps[-1] == "whole" and ctrl_c.pressed
    assert common.stopped_by() == ("SIGTERM", 143)
    assert signal.getsignal(signal.SIGTERM) == before


@pytest.mark.quick
def test_ctrl_c_ignored_at_start_works_under_sigterm_as_ctrl_c(ctrl_c_raises):
    """A shell script's `cmd &` starts its job with SIGINT ignored: within the block `kill -INT`
    is a Ctrl-C again; after it, ignored as it was."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    with common.sigterm_as_ctrl_c(), pytest.raises(KeyboardInterrupt):
        signal.raise_signal(signal.SIGINT)
    assert common.stopped_by() == ("Ctrl-C", 130)
    assert signal.getsignal(signal.SIGINT) == signal.SIG_IGN


@pytest.mark.quick
def test_save_checkpoint_that_cannot_write_is_a_user_error_and_leaves_no_tmp(tmp_path,
                                                                             monkeypatch):
    def full(fd):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(checkpoints.os, "fsync", full)
    with pytest.raises(UserError, match="cannot write .*m.pt: No space left on device"):
        checkpoints.save_checkpoint(dict(w=torch.ones(2)), tmp_path / "m.pt")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.quick
def test_load_checkpoint_refuses_another_scripts_model(tmp_path):
    checkpoints.save_checkpoint(dict(script="ppo_cartpole", w=torch.ones(1)), tmp_path / "a.pt")
    checkpoints.save_checkpoint(dict(w=torch.ones(1)), tmp_path / "old.pt")
    assert checkpoints.load_checkpoint(tmp_path / "a.pt", ("w",), script="ppo_cartpole")["w"] == 1
    with pytest.raises(UserError, match="not a model of ppo_kl_cartpole.py: it is a model "
                                               "of ppo_cartpole.py"):
        checkpoints.load_checkpoint(tmp_path / "a.pt", ("w",), script="ppo_kl_cartpole")
    with pytest.raises(UserError, match="older version .* train it again"):
        checkpoints.load_checkpoint(tmp_path / "old.pt", ("w",), script="ppo_cartpole")


@pytest.mark.quick
def test_stop_if_diverged(tmp_path):
    net, run = torch.nn.Linear(2, 1), tmp_path / "run"
    run.mkdir()
    runlog.stop_if_diverged(5, dict(loss=0.5, kl=torch.tensor(0.1)), [net], run)
    assert run.exists()  # all finite: nothing happens
    with pytest.raises(UserError, match=r"at step 7: nan or inf in loss_v; likely cause: "
                                               r"too high a learning rate .*run was removed"):
        runlog.stop_if_diverged(7, dict(loss_pi=0.1, loss_v=float("inf")), [net], run)
    assert not run.exists()
    run.mkdir()
    (run / "checkpoint.pt").touch()  # a run that can --resume from its last good state: kept
    with pytest.raises(UserError, match=r"at step 7: nan or inf in loss_v; .*smaller one\)$"):
        runlog.stop_if_diverged(7, dict(loss_v=float("nan")), [net], run)
    assert (run / "checkpoint.pt").exists()
    with torch.no_grad():
        net.weight[0, 0] = 1e38  # finite weights, an output of inf
        out = net(torch.tensor([[10., 0.]]))
    with pytest.raises(UserError, match="nan or inf in the networks' output"):
        runlog.stop_if_diverged(7, {}, [net], outputs=[out])
    with torch.no_grad():
        net.bias[0] = float("nan")
    with pytest.raises(UserError, match="nan or inf in Linear's weights"):
        runlog.stop_if_diverged(7, {}, [net])


@dataclasses.dataclass
class Device:
    cuda: bool = False
    """train on the GPU"""
    lr: float = 1e-3

    def __post_init__(self):
        cli.check(self.lr > 0, f"--lr must be positive, got {self.lr}")


@dataclasses.dataclass
class GpuFirst:
    cuda: bool = True
    """train on the GPU if there is one"""


@pytest.mark.quick
def test_cuda_asked_for_without_a_gpu_says_so_in_one_line(monkeypatch, capsys):
    monkeypatch.setattr(cli.torch.cuda, "is_available", lambda: False)
    assert cli.parse_config(Device, ["--cuda"]).cuda
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "torch sees no GPU" in err and "running on the CPU" in err
    with pytest.raises(SystemExit):  # bad input: its one error line, and no warning beside it
        cli.parse_config(Device, ["--cuda", "--lr", "0"])
    assert capsys.readouterr().err.count("\n") == 1
    cli.parse_config(Device, [])  # not asked for: nothing to say
    cli.parse_config(GpuFirst, [])  # the GPU when there is one (DDPG's default): no warning
    cli.parse_config(GpuFirst, ["--cuda"])
    assert capsys.readouterr().err == ""
    monkeypatch.setattr(cli.torch.cuda, "is_available", lambda: True)
    cli.parse_config(Device, ["--cuda"])
    assert capsys.readouterr().err == ""


@pytest.mark.quick
def test_load_weights_mismatch_is_a_user_error():
    small, big = torch.nn.Linear(3, 2), torch.nn.Linear(5, 2)
    checkpoints.load_state(small, torch.nn.Linear(3, 2).state_dict(), "ok.pt")
    with pytest.raises(UserError, match="other.pt does not fit this script's Linear"):
        checkpoints.load_state(small, big.state_dict(), "other.pt")



@pytest.mark.quick
def test_cartpole_maps_are_the_networks_at_grid_points():
    torch.manual_seed(0)
    policy, value = torch.nn.Linear(4, 2), torch.nn.Sequential(torch.nn.Linear(4, 1),
                                                                 torch.nn.Flatten(0))
    maps = cartpole_env.cartpole_maps(policy, value, "cpu", n=5)
    for i, j in ((0, 0), (2, 3), (4, 1)):  # row: angular velocity, column: pole angle
        obs = torch.tensor([[0.0, 0.0, maps["angle"][j], maps["velocity"][i]]], dtype=torch.float32)
        with torch.no_grad():
            assert maps["value"][i, j] == pytest.approx(value(obs).item(), rel=1e-5)
            assert maps["right"][i, j] == pytest.approx(torch.softmax(policy(obs), -1)[0, 1].item(),
                                                        rel=1e-5)
    assert maps["angle"][0] == -0.21 and maps["velocity"][-1] == 2.0


def test_runs_latest_is_the_newest_run_of_this_script(tmp_path, capsys):
    """runs/latest (and runs/latest/best.pt) name the newest run folder of the script, by the
    time in its name, whatever the env or seed; another script's runs do not count. A newer
    run without the file asked for (killed before writing model.pt, or still training) is
    passed over in a line that says so."""
    for name in ("ddpg_walker__Walker2d-v5__seed0__20260101-120000",
                 "ddpg_walker__Hopper-v5__seed3__20260102-090000",
                 "td3_walker__Walker2d-v5__seed0__20260105-000000"):
        (tmp_path / name).mkdir()
        for file in ("model.pt", "best.pt", "checkpoint.pt"):
            (tmp_path / name / file).touch()
    newest = tmp_path / "ddpg_walker__Hopper-v5__seed3__20260102-090000"
    assert cli.latest_run(str(tmp_path / "latest"), "ddpg_walker") == str(newest)
    assert cli.latest_run(str(tmp_path / "latest" / "best.pt"), "ddpg_walker") == str(
        newest / "best.pt")
    with pytest.raises(UserError, match="no run of ppo_cartpole.py"):
        cli.latest_run(str(tmp_path / "latest"), "ppo_cartpole")
    assert capsys.readouterr().err == ""
    killed = tmp_path / "ddpg_walker__Walker2d-v5__seed1__20260103-000000"
    killed.mkdir()
    (killed / "episodes.csv").touch()
    assert cli.latest_run(str(tmp_path / "latest"), "ddpg_walker") == str(newest)
    assert cli.latest_run(str(tmp_path / "latest"), "ddpg_walker", "checkpoint.pt") == str(newest)
    err = capsys.readouterr().err
    assert err.count("\n") == 2 and f"{killed.name} has no model.pt" in err, err
    (killed / "model.pt").touch()  # it wrote one: it is the newest again
    assert cli.latest_run(str(tmp_path / "latest"), "ddpg_walker") == str(killed)
    assert cli.latest_run(str(tmp_path / "latest"), "ddpg_walker", "checkpoint.pt") == str(newest)
    assert f"{killed.name} has no checkpoint.pt" in capsys.readouterr().err
    for file in ("model.pt", "best.pt", "checkpoint.pt"):
        for run in tmp_path.glob("ddpg_walker__*"):
            (run / file).unlink(missing_ok=True)
    with pytest.raises(UserError, match="has model.pt yet"):
        cli.latest_run(str(tmp_path / "latest"), "ddpg_walker")


def test_runs_latest_is_a_link_to_the_newest_run_folder(tmp_path, capsys):
    """runs/latest is a folder a reader can open: a link (relative, so runs/ can move) to the
    newest run folder of any script, made as each run folder is. --eval and --resume still
    read it as their own script's newest run, not another script's. A diverged run's removal
    points it back at the newest run left, or removes it when none is left."""
    root = tmp_path / "runs"
    older = runlog.make_run_dir(root, "script_a", "Env-v1", 0)
    assert (root / "latest").is_symlink() and (root / "latest").resolve() == older.resolve()
    newer = runlog.make_run_dir(root, "script_b", "Env/v2", 1)
    assert os.readlink(root / "latest") == newer.name
    assert sorted(p.name for p in root.iterdir()) == sorted([older.name, newer.name, "latest"])
    for run in (older, newer):
        (run / "model.pt").touch()
    assert cli.latest_run(str(root / "latest"), "script_a") == str(older)
    assert cli.latest_run(str(root / "latest" / "model.pt"), "script_a") == str(
        older / "model.pt")
    for diverged, left in ((newer, older), (older, None)):
        with pytest.raises(UserError, match="was removed"):
            runlog.stop_if_diverged(7, dict(loss=float("nan")), (), diverged)
        assert (root / "latest").resolve() == left.resolve() if left else not any(
            root.iterdir())
    assert capsys.readouterr().out == ""


def test_runs_latest_where_links_cannot_be_made(tmp_path, capsys, monkeypatch):
    """Windows without the privilege, a filesystem without links: one line says so, nothing
    half made is left, and --eval runs/latest still finds the script's newest run."""
    def refused(*args, **kwargs):
        raise OSError(errno.EPERM, "Operation not permitted")

    monkeypatch.setattr(Path, "symlink_to", refused)
    run = runlog.make_run_dir(tmp_path, "script_a", "Env-v1", 0)
    out = capsys.readouterr().out
    assert out.count("\n") == 1 and "cannot be made a link" in out, out
    assert list(tmp_path.iterdir()) == [run]
    (run / "model.pt").touch()
    assert cli.latest_run(str(tmp_path / "latest"), "script_a") == str(run)


def test_a_folder_of_ones_own_named_latest_stays_as_it_is(tmp_path):
    (tmp_path / "latest").mkdir()
    assert cli.latest_run(str(tmp_path / "latest"), "script_a") == str(tmp_path / "latest")


def test_eval_runs_latest_from_the_command_line(tmp_path):
    """The README's `--eval runs/latest` pastes as it is and plays the newest run."""
    import ppo_cartpole

    ppo_cartpole.train(ppo_cartpole.Config(total_timesteps=512, stop_when_solved=False,
                                           gifs=False, curves=False, eval_episodes=1,
                                           run_dir=str(tmp_path / "runs"), print_every=10**6))
    p = run_script("ppo_cartpole.py", "--eval", "runs/latest", "--eval-episodes", 1,
                   cwd=tmp_path, timeout=120)
    assert p.returncode == 0, p.stderr
    assert "ppo_cartpole__CartPole-v1__seed0__" in p.stdout
    p = run_script("ppo_cartpole.py", "--eval", "elsewhere/latest", cwd=tmp_path, timeout=120)
    assert p.returncode == 2 and "no run of ppo_cartpole.py in elsewhere" in p.stderr


@pytest.mark.quick
def test_the_time_left_does_not_flicker_at_a_minute():
    """34 s left read "under a minute" at one line and "about 1 min" at the next (round())."""
    assert [runlog.hours_minutes(s) for s in (20, 34, 59.9, 60, 89, 91, 5000)] == [
        "under a minute", "under a minute", "under a minute", "about 1 min", "about 1 min",
        "about 2 min", "about 1 h 23 min"]


@pytest.mark.quick
def test_a_csv_row_with_other_columns_than_its_header_is_refused(tmp_path):
    """A column missing from some rows (an 8-field header over 9-field rows) cannot happen."""
    runlog.append_csv(tmp_path / "log.csv", dict(global_step=1, a=1.0, b=None))
    with pytest.raises(UserError, match="under the header"):
        runlog.append_csv(tmp_path / "log.csv", dict(global_step=2, a=1.0))
    assert (tmp_path / "log.csv").read_text().splitlines() == ["global_step,a,b", "1,1,nan"]


@pytest.mark.quick
def test_an_update_logs_exactly_the_declared_columns(tmp_path):
    """A column logged but not declared, or declared but not logged, fails at the first update;
    None is "not measured": nan in the CSV, left out of the progress line."""
    logged = dict(lr=(None, "lr"), loss=(".3f", "loss"), pass1=(".2f", "pass@1"))
    run = a_run(tmp_path / "a", threshold=1.0, logged=logged)
    with pytest.raises(ValueError, match="declares the columns"):
        run.update(dict(loss=0.5, extra=1.0), lr=0.1, pass1=None)
    run = a_run(tmp_path / "b", threshold=1.0, logged=logged)
    with pytest.raises(ValueError, match="declares the columns"):
        run.update(dict(loss=0.5), lr=0.1)


@pytest.mark.quick
def test_none_is_not_divergence_but_nan_is():
    runlog.stop_if_diverged(1, dict(loss=0.5, pass1=None), ())
    with pytest.raises(UserError, match="diverged at step 1: nan or inf in loss"):
        runlog.stop_if_diverged(1, dict(loss=float("nan")), ())


@pytest.mark.quick
def test_an_evaluations_numpy_or_tensor_number_is_kept_as_a_plain_one(tmp_path, capsys):
    """A script's column given as np.float64 (np.mean's) or a 0-dim tensor is written and kept
    as a plain number: checkpoint.pt, which holds every row, still loads with weights_only."""
    import types

    cfg = types.SimpleNamespace(resume=None, run_dir=str(tmp_path), env_id="Env-v0", seed=0,
                                print_every=1000, total_timesteps=100)
    logged = dict(length=(None, "mean episode length"), q=(None, "Q"))
    run = runlog.EvaluationLog("some_script", cfg, "cpu", logged, 0, 10)
    run.evaluation(10, [1.0, 2.0], length=np.mean([3, 4]), q=torch.tensor(0.5))
    row = run.state_dict()["evaluations"][0]
    assert type(row["length"]) is float and type(row["q"]) is float and row["q"] == 0.5
    checkpoints.save_checkpoint(dict(log=run.state_dict()), tmp_path / "c.pt")
    loaded = checkpoints.load_checkpoint(tmp_path / "c.pt")["log"]["evaluations"][0]
    assert (loaded["length"], loaded["q"]) == (3.5, 0.5)
    assert (run.dir / "evaluations.csv").read_text().splitlines()[1].endswith(",3.5,0.5")


@pytest.mark.quick
def test_a_flag_this_script_lacks_gets_no_far_fetched_suggestion(capsys):
    """--resume on a script without it (another script's flag) is named as unrecognized, with
    no "did you mean --curves?"; a typo still gets its flag."""
    p = run_main("ppo_cartpole.py", "--resume", "runs/latest", capsys=capsys)
    assert p.returncode == 2 and "unrecognized arguments: --resume runs/latest" in p.stderr
    assert "did you mean" not in p.stderr, p.stderr
    p = run_main("ppo_cartpole.py", "--lerning-rate", "1e-3", capsys=capsys)
    assert p.returncode == 2 and "(did you mean --learning-rate?)" in p.stderr, p.stderr


# --- read-only and missing places; what --resume does with the files of later evaluations ---

@pytest.fixture
def read_only():
    """make(folder): `folder` and what it holds read-only until the test ends. As root, whom
    chmod does not stop, a read-only bind mount of the folder onto itself; otherwise chmod a-w
    of each path in it. Skipped where root may not mount."""
    from pathlib import Path

    undo = []

    def make(folder):
        folder = Path(folder)
        if os.geteuid() != 0:
            for path in [folder, *folder.rglob("*")]:
                mode = path.stat().st_mode
                path.chmod(mode & ~0o222)
                undo.append(lambda path=path, mode=mode: path.chmod(mode))
            return folder
        if subprocess.run(["mount", "--bind", folder, folder], capture_output=True).returncode:
            pytest.skip("a read-only folder for root needs a bind mount, not allowed here")
        undo.append(lambda: subprocess.run(["umount", "-l", folder], check=True))
        subprocess.run(["mount", "-o", "remount,ro,bind", folder], check=True)
        return folder

    yield make
    for step in reversed(undo):
        step()


@pytest.mark.quick
def test_a_write_into_a_read_only_or_missing_folder_is_one_clear_error(tmp_path, read_only):
    """written_whole: the clear error, not the traceback of its .tmp's cleanup (which cannot
    remove a file from a read-only folder either); check_writable: the same, before any work,
    and nothing left behind where the folder takes files."""
    folder = tmp_path / "out"
    folder.mkdir()
    read_only(folder)
    with pytest.raises(UserError, match=r"cannot write .*x\.gif: (Read-only|Permission)"):
        with common.written_whole(folder / "x.gif") as tmp:
            tmp.write_bytes(b"GIF89a")
    with pytest.raises(UserError, match=r"^--gif x\.gif: cannot write into .*out: "
                                        r"(Read-only|Permission).*; copy it$"):
        common.check_writable(folder, "--gif x.gif", "copy it")
    with pytest.raises(UserError, match="--gif: no folder .*missing"):
        common.check_writable(tmp_path / "missing", "--gif")
    common.check_writable(tmp_path, "--gif")
    assert [p.name for p in tmp_path.iterdir()] == ["out"]  # the tried write left nothing


def evaluation_log(tmp_path, **flags):
    cfg = dataclasses.make_dataclass("Cfg", [("env_id", str, "Env-v0"), ("seed", int, 0),
                                             ("total_timesteps", int, 100)],
                                     bases=(cli.CheckpointFlags,))(
        **{"run_dir": str(tmp_path), "print_every": 1000, **flags})
    return runlog.EvaluationLog("some_script", cfg, "cpu", {}, 0, 10)


# what report.after_evaluation writes besides the row (a planted bug may leave one out of
# runlog.EVALUATION_FILES: the tests name them themselves)
WRITTEN_AT_AN_EVALUATION = ("model.pt", "best.pt", "best.gif", "curve.png", "inside.png")


def files_of(run):
    return {p.name: p.read_bytes() for p in run.dir.iterdir() if p.suffix != ".csv"}


@pytest.mark.quick
def test_resume_puts_back_the_files_of_the_evaluations_up_to_its_checkpoint(tmp_path):
    """What the evaluations wrote besides their rows (model.pt, best.pt, best.gif, curve.png,
    inside.png) is in checkpoint.pt, loaded with weights_only: a resume puts it back, and a
    file first written past the checkpoint goes."""
    run = evaluation_log(tmp_path)
    run.evaluation(10, [1.0])
    for name in ("model.pt", "best.pt", "curve.png"):
        (run.dir / name).write_bytes(f"{name} at step 10".encode())
    checkpoints.save_checkpoint(dict(log=run.state_dict()), tmp_path / "c.pt")
    state = checkpoints.load_checkpoint(tmp_path / "c.pt")["log"]
    run.evaluation(20, [5.0])  # past the checkpoint: a new best, drawn, recorded
    for name in WRITTEN_AT_AN_EVALUATION:
        (run.dir / name).write_bytes(f"{name} at step 20".encode())
    evaluation_log(tmp_path, resume=str(run.dir)).load_state_dict(state)
    assert files_of(run) == {name: f"{name} at step 10".encode()
                             for name in ("model.pt", "best.pt", "curve.png")}
    assert (run.dir / "evaluations.csv").read_text().splitlines()[1:] == ["10,1,0,0,nan"]


@pytest.mark.quick
def test_resume_from_an_older_checkpoint_removes_what_is_past_it(tmp_path, capsys):
    """A checkpoint of an older version keeps no copies: the pictures of the rows it cuts go,
    and best.pt with its best.gif if best.pt is of an evaluation past it; model.pt stays,
    and so does a best.pt of an evaluation it keeps."""
    run = evaluation_log(tmp_path)
    run.evaluation(10, [1.0])
    older = {key: copy.deepcopy(value) for key, value in run.state_dict().items()
             if key != "files"}
    run.evaluation(20, [5.0])
    for name in WRITTEN_AT_AN_EVALUATION:
        (run.dir / name).write_bytes(b"step 20")
    torch.save(dict(global_step=20), run.dir / "best.pt")
    evaluation_log(tmp_path, resume=str(run.dir)).load_state_dict(older)
    assert files_of(run) == {"model.pt": b"step 20"}
    out = capsys.readouterr().out.splitlines()
    assert out[-1].startswith("curve.png, inside.png, best.pt, best.gif: of evaluations past "
                              "the checkpoint, removed"), out
    torch.save(dict(global_step=10), run.dir / "best.pt")  # the best of the kept rows
    (run.dir / "curve.png").write_bytes(b"step 10")  # drawn from them
    evaluation_log(tmp_path, resume=str(run.dir)).load_state_dict(older)
    assert set(files_of(run)) == {"model.pt", "best.pt", "curve.png"}


@pytest.mark.quick
def test_a_new_best_without_gifs_removes_the_best_gif_of_an_earlier_one(tmp_path):
    """A run resumed with --no-gifs: best.gif would show an earlier best than best.pt."""
    import report

    run = evaluation_log(tmp_path, gifs=False, curves=False)
    (run.dir / "best.gif").write_bytes(b"an earlier best")
    best = run.evaluation(10, [1.0])
    report.after_evaluation(run, torch.nn.Linear(2, 1), best, "cpu", {}, {})
    assert set(files_of(run)) == {"model.pt", "best.pt"}
