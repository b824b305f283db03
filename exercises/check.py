"""Check an exercise: python exercises/check.py gae   (no name: a table of all of them)

Three stages, each stopped at the first that fails:
  (a) worked cases: your function on hand-computed examples, the traps included; for a loss,
      its gradient too, against the script's own function's (cut, reversed, or wrong); a wrong
      value that a known mistake gives is named;
  (b) the real loop: the script's own train() on a fixed seed, for a few updates, once with
      your function swapped in and once with the script's own; their logs are compared update
      by update, and the first quantity that differs is named with both values (and a loop
      that never calls your function fails loudly);
  (c) learning: the script with your function does what it is for (docs/exercises.md gives
      each one's bar and time). --no-learning stops after (b).
Your function reaches the script as the experiments' variants do (experiments/lab.swapped):
the script itself has no branch and no flag for it. Messages in Chinese or English: --lang,
else the locale. Exit status 0 only when every stage run passed.

检查练习，分三关：(a) 手算的例子（损失函数还比较梯度）；(b) 把你的函数换进脚本自己的 train()，
和原版逐次更新比较日志；(c) 用你的函数把任务学会。--lang zh 显示中文（不写时看系统语言）。

Where things are: each exercise's checks are exercises/cases/<name>.py (its worked cases, its
named mistakes, its hooks and its messages in both languages); this file finds them and runs
the stages; exercises/checking.py holds what they share, exercises/runs.py the scripts' runs
(docs/exercises.md, "For maintainers").
"""

import argparse
import contextlib
import importlib
import importlib.util
import io
import math
import sys
import tempfile
import time
from pathlib import Path
from types import SimpleNamespace

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE.parent / "experiments"))

import checking  # noqa: E402
import runs  # noqa: E402
import help_zh  # noqa: E402
from checking import Failed, raised, tr  # noqa: E402
from lab import swapped  # noqa: E402
from runs import HOLD  # noqa: E402, F401  (the scripts' tests read it here)

NOT_WRITTEN = "not written yet"


# ==== The exercises: exercises/<name>.py, checked by exercises/cases/<name>.py ================


def exercise(name, m):
    """The exercise `name` as the stages see it, from its checks' module `m` (cases/<name>.py):
    what it does not say takes the default."""
    return SimpleNamespace(
        name=name, script=m.SCRIPT, function=m.FUNCTION, checks=f"exercises/cases/{name}.py",
        owner=lambda: importlib.import_module(getattr(m, "OWNER", m.SCRIPT)), run=m.RUN,
        loop=m.LOOP, learn=m.LEARN, loop_hint=m.loop_hint, order=m.ORDER,
        outputs=getattr(m, "OUTPUTS", ("output",)), cases=getattr(m, "cases", list),
        worked_cases=getattr(m, "worked_cases", None), mistakes=getattr(m, "mistakes", None),
        narrow_mistakes=getattr(m, "narrow_mistakes", None),
        config_names=getattr(m, "CONFIG_NAMES", {}),
        named_error=getattr(m, "named_error", None), cut=getattr(m, "cut", None),
        losses=getattr(m, "LOSSES", (0,)), gradient_mistake=getattr(m, "gradient_mistake", None),
        learned=getattr(m, "learned", None) or m.RUN.learned)


def find_exercises():
    """{name: exercise} for every exercises/cases/<name>.py (a leading _: shared, not one), in
    docs/exercises.md's order, the planted bugs last; and {bug: the exercise it is checked as}."""
    found, bugs = {}, {}
    for path in sorted((HERE / "cases").glob("[!_]*.py")):
        m = importlib.import_module(f"cases.{path.stem}")
        if hasattr(m, "BUG_IN"):
            bugs[path.stem] = m.BUG_IN
        else:
            found[path.stem] = exercise(path.stem, m)
    for bug, of in bugs.items():
        found[bug] = SimpleNamespace(**{**vars(found[of]), "name": bug})
    order = sorted(found, key=lambda name: (name in bugs, found[name].order))
    return {name: found[name] for name in order}, {bug: bugs[bug] for bug in order if bug in bugs}


EXERCISES, BUGS = find_exercises()


def worked_cases(ex, fn):
    """Stage (a): the exercise's own worked cases where it has them, else its cases() run
    by checking.check_cases."""
    return ex.worked_cases(fn) if ex.worked_cases else checking.check_cases(ex, fn)


# ==== Stage (b): the real loop, beside the script's own function ============================


