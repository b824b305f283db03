"""Ctrl-C anywhere and bad input, for every script: one line, and the exit code
docs/running.md states (130 for Ctrl-C, 143 for SIGTERM, 2 for bad input), the last good files
kept, no *.tmp, no half-made run folder. To interrupt at an exact point (an import, the middle
of a file write), the child interrupts itself there: a sitecustomize.py on its PYTHONPATH
patches the module in question as it is imported. Nothing here waits on the clock."""

import csv
import importlib
import os
import textwrap

import imageio.v3 as iio
import pytest
import torch

from conftest import interrupt, run_main, run_script

CARTPOLE = ["ppo_cartpole", "ppo_kl_cartpole", "actor_critic_cartpole"]
QUICK = ["--total-timesteps", 512, "--no-stop-when-solved", "--eval-episodes", 1,
         "--print-every", 1]

# Shared by every child below: after_import(name, patch) calls patch(module) right after
# `name` is first imported; the test appends what it patches.
AFTER_IMPORT = '''
import importlib.machinery, signal, sys

def after_import(target, patch):
    class Finder:
        def find_spec(self, name, path=None, module=None):
            if name != target:
                return None
            sys.meta_path.remove(self)
            spec = importlib.machinery.PathFinder.find_spec(name, path)
            run = spec.loader.exec_module
            def exec_module(module):
                run(module)
                patch(module)
            spec.loader.exec_module = exec_module
            return spec
    sys.meta_path.insert(0, Finder())
'''


def hooked(tmp_path, code):
    """Environment variables that make the child run AFTER_IMPORT + `code` at start-up."""
    folder = tmp_path / "hook"
    folder.mkdir()
    (folder / "sitecustomize.py").write_text(AFTER_IMPORT + textwrap.dedent(code))
    paths = [str(folder), os.environ.get("PYTHONPATH")]
    return {"PYTHONPATH": os.pathsep.join(filter(None, paths))}


def run_folders(path):
    """The run folders in `path`: not the hook's folder, nor the runs/latest link."""
    return [p for p in path.iterdir() if p.name != "hook" and not p.is_symlink()]


def one_line(stderr, needle):
    lines = stderr.strip().splitlines()
    return "Traceback" not in stderr and len(lines) == 1 and needle in lines[0]


# --- Ctrl-C, and SIGTERM (kill PID), which does what Ctrl-C does ------------------------------

# (the signal the child sends itself, its exit code, its one line)
SIGNALS = [pytest.param(("SIGINT", 130, "interrupted (Ctrl-C)"), id="ctrl_c"),
           pytest.param(("SIGTERM", 143, "interrupted (SIGTERM)"), id="sigterm")]


@pytest.mark.parametrize("sent", SIGNALS)
def test_ctrl_c_while_mujoco_is_imported_is_no_missing_package(tmp_path, sent):
    """A Ctrl-C inside MuJoCo's C import comes out of gym.make as DependencyNotInstalled from
    ImportError("initialization failed") from KeyboardInterrupt: it is a Ctrl-C."""
    name, code, line = sent
    env = hooked(tmp_path, f'''
        class CtrlC:
            def find_spec(self, name, path=None, module=None):
                if name == "mujoco":
                    sys.meta_path.remove(self)
                    try:
                        signal.raise_signal(signal.{name})
                    except KeyboardInterrupt as e:  # what MuJoCo's C import turns it into
                        raise ImportError("initialization failed") from e
        sys.meta_path.insert(0, CtrlC())
    ''')
    p = run_script("ppo_cartpole.py", "--env-id", "Walker2d-v5", "--run-dir", tmp_path, env=env,
                   timeout=120)
    assert p.returncode == code, p.stderr
    assert one_line(p.stderr, line), p.stderr
    assert run_folders(tmp_path) == []


# The tools' paths (checkpoints' atomic save, report's pictures after a Ctrl-C, cli's --cuda),
# the same for every script: one script's real command stands for them (each script's own
# Ctrl-C and pictures: tests/test_every_script.py).
ONE = ["ppo_cartpole"]


