"""The checks every algorithm script gets without being listed: a top-level *.py with a
`def train(` is a script, found here by itself. Each declares SMOKE, the Config overrides of
a run of seconds that still writes every file, and gets: --help, one-line errors for bad
input, its smoke run (files written, pictures drawn, --eval replays it), the same seed giving
the same logs, and Ctrl-C ending in one line with exit 130 and its files kept (SIGTERM too,
exit 143; and `kill -INT` where the run started with SIGINT ignored, as `cmd &` starts it).

A new script is one new file: if it crashes while drawing, forgets to declare SMOKE or a
column, or leaves a *.tmp behind, these tests fail in the quick layer (pytest -m quick). Its
numbers (its defaults, its smoke run's first logged rows) are held to those recorded in
tests/fingerprints.json once `python tests/fingerprints.py --accept NAME` has recorded them.
"""

import re
import dataclasses
import importlib
import signal

import imageio.v3 as iio
import pytest

import fingerprints
import plots
from conftest import interrupt, run_folders, run_main, run_script
from fingerprints import LOGS, SCRIPTS, quick_smoke, smoke


@pytest.fixture(params=SCRIPTS)
def script(request):
    return importlib.import_module(request.param)


def as_flags(overrides):
    """Config overrides as the command line's flags."""
    flags = []
    for name, value in overrides.items():
        flag = "--" + name.replace("_", "-")
        if isinstance(value, bool):
            flags.append(flag if value else flag.replace("--", "--no-", 1))
        else:
            flags += [flag, str(value)]
    return flags


def not_blank(path):
    """A PNG whose plot area holds more than the background and the axes."""
    image = iio.imread(path)[..., :3].astype(int)
    colours = {tuple(c) for c in image.reshape(-1, 3)[::7]}
    return image.shape[0] > 100 and image.shape[1] > 100 and len(colours) > 20


def test_the_scripts_are_found():
    assert {"ppo_cartpole", "ddpg_walker", "grpo_addition"} <= set(SCRIPTS)
    assert not {"common", "cli", "runlog", "report", "plots", "checkpoints"} & set(SCRIPTS)


@pytest.mark.quick
def test_help_lists_the_scripts_own_flags_first(script, capsys):
    p = run_main(f"{script.__name__}.py", "--help", capsys=capsys)
    assert p.returncode == 0 and "--seed" in p.stdout and "--run-dir" in p.stdout
    own = [f.name for f in dataclasses.fields(script.Config)
           if f.name in vars(script.Config).get("__annotations__", {})]
    at = [p.stdout.index("--" + name.replace("_", "-") + " ") for name in own[:2]]
    assert at and max(at) < p.stdout.index("--run-dir")


@pytest.mark.quick
@pytest.mark.parametrize("flags, needle", [
    (["--seed", "x"], "invalid int value"),
    (["--no-such-flag"], "unrecognized arguments"),
    (["--seeds", "1"], "did you mean --seed"),
])
def test_bad_input_is_one_line_and_exit_2(script, flags, needle, capsys, tmp_path):
    p = run_main(f"{script.__name__}.py", *flags, "--run-dir", tmp_path, capsys=capsys)
    lines = p.stderr.strip().splitlines()
    assert p.returncode == 2 and len(lines) == 1 and needle in lines[0], p.stderr
    assert "Traceback" not in p.stderr and not any(tmp_path.iterdir())  # no half-made folder


@pytest.mark.quick
def test_config_defaults_are_their_fingerprints(script):
    """Every field's default as tests/fingerprints.json records it: a default that the SMOKE run
    overrides (DDPG's warm-up, its buffer size) moves no smoke number, yet every real run's."""
    moved = fingerprints.moved(script.__name__, "defaults", fingerprints.defaults(script))
    assert not moved, fingerprints.message(script.__name__, moved)


