"""The pictures and logs a user looks at: curve.png, TensorBoard scalars, runs compared."""

import importlib
import subprocess
import sys

import imageio.v3 as iio
import numpy as np
import pytest
import torch

import cartpole_env
import ppo_cartpole as ppo
from conftest import ROOT, run_main
from fingerprints import SCRIPTS, quick_smoke
from test_cartpole_scripts import assert_curve_drawn


def quick_run(tmp_path, seed, **kw):
    return ppo.train(ppo.Config(**{**dict(seed=seed, total_timesteps=1024, stop_when_solved=False,
                                          gifs=False, eval_episodes=1, run_dir=str(tmp_path),
                                          print_every=10**6), **kw}))


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


def test_compare_overlays_three_runs_into_one_png(tmp_path, capsys):
    runs = [quick_run(tmp_path / "runs", seed, curves=False)["run_dir"] for seed in range(3)]
    out = tmp_path / "compare.png"
    p = run_main("plots.py", *runs, "--out", out, capsys=capsys)
    assert p.returncode == 0, p.stderr
    assert_curve_drawn(out)
    assert [f.name for f in tmp_path.iterdir() if f.suffix == ".png"] == ["compare.png"]


def test_compare_leaves_out_a_folder_that_is_not_a_run(tmp_path, capsys):
    """`python plots.py runs/*` once an experiment has run: runs/experiments is left out with a
    note, the runs are drawn; with no run at all, one line and exit 2."""
    p = run_main("plots.py", tmp_path, capsys=capsys)
    assert p.returncode == 2 and "is not a run folder" in p.stderr and "Traceback" not in p.stderr
    assert "none of these folders is a run" in p.stderr
    run = quick_run(tmp_path / "runs", seed=0)["run_dir"]
    (tmp_path / "runs" / "experiments").mkdir()
    p = run_main("plots.py", *sorted((tmp_path / "runs").iterdir()), "--out", tmp_path / "c.png",
                 capsys=capsys)
    assert p.returncode == 0 and "experiments is not a run folder" in p.stderr, p.stderr
    assert_curve_drawn(tmp_path / "c.png") and run.exists()


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


def fake_ddpg_run(root, env_id, last_step):
    """A run folder of ddpg_walker.py as plots.py reads it: evaluations.csv every 5000 steps."""
    run = root / f"ddpg_walker__{env_id}__seed0__20260101-000000"
    run.mkdir(parents=True)
    rows = ["global_step,eval_mean,eval_std,episodes,train_return_mean10"]
    rows += [f"{s},{s / 100},1.0,{s // 1000},{s / 200}" for s in range(5000, last_step + 1, 5000)]
    (run / "evaluations.csv").write_text("\n".join(rows) + "\n")
    return run


def test_compare_draws_one_panel_per_env_and_no_run_past_its_end(tmp_path, capsys):
    """`plots.py runs/*` with CartPole runs of two lengths and a Walker2d run: a panel per
    env, each labelled with what it plots; no line goes on past the end of the runs it
    is drawn from (a run that stopped is not stretched to the longest)."""
    import plots

    short, long = (quick_run(tmp_path, seed, total_timesteps=steps, curves=False)["run_dir"]
                   for seed, steps in ((0, 1024), (1, 3072)))
    walker = fake_ddpg_run(tmp_path, "Walker2d-v5", 60_000)
    fig = plots.compare_figure([short, long, walker])
    panels = {ax.get_title(): ax for ax in fig.axes}
    assert set(panels) == {"CartPole-v1", "Walker2d-v5"}
    assert "mean return of the recent training episodes" in \
        " ".join(panels["CartPole-v1"].get_ylabel().split())
    assert "evaluation return" in " ".join(panels["Walker2d-v5"].get_ylabel().split())
    curves = {run: plots.read_csv(run / "progress.csv") for run in (short, long)}
    short_end = curves[short]["global_step"][-1]
    drawn = [(line.get_xdata(), line.get_ydata()) for line in panels["CartPole-v1"].lines
             if len(line.get_xdata())]
    assert len(drawn) == 3  # each run, and their mean
    for x, y in drawn:
        assert x.max() <= curves[long]["global_step"][-1]
        if x.max() > short_end:  # only the long run itself goes on past the short run's end
            assert list(x) == list(curves[long]["global_step"])
            assert list(y) == list(curves[long]["recent_return"])
    walker_x = [line.get_xdata() for line in panels["Walker2d-v5"].lines if len(line.get_xdata())]
    assert [x.max() for x in walker_x] == [60_000]
    p = run_main("plots.py", short, long, walker, "--out", tmp_path / "compare.png", capsys=capsys)
    assert p.returncode == 0, p.stderr
    assert_curve_drawn(tmp_path / "compare.png")


