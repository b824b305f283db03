import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def run_script(script, *args, timeout=300, cwd=None, env=None):
    """Run `python <script> args...` as a user would (Ctrl-C as in a terminal); return the
    CompletedProcess. `env`: environment variables to add for the child."""
    env = {**os.environ, "PYTHONUNBUFFERED": "1", **(env or {})}
    env.pop("DISPLAY", None)  # the tests are about a headless machine, like CI
    return subprocess.run([sys.executable, str(ROOT / script), *map(str, args)], capture_output=True,
                          text=True, timeout=timeout, cwd=cwd or ROOT, env=env,
                          preexec_fn=ctrl_c_default)


def run_folders(root):
    """The run folders in `root`, sorted: its entries but the runs/latest link
    (runlog.point_latest)."""
    return sorted(p for p in Path(root).iterdir() if not p.is_symlink())


# The bad inputs whose tests run the real command, each in a new process: the allocation that
# fails, and an env that gymnasium cannot make (where a package's warning would show).
IN_A_PROCESS = ("not enough memory", "unknown environment")


def run_main(script, *args, capsys):
    """`python <script> args...` in this process: the script's main(args), as its __main__
    block calls it, with no display; returns what run_script does (returncode, stdout,
    stderr). For what main() does with its flags (the one-line errors): no new interpreter
    each time (importing torch alone takes over a second). What needs a process of its own
    (a signal, a warning printed to stderr, too large an allocation) uses run_script."""
    import importlib
    import types

    module = importlib.import_module(Path(script).stem)
    environ, argv0, streams = dict(os.environ), sys.argv[0], (sys.stdout, sys.stderr)
    for name in ("DISPLAY", "WAYLAND_DISPLAY"):
        os.environ.pop(name, None)
    sys.argv[0], code = script, 0  # argparse's prog, as on the command line
    try:
        module.main([str(a) for a in args])
    except SystemExit as e:
        code = e.code if isinstance(e.code, int) else int(e.code is not None)
    finally:
        os.environ.clear()
        os.environ.update(environ)
        sys.argv[0] = argv0
        sys.stdout, sys.stderr = streams  # --lang zh puts a translating stream in their place
    out, err = capsys.readouterr()
    return types.SimpleNamespace(returncode=code, stdout=out, stderr=err)


def ctrl_c_default():
    """In the child: Ctrl-C (SIGINT) does what it does in a terminal. A shell that starts a
    job in the background (`cmd &`) makes its children ignore SIGINT, tests included."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_DFL)


def ctrl_c_ignored():
    """In the child: SIGINT ignored, as a shell script's `cmd &` starts it."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)


def interrupt(script, *args, after, cwd=None, env=None, signal=None, background=False):
    """Start `python <script> args...`, send Ctrl-C (SIGINT; or `signal`, e.g. SIGTERM as
    `kill PID` sends it) once a stdout line starts with `after`; return (returncode, stdout,
    stderr). `cwd`: the folder it runs in (the repository's by default); `env`: environment
    variables to add; `background`: started with SIGINT ignored, as a shell script's `cmd &`."""
    code, out, err, _ = ctrl_c(script, *args, after=after, cwd=cwd, env=env, group=False,
                               signal=signal, background=background)
    return code, out, err


def interrupt_in_a_terminal(script, *args, after, cwd=None, env=None, signal=None):
    """interrupt(), with Ctrl-C (or `signal`) sent as a terminal sends it: to the whole
    foreground process group, the script and every process it started (as Slurm sends SIGTERM
    to every process of a job). `after`: the start of a line, or a tuple of them, seen in that
    order. Returns (returncode, stdout, stderr, left): left, whether any process of the group
    was still there once the script had exited (they are then killed)."""
    return ctrl_c(script, *args, after=after, cwd=cwd, env=env, group=True, signal=signal)


def ctrl_c(script, *args, after, cwd, env, group, signal=None, background=False):
    import signal as signals

    signal = signals.SIGINT if signal is None else signal
    env = {**os.environ, "PYTHONUNBUFFERED": "1", **(env or {})}
    env.pop("DISPLAY", None)
    proc = subprocess.Popen([sys.executable, str(ROOT / script), *map(str, args)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=env, cwd=cwd or ROOT,
                            preexec_fn=ctrl_c_ignored if background else ctrl_c_default,
                            start_new_session=group)
    seen, waiting = [], [after] if isinstance(after, str) else list(after)
    for line in proc.stdout:  # wait until training is under way
        seen.append(line)
        if line.startswith(waiting[0]):
            waiting.pop(0)
            if not waiting:
                break
    if group:  # its own session, so its group's id is its pid
        os.killpg(proc.pid, signal)
    else:
        proc.send_signal(signal)
    try:
        out, err = proc.communicate(timeout=60)
    except subprocess.TimeoutExpired:  # it went on: end it (and its group), then fail
        os.killpg(proc.pid, signals.SIGKILL) if group else proc.kill()
        proc.communicate()
        raise
    left = False
    if group:
        try:
            os.killpg(proc.pid, signals.SIGKILL)  # raises if no process of the group is left
            left = True
        except ProcessLookupError:
            pass
    return proc.returncode, "".join(seen) + out, err, left


import pytest  # noqa: E402


@pytest.fixture(autouse=True, scope="session")
def no_mujoco_log_left():
    """MuJoCo writes its warnings (e.g. an unstable simulation from an untrained actor) to
    MUJOCO_LOG.TXT in the folder it runs in: the repository's, for the scripts the tests
    start. A file the tests made is removed at the end; one that was there is kept."""
    log = ROOT / "MUJOCO_LOG.TXT"
    there = log.exists()
    yield
    if not there:
        log.unlink(missing_ok=True)


# Files whose tests each start a training run of several seconds or more.
HEAVY = ("test_experiments.py", "test_ddpg_walker.py", "test_td3_walker.py",
         "test_grpo_addition.py", "test_exercises.py")


def pytest_collection_modifyitems(config, items):
    """The worked examples in common.py's docstrings are part of the quick layer; a slow test
    is not, even in a file whose tests are quick. The longest tests go first: pytest-xdist
    hands tests out one at a time (--maxschedchunk 1, pytest.ini), so the workers, busy with
    the long ones from the start, end together."""
    for item in items:
        if isinstance(item, pytest.DoctestItem):
            item.add_marker(pytest.mark.quick)
    if config.getoption("markexpr") == "quick":  # pytest -m quick: no learning runs
        slow = [item for item in items if item.get_closest_marker("slow")]
        config.hook.pytest_deselected(items=slow)
        items[:] = [item for item in items if not item.get_closest_marker("slow")]
    items.sort(key=lambda item: (item.get_closest_marker("slow") is None,
                                 item.path.name not in HEAVY))