def loop_logs(ex, fn, tmp):
    """The run's logs, per update: rows of numbers, with the learner's `fn` swapped in (or the
    script's own, fn=None)."""
    script = importlib.import_module(ex.script)
    swaps = [] if fn is None else [(ex.owner(), ex.function, fn)]
    losses = []  # the off-policy scripts: every gradient step's numbers, to 6 significant digits
    update_fn, names = ex.run.update or (None, ())
    if update_fn:
        # the learner's function where it is the update itself, else the script's own
        update = fn if fn is not None and ex.function == update_fn else getattr(script, update_fn)

        def recorded(*args):
            out = update(*args)
            values = list(out) if isinstance(out, tuple) else list(out.reshape(-1))
            losses.append({k: f"{float(v):.6g}" for k, v in zip(names, values)})
            return out
        swaps = [s for s in swaps if s[1] != update_fn] + [(script, update_fn, recorded)]
    with swapped(swaps), contextlib.redirect_stdout(io.StringIO()):
        result = script.train(script.Config(**ex.loop, run_dir=str(tmp)))
    return ex.run.rows(losses, Path(result["run_dir"]), ex.loop)


REFERENCE = {}  # the script's own logs per loop setting, run once per process
ROUNDING = 1e-5  # a first difference in (b) this small (relative) is float rounding, not a bug
# or this small (absolute): a logged number near 0 made from numbers near 1 (a KL as
# rho - log(rho) - 1, a mean of terms that nearly cancel) keeps only their float32 rounding,
# 2**-23 of 1, however few of its own digits that leaves
FLOAT32_EPS = 2.0 ** -23


def relative(a, b):
    a, b = float(a), float(b)
    return abs(a - b) / max(abs(a), abs(b), 1e-30)


def rounding_only(a, b):
    """True where two logged numbers differ in their last digits only."""
    try:
        return math.isfinite(float(a)) and math.isfinite(float(b)) and (
            relative(a, b) < ROUNDING or abs(float(a) - float(b)) < FLOAT32_EPS)
    except (TypeError, ValueError):
        return False


def never_called(ex, stage):
    return Failed(tr(
        f"{ex.script}.train() never called {ex.function} in {stage}: the script no longer uses "
        f"the function this\n  exercise checks (its settings or its code changed), so the stage "
        f"would pass whatever you wrote.\n  This is the checker's fault, not yours: please "
        f"report it.",
        f"{ex.script}.train() 在{stage}里一次也没有调用 {ex.function}：脚本已经不用这个练习检查的函数了"
        f"（它的设置或代码变了），\n  所以这一关无论你写什么都会通过。这是检查程序的问题，不是你的：请报告它。"))


def real_loop(ex, fn):
    with tempfile.TemporaryDirectory() as tmp:
        key = (ex.script, tuple(sorted(ex.loop.items())))
        if key not in REFERENCE:
            REFERENCE[key] = loop_logs(ex, None, Path(tmp) / "reference")
        reference = REFERENCE[key]
        if ex.run.guard:
            ex.run.guard(reference)
        calls = [0]

        def counted(*args, **kw):
            calls[0] += 1
            return fn(*args, **kw)

        counted.__name__ = ex.function
        try:
            yours = loop_logs(ex, counted, Path(tmp) / "yours")
        except Exception as e:  # noqa: BLE001  the learner's error, named in one line
            raise Failed(tr(f"in {ex.script}.train(), at call {calls[0]} of your function: ",
                            f"在 {ex.script}.train() 里，你的函数第 {calls[0]} 次被调用时出错：")
                         + raised(e, fn))
    if calls[0] == 0:
        raise never_called(ex, tr("stage (b)", "第 (b) 关"))
    unit = tr(*ex.run.unit)
    for i, (a, b) in enumerate(zip(reference, yours)):
        for key in a:
            if key in ("sps",) or a[key] == b.get(key):
                continue
            n = a["step"] if "step" in a else i + 1
            where = (tr(f"evaluation at step {a['global_step']}", f"第 {a['global_step']} 步的评估")
                     if a.get("where") == "evaluation" else
                     tr(f"the learning phase ending at step {a['global_step']} (progress.csv)",
                        f"在第 {a['global_step']} 步结束的那次学习（progress.csv）")
                     if a.get("where") == "progress" else
                     (f"{unit} {n}" if checking.LANG == "en" else unit.format(n)))
            if rounding_only(a[key], b.get(key)):
                # (a) passed and the first difference is in the last digits: the same formula
                # with its float operations in another order (e.g. lerp_, or add_(tau * (p -
                # p')), for mul_ then add_); from there the two runs drift apart, as any would
                return tr(f"the logs first differ at {where}, in {key}, by rounding only "
                          f"({a[key]} vs {b.get(key)}): probably only the order of float "
                          f"operations;\n  your function is right in value (written in the "
                          f"script's own order, it gives identical logs)",
                          f"日志第一次不同是在{where}，{key}，只差在舍入上（{a[key]} 对 "
                          f"{b.get(key)}）：多半只是浮点运算的顺序不同；\n  你的函数在数值上"
                          f"是对的（按脚本自己的运算顺序写，日志会完全相同）")
            raise Failed(tr(f"{ex.script}.train() with your function: the logs first differ at "
                            f"{where}, in {key}: the script's own gives {a[key]}, yours "
                            f"{b.get(key)}",
                            f"换上你的函数后，{ex.script}.train() 的日志第一次不同是在{where}，"
                            f"{key}：脚本自己的是 {a[key]}，你的是 {b.get(key)}")
                         + f"\n  {ex.loop_hint()}")
    if len(reference) != len(yours):
        raise Failed(tr(f"{ex.script}.train() with your function logged {len(yours)} rows, the "
                        f"script's own {len(reference)}",
                        f"换上你的函数后，{ex.script}.train() 记了 {len(yours)} 行日志，"
                        f"脚本自己的是 {len(reference)} 行"))