def test_ctrl_c_while_curve_png_is_written_keeps_the_old_one_and_no_tmp(tmp_path, monkeypatch):
    import plots
    from matplotlib.figure import Figure

    run = quick_run(tmp_path, seed=0)["run_dir"]
    before = (run / "curve.png").read_bytes()

    def interrupted_savefig(self, fname, **kw):
        open(fname, "wb").write(b"half a png")  # the write has begun...
        raise KeyboardInterrupt  # ...when Ctrl-C lands
    monkeypatch.setattr(Figure, "savefig", interrupted_savefig)
    with pytest.raises(KeyboardInterrupt):
        plots.draw(run, "curve.png", [[plots.episode_returns(20)]], plots.load_logs(run))
    assert (run / "curve.png").read_bytes() == before
    assert not list(run.glob("*.tmp*"))



def test_maps_of_several_runs_side_by_side(tmp_path, capsys):
    """Each CartPole run keeps its maps in maps.npz; --maps draws the trained ones, a row per
    run, and refuses a folder without them in one line."""
    import importlib

    runs = []
    for name in ("ppo_cartpole", "actor_critic_cartpole"):
        module = importlib.import_module(name)
        runs.append(module.train(module.Config(
            run_dir=str(tmp_path / name), total_timesteps=1024, stop_when_solved=False,
            gifs=False, eval_episodes=1, print_every=10**6))["run_dir"])
        maps = np.load(runs[-1] / "maps.npz")
        assert maps["trained_value"].shape == maps["untrained_policy"].shape == (41, 41)
    out = tmp_path / "maps.png"
    p = run_main("plots.py", "--maps", *runs, "--out", out, capsys=capsys)
    assert p.returncode == 0, p.stderr
    assert_curve_drawn(out)
    bad = run_main("plots.py", "--maps", tmp_path, capsys=capsys)
    assert bad.returncode == 2 and "none of these runs has a maps.npz" in bad.stderr
    skipped = run_main("plots.py", "--maps", *runs, tmp_path, "--out", out,  # one without
                       capsys=capsys)
    assert skipped.returncode == 0 and f"{tmp_path} has no maps.npz" in skipped.stderr


class Lean(torch.nn.Module):
    """A deterministic policy: push toward the side the pole falls to (angle + velocity / 4),
    so that a Monte-Carlo value equals one brute-force rollout exactly."""

    def forward(self, obs):
        lean = obs[..., 2] + obs[..., 3] / 4
        return torch.stack([-1e4 * lean, 1e4 * lean], -1)  # logits: pi is 0 or 1


def brute_force_value(angle, velocity, gamma, scale):
    """One rollout of Lean from (0, 0, angle, velocity) in gymnasium's own CartPole, the
    discounted scaled rewards summed until it terminates or gamma^t < 0.001."""
    import gymnasium as gym

    env = gym.make("CartPole-v1").unwrapped
    env.reset(seed=0)
    env.state = np.array([0.0, 0.0, angle, velocity])
    total, discount, obs = 0.0, 1.0, env.state.astype(np.float32)
    while discount >= 1e-3:
        with torch.no_grad():
            action = int(Lean()(torch.as_tensor(obs)).argmax())
        obs, reward, terminated, _, _ = env.step(action)
        total += discount * scale * reward
        discount *= gamma
        if terminated:
            break
    return total


def test_true_value_map_is_the_brute_force_rollout_at_each_state():
    """cartpole_env.cartpole_true_values against a hand-written rollout in the single env, at
    the grid's corners (one step from failure) and its centre (balanced to the horizon)."""

    true = cartpole_env.cartpole_true_values(Lean(), "cpu", 0.99, 0.05, seed=0, n=3, rollouts=2)
    assert true["angle"].tolist() == [-0.21, 0.0, 0.21]
    for i, velocity in enumerate(true["velocity"]):
        for j, angle in enumerate(true["angle"]):
            expected = brute_force_value(angle, velocity, 0.99, 0.05)
            assert true["value"][i, j] == pytest.approx(expected, rel=1e-9), (angle, velocity)
    assert true["value"][1, 1] > 4.9 and true["value"][0, 0] < 0.2  # balanced; falling