@pytest.mark.quick
def test_smoke_run_writes_its_files_draws_and_replays(script, tmp_path, capsys):
    """Its files, pictures and --eval replay, and its fingerprint: the numbers of its logs'
    first two rows that tests/fingerprints.json records, integers exact, floats within 1e-3 of
    the larger of the two values or of their column's largest recorded value (a loss that
    cancels to 3e-05 carries its column's noise). A shifted initialisation or default moved
    them by 0.6% or more; another machine's float order (SIMD width, BLAS) by under 1e-4 where
    it was tried, and 1e-6 of noise on every initial weight moved none: such differences grow
    only later in a run, once a sampled action or a clipped ratio flips."""
    # no GIFs here (seconds of the quick layer): test_same_seed_same_logs checks them
    result = script.train(quick_smoke(script, tmp_path))
    run = result["run_dir"]
    numbers = fingerprints.logged(run)
    assert run.parent == tmp_path and run.name.startswith(f"{script.__name__}__")
    names = {p.name for p in run.iterdir()}
    assert "model.pt" in names and names & set(LOGS), names
    if hasattr(script.Config, "env_id"):  # a run of seconds in which an episode ends
        assert "episodes.csv" in names, "no episode ended in the SMOKE run: make it longer"
    assert not any(".tmp" in name for name in names), names
    for picture in ("curve.png", "inside.png"):
        assert picture in names and not_blank(run / picture), picture
    assert (tmp_path / "latest").resolve() == run.resolve()  # runs/latest: a folder to open
    # plots.py takes any finished run, and runs/latest is that run again, not a second one
    fig = plots.compare_figure([run, tmp_path / "latest"])
    legends = [[t.get_text() for t in ax.get_legend().get_texts()] for ax in fig.axes]
    assert legends == [[f"{script.__name__}: 1 run"]], legends
    capsys.readouterr()
    episodes = [] if "eval_episodes" in getattr(script.Config, "UNUSED_FLAGS", ()) else [
        "--eval-episodes", "1"]  # a script with no env refuses the flag
    p = run_main(f"{script.__name__}.py", "--eval", run, *episodes, capsys=capsys)
    assert p.returncode == 0, p.stderr
    assert p.stdout.strip(), "--eval printed nothing"
    moved = fingerprints.moved(script.__name__, "smoke", numbers)
    assert not moved, fingerprints.message(script.__name__, moved)


@pytest.mark.slow
def test_same_seed_same_logs(script, tmp_path):
    """Same seed, same bytes in every log, from this process and from the command line in a
    new one (another PYTHONHASHSEED: no set or dict order may leak into the numbers); another
    seed, another log (the seed is used)."""
    seed = script.Config().seed
    quiet = {name: False for name in ("curves", "gifs")
             if name not in getattr(script.Config, "UNUSED_FLAGS", ())}
    p = run_script(f"{script.__name__}.py", *as_flags({**script.SMOKE, **quiet}), "--run-dir",
                   tmp_path / "0", env={"PYTHONHASHSEED": "12345"})
    assert p.returncode == 0, p.stderr
    gifs = {"gifs": True} if "gifs" in quiet else {}  # the other seed's run writes its GIFs
    runs = [run_folders(tmp_path / "0")[0]] + [
        script.train(smoke(script, tmp_path / str(i), seed=seed + (i == 2),
                           **{**quiet, **(gifs if i == 2 else {})}))["run_dir"]
        for i in (1, 2)]
    if gifs:  # a finished run's GIFs, whole (the smoke run in the quick layer writes none)
        for name in ("before.gif", "after.gif"):
            assert iio.imread(runs[2] / name).shape[0] >= 2, name
    logs = [name for name in LOGS if (runs[0] / name).exists()]
    assert logs
    def read(run, name):  # b"" where a run wrote no such log (e.g. no episode ended in it)
        return (run / name).read_bytes() if (run / name).exists() else b""

    for name in logs:
        assert read(runs[0], name) == read(runs[1], name), name
    assert [read(runs[0], n) for n in logs] != [read(runs[2], n) for n in logs]


@pytest.mark.parametrize("how,code", [
    pytest.param(dict(), 130, id="ctrl_c"),
    pytest.param(dict(signal=signal.SIGTERM), 143, id="sigterm"),  # kill PID, Slurm, docker stop
    pytest.param(dict(background=True), 130, id="kill_int_in_background")])  # cmd &: SIGINT ignored