@pytest.mark.parametrize("sent", SIGNALS)
@pytest.mark.parametrize("script", ONE)
def test_ctrl_c_in_the_middle_of_writing_model_pt(script, tmp_path, sent):
    """torch.save cut short raised RuntimeError("... unexpected pos") and left model.pt.tmp:
    now the write finishes, then the Ctrl-C (or SIGTERM) ends the run."""
    name, code, line = sent
    env = hooked(tmp_path, f'''
        def patch(torch):
            real_save = torch.save
            def save(obj, f, *args, **kwargs):
                class HalfWay:  # Ctrl-C during the third of the file's writes
                    writes = 0
                    def write(self, data):
                        HalfWay.writes += 1
                        if HalfWay.writes == 3:
                            signal.raise_signal(signal.{name})
                        return f.write(data)
                    def __getattr__(self, name):
                        return getattr(f, name)
                torch.save = real_save  # once
                return real_save(obj, HalfWay(), *args, **kwargs)
            torch.save = save
        after_import("torch", patch)
    ''')
    p = run_script(f"{script}.py", "--run-dir", tmp_path, "--no-gifs", *QUICK, env=env,
                   timeout=300)
    assert p.returncode == code, p.stderr
    assert one_line(p.stderr, line), p.stderr
    (run,) = run_folders(tmp_path)
    assert torch.load(run / "model.pt", weights_only=True)["global_step"] == 512
    assert not list(run.glob("*.tmp*"))


@pytest.mark.parametrize("sent", SIGNALS)
def test_ctrl_c_while_a_gif_is_written(tmp_path, sent):
    """The GIF being written is finished, then the Ctrl-C (or SIGTERM) ends the run, with the
    line that says where the run folder and its model.pt are (a late Ctrl-C, as below)."""
    name, code, _ = sent
    env = hooked(tmp_path, f'''
        def patch(v2):
            real = v2.mimsave
            def mimsave(path, *args, **kwargs):
                if str(path).endswith("after.gif.tmp"):
                    signal.raise_signal(signal.{name})
                return real(path, *args, **kwargs)
            v2.mimsave = mimsave
        after_import("imageio.v2", patch)
    ''')
    p = run_script("ppo_cartpole.py", "--run-dir", tmp_path, *QUICK, env=env, timeout=300)
    assert p.returncode == code, p.stderr
    assert p.stderr.strip() == "", p.stderr
    (run,) = run_folders(tmp_path)
    last = p.stdout.strip().splitlines()[-1]
    assert last.startswith("interrupted") and str(run) in last and "model.pt" in last, last
    assert len(iio.imread(run / "after.gif", index=None)) > 1  # whole, every frame
    assert not list(run.glob("*.tmp*"))


@pytest.mark.parametrize("script", ONE)
def test_interrupted_run_draws_its_curve_and_says_where_it_is(script, tmp_path):
    code, out, err = interrupt(f"{script}.py", "--run-dir", tmp_path, "--no-stop-when-solved",
                               "--total-timesteps", 10_000_000, "--print-every", 1, after="step")
    assert code == 130, err
    assert "Traceback" not in err
    (run,) = run_folders(tmp_path)
    assert (run / "curve.png").stat().st_size > 0 and not list(run.glob("*.tmp*"))
    last = out.strip().splitlines()[-1]
    assert last.startswith("interrupted at step") and str(run) in last, out
    assert all(name in last for name in ("model.pt", "progress.csv", "curve.png", "--eval"))


# --- bad input -----------------------------------------------------------------------------

@pytest.mark.parametrize("script,args,needle", [
    *[(s, ["--learning-rate", "inf"], "--learning-rate must be a finite number") for s in CARTPOLE],
    ("ppo_cartpole", ["--learning-rate", "nan"], "--learning-rate must be a finite number"),
    ("ppo_kl_cartpole", ["--solved-return", "nan"], "--solved-return must be a finite number"),
    ("actor_critic_cartpole", ["--gamma=-inf"], "--gamma must be a finite number"),
    ("ddpg_walker", ["--gamma", "nan"], "--gamma must be a finite number"),
    ("ddpg_walker", ["--eval", "a.pt", "--resume", "b"], "--resume"),
    # found only once training or --eval starts, and named as argparse names its errors
    ("ppo_cartpole", ["--eval", "nowhere"], "ppo_cartpole.py: error: no checkpoint at nowhere"),
])
def test_bad_flags_are_one_line_and_exit_2(script, args, needle, tmp_path, capsys):
    p = run_main(f"{script}.py", *args, "--run-dir", tmp_path, capsys=capsys)
    assert p.returncode == 2, (p.stdout, p.stderr)
    assert one_line(p.stderr, needle), p.stderr
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("script,args,needle", [
    *[(s, ["--learning-rate", "1e30"], "training diverged at step") for s in CARTPOLE],
    ("ppo_cartpole", ["--reward-scale", "1e30"], "nan or inf in loss_v"),
])
def test_a_run_that_diverges_stops_in_one_line_without_a_run_folder(script, args, needle,
                                                                    tmp_path, capsys):
    p = run_main(f"{script}.py", *args, "--run-dir", tmp_path, *QUICK, capsys=capsys)
    assert p.returncode == 2, (p.stdout, p.stderr)
    assert one_line(p.stderr, needle) and "learning rate" in p.stderr, p.stderr
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("script", ["ddpg_walker", "td3_walker", "sac_walker"])
def test_a_walker_that_diverges_stops_in_one_line_without_a_run_folder(script, tmp_path, capsys):
    """The losses a walker names on its progress line and every network it hands over are
    checked (the losses at every step): a critic step size of 1e30 is caught in one line."""
    p = run_main(f"{script}.py", "--env-id", "InvertedPendulum-v5", "--total-timesteps", 400,
                 "--start-steps", 200, "--batch-size", 64, "--print-every", 100, "--critic-lr",
                 "1e30", "--no-gifs", "--eval-episodes", 1, "--run-dir", tmp_path, capsys=capsys)
    assert p.returncode == 2, (p.stdout, p.stderr)
    assert one_line(p.stderr, "training diverged at step"), p.stderr
    assert "learning rate" in p.stderr
    assert list(tmp_path.iterdir()) == []