def test_the_maps_mark_the_states_of_the_runs_last_batches(tmp_path, monkeypatch):
    """maps.npz's visited states are (pole angle, angular velocity) of the observations in
    the last 10 batches the run trained on, and its true V map has the trained V's range."""
    batches = []
    real = ppo.ppo_update
    monkeypatch.setattr(ppo, "ppo_update", lambda policy, value, opt, data, cfg: (
        batches.append(data["obs"].clone()), real(policy, value, opt, data, cfg))[1])
    run = quick_run(tmp_path, 0, total_timesteps=256 * 12)["run_dir"]
    maps = np.load(run / "maps.npz")
    expected = torch.cat(batches[-10:])[:, 2:4].numpy()
    np.testing.assert_array_equal(maps["visited"], expected)
    assert maps["true_value"].shape == (11, 11) and np.isfinite(maps["true_value"]).all()
    assert 0 < maps["true_value"].max() <= 1 / (1 - 0.99) * 0.05 + 1e-9  # scaled rewards


def test_compare_legend_counts_every_run_drawn(tmp_path):
    """Two DDPG runs, one with a single evaluation: the legend says 2 runs (it said 1)."""
    import plots

    for name, rows in (("ddpg_walker__Walker2d-v5__seed0__20260101-000000", [5000]),
                       ("ddpg_walker__Walker2d-v5__seed1__20260101-000001", [5000, 10000, 15000])):
        (tmp_path / name).mkdir()
        lines = ["global_step,eval_mean,eval_std"] + [f"{s},{s / 100},1" for s in rows]
        (tmp_path / name / "evaluations.csv").write_text("\n".join(lines) + "\n")
    fig = plots.compare_figure(sorted(tmp_path.iterdir()))
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert labels == ["ddpg_walker: 2 runs"], labels


# ---- the panels of the language-model scripts: a stage per axis, text, histograms ----------

def drawn(panel, logs):
    """Fill a panel's axes from `logs` as plots.draw does; returns its axes."""
    import plots

    n, fill = panel
    fig, axes = plots.pyplot().subplots(1, n, squeeze=False)
    fill(list(axes[0]), logs)
    return list(axes[0])


def stage_logs():
    """Ten rows in two stages: loss at every row, score only in stage b, pass1 at some rows
    of b, kl (for the x axis) at every row."""
    nan = np.nan
    table = dict(global_step=np.arange(1.0, 11.0), phase=np.array(["a"] * 4 + ["b"] * 6),
                 loss=np.arange(10.0) / 10, score=np.array([nan] * 4 + [1, 2, 3, 4, 5, 6.0]),
                 pass1=np.array([nan] * 5 + [0.5, nan, 0.6, nan, 0.7]),
                 kl=np.array([0, 1, 4, 9, 16, 25, 36, 49, 64, 81.0]))
    return dict(table=table, kept=[], labels=dict(loss="the loss", score="the score"))


@pytest.mark.quick
def test_read_csv_keeps_a_text_column_as_text(tmp_path):
    """progress.csv with a stage's name in a column: the names, as strings; the numbers, nan
    where empty."""
    import plots

    (tmp_path / "progress.csv").write_text("global_step,phase,loss\n1,sft,0.5\n2,rm,\n")
    table = plots.read_csv(tmp_path / "progress.csv")
    assert table["phase"].tolist() == ["sft", "rm"]
    assert table["global_step"].tolist() == [1.0, 2.0] and table["loss"][0] == 0.5
    assert np.isnan(table["loss"][1])


