"""The pictures: each run's curve.png and inside.png, several runs compared, TensorBoard.

From the command line, compare runs: a panel per env, a colour per script, each run a thin
line that ends where the run stopped, their mean (thick) where all of them ran.

    python plots.py runs/ppo_cartpole__* runs/actor_critic_cartpole__*   # -> compare.png
    python plots.py runs/ddpg_walker__* --out walker.png
    python plots.py --maps runs/ppo_cartpole__* runs/actor_critic_cartpole__*   # -> maps.png

matplotlib is imported only here, with its Agg backend (no display needed); labels are
ASCII (not every machine has CJK fonts). to_tensorboard writes the CSV logs as TensorBoard
scalars under CleanRL's tag names, so that our runs and CleanRL's overlay.
"""

import argparse
import csv
import importlib.util
import sys
import textwrap
from pathlib import Path

import numpy as np


def read_csv(path):
    """A CSV file as {column: float array}; empty cells are nan."""
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    columns = rows[0].keys() if rows else []
    return {k: np.array([float(r[k]) if r[k] not in ("", None) else np.nan for r in rows])
            for k in columns}


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


def draw_run(run_dir, solved_return=None, solved_step=None, window=20):
    """Write run_dir/curve.png from the run's CSV logs; returns its path."""
    run_dir = Path(run_dir)
    plt = pyplot()
    if (run_dir / "evaluations.csv").exists():  # DDPG
        fig = draw_ddpg(plt, read_csv(run_dir / "evaluations.csv"))
    else:
        episodes = run_dir / "episodes.csv"  # absent when no episode has finished yet
        fig = draw_cartpole(plt, read_csv(episodes) if episodes.exists() else {},
                            read_csv(run_dir / "progress.csv"), solved_return, solved_step, window)
    fig.axes[0].set_title(run_dir.name, fontsize=8)
    fig.tight_layout()
    return save_whole(plt, fig, run_dir / "curve.png", dpi=90)


def save_whole(plt, fig, path, dpi):
    """Save `fig` as `path`, written whole (aside, then renamed), Ctrl-C or not; close it."""
    tmp = Path(f"{path}.tmp.png")
    try:
        fig.savefig(tmp, dpi=dpi, bbox_inches="tight")  # nothing cut at the edges
        tmp.replace(path)
    finally:
        plt.close(fig)
        tmp.unlink(missing_ok=True)
    return path


def draw_cartpole(plt, episodes, progress, solved_return, solved_step, window):
    """Episode returns (faint), their mean over `window` episodes; below, the diagnostics."""
    fig, (ax, ax2) = plt.subplots(2, 1, figsize=(7, 5.5), sharex=True,
                                  gridspec_kw=dict(height_ratios=[3, 1.4]))
    steps, returns = episodes.get("global_step", []), episodes.get("return", [])
    ax.plot(steps, returns, color="C0", alpha=0.3, lw=0.8, label="episode return")
    ax.plot(steps, running_mean(np.asarray(returns), window), color="C0", lw=2,
            label=f"mean of the last {window} episodes")
    if solved_return is not None:
        ax.axhline(solved_return, color="gray", ls="--", lw=1, label=f"solved: {solved_return:g}")
    if solved_step is not None:
        ax.axvline(solved_step, color="C2", ls=":", lw=1.5, label=f"solved at step {solved_step}")
    ax.set_ylabel("return")
    ax.legend(loc="upper left", fontsize=8)
    # The diagnostics: entropy of pi (left axis); how far each update moved pi (right axis).
    if "entropy" in progress:
        ax2.plot(progress["global_step"], progress["entropy"], color="C1", label="entropy")
        ax2.set_ylabel("entropy (nats)", color="C1")
    moved = [k for k in ("approx_kl", "kl", "beta") if k in progress]
    if moved:
        right = ax2.twinx()
        for key, color in zip(moved, ("C3", "C4")):
            right.plot(progress["global_step"], progress[key], color=color, lw=1, label=key)
        right.set_yscale("log")
        right.legend(loc="upper right", fontsize=8)
    ax2.set_xlabel("env steps")
    fig.tight_layout()
    return fig