@pytest.fixture(scope="module")
def models(tmp_path_factory):
    """A model.pt of each CartPole script, from a tiny run."""
    out = {}
    for name in CARTPOLE:
        module = importlib.import_module(name)
        cfg = module.Config(run_dir=str(tmp_path_factory.mktemp(name)), total_timesteps=512,
                            stop_when_solved=False, gifs=False, curves=False, eval_episodes=1,
                            print_every=10**6)
        out[name] = module.train(cfg)["run_dir"] / "model.pt"
    return out


@pytest.mark.parametrize("script,other", [("ppo_kl_cartpole", "ppo_cartpole"),
                                          ("actor_critic_cartpole", "ppo_kl_cartpole"),
                                          ("ppo_cartpole", "actor_critic_cartpole")])
def test_eval_refuses_another_scripts_model(script, other, models, capsys):
    p = run_main(f"{script}.py", "--eval", models[other], capsys=capsys)
    assert p.returncode == 2, (p.stdout, p.stderr)
    assert one_line(p.stderr, f"is not a model of {script}.py: it is a model of {other}.py")
    ok = run_main(f"{other}.py", "--eval", models[other], "--eval-episodes", 1, capsys=capsys)
    assert ok.returncode == 0, ok.stderr


@pytest.mark.parametrize("script", ONE)
def test_cuda_without_a_gpu_says_so_and_trains_on_the_cpu(script, tmp_path):
    p = run_script(f"{script}.py", "--cuda", "--run-dir", tmp_path, "--no-gifs", "--no-curves",
                   *QUICK, env={"CUDA_VISIBLE_DEVICES": ""}, timeout=300)
    assert p.returncode == 0, p.stderr
    assert one_line(p.stderr, "warning: --cuda, but torch sees no GPU"), p.stderr
    assert "running on the CPU" in p.stderr
    (run,) = run_folders(tmp_path)
    with open(run / "progress.csv") as f:
        assert len(list(csv.DictReader(f))) >= 1  # it trained


# --- a late Ctrl-C, after training: the line still says where the model is --------------------

WALKER = ["--env-id", "InvertedPendulum-v5", "--total-timesteps", 300, "--start-steps", 200,
          "--eval-every", 150, "--eval-episodes", 1, "--batch-size", 64, "--hidden", 64]
# (script, its flags, the function of common.py the child stops itself in, at the first call
# with an argument that ends so): the final evaluation of a script that updates on batches; a
# walker's before.gif, recorded after its training and its last evaluation
LATE = [pytest.param("ppo_cartpole", QUICK, "evaluate", "", id="ppo_cartpole"),
        pytest.param("ddpg_walker", WALKER, "record_gif", "before.gif", id="ddpg_walker")]


@pytest.mark.parametrize("sent", SIGNALS)
@pytest.mark.parametrize("script,flags,function,path_ends", LATE)
def test_a_late_ctrl_c_names_the_run_folder_and_model_pt(script, flags, function, path_ends,
                                                          tmp_path, sent):
    """A Ctrl-C (or SIGTERM) after training, in its final evaluation or GIFs, ends with a line
    like that of every other stop, which names the run folder and model.pt (not with
    cli.clear_exit's bare "interrupted (Ctrl-C)"); exit 130 (143)."""
    name, code, _ = sent
    env = hooked(tmp_path, f'''
        def patch(common):
            real = common.{function}
            def stopped(*args, **kwargs):
                if any(str(arg).endswith("{path_ends}") for arg in args):
                    signal.raise_signal(signal.{name})
                return real(*args, **kwargs)
            common.{function} = stopped
        after_import("common", patch)
    ''')
    p = run_script(f"{script}.py", "--run-dir", tmp_path, *flags, env=env, timeout=300)
    assert p.returncode == code, (p.stdout, p.stderr)
    assert p.stderr.strip() == "", p.stderr  # the one line goes to stdout, as at other stops
    (run,) = run_folders(tmp_path)
    last = p.stdout.strip().splitlines()[-1]
    assert last.startswith("interrupted") and "after training" in last, p.stdout
    assert str(run) in last and "model.pt" in last and (run / "model.pt").exists(), last