@pytest.mark.quick
def test_lines_draws_only_the_rows_of_a_stage():
    """where=("phase", "a"): the rows of stage a only, and a column not measured there (score)
    left out, legend included; within=(3, 6): steps 3 to 6, both ends drawn; a column
    measured at some of those rows only (pass1): those rows, as points."""
    import plots

    (ax,) = drawn(plots.lines("loss", "score", where=("phase", "a")), stage_logs())
    assert [line.get_xdata().tolist() for line in ax.lines] == [[1, 2, 3, 4]]
    assert ax.lines[0].get_ydata().tolist() == [0.0, 0.1, 0.2, 0.3]
    assert [t.get_text() for t in ax.get_legend().get_texts()] == ["the loss"]
    (ax,) = drawn(plots.lines("score", "pass1", within=(3, 6)), stage_logs())
    score, pass1 = ax.lines
    assert score.get_xdata().tolist() == [5, 6] and score.get_ydata().tolist() == [1, 2]
    assert pass1.get_xdata().tolist() == [6] and pass1.get_marker() == "o"
    (ax,) = drawn(plots.lines("score", where=("phase", "b"), within=(1, 7)), stage_logs())
    assert ax.lines[0].get_xdata().tolist() == [5, 6, 7]  # both: the rows of b up to step 7


@pytest.mark.quick
def test_lines_against_another_column():
    """x="kl", x_of=np.sqrt: each row of stage b a point at (sqrt(kl), score), in the log's
    order, and the x label as given."""
    import plots

    (ax,) = drawn(plots.lines("score", where=("phase", "b"), x="kl", x_of=np.sqrt,
                              xlabel="sqrt(kl)"), stage_logs())
    assert ax.lines[0].get_xdata().tolist() == [4, 5, 6, 7, 8, 9]
    assert ax.lines[0].get_ydata().tolist() == [1, 2, 3, 4, 5, 6]
    assert ax.get_xlabel() == "sqrt(kl)"


@pytest.mark.quick
def test_histograms_of_the_updates_that_keep_the_array():
    """Kept arrays from a stage without a ratio (steps 1, 3) and four updates with one: the
    first, middle and last of those four, numbered among them, every value counted, the band
    dashed; no split by sign."""
    import plots

    rng = np.random.default_rng(0)
    ratios = {step: 1 + 0.05 * rng.standard_normal(100 + step) for step in (5, 6, 7, 8)}
    kept = [(1, {}), (3, {})] + [(step, {"ratio": r}) for step, r in ratios.items()]
    axes = drawn(plots.histograms("ratio", band=(0.8, 1.2)), dict(kept=kept, labels={}))
    assert [ax.get_title() for ax in axes] == ["ratio at update 1 (step 5)",
                                               "ratio at update 3 (step 7)",
                                               "ratio at update 4 (step 8)"]
    for ax, step in zip(axes, (5, 7, 8)):
        (outline,) = ax.patches  # stepfilled: one polygon, the outline of the bars
        corners = outline.get_xy()[1:80]  # (left edge, count), (right edge, count), ...
        counts, edges = np.histogram(ratios[step], bins=40)  # bins over the values
        np.testing.assert_array_equal(corners[::2, 1], counts)
        np.testing.assert_allclose(corners[::2, 0], edges[:-1])
        assert counts.sum() == len(ratios[step])
        assert [line.get_xdata()[0] for line in ax.lines] == [0.8, 1.2]
    none = drawn(plots.histograms("ratio", band=(0.8, 1.2)), dict(kept=kept[:2], labels={}))
    assert all(not ax.patches for ax in none)  # a run stopped before any: blank, no error
    with pytest.raises(KeyError, match=r"\['ratios'\], which no update kept .kept: .'ratio'.."):
        drawn(plots.histograms("ratios"), dict(kept=kept, labels={}))  # a wrong name
    with pytest.raises(KeyError, match=r"\['value'\], which no update kept"):
        drawn(plots.scatters("ratio", "value", "x", "y"), dict(kept=kept, labels={}))


@pytest.mark.quick
def test_distributions_count_each_array_over_the_same_bins():
    """Two arrays: one histogram each, labelled, their bars on the same bin edges, every
    value counted once."""
    import plots

    a, b = np.linspace(0, 1, 50), np.linspace(0.5, 3, 30)
    (ax,) = drawn(plots.distributions({"chosen": a, "rejected": b}, "scores", "r"),
                  dict(kept=[], labels={}))
    assert [len(c.patches) for c in ax.containers] == [40, 40]
    left = [[p.get_x() for p in c.patches] for c in ax.containers]
    assert left[0] == left[1]  # the same bins: the two can be compared bar by bar
    assert [sum(p.get_height() for p in c.patches) for c in ax.containers] == [50, 30]
    assert [t.get_text() for t in ax.get_legend().get_texts()] == ["chosen", "rejected"]
    assert ax.get_title() == "scores" and ax.get_xlabel() == "r"