def test_ctrl_c_or_sigterm_is_one_line_and_keeps_its_files(script, how, code, tmp_path):
    if how.get("background") and script.__name__ != "ppo_cartpole":  # the tools' behaviour
        pytest.skip("SIGINT re-enabled by cli.clear_exit for every script: one script shows it")
    flags = as_flags({**script.SMOKE, "print_every": 1})
    first = "episode" if script.__name__ == "q_learning_cliffwalking" else "step"  # its log's step
    got, out, err = interrupt(f"{script.__name__}.py", *flags, "--run-dir", tmp_path,
                              after=first, **how)
    assert got == code, (out, err)
    assert "Traceback" not in err and len(err.strip().splitlines()) <= 1, err
    assert "interrupted" in out + err, (out, err)
    (run,) = run_folders(tmp_path)
    names = {p.name for p in run.iterdir()}
    assert "model.pt" in names and not any(".tmp" in n for n in names), names
    if "resume" in {f.name for f in dataclasses.fields(script.Config)}:  # its checkpoint, of
        stopped = re.search(r"interrupted at step (\d+)", out)[1]  # the step it stopped at
        assert f"its checkpoint is at step {stopped}" in out, out
    if "progress.csv" in names:  # a row per update: the one the progress line showed is kept,
        assert len((run / "progress.csv").read_text().splitlines()) >= 2  # and drawn
        assert {"curve.png", "inside.png"} <= names, names
    last = out.strip().splitlines()[-1]
    assert last.startswith("interrupted") and str(run) in last, out  # says where its files are
    promised = "before.gif and after.gif come when a run finishes"  # the walkers' line
    named = re.findall(r"\w+\.(?:gif|png|pt|csv)\b", last.replace(promised, ""))
    assert set(named) <= names, (named, names)  # it names no file that is not there


def english_sentences(text, names=()):
    """The runs of three or more English words in `text`, once names, numbers, paths and flags
    are taken out (without_names)."""
    return [run for line in text.splitlines() for run in re.findall(
        r"[A-Za-z]{2,}(?:[ ,;:()]+[A-Za-z]{2,}){2,}", without_names(line, names))]


def without_names(line, names=()):
    """`line` less its names, numbers, paths and flags: `names`, file and folder paths, --flags,
    identifiers (loss_pi, pass@1, CartPole-v1), words in backquotes or in capitals (PPO, DPO).
    tests/test_pictures_zh.py holds a picture's texts to it too."""
    line = re.sub(r"`[^`]*`|\S*[/\\]\S*|\S+\.(?:py|pt|png|csv|gif|npz|md)\b|--[\w-]+", " ", line)
    line = re.sub(r"\b(?:%s)\b" % "|".join(map(re.escape, names)) if names else "$^", " ", line)
    return re.sub(r"[\w@*'-]*[_\d@][\w@*'-]*|\b[A-Z][A-Z-]+\b", " ", line)


def test_smoke_run_in_chinese_prints_no_english_sentence(script, tmp_path, capsys):
    """--lang zh: every line of the smoke run (its progress lines, stages, last lines), of
    --eval, of a one-line error and of a Ctrl-C is in Chinese, but for names, numbers, paths
    and flags; without it the English is what it always was (the other tests)."""
    names = [*getattr(script, "LOGGED", {}), "sft", "rm", "ppo", "dpo", "grpo", "Sarsa", "nan",
             "cpu", "n/a", "pi", "argmax_a"]
    flags = as_flags({**script.SMOKE, "print_every": 1})
    p = run_script(f"{script.__name__}.py", *flags, "--run-dir", tmp_path / "runs", "--lang",
                   "zh")
    assert p.returncode == 0, p.stderr
    assert "运行目录" in p.stdout and not english_sentences(p.stdout + p.stderr, names), (
        english_sentences(p.stdout + p.stderr, names))
    stages = re.findall(r"\bphase\b|\b(?:sft|rm|ppo|dpo|grpo|rft|more_labels)\b", p.stdout)
    assert not stages, f"a stage named in English: {stages}"  # 阶段 监督学习, GRPO, ...
    episodes = [] if "eval_episodes" in getattr(script.Config, "UNUSED_FLAGS", ()) else [
        "--eval-episodes", "1"]
    for args in (["--eval", tmp_path / "runs" / "latest", *episodes], ["--print-every", "0"]):
        p = run_main(f"{script.__name__}.py", *args, "--lang", "zh", capsys=capsys)
        assert not english_sentences(p.stdout + p.stderr, names), (p.stdout, p.stderr)
    assert p.returncode == 2 and "必须是正数" in p.stderr, p.stderr
    got, out, err = interrupt(f"{script.__name__}.py", *flags, "--run-dir", tmp_path / "cut",
                              "--lang", "zh", after="第")
    assert got == 130 and "中断" in out + err, (out, err)
    assert not english_sentences(out + err, names), english_sentences(out + err, names)