# --- read-only and missing places: one line, exit 2, before any long work ------------------

from test_tools import read_only  # noqa: E402,F401  (the fixture)


@pytest.mark.parametrize("where", ["missing", "read-only"])
def test_a_gif_into_a_missing_or_read_only_folder_is_refused_before_playing(where, models,
                                                                          tmp_path, read_only,
                                                                          monkeypatch, capsys):
    """--gif's folder is checked with the flags, before the model is loaded or an episode
    played: one line, exit 2."""
    import common

    folder = tmp_path / "out"
    if where == "read-only":
        folder.mkdir()
        read_only(folder)
    monkeypatch.setattr(common, "record_gif", lambda *args, **kw: pytest.fail("it played"))
    p = run_main("ppo_cartpole.py", "--eval", models["ppo_cartpole"], "--gif",
                 folder / "x.gif", capsys=capsys)
    assert p.returncode == 2, (p.stdout, p.stderr)
    assert one_line(p.stderr, f"error: --gif {folder / 'x.gif'}: "
                    + ("no folder" if where == "missing" else "cannot write into")), p.stderr


@pytest.mark.parametrize("script", ["ppo_cartpole", "ddpg_walker"])  # UpdateLog, EvaluationLog
def test_a_read_only_run_dir_is_one_line_and_a_missing_one_is_made(script, tmp_path, read_only,
                                                                  capsys):
    folder = tmp_path / "runs"
    folder.mkdir()
    read_only(folder)
    small = {"ppo_cartpole": QUICK, "ddpg_walker": WALKER}[script]
    for run_dir in (folder, folder / "inside"):
        p = run_main(f"{script}.py", "--run-dir", run_dir, "--no-gifs", *small, capsys=capsys)
        assert p.returncode == 2, (p.stdout, p.stderr)
        assert one_line(p.stderr, f"error: cannot create run folder {run_dir}"), p.stderr
    p = run_main(f"{script}.py", "--run-dir", tmp_path / "new" / "runs", "--no-gifs",
                 "--no-curves", *small, capsys=capsys)
    assert p.returncode == 0, p.stderr
    assert len(run_folders(tmp_path / "new" / "runs")) == 1


def test_resume_of_a_read_only_run_is_one_line_and_eval_of_it_writes_nothing(tmp_path,
                                                                            read_only, capsys):
    """--resume writes into the run's folder: refused at once, in one line, before the
    checkpoint is loaded. --eval only reads: it plays the run (runs/latest too), and writes
    its --gif elsewhere."""
    assert run_main("ddpg_walker.py", "--run-dir", tmp_path / "runs", *WALKER,
                    capsys=capsys).returncode == 0
    (run,) = run_folders(tmp_path / "runs")
    read_only(tmp_path / "runs")
    before = {p.name: p.read_bytes() for p in run.iterdir()}
    p = run_main("ddpg_walker.py", "--resume", run, "--total-timesteps", 600, capsys=capsys)
    assert p.returncode == 2, (p.stdout, p.stderr)
    assert one_line(p.stderr, "--resume goes on in the run's folder: cannot write into "
                    f"{run}: "), p.stderr
    assert "resume a writable copy of it (--eval only reads it)" in p.stderr
    for played in (run, tmp_path / "runs" / "latest", tmp_path / "runs" / "latest" / "best.pt"):
        p = run_main("ddpg_walker.py", "--eval", played, "--eval-episodes", 1, capsys=capsys)
        assert p.returncode == 0 and p.stderr == "", p.stderr
    (tmp_path / "out").mkdir()
    p = run_main("ddpg_walker.py", "--eval", tmp_path / "runs" / "latest", "--gif",
                 tmp_path / "out" / "x.gif", capsys=capsys)
    assert p.returncode == 0 and (tmp_path / "out" / "x.gif").stat().st_size > 0, p.stderr
    assert {p.name: p.read_bytes() for p in run.iterdir()} == before