@pytest.mark.quick
def test_text_shows_every_line_in_order():
    import plots

    lines = ["1+2= 03. 04.x", "5+5= 10. 11.x", "9+9= 18. 18."]
    (ax,) = drawn(plots.text(lines, "answers"), dict(kept=[], labels={}))
    assert [t.get_text() for t in ax.texts] == ["1+2= 03. 04.x\n5+5= 10. 11.x\n9+9= 18. 18."]
    assert ax.get_title() == "answers" and not ax.axison


def test_tensorboard_leaves_out_a_text_column(tmp_path):
    """A stage's name is text: no scalar of it, the numbers beside it written."""
    pytest.importorskip("tensorboard")
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator
    import plots

    (tmp_path / "progress.csv").write_text("global_step,phase,loss\n1,sft,0.5\n2,rm,0.25\n")
    plots.to_tensorboard(tmp_path)
    events = EventAccumulator(str(tmp_path))
    events.Reload()
    assert events.Tags()["scalars"] == ["charts/loss"]
    assert [(e.step, e.value) for e in events.Scalars("charts/loss")] == [(1, 0.5), (2, 0.25)]


@pytest.mark.quick
def test_the_maps_are_titled_with_what_the_script_says_they_show():
    """The maps' titles name what they show: V(s) and pi(right | s) by default, what a script
    hands over otherwise (DQN's are max_a Q and the greedy action)."""
    import plots
    from matplotlib.figure import Figure

    grid = np.zeros((3, 3))
    maps = dict(untrained=dict(value=grid, policy=grid), trained=dict(value=grid + 1, policy=grid),
                true=dict(value=grid + 2), x=np.arange(3.0), y=np.arange(3.0))
    for labels, value, policy in (({}, "V(s)", "policy"),
                                  (dict(value_label="max_a Q(s, a)", policy_label="greedy"),
                                   "max_a Q(s, a)", "greedy")):
        n, fill = plots.maps_row({**maps, **labels})
        axes = Figure().subplots(1, n)
        fill(axes, None)
        assert [ax.get_title() for ax in axes] == [
            f"{value}, untrained", f"{value}, trained", "true V^pi(s), Monte-Carlo",
            f"{policy}, untrained", f"{policy}, trained"]


def test_a_run_that_logs_no_return_is_drawn_by_its_last_column(tmp_path, capsys):
    """A finished run whose log holds other measures (a language model's held-out checks, which
    its script logs last) is drawn by its last column of numbers, named on the axis; a run with
    nothing measured yet is left out with a line that says so."""
    import plots

    run = tmp_path / "some_script__task__seed0__20260101-000000"
    run.mkdir()
    (run / "progress.csv").write_text("global_step,phase,loss,pass1\n10,sft,2.4,\n"
                                      "20,sft,2.1,0.3\n30,rl,1.9,0.5\n")
    (ax,) = plots.compare_figure([run]).axes
    assert ax.get_title() == "task" and "pass1" in ax.get_ylabel()
    np.testing.assert_array_equal(ax.lines[0].get_xydata(), [[20, 0.3], [30, 0.5]])
    (run / "progress.csv").write_text("global_step,phase\n10,sft\n")
    with pytest.raises(SystemExit):
        plots.compare_figure([run])
    assert "holds nothing to compare yet" in capsys.readouterr().err


def test_plots_takes_runs_latest_as_the_run_it_names(tmp_path, capsys):
    """`python plots.py runs/latest` draws the newest run under its own script's name, and
    `python plots.py runs/*` draws it once, not again as a run of a script named latest."""
    import plots
    import runlog

    for seed in (0, 1):
        run = runlog.make_run_dir(tmp_path, "ddpg_walker", "Walker2d-v5", seed)
        (run / "evaluations.csv").write_text("global_step,eval_mean,eval_std\n5000,1,0\n"
                                             "10000,2,0\n")
    for runs, label in (([tmp_path / "latest"], "ddpg_walker: 1 run"),
                        (sorted(tmp_path.iterdir()), "ddpg_walker: 2 runs (thin), their mean "
                                                     "while all ran")):
        (ax,) = plots.compare_figure(runs).axes
        assert [t.get_text() for t in ax.get_legend().get_texts()] == [label]