def draw_ddpg(plt, evaluations):
    """Evaluation returns (mean +- std over the evaluation episodes) and the training return."""
    fig, ax = plt.subplots(figsize=(7, 4.5))
    x, mean, std = evaluations["global_step"], evaluations["eval_mean"], evaluations["eval_std"]
    ax.plot(x, mean, color="C0", lw=2, label="evaluation: mean return, no noise")
    ax.fill_between(x, mean - std, mean + std, color="C0", alpha=0.2, label="+- std")
    ax.plot(x, evaluations["train_return_mean10"], color="C1", lw=1,
            label="training: mean of the last 10 episodes")
    ax.set(xlabel="env steps", ylabel="return")
    ax.legend(loc="upper left", fontsize=8)
    fig.tight_layout()
    return fig


# ==== inside.png: what the updates do ====================================================


def draw_inside(run_dir, script, cfg, kept=None, maps=None):
    """Write run_dir/inside.png (docs/inside.md); returns its path. `kept`: (env step, {name:
    array}) per update (PPO-clip: ratios and advantages; A2C: V and its targets); `maps`:
    CartPole's maps (report.draw_inside)."""
    run_dir, plt = Path(run_dir), pyplot()
    evaluations = (read_csv(run_dir / "evaluations.csv")
                   if (run_dir / "evaluations.csv").exists() else None)  # DDPG, TD3, SAC
    entropy = evaluations is not None and "alpha" in evaluations  # SAC's temperature
    rows = 1 + (script == "ppo_cartpole") + (maps is not None) + entropy
    height = 3.3 * rows  # inches; margins of half an inch above and below
    fig = plt.figure(figsize=(12, height))
    grid = fig.add_gridspec(rows, 4, hspace=0.55, wspace=0.45, left=0.06, right=0.97,
                            top=1 - 0.5 / height, bottom=0.55 / height)
    if evaluations is not None:
        overestimation(fig.add_subplot(grid[0, :]), evaluations)
        if entropy:
            entropy_panels(fig, grid, evaluations)
    else:
        progress = read_csv(run_dir / "progress.csv")
        if script == "ppo_cartpole":
            ratio_panels(fig, grid, progress, kept, cfg["clip_coef"])
        elif script == "ppo_kl_cartpole":
            beta_panels(fig, grid, progress, cfg)
        else:
            value_fit_panels(fig, grid, progress, kept)
        if maps is not None:
            map_panels(fig, grid[rows - 1, :], maps)
    fig.suptitle(run_dir.name, fontsize=8, y=1 - 0.1 / height)
    return save_whole(plt, fig, run_dir / "inside.png", dpi=72)


