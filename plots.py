"""The pictures: each run's curve.png and inside.png, several runs compared, TensorBoard.

From the command line, compare runs: a panel per env, a colour per script, each run a thin
line that ends where the run stopped, their mean (thick) where all of them ran.

    python plots.py runs/*                             # every run there -> compare.png
    python plots.py runs/latest                        # the newest run (a link to its folder)
    python plots.py runs/<script>__* --out mine.png    # the runs of one script
    python plots.py --maps runs/*                      # the runs that keep maps -> maps.png

matplotlib is imported only here, with its Agg backend (no display needed). The code writes
the labels in English; under --lang zh (a Chinese locale too) a run's pictures are saved with
their words in Chinese, from locale/output.zh-CN.md, where a CJK font is found (in_chinese:
CJK_FONTS, then the optional package mplfonts), else English, and one line says so.
to_tensorboard writes the CSV logs as TensorBoard scalars under CleanRL's tag names, so that
our runs and CleanRL's overlay.
"""

import argparse
import contextlib
import csv
import importlib.util
import itertools
import re
import sys
import textwrap
from pathlib import Path

import numpy as np

import help_zh


def read_csv(path):
    """A CSV file as {column: float array}; empty cells are nan. A column of text (a stage's
    name) stays an array of its strings."""
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    columns = rows[0].keys() if rows else []
    return {k: numbers_or_text([r[k] for r in rows]) for k in columns}


def numbers_or_text(cells):
    """CSV cells -> a float array (empty cells: nan), or, where one is not a number, the text."""
    try:
        return np.array([float(c) if c not in ("", None) else np.nan for c in cells])
    except ValueError:
        return np.array([c or "" for c in cells])


def running_mean(y, k):
    """Mean of the last k values at each point (fewer at the start)."""
    c = np.cumsum(np.insert(np.asarray(y, dtype=float), 0, 0.0))  # c[i] = sum of the first i
    i = np.arange(1, len(y) + 1)
    lo = np.maximum(i - k, 0)
    return (c[i] - c[lo]) / (i - lo)


def pyplot():
    import matplotlib
    matplotlib.use("Agg")  # files only: works on a machine without a display
    import matplotlib.pyplot as plt
    return plt


# A picture is rows of panels. A panel is (n, draw): it takes n axes side by side in its row
# and draw(axes, logs) fills them from `logs`, the run's tables read from its CSVs
# ("progress", "evaluations", "episodes": {column: array}), "kept" (per update: (env step,
# {name: array})), "labels" ({column: what it is}, from the script's declaration of what
# it logs) and "warm_up" (the env steps of random actions before learning starts, shaded;
# 0: none). The scripts choose their panels from the builders below; none of them knows a
# script. A few hold what they show, handed over when the script declares them (maps_row's
# maps, distributions' arrays, text's lines). Every axis of a row has the same width, and
# every axis says on its y label what it measures: one quantity per axis.


def load_logs(run_dir, kept=(), labels=None, warm_up=0):
    """The `logs` of a run folder's pictures (see above)."""
    run_dir = Path(run_dir)
    logs = dict(kept=list(kept), labels=dict(labels or {}), warm_up=warm_up)
    for name in ("progress", "evaluations", "episodes"):
        if (run_dir / f"{name}.csv").exists():  # episodes.csv: absent before the first ends
            logs[name] = read_csv(run_dir / f"{name}.csv")
    logs["table"] = logs.get("evaluations", logs.get("progress", {}))  # one per update or eval
    return logs


def figure(rows, logs, title, width=12, row_height=3.3, heights=None, gap=1.0):
    """The figure of `rows` of panels, filled from `logs`, `title` on top: `width` inches
    wide, or wider where a row's axes would be narrower than 1.8 inches. `gap`: inches
    between two axes of a row, room for the tick labels and y label of the one on the right;
    0.7 more in a row with a right-hand axis (a panel whose fill has right_axis true). A row is
    `row_height` high, or its tallest panel's `height` where its fills give one (a flat map)."""
    plt = pyplot()
    left, right, narrowest = 1.0, 1.0, 1.8  # inches: the margins, the narrowest axis
    # per row: its axes, and the inches between two of them
    shape = [(sum(k for k, _ in row),
              gap + 0.7 * any(getattr(fill, "right_axis", False) for _, fill in row))
             for row in rows]
    width = max([width] + [left + right + n * narrowest + (n - 1) * space for n, space in shape])
    heights = heights or [max(getattr(fill, "height", row_height) for _, fill in row)
                          for row in rows]
    total = sum(heights) + 0.8  # inches; the run's name, then a legend and title above a panel
    fig = plt.figure(figsize=(width, total))
    # margins in inches, room for the outer labels (a right-hand axis' too), so that the
    # picture is saved as laid out, without a second drawing to fit it (bbox_inches="tight")
    grid = fig.add_gridspec(len(rows), 1, height_ratios=heights, hspace=0.6, left=left / width,
                            right=1 - right / width, top=1 - 0.85 / total, bottom=0.5 / total)
    for cell, row, (n, space) in zip(grid, rows, shape):
        axis = (width - left - right - (n - 1) * space) / n  # inches, each axis of the row
        sub = cell.subgridspec(1, n, wspace=space / axis)  # wspace: a share of an axis' width
        at = 0
        for k, fill in row:
            fill([fig.add_subplot(sub[0, at + i]) for i in range(k)], logs)
            at += k
    fig.suptitle(title, fontsize=8, y=1 - 0.12 / total)
    return fig