def axes_without_a_ylabel(fig):
    """The axes of `fig` that show a y axis and say nothing on it, by title (colour bars and
    text panels, which have no y axis to read, aside)."""
    return [ax.get_title() or "(a right-hand axis, or one without a title)" for ax in fig.axes
            if ax.axison and ax.get_label() != "<colorbar>" and not ax.get_ylabel().strip()]


@pytest.mark.quick
@pytest.mark.parametrize("name", SCRIPTS)
def test_every_axis_of_a_smoke_runs_pictures_says_what_it_measures(name, tmp_path, monkeypatch):
    """Every axis of every curve.png and inside.png the script's SMOKE run draws (a walker's
    at each evaluation too) has a y label: a reader knows what it measures without the
    legend. A panel of several columns gets one only where the script names the one quantity
    they share: two quantities on one axis have none, and fail here."""
    import plots

    figures, make = [], plots.figure

    def kept(rows, logs, title, **layout):
        figures.append(make(rows, logs, title, **layout))
        return figures[-1]
    monkeypatch.setattr(plots, "figure", kept)
    module = importlib.import_module(name)
    module.train(quick_smoke(module, tmp_path))
    assert len(figures) >= 2  # curve.png and inside.png, at least once
    for fig in figures:
        assert not axes_without_a_ylabel(fig), (fig.get_suptitle(), axes_without_a_ylabel(fig))


@pytest.mark.quick
def test_lines_says_on_its_y_axis_what_the_columns_measure():
    """One column: its declared label; several: the quantity the script names, or nothing
    (the smoke runs' test then fails); a right-hand axis: its own, linear if asked."""
    import plots

    (ax,) = drawn(plots.lines("loss"), stage_logs())
    assert ax.get_ylabel() == "the loss"
    (ax,) = drawn(plots.lines("loss", "score"), stage_logs())
    assert ax.get_ylabel() == ""  # two labels, no quantity named
    (ax,) = drawn(plots.lines("loss", "score", ylabel="nats"), stage_logs())
    assert ax.get_ylabel() == "nats"
    fig = drawn(plots.lines("loss", right=("score",), right_log=False), stage_logs())[0].figure
    main, twin = fig.axes
    assert (main.get_ylabel(), twin.get_ylabel()) == ("the loss", "the score")
    assert twin.get_yscale() == "linear" and not axes_without_a_ylabel(fig)
    texts = [t.get_text() for t in twin.get_legend().get_texts()]
    assert texts == ["the loss", "the score"]  # one legend for both axes, above their lines


def warm_up_logs():
    """Evaluations at steps 100 and 200, in a random warm-up of 250 steps, then 300 to 500."""
    steps = np.array([100, 200, 300, 400, 500.0])
    table = dict(global_step=steps, eval_mean=np.array([9, 8, 1, 5, 20.0]),
                 eval_std=np.ones(5), train_return_mean10=np.array([7, 7, 2, 4, 15.0]),
                 q_estimate=np.array([0, 0.1, 1, 2, 3.0]))
    return dict(table=table, evaluations=table, kept=[], labels={}, warm_up=250)


@pytest.mark.quick
@pytest.mark.parametrize("panel", ["evaluation_returns", "lines"])
def test_no_line_joins_the_random_warm_up_to_the_learned_evaluations(panel):
    """The warm-up (steps up to 250) shaded; its evaluations are points of their own: no
    line goes from one of them to a learned one, which would read as learning."""
    import plots

    builder = plots.evaluation_returns() if panel == "evaluation_returns" else plots.lines(
        "q_estimate")
    (ax,) = drawn(builder, warm_up_logs())
    spans = [p.get_extents() for p in ax.patches]  # the shaded warm-up, in pixels
    left, right = ax.transData.transform([(0, 0), (250, 0)])[:, 0]
    assert any(abs(s.x0 - left) < 1 and abs(s.x1 - right) < 1 for s in spans)
    for line in ax.lines:
        x = np.asarray(line.get_xdata(), dtype=float)
        assert not ((x <= 250).any() and (x > 250).any()), x
        if (x <= 250).any():
            assert line.get_linestyle() == "None"  # points (and error bars), no line
    assert any(list(line.get_xdata()) == [100, 200] and line.get_marker() == "o"
               for line in ax.lines)  # the warm-up's evaluations: shown, as open points
    (ax,) = drawn(builder, {**warm_up_logs(), "warm_up": 0})  # no warm-up: one line each
    assert not ax.patches or panel == "evaluation_returns"  # (its +- std band)
    assert all(len(line.get_xdata()) == 5 for line in ax.lines)