def three_updates(kept):
    """An early, a middle and a late update of `kept` (its first, middle and last)."""
    picks = sorted({0, len(kept) // 2, len(kept) - 1})
    return [(i + 1, *kept[i]) for i in picks]


def ratio_panels(fig, grid, progress, kept, eps):
    """PPO-clip: the ratio r over updates, with the band [1 - eps, 1 + eps]; the share of
    samples without gradient beside clipfrac; histograms of r at three updates, by sign of A."""
    ax = fig.add_subplot(grid[0, :2])
    x = progress["global_step"]
    ax.fill_between(x, progress["ratio_min"], progress["ratio_max"], color="C0", alpha=0.15,
                    label="min to max")
    ax.fill_between(x, progress["ratio_q05"], progress["ratio_q95"], color="C0", alpha=0.3,
                    label="5% to 95%")
    ax.plot(x, progress["ratio_median"], color="C0", lw=1, label="median")
    for y in (1 - eps, 1 + eps):
        ax.axhline(y, color="k", ls="--", lw=0.8)
    ax.set_title(f"r = pi/pi_old after each update; dashed: 1 -+ eps = {eps:g}", fontsize=9)
    ax.set_xlabel("env steps")
    ax.legend(fontsize=7, loc="upper right")
    ax = fig.add_subplot(grid[0, 2:])
    ax.plot(x, progress["clipfrac"], color="C3", lw=0.8, ls=":",
            label="clipfrac: |r - 1| > eps, during the update")
    if "clipfrac_after" in progress:  # the same ratios as zero_grad_frac: after the update
        ax.plot(x, progress["clipfrac_after"], color="C3", lw=1,
                label="clipfrac after the update")
    ax.plot(x, progress["zero_grad_frac"], color="C2", lw=1,
            label="no policy gradient after it (clip binds on A's side)")
    ax.set_title("share of the batch", fontsize=9)
    ax.set_xlabel("env steps")
    ax.legend(fontsize=7)
    for column, (update, step, arrays) in enumerate(three_updates(kept or [])):
        ax = fig.add_subplot(grid[1, column])
        r, adv = arrays["ratio"], arrays["adv"]
        bins = np.linspace(min(r.min(), 1 - 2 * eps), max(r.max(), 1 + 2 * eps), 40)
        for sign, color, label in ((1, "C2", "A > 0"), (-1, "C3", "A < 0")):  # one polygon each
            ax.hist(r[np.sign(adv) == sign], bins=bins, color=color, alpha=0.6, label=label,
                    histtype="stepfilled")
        ax.axvspan(1 + eps, bins[-1], color="C2", alpha=0.08)  # A > 0 here: no gradient
        ax.axvspan(bins[0], 1 - eps, color="C3", alpha=0.08)  # A < 0 here: no gradient
        for v in (1 - eps, 1 + eps):
            ax.axvline(v, color="k", ls="--", lw=0.8)
        ax.set_title(f"update {update} (step {step})", fontsize=8)
        ax.set_xlabel("r; shaded: no gradient for that colour", fontsize=7)
        if column == 0:
            ax.legend(fontsize=7)


def beta_panels(fig, grid, progress, cfg):
    """PPO-penalty: the KL against [d_targ / 1.5, 1.5 d_targ]; beta, its changes marked."""
    x, kl, beta = progress["global_step"], progress["kl"], progress["beta"]
    lo, hi = cfg["d_targ"] / cfg["kl_tolerance"], cfg["d_targ"] * cfg["kl_tolerance"]
    ax = fig.add_subplot(grid[0, :2])
    ax.axhspan(lo, hi, color="C2", alpha=0.2, label="beta stays")
    ax.plot(x, kl, color="C4", lw=1, label="KL(pi_old || pi) after the update")
    ax.set_yscale("log")
    ax.set_title(f"KL against [d_targ / {cfg['kl_tolerance']:g}, d_targ x "
                 f"{cfg['kl_tolerance']:g}], d_targ = {cfg['d_targ']:g}", fontsize=9)
    ax.set_xlabel("env steps")
    ax.legend(fontsize=7)
    ax = fig.add_subplot(grid[0, 2:])
    ax.plot(x, beta, color="C1", lw=1, drawstyle="steps-post")
    nxt = np.append(beta[1:], np.nan)  # the beta the next update uses
    for changed, marker, what in ((nxt > beta, "^", "doubled (KL too high)"),
                                  (nxt < beta, "v", "halved (KL too low)")):
        ax.scatter(x[changed], beta[changed], marker=marker, s=18, label=what)
    ax.set_yscale("log")
    ax.set_title("beta, the penalty's weight", fontsize=9)
    ax.set_xlabel("env steps")
    ax.legend(fontsize=7)


def value_fit_panels(fig, grid, progress, kept):
    """A2C: the share of its targets' variance V explains; V(s_t) against R_t at 3 updates."""
    ax = fig.add_subplot(grid[0, 0])
    ax.plot(progress["global_step"], progress["explained_var"], color="C0", lw=1)
    ax.set_ylim(-1, 1.05)
    ax.set_title("1 - Var(R - V) / Var(R)", fontsize=9)
    ax.set_xlabel("env steps")
    for column, (update, step, arrays) in enumerate(three_updates(kept or []), start=1):
        ax = fig.add_subplot(grid[0, column])
        ax.scatter(arrays["ret"], arrays["values"], s=3, alpha=0.4)
        lims = [min(arrays["ret"].min(), arrays["values"].min()),
                max(arrays["ret"].max(), arrays["values"].max())]
        ax.plot(lims, lims, color="k", lw=0.8)
        ax.set_title(f"update {update} (step {step})", fontsize=8)
        ax.set_xlabel("target R_t", fontsize=8)
        ax.set_ylabel("V(s_t)", fontsize=8)


def map_panels(fig, cell, maps, title=""):
    """V(s) and pi(right|s) over pole angle and angular velocity of maps "untrained" and
    "trained" in grid cell `cell`; the true V^pi (maps["true"]) beside V on its colour scale,
    the visited states (maps["visited"]) marked on both."""
    panels = [(k, w) for k in ("value", "right") for w in ("untrained", "trained", "true")
              if w in maps and not (k == "right" and w == "true")]
    sub = cell.subgridspec(1, len(panels), wspace=0.75)
    shared = [maps[w]["value"] for w in ("trained", "true") if w in maps]
    vmin, vmax = min(m.min() for m in shared), max(m.max() for m in shared)
    for column, (key, when) in enumerate(panels):
        ax, m = fig.add_subplot(sub[0, column]), maps[when]
        extent = [m["angle"][0], m["angle"][-1], m["velocity"][0], m["velocity"][-1]]
        scale = dict(vmin=0, vmax=1) if key == "right" else (
            dict(vmin=vmin, vmax=vmax) if when in ("trained", "true") and "true" in maps else {})
        image = ax.imshow(m[key], origin="lower", aspect="auto", extent=extent,
                          cmap="viridis" if key == "value" else "coolwarm", **scale)
        fig.colorbar(image, ax=ax, fraction=0.046)
        what = "V(s)" if key == "value" else "pi(right | s)"
        name = "true V^pi(s), Monte-Carlo" if when == "true" else f"{what}, {when}"
        ax.set_title(f"{title + ': ' if title else ''}{name}", fontsize=8)
        visited = maps.get("visited")
        if key == "value" and when in ("trained", "true") and visited is not None:
            ax.plot(visited[:, 0], visited[:, 1], ",", color="white", alpha=0.5)
            ax.set_xlim(extent[:2])
            ax.set_ylim(extent[2:])
        ax.set_xlabel("pole angle (rad)", fontsize=7)
        ax.set_ylabel("angular velocity", fontsize=7)


def overestimation(ax, evaluations):
    """DDPG and TD3, after the TD3 paper's Fig. 1: the critic's Q(s, mu(s)) against the
    discounted return mu obtained from the same states (the evaluations'), per evaluation."""
    x = evaluations["global_step"]
    ax.plot(x, evaluations["q_estimate"], color="C3", lw=1.5, label="critic: Q(s, mu(s))")
    ax.plot(x, evaluations["discounted_return"], color="C0", lw=1.5,
            label="what mu obtained: sum of gamma^k r from s")
    ax.set_title("at each evaluation: the critic's estimate against the discounted return "
                 "really obtained, over the same states", fontsize=9)
    ax.set_xlabel("env steps")
    ax.legend(fontsize=8)


def entropy_panels(fig, grid, evaluations):
    """SAC: the policy's entropy (-log pi at the last update's minibatch) against the target
    the temperature steers it to, and alpha, at each evaluation."""
    x = evaluations["global_step"]
    ax = fig.add_subplot(grid[1, :2])
    ax.plot(x, evaluations["entropy"], color="C2", lw=1.5, label="entropy: -mean log pi(a|s)")
    ax.plot(x, evaluations["target_entropy"], color="k", ls="--", lw=0.8, label="its target")
    ax.set_title("the policy's entropy (a minibatch's estimate) against its target", fontsize=9)
    ax.set_xlabel("env steps")
    ax.legend(fontsize=8)
    ax = fig.add_subplot(grid[1, 2:])
    ax.plot(x, evaluations["alpha"], color="C1", lw=1.5)
    ax.set_yscale("log")
    ax.set_title("alpha, the entropy's weight", fontsize=9)
    ax.set_xlabel("env steps")


# CSV column -> TensorBoard tag (CleanRL's names where CleanRL logs the same thing).
TAGS = {"return": "charts/episodic_return", "recent_return": "charts/recent_return",
        "lr": "charts/learning_rate", "sps": "charts/SPS", "loss_pi": "losses/policy_loss",
        "loss_v": "losses/value_loss", "entropy": "losses/entropy", "approx_kl": "losses/approx_kl",
        "clipfrac": "losses/clipfrac", "kl": "losses/kl", "beta": "charts/beta",
        "eval_mean": "eval/episodic_return", "eval_std": "eval/episodic_return_std",
        "train_return_mean10": "charts/episodic_return_mean10"}
NO_TENSORBOARD = "--tensorboard needs the tensorboard package: pip install tensorboard"


def tensorboard_installed():
    return importlib.util.find_spec("tensorboard") is not None


def to_tensorboard(run_dir, sps=None):
    """(Re)write run_dir's TensorBoard events from its CSV logs, and `sps` (steps/s so far,
    kept out of the CSVs, which are reproducible)."""
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
                    if key not in ("global_step", "episodes") and np.isfinite(values[i]):
                        writer.add_scalar(TAGS.get(key, f"charts/{key}"), values[i], int(step))
        if sps is not None:
            writer.add_scalar("charts/SPS", sps, int(step))


EVAL_RETURN = "evaluation return (mean of its episodes, no exploration noise)"
RECENT = "mean return of the recent training episodes (the solved rule's window)"


def curve_of(run_dir):
    """(steps, values, what the values are) of one run, points without a value dropped:
    DDPG's evaluation means, or the CartPole scripts' recent_return after each update."""
    if (run_dir / "evaluations.csv").exists():
        table, column, what = read_csv(run_dir / "evaluations.csv"), "eval_mean", EVAL_RETURN
    else:
        table, what = read_csv(run_dir / "progress.csv"), RECENT
        column = "recent_return" if "recent_return" in table else "return_mean20"  # older runs
    steps, values = table.get("global_step", np.array([])), table.get(column, np.array([]))
    ok = np.isfinite(values)  # nan before the first finished episode
    return steps[ok], values[ok], what


def compare_figure(run_dirs):
    """The figure of compare(): a panel per env and measure; per script, each run a thin line
    that ends where the run stopped, and their mean (thick) where every one has a value."""
    panels = {}  # (env, what) -> {script: [(steps, values), ...]}
    for run_dir in map(Path, run_dirs):
        if not ((run_dir / "progress.csv").exists() or (run_dir / "evaluations.csv").exists()):
            print(f"error: {run_dir} is not a run folder (no progress.csv or evaluations.csv)",
                  file=sys.stderr)
            sys.exit(2)
        parts = run_dir.name.split("__")  # <script>__<env>__seed<k>__<time>
        steps, values, what = curve_of(run_dir)
        if not len(steps):
            print(f"note: {run_dir} has nothing to draw yet; left out", file=sys.stderr)
            continue
        env = parts[1] if len(parts) > 1 else "env unknown"
        panels.setdefault((env, what), {}).setdefault(parts[0], []).append((steps, values))
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
        ax.set_ylabel(textwrap.fill(what, 34), fontsize=8)
        ax.legend(fontsize=7, loc="lower right")
    fig.tight_layout()
    return fig


def compare(run_dirs, out):
    """Write compare.png (see compare_figure) to `out`; returns `out`."""
    return save_whole(pyplot(), compare_figure(run_dirs), out, dpi=90)


def compare_maps(run_dirs, out):
    """Write `out`: the trained V(s) and pi(right|s) of CartPole runs (maps.npz), a row each."""
    plt, found = pyplot(), []
    for run_dir in map(Path, run_dirs):
        if not (run_dir / "maps.npz").exists():  # e.g. --no-curves, or a DDPG run: skipped
            print(f"note: {run_dir} has no maps.npz (a CartPole run that finished training "
                  "with its pictures writes one); left out", file=sys.stderr)
            continue
        found.append((run_dir.name.split("__")[0], dict(np.load(run_dir / "maps.npz"))))
    if not found:
        print("error: none of these runs has a maps.npz", file=sys.stderr)
        sys.exit(2)
    fig = plt.figure(figsize=(8, 3 * len(found)))
    grid = fig.add_gridspec(len(found), 1, hspace=0.5)
    for row, (script, m) in enumerate(found):
        map_panels(fig, grid[row, 0], {"trained": dict(
            angle=m["angle"], velocity=m["velocity"], value=m["trained_value"],
            right=m["trained_right"])}, title=script)
    return save_whole(plt, fig, out, dpi=72)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("runs", nargs="+", help="run folders, e.g. runs/ppo_cartpole__*")
    parser.add_argument("--out", default=None,
                        help="the PNG to write (default: compare.png, or maps.png with --maps)")
    parser.add_argument("--maps", action="store_true",
                        help="the runs' trained V(s) and pi(right|s) side by side (CartPole)")
    args = parser.parse_args(argv)
    out = args.out or ("maps.png" if args.maps else "compare.png")
    try:
        print(f"wrote {(compare_maps if args.maps else compare)(args.runs, out)}")
    except OSError as e:
        print(f"error: cannot write {out}: {e.strerror}", file=sys.stderr)
        sys.exit(2)


if __name__ == "__main__":
    main()