def draw(run_dir, name, rows, logs, dpi=96, **layout):
    """Write run_dir/<name>, the figure of `rows` (figure(); `layout`: its width, row_height,
    heights, gap); returns its path."""
    run_dir = Path(run_dir)
    fig = figure(rows, logs, run_dir.name, **layout)
    return save_whole(pyplot(), fig, run_dir / name, dpi=dpi, tight=False)


def save_whole(plt, fig, path, dpi, tight=True):
    """Save `fig` as `path`, written whole (aside, then renamed), Ctrl-C or not; close it.
    tight: fitted to what it holds, nothing cut at the edges (matplotlib draws it twice)."""
    tmp = Path(f"{path}.tmp.png")
    try:
        with in_chinese(fig):  # English, unless the output is in Chinese (--lang zh)
            fig.savefig(tmp, dpi=dpi, bbox_inches="tight" if tight else None)
        tmp.replace(path)
    finally:
        plt.close(fig)
        tmp.unlink(missing_ok=True)
    return path


# ---- the pictures in Chinese (--lang zh) ---------------------------------------------------

# The CJK fonts looked for among those matplotlib knows (the system's: fonts-noto-cjk,
# fonts-wqy-zenhei, Windows' and macOS' own), the first found drawn; then mplfonts' Noto Sans
# CJK SC (MPLFONTS: the optional package's font file, in its folder), registered with
# matplotlib. None found: the pictures stay English, and NO_CJK_FONT says so once.
CJK_FONTS = ("Noto Sans CJK SC", "Noto Sans SC", "Source Han Sans SC", "WenQuanYi Zen Hei",
             "WenQuanYi Micro Hei", "SimHei", "Microsoft YaHei", "PingFang SC", "Heiti SC")
MPLFONTS = ("mplfonts", "fonts/NotoSansCJKsc-Regular.otf")
NO_CJK_FONT = ("note: the pictures stay English: no CJK font found (looked for {fonts}, then "
               "the mplfonts package); pip install mplfonts, or a system CJK font such as "
               "fonts-noto-cjk, draws them in Chinese")
SAID = set()  # the lines said once per run (NO_CJK_FONT)
WRAP = 34  # characters (columns in Chinese) per line of a long axis label


def in_chinese(fig):
    """The context `fig` is saved in: as it is, unless the output is in Chinese (--lang zh, or
    a Chinese locale: help_zh.output_entries). Then, where a CJK font is found (cjk_font),
    every text of the figure (titles, axis labels, legends, the colour bar's, a panel's
    text) in its Chinese from locale/output.zh-CN.md, and that font behind the figure's own
    for the characters they lack (the numbers and names keep their font); without one, the
    pictures stay English and one line says so, once."""
    entries = help_zh.output_entries()
    if entries is None:
        return contextlib.nullcontext()
    font = cjk_font()
    if font is None:
        if NO_CJK_FONT not in SAID:
            SAID.add(NO_CJK_FONT)
            print(NO_CJK_FONT.format(fonts=", ".join(CJK_FONTS)), file=sys.stderr, flush=True)
        return contextlib.nullcontext()
    import matplotlib
    from matplotlib.text import Text

    for text in fig.findobj(Text):
        text.set_text(chinese(text.get_text(), entries))
        text.set_fontfamily([*text.get_fontfamily(), font])
    # and the tick labels, made as the figure is drawn
    return matplotlib.rc_context({"font.family": [*matplotlib.rcParams["font.family"], font]})


def chinese(english, entries):
    """A picture's text in Chinese (help_zh.translate) where the catalogue has it: an axis
    label wrapped by textwrap is looked up as one line and wrapped again; a text of several
    lines that is not (a panel of sampled answers), line by line."""
    lines = english.split("\n")
    whole = lines[0]
    for line in lines[1:]:  # textwrap breaks after a hyphen (cross-entropy) or at a space
        whole += ("" if whole.endswith("-") and line[:1].isalpha() else " ") + line
    found = help_zh.translate(whole, entries)
    if found == whole:
        return "\n".join(help_zh.translate(line, entries) for line in lines)
    return "\n".join(evenly_wrapped(found, WRAP)) if len(lines) > 1 else found