# ==== Stage (c): learning ===================================================================


def learns(ex, fn):
    """Stage (c): train() with `fn` clears the script's bar (ex.learned), and gives its
    result; or, where it fell short, the same run beside the script's own function agrees
    with `fn` at every call (runs.beside_own), and gives a note that says so."""
    try:
        return learning_run(ex, fn)
    except Failed as e:
        short = e
    calls = [0]
    try:
        learning_run(ex, runs.beside_own(fn, getattr(ex.owner(), ex.function), calls))
    except Exception:  # noqa: BLE001  Differs, Failed, or your function's own error: it stands
        raise short from None
    return runs.fell_short_by_rounding(str(short), calls[0])


def learning_run(ex, fn):
    script = importlib.import_module(ex.script)
    calls = [0]

    def counted(*args, **kw):
        calls[0] += 1
        return fn(*args, **kw)

    with tempfile.TemporaryDirectory() as tmp, swapped([(ex.owner(), ex.function, counted)]):
        with contextlib.redirect_stdout(io.StringIO()):
            result = script.train(script.Config(**ex.learn, run_dir=tmp))
    if calls[0] == 0:
        raise never_called(ex, tr("stage (c)", "第 (c) 关"))
    ex.learned(result)
    return result


# ==== The command line ======================================================================