@pytest.mark.quick
@pytest.mark.parametrize("panel", ["evaluation_returns", "lines"])
def test_a_lone_learned_evaluation_is_a_dot(panel):
    """The first evaluation after a random warm-up, alone: a line of one point draws nothing,
    so it is drawn as a dot (a walker's picture after its first learned evaluation)."""
    import plots

    builder = plots.evaluation_returns() if panel == "evaluation_returns" else plots.lines(
        "q_estimate")
    logs = warm_up_logs()
    logs["table"] = logs["evaluations"] = {k: v[:3] for k, v in logs["table"].items()}
    (ax,) = drawn(builder, logs)
    learned = [line for line in ax.lines if list(line.get_xdata()) == [300]]
    assert learned and all(line.get_marker() not in ("None", "", None) for line in learned)


@pytest.mark.quick
def test_a_doubled_and_halved_quantity_is_ticked_at_powers_of_two():
    """PPO-penalty's beta, 1/8 to 4 on a log axis: its ticks are the values it takes (the
    default 1-2-5 ticks would show neither end)."""
    import plots

    table = dict(global_step=np.arange(1, 7.0), beta=np.array([1, 2, 4, 1, 0.25, 0.125]))
    (ax,) = drawn(plots.lines("beta", log=2), dict(table=table, kept=[], labels={}, warm_up=0))
    ax.figure.canvas.draw()
    low, high = ax.get_ylim()
    shown = [t for t in ax.get_yticks() if low <= t <= high]
    assert {0.125, 0.25, 0.5, 1, 2, 4} <= set(shown), shown
    assert all(np.log2(t) == round(np.log2(t)) for t in shown), shown


@pytest.mark.quick
def test_dashed_columns_lie_over_the_others_and_both_show_where_they_coincide():
    """DQN's two targets, equal where the online argmax and the target's agree: the dashed
    one drawn over the other, which is wider, so that its colour shows in the dashes' gaps."""
    import plots

    (ax,) = drawn(plots.lines("loss", "kl", dashed=("kl",), ylabel="x"), stage_logs())
    solid, dashed = ax.lines
    assert dashed.get_linestyle() == "--" and solid.get_linestyle() == "-"
    assert dashed.get_zorder() > solid.get_zorder()
    assert solid.get_linewidth() > dashed.get_linewidth()


@pytest.mark.quick
def test_text_is_as_large_as_its_panel_holds():
    """GRPO's answers: 8 lines of 8 answers of 2-digit sums, two panels side by side in
    inside.png's 12 inches: the text within its panel, at 9.5 points or more."""
    import plots

    lines = ["12+34= " + " ".join(["046.x"] * 8)] * 8
    fig = plots.figure([[plots.text(lines, "before"), plots.text(lines, "after")]],
                       dict(kept=[], labels={}), "answers")
    renderer = fig.canvas.get_renderer()
    for ax in fig.axes:
        (text,) = ax.texts
        box, inside = text.get_window_extent(renderer), ax.get_window_extent(renderer)
        assert text.get_fontsize() >= 9.5
        assert inside.x0 - 1 <= box.x0 and box.x1 <= inside.x1 + 1, (box, inside)
        assert inside.y0 - 1 <= box.y0 and box.y1 <= inside.y1 + 1, (box, inside)
    # before with its x marks, after without: sized for the same columns, one type size
    short = ["12+34= " + " ".join(["046."] * 8)] * 8
    fig = plots.figure([[plots.text(lines, "before", columns=len(lines[0])),
                         plots.text(short, "after", columns=len(lines[0]))]],
                       dict(kept=[], labels={}), "answers")
    assert len({round(ax.texts[0].get_fontsize(), 6) for ax in fig.axes}) == 1