def evenly_wrapped(text, width):
    """`text` (Chinese) in as few lines of at most `width` columns as help_zh.wrapped makes,
    broken after a comma, semicolon or colon where its phrases fit so, the lines as even as
    they go; else as even as wrapping them narrower makes them (no character alone on the
    last line)."""
    lines = help_zh.wrapped(text, width).split("\n")
    if len(lines) < 2:
        return lines
    phrases = re.split(r"(?<=[，；：])", text)
    best = None
    for cuts in itertools.combinations(range(1, len(phrases)), len(lines) - 1):
        parts = ["".join(phrases[a:b]).strip() for a, b in zip((0, *cuts), (*cuts, None))]
        longest = max(help_zh.columns(part) for part in parts)
        if longest <= width and (best is None or longest < best[0]):
            best = (longest, parts)
    if best is not None:
        return best[1]
    for narrower in range(-(-help_zh.columns(text) // len(lines)), width):
        even = help_zh.wrapped(text, narrower).split("\n")
        if len(even) == len(lines):
            return even
    return lines


def cjk_font():
    """The name of the CJK font the Chinese pictures are drawn with, or None: the first of
    CJK_FONTS that matplotlib knows, else mplfonts' font file (registered here)."""
    from matplotlib import font_manager

    known = {font.name for font in font_manager.fontManager.ttflist}
    found = next((name for name in CJK_FONTS if name in known), None)
    path = mplfonts_font() if found is None else None
    if path is not None:
        font_manager.fontManager.addfont(str(path))
        found = font_manager.FontProperties(fname=str(path)).get_name()
    return found


def mplfonts_font():
    """The path of the CJK font file the package mplfonts ships, where it is installed, else
    None. Found without importing mplfonts (its import needs its own dependencies)."""
    try:
        spec = importlib.util.find_spec(MPLFONTS[0])
    except (ImportError, ValueError):  # ValueError: sys.modules holds None for it
        return None
    folders = (spec.submodule_search_locations or []) if spec else []
    return next((Path(f) / MPLFONTS[1] for f in folders if (Path(f) / MPLFONTS[1]).is_file()),
                None)


def episode_returns(window, solved_return=None, solved_step=None):
    """Panel: the training episodes' returns (faint) and their mean over `window` episodes,
    the solved return and the step it was reached at."""
    def fill(axes, logs):
        ax, episodes = axes[0], logs.get("episodes", {})
        steps, returns = episodes.get("global_step", []), episodes.get("return", [])
        ax.plot(steps, returns, color="C0", alpha=0.3, lw=0.8, label="episode return")
        ax.plot(steps, running_mean(np.asarray(returns), window), color="C0", lw=2,
                label=f"mean of the last {window} episodes")
        if solved_return is not None:
            ax.axhline(solved_return, color="gray", ls="--", lw=1,
                       label=f"solved: {solved_return:g}")
        if solved_step is not None:
            ax.axvline(solved_step, color="C2", ls=":", lw=1.5,
                       label=f"solved at step {solved_step}")
        ax.set(xlabel="env steps", ylabel="return")
        legend_above(ax)
    return 1, fill


def evaluation_returns():
    """Panel: the evaluations' mean return +- std, and the training return before each; an
    evaluation in the random warm-up is a point of its own, on the shaded warm-up."""
    def fill(axes, logs):
        ax, table, labels = axes[0], logs["evaluations"], logs["labels"]
        x, mean, std = table["global_step"], table["eval_mean"], table["eval_std"]
        warm = warm_up_shaded(ax, x, logs.get("warm_up", 0))
        series(ax, x, mean, warm, color="C0", lw=2, label=labels.get("eval_mean", "eval_mean"))
        ax.fill_between(x[~warm], (mean - std)[~warm], (mean + std)[~warm], color="C0",
                        alpha=0.2, label="+- std")
        if warm.any():
            ax.errorbar(x[warm], mean[warm], std[warm], fmt="none", color="C0", capsize=3)
        series(ax, x, table["train_return_mean10"], warm, color="C1", lw=1,
               label=labels.get("train_return_mean10", "train_return_mean10"))
        ax.set(xlabel="env steps", ylabel="return")
        legend_above(ax)
    return 1, fill


def legend_above(ax, handles=None, title=None, on=None, stack=False):
    """The legend of `ax` over it, in one row, covering no line, `title` above it; where the
    row would be wider than the axis, one entry under another above it (`stack`, for a panel
    with room above it) or inside the axis where it covers the least (matplotlib's "best").
    `on`: the axis to draw it on (the one drawn last, where a right-hand axis shares ax)."""
    handles = handles or ax.get_legend_handles_labels()[0]
    points = sum(4 * len(h.get_label()) + 30 for h in handles)  # 7-point text
    wide = 72 * ax.get_position().width * ax.figure.get_figwidth() > points
    if wide or stack:
        ncol = max(len(handles), 1) if wide else 1
        (on or ax).legend(handles=handles, fontsize=7, loc="lower left", bbox_to_anchor=(0, 1),
                          ncol=ncol, frameon=False, borderaxespad=0.2)
        if title:
            ax.set_title(title, fontsize=9, pad=6 + 10 * -(-len(handles) // ncol))
        return
    (on or ax).legend(handles=handles, fontsize=7, loc="best")
    if title:
        ax.set_title(title, fontsize=9)


def warm_up_shaded(ax, steps, warm_up):
    """Shade the random warm-up (env steps up to `warm_up`; none if 0) on `ax`; returns which
    of `steps` lie in it."""
    if warm_up:
        ax.axvspan(0, warm_up, color="0.85", zorder=0, label="random warm-up: no learning yet")
    return np.asarray(steps) <= warm_up if warm_up else np.zeros(len(steps), dtype=bool)


def series(ax, x, y, warm, **style):
    """y over x, drawn in `style`; the points where `warm` (the random warm-up's) as open
    circles, not joined to the line of the learned ones: a line from them reads as learning.
    A line of one point draws nothing: a lone learned point is a dot."""
    if (~warm).sum() == 1 and not style.get("marker"):
        style = dict(style, marker="o", ms=4)
    ax.plot(x[~warm], y[~warm], **style)
    if warm.any():
        ax.plot(x[warm], y[warm], "o", ms=5, mfc="none", color=style["color"])


def axis_label(columns, labels, given):
    """An axis' y label: `given`, else the declared label of its one column (several columns:
    the script names what they share); wrapped to fit beside the axis."""
    if given is None and len(columns) == 1:
        given = labels.get(columns[0], columns[0])
    return textwrap.fill(given, WRAP) if given else ""


def lines(*columns, title=None, ylabel=None, right=(), right_ylabel=None, right_log=True,
          log=False, ylim=None, between=None, hlines=(), steps=False, dashed=(), within=None,
          where=None, x="global_step", x_of=None, xlabel="env steps", legend="auto",
          coloured_by=None):
    """Panel: `columns` of the run's table over env steps, labelled as declared; `ylabel`:
    what they measure (one column: its declared label unless given; several: name the one
    quantity they share); `right`: a second quantity's columns on a right-hand axis
    (`right_ylabel`, log-scaled unless `right_log` is False); `between`: (low, high, label)
    shaded; `hlines`: dashed levels; `steps`: drawn as steps, each rise and fall marked;
    `dashed`: columns drawn dashed over the others (wide), so that where they coincide both
    show. A column measured only at some rows (None elsewhere) is drawn at those rows, as
    points; one with no value in the rows drawn is left out. A column the log lacks stops the
    picture with a KeyError naming it. The random warm-up (logs["warm_up"]) is shaded, its points
    not joined to the learned ones. Only some rows, e.g. a stage on its own axis: `within`:
    (first, last) env step, both drawn; `where`: (column, value), the rows whose column holds
    value (a stage's name). Against another column: `x`, each row a point, joined in the
    log's order; `x_of`: a function of that column drawn instead (e.g. its square root);
    `xlabel`: what x is; `log`: a log y axis (2: ticked at powers of 2), or "wide": one where
    the values drawn span a factor of 10 or more, else linear (a log axis over 0.6 to 1 reads
    as flat); `legend`: over the axis where it fits, else in it ("auto"), "above" it always
    (legend_above), or where it goes in the axis (matplotlib's loc); `coloured_by`: (column,
    label): each row a point, not joined, coloured by that column (a colour bar, `label`, says
    how), a marker per column (the legend's, in grey, says which)."""
    def fill(axes, logs):
        ax, table, labels = axes[0], logs["table"], logs["labels"]
        needed = (*columns, *right, x, *([where[0]] if where else []))
        missing = [c for c in needed if c not in table]
        if missing:
            raise KeyError(f"a panel draws {missing}, which the run's log lacks (columns: "
                           f"{sorted(table)})")
        rows = np.ones(len(table[x]), dtype=bool)
        if within is not None:
            rows &= (table["global_step"] >= within[0]) & (table["global_step"] <= within[1])
        if where is not None:
            rows &= table[where[0]] == where[1]
        xs = (x_of(table[x]) if x_of else table[x])[rows]
        warm = (warm_up_shaded(ax, xs, logs.get("warm_up", 0)) if x == "global_step"
                else np.zeros(len(xs), dtype=bool))
        if between is not None:
            ax.axhspan(between[0], between[1], color="C2", alpha=0.2, label=between[2])

        from matplotlib.ticker import MaxNLocator

        coloured = []  # the points coloured_by draws, per column

        def draw_columns(ax, names, colors):
            for column, color in zip(names, colors):
                y = table[column][rows]
                at = np.isfinite(y)
                if not at.any():  # not measured in these rows (another stage's number)
                    continue
                if coloured_by is not None:  # points only: a line in row order reads as noise
                    by = np.asarray(table[coloured_by[0]][rows], dtype=float)
                    coloured.append(ax.scatter(
                        xs[at], y[at], c=by[at], cmap="viridis", vmin=np.nanmin(by),
                        vmax=np.nanmax(by), s=16, marker=MARKERS[len(coloured) % len(MARKERS)],
                        label=labels.get(column, column), zorder=2))
                    continue
                sparse = (at.sum() < len(at) or x != "global_step") and not steps
                on_top = column in dashed  # the others wide beneath it, to show at its gaps
                style = dict(color=color, label=labels.get(column, column), ms=3,
                             marker="o" if sparse else None, ls="--" if on_top else "-",
                             lw=1 if on_top or not dashed else 3, zorder=3 if on_top or sparse
                             else 2,  # dashed, or drawn as points: over the dense lines
                             drawstyle="steps-post" if steps else "default")
                series(ax, xs[at], y[at], warm[at], **style)
                if steps:  # the value the next row has: up or down from here
                    nxt = np.append(y[1:], np.nan)
                    for changed, marker, what in ((nxt > y, "^", "rises next"),
                                                  (nxt < y, "v", "falls next")):
                        ax.scatter(xs[changed], y[changed], marker=marker, s=18, label=what)

        draw_columns(ax, columns, [f"C{i + 1}" for i in range(len(columns))])
        for level in hlines:
            ax.axhline(level, color="k", ls="--", lw=0.8)
        ax.set(yscale="log" if wide_enough(log, table, columns, rows) else "linear",
               xlabel=xlabel)
        ax.set_ylabel(axis_label(columns, labels, ylabel), fontsize=8)
        if ylim is not None:
            ax.set_ylim(*ylim)
        few_ticks(ax, ax.xaxis)
        few_ticks(ax, ax.yaxis, base=2 if log == 2 else 10)
        if title:
            ax.set_title(title, fontsize=9)
        top = ax
        if right:  # its own axis, its own colours: one legend says which line is which
            top = ax.twinx()
            draw_columns(top, right, [f"C{i + len(columns) + 1}" for i in range(len(right))])
            top.set_yscale("log" if right_log else "linear")
            top.set_ylabel(axis_label(right, labels, right_ylabel), fontsize=8)
            few_ticks(top, top.yaxis)
        if coloured:  # one scale for every column's points; room for a right-hand axis' labels
            bar = ax.figure.colorbar(coloured[0], ax=list(dict.fromkeys((ax, top))),
                                     fraction=0.04, pad=0.12 if right else 0.03)
            bar.ax.set_title(coloured_by[1], fontsize=8)  # above the bar: upright in any script
            bar.ax.yaxis.set_major_locator(MaxNLocator(integer=True))  # steps: whole numbers
        handles = [h for a in dict.fromkeys((ax, top)) for h in a.get_legend_handles_labels()[0]]
        if handles and legend in ("auto", "above"):
            legend_above(ax, handles, title, top, stack=legend == "above")
        elif handles:  # on the axis drawn last, above every line
            shown = top.legend(handles=handles, fontsize=7, loc=legend)
            if coloured:  # the marker says which column; the colour is the colour bar's
                for handle in shown.legend_handles:
                    handle.set_color("0.4")
    fill.right_axis = bool(right)  # figure() leaves room for its labels
    return 1, fill


def wide_enough(log, table, columns, rows):
    """Whether the panel's y axis is log-scaled: `log` True, or "wide" and the values of
    `columns` in `rows` span a factor of 10 or more (all above 0)."""
    if log != "wide":
        return bool(log)
    values = np.concatenate([np.asarray(table[c][rows], dtype=float) for c in columns])
    values = values[np.isfinite(values)]
    return bool(len(values) and values.min() > 0 and values.max() >= 10 * values.min())


def few_ticks(ax, axis, base=10):
    """As many tick labels on `axis` (ax's x or y axis) as its length holds without their
    running together: about one an inch across (env steps run to 6 digits), one per 0.4
    inch up. A log axis over less than 3 decades: its ticks at 1, 2 and 5 (1 and 3 over 2
    decades or more) times a power of ten, written as plain numbers, the others unlabelled;
    `base` 2: at every power of 2 (a quantity doubled and halved), as plain numbers."""
    from matplotlib import ticker

    if base == 2 and axis.get_scale() == "log":
        axis.set_major_locator(ticker.LogLocator(base=2, numticks=99))
        axis.set_major_formatter(ticker.FuncFormatter(lambda v, _: f"{v:g}"))
        axis.set_minor_locator(ticker.NullLocator())
        return

    box = ax.get_position()
    across = axis is ax.xaxis
    inches = (box.width * ax.figure.get_figwidth() if across
              else box.height * ax.figure.get_figheight())
    most = max(2, int(inches / (1.0 if across else 0.4)))
    if axis.get_scale() == "linear" and across:  # up, matplotlib's own spacing holds them
        axis.set_major_locator(ticker.MaxNLocator(nbins=most, steps=[1, 2, 2.5, 5, 10]))
        return
    if axis.get_scale() != "log":
        return
    lo, hi = ax.get_xlim() if across else ax.get_ylim()
    if not (0 < lo < hi and np.isfinite(hi)):
        return
    decades = np.log10(hi / lo)
    if decades >= 3:  # matplotlib's powers of ten
        return
    subs = (1.0, 3.0) if decades >= 2 or most < 4 else (1.0, 2.0, 5.0)
    axis.set_major_locator(ticker.LogLocator(subs=subs, numticks=99))
    axis.set_major_formatter(ticker.FuncFormatter(lambda v, _: f"{v:g}"))
    axis.set_minor_formatter(ticker.NullFormatter())


def spread(prefix, title, hlines=(), ylabel=None):
    """Panel: a batch's distribution of a number after each update, from the columns
    <prefix>_min, _q05, _median, _q95, _max (common.ratio_stats): bands and the median;
    `ylabel`: what the number is (its prefix if not given)."""
    def fill(axes, logs):
        ax, table = axes[0], logs["table"]
        x = table["global_step"]
        ax.fill_between(x, table[f"{prefix}_min"], table[f"{prefix}_max"], color="C0",
                        alpha=0.15, label="min to max")
        ax.fill_between(x, table[f"{prefix}_q05"], table[f"{prefix}_q95"], color="C0",
                        alpha=0.3, label="5% to 95%")
        ax.plot(x, table[f"{prefix}_median"], color="C0", lw=1, label="median")
        for y in hlines:
            ax.axhline(y, color="k", ls="--", lw=0.8)
        ax.set_xlabel("env steps")
        ax.set_ylabel(ylabel or prefix, fontsize=8)
        legend_above(ax, title=title)
    return 1, fill


def kept_with(logs, *names):
    """The updates that kept the arrays `names` (none in a supervised stage, say); a name that
    no update kept, where updates kept others, stops the picture with a KeyError naming it."""
    kept = [k for k in logs["kept"] if all(name in k[1] for name in names)]
    named = sorted({name for _, arrays in logs["kept"] for name in arrays})
    if named and not kept:  # updates kept arrays, not these: a wrong name
        missing = [name for name in names if name not in named]
        raise KeyError(f"a panel draws the arrays {missing}, which no update kept (kept: "
                       f"{named})")
    return kept


def three_updates(kept):
    """An early, a middle and a late update of `kept` (its first, middle and last)."""
    picks = sorted({0, len(kept) // 2, len(kept) - 1}) if kept else []
    return [(i + 1, *kept[i]) for i in picks]


def histograms(array, by_sign_of=None, band=None, ylabel="samples in the batch"):
    """Panels (3): the kept `array` at an early, a middle and a late update of those that keep
    it (update k: the k-th of them; kept_with), split by the sign of the kept `by_sign_of` if
    given;
    `band`: (low, high) dashed, and, split by sign, shaded outside where a sample of that sign
    gets no gradient (the clip binds: above high for +, below low for -); `ylabel`: what
    one count is."""
    def fill(axes, logs):
        lo, hi = band if band is not None else (np.inf, -np.inf)
        kept = kept_with(logs, array)
        for ax, (update, step, arrays) in zip(axes, three_updates(kept)):
            r = arrays[array]
            if by_sign_of is None:  # bins over the values, fine where they crowd; band: dashed
                ax.hist(r, bins=40, color="C0", histtype="stepfilled")
            else:  # bins on past the band, where the shading shows
                bins = np.linspace(min(r.min(), 2 * lo - 1), max(r.max(), 2 * hi - 1), 40)
                sign = np.sign(arrays[by_sign_of])
                for s, color in ((1, "C2"), (-1, "C3")):  # one polygon each
                    ax.hist(r[sign == s], bins=bins, color=color, alpha=0.6,
                            histtype="stepfilled", label=f"{by_sign_of} {'>' if s > 0 else '<'} 0")
                if band is not None:
                    ax.axvspan(hi, bins[-1], color="C2", alpha=0.08)
                    ax.axvspan(bins[0], lo, color="C3", alpha=0.08)
            for v in band or ():
                ax.axvline(v, color="k", ls="--", lw=0.8)
            ax.set_title(f"{array} at update {update} (step {step})", fontsize=8)
            ax.set_xlabel(f"{array}; shaded: no gradient for that colour" if by_sign_of and band
                          else array, fontsize=7)
            ax.set_ylabel(ylabel, fontsize=7)
        if axes and kept and by_sign_of is not None:
            axes[0].legend(fontsize=7)
    return 3, fill


def distributions(arrays, title, xlabel, ylabel="count", vline=None):
    """Panel: histograms of `arrays` ({label: numbers}), over the same bins, one on another;
    `ylabel`: what one count is; `vline`: an x marked by a dashed line (e.g. 0)."""
    def fill(axes, logs):
        ax, values = axes[0], [np.asarray(a, dtype=float) for a in arrays.values()]
        bins = np.histogram_bin_edges(np.concatenate(values), bins=40)
        for i, (label, a) in enumerate(zip(arrays, values)):
            ax.hist(a, bins=bins, color=f"C{i}", alpha=0.6, label=label)
        if vline is not None:
            ax.axvline(vline, color="k", ls="--", lw=1)
        ax.set_title(title, fontsize=9)
        ax.set_xlabel(xlabel)
        ax.set_ylabel(ylabel, fontsize=8)
        ax.legend(fontsize=7)
    return 1, fill


def text(lines, title, largest=12, columns=None):
    """Panel: `lines` of text (e.g. sampled answers), top-down in a fixed-width font, no axes,
    as large as the panel holds them (at most `largest` points); `columns`: the characters a
    line is sized for, the longest line's if not given (panels side by side: one size)."""
    def fill(axes, logs):
        ax = axes[0]
        ax.axis("off")
        ax.set_title(title, fontsize=9)
        box = ax.get_position()  # a share of the figure: its size in points
        wide, high = (72 * box.width * ax.figure.get_figwidth(),
                      72 * box.height * ax.figure.get_figheight())
        chars = columns or max((len(line) for line in lines), default=1)
        # a monospace character is about 0.6 of the font size wide; a line 1.2 of it high
        size = min(largest, wide / (0.6 * chars), high / (1.2 * max(len(lines), 1)))
        ax.text(0, 1, "\n".join(lines), va="top", family="monospace", fontsize=size,
                transform=ax.transAxes)
    fill.height = min(3.3, 0.8 + 0.15 * len(lines))  # inches: a few lines leave no empty row
    return 1, fill


def scatters(x, y, xlabel, ylabel):
    """Panels (3): the kept `y` against the kept `x` at an early, a middle and a late update,
    with the diagonal y = x."""
    def fill(axes, logs):
        for ax, (update, step, arrays) in zip(axes, three_updates(kept_with(logs, x, y))):
            ax.scatter(arrays[x], arrays[y], s=3, alpha=0.4)
            both = np.concatenate([arrays[x], arrays[y]])
            ax.plot([both.min(), both.max()], [both.min(), both.max()], color="k", lw=0.8)
            ax.set_title(f"update {update} (step {step})", fontsize=8)
            ax.set_xlabel(xlabel, fontsize=8)
            ax.set_ylabel(ylabel, fontsize=8)
    return 3, fill


MARKERS = "o^sD"  # lines(coloured_by=...): a column's points


# maps_row's states visited: at most DOTS_DRAWN of them marked on a map, and what they are
DOTS, DOTS_DRAWN = "white dots: states from the last batches", 800


def maps_row(maps, title=""):
    """Panels: 2-D maps over two state variables (an env helper makes them): maps[when] for
    when in "untrained", "trained" holds "value" and "policy" (x: columns, y: rows); "true",
    if there, the true value beside the learned one on its colour scale; "visited", states
    marked on the value maps; "x", "y", "xlabel", "ylabel", "value_label", "policy_label"
    describe them."""
    panels = [(k, w) for k in ("value", "policy") for w in ("untrained", "trained", "true")
              if w in maps and not (k == "policy" and w == "true")]

    def fill(axes, logs):
        shared = [maps[w]["value"] for w in ("trained", "true") if w in maps]
        vmin, vmax = min(m.min() for m in shared), max(m.max() for m in shared)
        extent = [maps["x"][0], maps["x"][-1], maps["y"][0], maps["y"][-1]]
        for ax, (key, when) in zip(axes, panels):
            scale = dict(vmin=0, vmax=1) if key == "policy" else (
                dict(vmin=vmin, vmax=vmax) if when in ("trained", "true") and "true" in maps
                else {})
            image = ax.imshow(maps[when][key], origin="lower", aspect="auto", extent=extent,
                              cmap="viridis" if key == "value" else "coolwarm", **scale)
            ax.figure.colorbar(image, ax=ax, fraction=0.046)
            what = maps.get(f"{key}_label", "V(s)" if key == "value" else "policy")
            name = "true V^pi(s), Monte-Carlo" if when == "true" else f"{what}, {when}"
            visited = maps.get("visited")
            dots = (key == "value" and when in ("trained", "true") and visited is not None
                    and len(visited) > 0)
            ax.set_title(f"{title + ': ' if title else ''}{name}" + (f"\n{DOTS}" if dots else ""),
                         fontsize=8)
            if dots:  # at most DOTS_DRAWN, evenly through them, small and faint: the map
                shown = visited[::-(-len(visited) // DOTS_DRAWN)]  # shows through the cloud
                ax.plot(shown[:, 0], shown[:, 1], ".", ms=2, mew=0, color="white", alpha=0.4)
                ax.set_xlim(extent[:2])
                ax.set_ylim(extent[2:])
            ax.set_xlabel(maps.get("xlabel", ""), fontsize=8)
            ax.set_ylabel(maps.get("ylabel", ""), fontsize=8)
    fill.right_axis = True  # each map's colour bar and its ticks: room before the next map
    return len(panels), fill


# The columns every run of a kind writes (runlog's) -> TensorBoard tag, CleanRL's names; a
# script's own columns take the tags it declares (charts/<column> if none).
TAGS = {"return": "charts/episodic_return", "recent_return": "charts/recent_return",
        "sps": "charts/SPS", "eval_mean": "eval/episodic_return",
        "eval_std": "eval/episodic_return_std",
        "train_return_mean10": "charts/episodic_return_mean10"}
NO_TENSORBOARD = "--tensorboard needs the tensorboard package: pip install tensorboard"


def tensorboard_installed():
    return importlib.util.find_spec("tensorboard") is not None


def to_tensorboard(run_dir, sps=None, tags=None):
    """(Re)write run_dir's TensorBoard events from its CSV logs, and `sps` (steps/s so far,
    kept out of the CSVs, which are reproducible); `tags`: {column: tag} of the script's."""
    from torch.utils.tensorboard import SummaryWriter

    run_dir = Path(run_dir)
    for old in run_dir.glob("events.out.tfevents.*"):
        old.unlink()
    with SummaryWriter(log_dir=str(run_dir)) as writer:
        for name in ("episodes.csv", "progress.csv", "evaluations.csv"):
            if not (run_dir / name).exists():
                continue
            table = read_csv(run_dir / name)
            for i, step in enumerate(table["global_step"]):
                for key, values in table.items():
                    if (key not in ("global_step", "episodes") and values.dtype.kind == "f"
                            and np.isfinite(values[i])):  # text (a stage's name): no scalar
                        tag = {**TAGS, **(tags or {})}.get(key, f"charts/{key}")
                        writer.add_scalar(tag, values[i], int(step))
        if sps is not None:
            writer.add_scalar("charts/SPS", sps, int(step))


EVAL_RETURN = "evaluation return (mean of its episodes, no exploration noise)"
RECENT = "mean return of the recent training episodes (the solved rule's window)"


def curve_of(run_dir):
    """(steps, values, what the values are) of one run, points without a value dropped: the
    evaluation means of a run that evaluates, or the recent_return after each update; a run
    that logs neither (a language model's, whose checks come last): its last column of numbers
    in progress.csv."""
    if (run_dir / "evaluations.csv").exists():
        table, column, what = read_csv(run_dir / "evaluations.csv"), "eval_mean", EVAL_RETURN
    else:
        table, what = read_csv(run_dir / "progress.csv"), RECENT
        column = "recent_return" if "recent_return" in table else "return_mean20"  # older runs
        numbers = [c for c, v in table.items() if c != "global_step" and v.dtype.kind == "f"
                   and np.isfinite(v).any()]
        if column not in table and numbers:
            column = numbers[-1]
            what = f"{column} (no return logged: the last column of progress.csv)"
    steps, values = table.get("global_step", np.array([])), table.get(column, np.array([]))
    ok = np.isfinite(values)  # nan before the first finished episode
    return steps[ok], values[ok], what


def distinct(run_dirs):
    """`run_dirs` as paths, each folder once: a link (runs/latest) is read as the folder it
    names, so that `plots.py runs/*` draws the newest run once, under its own name."""
    found = {}  # the folder -> the path it is shown by (the one given, unless a link)
    for path in map(Path, run_dirs):
        if not path.is_symlink():
            found[path.resolve()] = path
        else:
            found.setdefault(path.resolve(), path.resolve())
    return list(found.values())


def compare_figure(run_dirs):
    """The figure of compare(): a panel per env and measure; per script, each run a thin line
    that ends where the run stopped, and their mean (thick) where every one has a value."""
    panels = {}  # (env, what) -> {script: [(steps, values), ...]}
    for run_dir in distinct(run_dirs):
        if not ((run_dir / "progress.csv").exists() or (run_dir / "evaluations.csv").exists()):
            print(f"note: {run_dir} is not a run folder (no progress.csv or evaluations.csv); "
                  "left out", file=sys.stderr)
            continue
        parts = run_dir.name.split("__")  # <script>__<env>__seed<k>__<time>
        steps, values, what = curve_of(run_dir)
        if not len(steps):  # no episode ended yet, or no row measured anything
            print(f"note: {run_dir} holds nothing to compare yet (no recent_return, eval_mean "
                  "or other measure with a value); left out", file=sys.stderr)
            continue
        env = parts[1] if len(parts) > 1 else "env unknown"
        panels.setdefault((env, what), {}).setdefault(parts[0], []).append((steps, values))
    if not panels:
        print("error: none of these folders is a run with something to draw", file=sys.stderr)
        sys.exit(2)
    plt = pyplot()
    fig, axes = plt.subplots(max(len(panels), 1), 1, figsize=(7, 1 + 3.5 * max(len(panels), 1)),
                             squeeze=False)
    for ax, ((env, what), scripts) in zip(axes[:, 0], panels.items()):
        for color, (script, curves) in enumerate(scripts.items()):
            alone = len(curves) == 1
            for steps, values in curves:  # each run's line ends where the run stopped
                ax.plot(steps, values, color=f"C{color}", lw=2 if alone else 0.8,
                        alpha=1 if alone else 0.4)
            label = f"{script}: {len(curves)} run{'s' if len(curves) > 1 else ''}"
            lo, hi = max(s[0] for s, _ in curves), min(s[-1] for s, _ in curves)
            if len(curves) > 1 and lo < hi:  # the mean where every run has a value: no stretch
                grid = np.linspace(lo, hi, 200)
                mean = np.mean([np.interp(grid, s, v) for s, v in curves], axis=0)
                ax.plot(grid, mean, color=f"C{color}", lw=2)
                label = f"{script}: {len(curves)} runs (thin), their mean while all ran"
            ax.plot([], [], color=f"C{color}", lw=2, label=label)
        ax.set_title(env, fontsize=10)
        ax.set_xlabel("env steps")
        ax.set_ylabel(textwrap.fill(what, WRAP), fontsize=8)
        ax.legend(fontsize=7, loc="lower right")
    fig.tight_layout()
    return fig


def compare(run_dirs, out):
    """Write compare.png (see compare_figure) to `out`; returns `out`."""
    return save_whole(pyplot(), compare_figure(run_dirs), out, dpi=90)


def compare_maps(run_dirs, out):
    """Write `out`: the trained maps of value and policy of runs that keep a maps.npz (an env
    helper's maps_row), a row each."""
    plt, found = pyplot(), []
    for run_dir in distinct(run_dirs):
        if not (run_dir / "maps.npz").exists():  # e.g. --no-curves, or a run without maps
            print(f"note: {run_dir} has no maps.npz (a run whose env has maps writes one when "
                  "it finishes training with its pictures); left out", file=sys.stderr)
            continue
        m = dict(np.load(run_dir / "maps.npz"))
        found.append((run_dir.name.split("__")[0], dict(
            trained=dict(value=m["trained_value"], policy=m["trained_policy"]),
            **{k: (m[k].item() if m[k].ndim == 0 else m[k])
               for k in ("x", "y", "xlabel", "ylabel", "value_label", "policy_label")
               if k in m})))  # an older maps.npz has no value_label
    if not found:
        print("error: none of these runs has a maps.npz", file=sys.stderr)
        sys.exit(2)
    fig = plt.figure(figsize=(8, 3 * len(found)))
    grid = fig.add_gridspec(len(found), 1, hspace=0.5)
    for row, (script, maps) in enumerate(found):
        n, fill = maps_row(maps, title=script)
        sub = grid[row, 0].subgridspec(1, n, wspace=0.75)
        fill([fig.add_subplot(sub[0, i]) for i in range(n)], {})
    return save_whole(plt, fig, out, dpi=72)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("runs", nargs="+", help="run folders, e.g. runs/* or runs/<script>__*")
    parser.add_argument("--out", default=None,
                        help="the PNG to write (default: compare.png, or maps.png with --maps)")
    parser.add_argument("--maps", action="store_true",
                        help="the runs' trained maps of V and pi side by side (runs that keep "
                             "maps.npz)")
    args = parser.parse_args(argv)
    out = args.out or ("maps.png" if args.maps else "compare.png")
    try:
        print(f"wrote {(compare_maps if args.maps else compare)(args.runs, out)}")
    except OSError as e:
        print(f"error: cannot write {out}: {e.strerror}", file=sys.stderr)
        sys.exit(2)


if __name__ == "__main__":
    main()
