"""The find-the-bug exercises' curves: each planted bug's run beside the script's own, seed 0,
at the settings of stage (c). Writes docs/exercises_bugs.png (about 3 minutes on a CPU).

    python exercises/draw_bugs.py
    python exercises/draw_bugs.py --lang zh   # its Chinese twin, docs/exercises_bugs.zh-CN.png
"""

import contextlib
import importlib
import io
import sys
import tempfile
from pathlib import Path

import check  # noqa: F401  (first: it puts the scripts on the path)

import help_zh
import plots

ZH = help_zh.wanted(sys.argv[1:])[2]  # --lang zh (or a Chinese locale), as the scripts read it
OUT = check.HERE.parent / "docs" / f"exercises_bugs{'.zh-CN' if ZH else ''}.png"


def curve(ex, fn, tmp):
    """(steps, values, what) of a stage-(c) run with `fn` swapped in."""
    script = importlib.import_module(ex.script)
    with check.swapped([(ex.owner(), ex.function, fn)]), contextlib.redirect_stdout(io.StringIO()):
        result = script.train(script.Config(**{**ex.learn, "stop_when_solved": False}
                                            if "ddpg" not in ex.script else ex.learn,
                                            run_dir=str(tmp)))
    return plots.curve_of(Path(result["run_dir"]))


def main():
    if ZH:  # the picture's words from locale/output.zh-CN.md
        help_zh.print_in_chinese()
    plt = plots.pyplot()
    fig, axes = plt.subplots(1, len(check.BUGS), figsize=(13, 3.6))
    with tempfile.TemporaryDirectory() as tmp:
        for ax, (bug, of) in zip(axes, check.BUGS.items()):
            ex = check.EXERCISES[bug]
            for label, fn, color in (("the script's own", getattr(ex.owner(), ex.function), "C0"),
                                     (f"exercises/{bug}.py", check.load(bug), "C3")):
                steps, values, what = curve(ex, fn, Path(tmp) / f"{bug}_{color}")
                ax.plot(steps, values, color=color, lw=1.5, label=label)
                print(f"{bug}: {label}: last {values[-1]:.0f}", flush=True)
            ax.set_xlabel("env steps")
            ax.set_ylabel("\n".join(plots.textwrap.wrap(what, 40)), fontsize=7)
            # the legend over the axis, one entry under another: the peaks stay in view
            plots.legend_above(ax, title=f"{bug} ({ex.script}.py, seed 0)", stack=True)
    fig.tight_layout()
    print(f"wrote {plots.save_whole(plt, fig, OUT, dpi=80)}")


if __name__ == "__main__":
    sys.exit(main())