def load(name, path=None):
    """The learner's function from exercises/<name>.py (or `path`)."""
    ex = EXERCISES[name]
    path = Path(path or HERE / f"{name}.py")
    spec = importlib.util.spec_from_file_location(f"exercise_{name}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return getattr(module, ex.function)


def stage_names():
    return (tr("(a) worked cases", "第 (a) 关“手算的例子”"),
            tr("(b) the real loop", "第 (b) 关“真实的训练循环”"),
            tr("(c) learning", "第 (c) 关“学会任务”"))


def line(name, stage, verdict, why=""):
    """One line of output: the exercise, the stage, its verdict and why, punctuated as the
    language is (Chinese: full-width colons, no colon between the stage and its verdict)."""
    if checking.LANG == "zh":
        return f"{name}：{stage}{verdict}" + (f"：{why}" if why else "")
    return f"{name}: {stage}: {verdict}" + (f": {why}" if why else "")


def check(name, fn=None, learning=True, say=print):
    """Run the stages on `fn` (default: exercises/<name>.py's); True if all pass."""
    ex, fn = EXERCISES[name], fn or load(name)
    names = stage_names()
    stages = [(names[0], worked_cases), (names[1], real_loop)]
    stages += [(names[2], learns)] if learning else []
    fail = tr("FAIL", "未通过")
    for stage, run in stages:
        start = time.time()
        try:
            note = run(ex, fn)
        except NotImplementedError as e:
            if str(e) != NOT_WRITTEN:  # raised by something the answer called, not the blank
                say(line(name, stage, fail, raised(e, fn)))
                return False
            say(line(name, stage, fail, tr(
                f"{NOT_WRITTEN} (fill in the blank in exercises/{name}.py)",
                f"还没写（在 exercises/{name}.py 里填空）")))
            return False
        except Failed as e:
            say(line(name, stage, fail, str(e)))
            return False
        except Exception as e:  # noqa: BLE001  the learner's code raised: name it
            say(line(name, stage, fail, raised(e, fn)))
            return False
        seconds = time.time() - start
        say(line(name, stage, tr(f"pass ({seconds:.1f} s)", f"通过（{seconds:.1f} 秒）"),
                 note if isinstance(note, str) else ""))  # (c) returns train()'s result
    return True


def ChineseHelp(prog):
    """The scripts' --help-zh layout (help_zh.py: Chinese wrapped by columns), no defaults."""
    class Layout(help_zh.HelpFormatter):
        def _get_help_string(self, action):
            return action.help

    return Layout(prog)


def main(argv=None):
    argv = sys.argv[1:] if argv is None else list(argv)  # --help in the messages' language too:
    if "--help-zh" in argv:  # as the scripts' --help-zh: the help in Chinese
        argv = [a for a in argv if a != "--help-zh"] + ["--help", "--lang", "zh"]
    given = [b for a, b in zip(argv, argv[1:]) if a == "--lang"] + [
        a.partition("=")[2] for a in argv if a.startswith("--lang=")]
    checking.LANG = given[-1] if given and given[-1] in ("zh", "en") else checking.locale_lang()
    chinese = next(p for p in __doc__.split("\n\n") if p.startswith("检查练习"))
    parser = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0] + tr("", "\n\n" + chinese.replace("\n", "")),
        formatter_class=tr(argparse.HelpFormatter, ChineseHelp), add_help=False)
    parser.add_argument("-h", "--help", action="help", help=tr(
        "show this help message and exit", "show this help message and exit\n显示本帮助并退出"))
    parser.add_argument("name", nargs="?", choices=sorted(EXERCISES), help=tr(
        "the exercise", "the exercise\n练习名；不写时，列出所有练习的第 (a)、(b) 关"))
    parser.add_argument("--no-learning", action="store_true", help=tr(
        "stop after stage (b)", "stop after stage (b)\n只跑第 (a)、(b) 两关，不跑第 (c) 关“学会任务”"))
    en = ("the messages' language (default: from the locale, e.g. LANG=zh_CN.UTF-8 gives zh; "
          "else en)")
    parser.add_argument("--lang", choices=("zh", "en"), default=None, help=tr(en, en + (
        "\n提示用的语言；不写时看系统语言：LANG 等以 zh 开头就用中文，否则用英文")))
    args = parser.parse_args(argv)
    checking.LANG = args.lang or checking.locale_lang()
    again = f" --lang {args.lang}" if args.lang else ""  # a suggested command keeps --lang
    if args.name:
        passed = check(args.name, learning=not args.no_learning)
        if passed and args.no_learning:  # say so: all-pass lines alone read as if (c) passed too
            print(line(args.name, stage_names()[2], tr("not run (--no-learning)",
                                                       "没有跑（加了 --no-learning）"),
                       tr(f"python exercises/check.py {args.name}{again} runs it",
                          f"要跑这一关，运行 python exercises/check.py {args.name}{again}")))
        sys.exit(0 if passed else 1)
    all_passed = True
    fail = tr("FAIL", "未通过")
    for name in EXERCISES:  # no name: (a) and (b) of every exercise, one line each
        lines = []
        passed = check(name, learning=False, say=lines.append)
        all_passed &= passed
        head, gap = ((f"{name}：", f"{fail}：") if checking.LANG == "zh"
                     else (f"{name}: ", f": {fail}: "))
        stage, _, why = lines[-1].removeprefix(head).partition(gap)  # as line() wrote it
        verdict = (tr("(a) and (b) pass", "第 (a)、(b) 关都通过") if passed else
                   tr(f"FAIL at {stage}: ", f"{stage}未通过：") + why.splitlines()[0])
        if name in BUGS and not passed:  # where it fails would give the bug away
            verdict = tr("not fixed yet", "还没改好")
        print(f"{name:20} {verdict}", flush=True)
    print(tr("(stage (c), learning, runs one exercise at a time: "
             f"python exercises/check.py NAME{again})",
             f"（第 (c) 关要训练，一次只查一个练习：python exercises/check.py 练习名{again}）"))
    # exit status 0 only when every exercise passed (a) and (b): scripts and tests can rely on it
    sys.exit(0 if all_passed else 1)


if __name__ == "__main__":
    main()
