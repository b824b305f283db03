"""The experiments: each variant differs from the original only as its docstring says, the
code it replaces is put back after its runs, and each file runs in its quick mode."""

import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import torch

import common
import ppo_cartpole
from conftest import ROOT, interrupt_in_a_terminal, run_script
from test_ppo_cartpole import batch

sys.path.insert(0, str(ROOT / "experiments"))
import advantage_normalization  # noqa: E402
import autoreset_not_masked  # noqa: E402
import clip_or_penalty  # noqa: E402
import critic_output_shape  # noqa: E402
import gae_lambda  # noqa: E402
import lab  # noqa: E402
import reinforce_baseline  # noqa: E402
import sarsa_vs_q_learning  # noqa: E402
import sac_temperature  # noqa: E402
import double_dqn  # noqa: E402
import dqn_target_period  # noqa: E402
import target_networks  # noqa: E402
import td3_fixes  # noqa: E402
import truncation_as_termination  # noqa: E402
import truncation_as_termination_ddpg  # noqa: E402

EXPERIMENTS = ("truncation_as_termination", "autoreset_not_masked", "advantage_normalization",
               "gae_lambda", "critic_output_shape", "truncation_as_termination_ddpg",
               "clip_or_penalty", "target_networks", "double_dqn", "dqn_target_period",
               "reinforce_baseline", "sarsa_vs_q_learning")


def rollout(truncate_at=None):
    torch.manual_seed(0)
    T, N = 12, 3
    r, v, nv = torch.rand(T, N), torch.rand(T, N), torch.rand(T, N)
    term = torch.zeros(T, N, dtype=torch.bool)
    term[4, 0] = True
    trunc = torch.zeros(T, N, dtype=torch.bool)
    if truncate_at is not None:
        trunc[truncate_at, 1] = True
    return r, v, nv, term, trunc


def test_gae_variant_equals_common_gae_without_truncations_and_differs_with_one():
    variant = truncation_as_termination.gae_truncation_as_termination
    args = rollout()
    assert torch.equal(variant(*args, 0.99, 0.95), common.gae(*args, 0.99, 0.95))
    args = rollout(truncate_at=6)
    got, want = variant(*args, 0.99, 0.95), common.gae(*args, 0.99, 0.95)
    differs = (got != want).any(0)
    assert differs.tolist() == [False, True, False]  # only the truncated env's column
    # there, exactly the bootstrap is gone: gamma * V(final obs) at the truncated step
    assert got[6, 1] == pytest.approx((want[6, 1] - 0.99 * args[2][6, 1]).item(), rel=1e-6)


def test_store_variant_keeps_the_autoreset_steps_and_nothing_else_changes():
    original, variant = ppo_cartpole.RolloutBuffer(2, 3, 4), ppo_cartpole.RolloutBuffer(2, 3, 4)
    valid = np.array([True, False, True])
    args = (0, np.ones((3, 4)), np.array([0, 1, 0]), np.ones(3), np.zeros(3, bool),
            np.zeros(3, bool))
    original.store(*args, valid=valid)
    autoreset_not_masked.store_without_mask(variant, *args, valid=valid)
    assert original.valid[0].tolist() == [True, False, True]
    assert variant.valid[0].tolist() == [True, True, True]
    for name in ("obs", "actions", "rewards", "terminated", "truncated"):
        assert np.array_equal(getattr(original, name), getattr(variant, name))


def test_advantage_variant_is_only_the_flag():
    (original, variant) = advantage_normalization.VARIANTS.values()
    assert original == {} and variant == {"config": {"norm_adv": False}}


def test_gae_lambda_variants_are_only_the_setting_and_its_ends_are_td_and_returns():
    assert [v.get("config", {}) for v in gae_lambda.VARIANTS.values()] == [
        {}, {"lam": 0.0}, {"lam": 1.0}]
    r, v, last, term, trunc = rollout(truncate_at=6)
    nv = torch.cat([v[1:], last[:1]])  # V(s_{t+1}): the next stored obs's value, as in train()
    delta = r + 0.99 * nv * (~term) - v  # lam = 0: the one-step TD error
    assert torch.allclose(common.gae(r, v, nv, term, trunc, 0.99, 0.0), delta)
    ret = common.discounted_returns(r, nv, term, trunc, 0.99)  # lam = 1: return minus V
    assert torch.allclose(common.gae(r, v, nv, term, trunc, 0.99, 1.0), ret - v, atol=1e-6)


def test_critic_variant_is_the_same_q_with_its_last_dimension_kept():
    """Spinning Up's planted bug: the same numbers, shaped (B, 1); against (B,) targets the
    TD target and the loss broadcast to (B, B)."""
    import ddpg_walker

    torch.manual_seed(0)
    critic = ddpg_walker.Critic(3, 2, 16)
    obs, action = torch.randn(5, 3), torch.randn(5, 2)
    q = critic(obs, action)
    q_variant = critic_output_shape.forward_keeping_its_dimension(critic, obs, action)
    assert q.shape == (5,) and q_variant.shape == (5, 1)
    assert torch.equal(q_variant.squeeze(-1), q)
    y = ddpg_walker.td_target(torch.zeros(5), torch.ones(5), q_variant, 0.99)
    assert y.shape == (5, 5)  # what the variant's critic is then trained toward


def test_time_limit_wrapper_changes_only_terminated_and_only_at_the_truncation():
    """The DDPG variant: step for step the same env, except that the truncated step also
    reports terminated (so ddpg_walker stores not_done = 0 there)."""
    import gymnasium as gym

    def steps(env):
        env.reset(seed=0)
        return [env.step(np.zeros(1, dtype=np.float32)) for _ in range(4)]

    limit = 4  # a short limit, so that the pole is still up when it is reached
    plain = gym.wrappers.TimeLimit(gym.make("InvertedPendulum-v5"), limit)
    variant = truncation_as_termination_ddpg.TimeLimitAsTermination(
        gym.wrappers.TimeLimit(gym.make("InvertedPendulum-v5"), limit))
    for t, (a, b) in enumerate(zip(steps(plain), steps(variant))):
        assert np.array_equal(a[0], b[0]) and a[1] == b[1] and a[3] == b[3]
        assert a[2] is False  # the pole did not fall: only the time limit ends the episode
        assert b[2] == (t == limit - 1) == a[3]
    env = truncation_as_termination_ddpg.make_env_time_limit_as_termination("InvertedPendulum-v5")
    assert isinstance(env, truncation_as_termination_ddpg.TimeLimitAsTermination)
    assert isinstance(env.env, gym.wrappers.RecordEpisodeStatistics)  # common's env inside


def test_loss_without_clip_is_the_clipped_loss_with_an_infinite_band():
    """The no-clip variant: the same loss and gradient as compute_loss_pi with eps so large
    that no ratio leaves the band; with eps = 0.2 and ratios outside it, a different one."""
    policy, _, data = batch(40)
    with torch.no_grad():
        for p in policy.parameters():
            p.add_(0.5 * torch.randn_like(p))  # pi moved: some ratios leave [0.8, 1.2]

    def loss_and_grad(fn, eps):
        policy.zero_grad()
        loss = fn(policy, data, eps)[0]
        loss.backward()
        return loss.item(), [p.grad.clone() for p in policy.parameters()]

    variant = loss_and_grad(clip_or_penalty.compute_loss_pi_without_clip, 0.2)
    unbounded = loss_and_grad(ppo_cartpole.compute_loss_pi, 1e9)
    clipped = loss_and_grad(ppo_cartpole.compute_loss_pi, 0.2)
    assert variant[0] == pytest.approx(unbounded[0], rel=1e-6)
    assert all(torch.allclose(a, b) for a, b in zip(variant[1], unbounded[1]))
    assert variant[0] != pytest.approx(clipped[0], rel=1e-3)


@pytest.mark.parametrize("script", ["ppo_cartpole", "ppo_kl_cartpole"])
def test_measured_update_is_the_update_plus_three_numbers_it_only_reads(script):
    """clip_or_penalty.measured: the same parameters and stats as the bare update from the
    same state and seed, plus kl_after and the ratio's range, computed here by brute force."""
    import importlib

    module = importlib.import_module(script)
    cfg = module.Config()
    results = []
    for update in (module.ppo_update, clip_or_penalty.measured(module.ppo_update)):
        policy, value_net, data = batch(40)
        with torch.no_grad():
            data["logits_old"] = policy(data["obs"])  # ppo_kl_cartpole's exact KL needs it
        opt = torch.optim.Adam([*policy.parameters(), *value_net.parameters()], lr=0.01)
        rest = (cfg,) if script == "ppo_cartpole" else (1.0, cfg)  # ppo_kl's beta
        torch.manual_seed(1)
        stats = update(policy, value_net, opt, data, *rest)
        results.append((stats, [p.detach().clone() for p in policy.parameters()], data, policy))
    (bare, bare_params, _, _), (stats, params, data, policy) = results
    assert all(torch.equal(a, b) for a, b in zip(bare_params, params))
    assert set(stats) - set(bare) == {"kl_after", "ratio_low", "ratio_high"}
    for key in bare:
        if not torch.is_tensor(bare[key]):
            assert stats[key] == bare[key]
    with torch.no_grad():
        p_old = torch.softmax(data["logits_old"], -1)
        p_new = torch.softmax(policy(data["obs"]), -1)
        kl = (p_old * (p_old.log() - p_new.log())).sum(-1).mean().item()
        ratio = p_new.gather(1, data["act"][:, None]).squeeze(1) / data["logp"].exp()
    assert stats["kl_after"] == pytest.approx(kl, rel=1e-4) and kl > 0
    assert stats["ratio_low"] == pytest.approx(ratio.min().item(), rel=1e-5)
    assert stats["ratio_high"] == pytest.approx(ratio.max().item(), rel=1e-5)


def test_target_network_variants_are_only_the_setting_and_tau_1_copies():
    import ddpg_walker

    assert [v["config"] for v in target_networks.VARIANTS.values()] == [
        {"tau": 0.005}, {"tau": 1.0}]
    source, target = torch.nn.Linear(3, 2), torch.nn.Linear(3, 2)
    ddpg_walker.soft_update(target, source, 1.0)  # tau = 1: the target is the network itself
    assert torch.equal(target.weight, source.weight) and torch.equal(target.bias, source.bias)


def test_a_variant_may_run_another_script_and_keep_its_log_columns(tmp_path):
    """lab.run: the variant's own script is trained, and the kept columns are its log's."""
    import ppo_kl_cartpole

    variants = {"original": {}, "variant": {"script": ppo_kl_cartpole}}
    curves = lab.run(ppo_cartpole, variants, (0,), 512, ["approx_kl", "beta", "lr"])
    assert set(curves["original"][0][2]) == {"approx_kl", "lr"}  # PPO-clip logs no beta
    assert set(curves["variant"][0][2]) == {"beta", "lr"}  # PPO-penalty logs no approx_kl
    steps, betas = curves["variant"][0][2]["beta"]
    assert len(steps) == len(betas) == 2 and betas[0] == 1.0  # 512 steps: two updates of 256
    lab.report("x", curves, tmp_path, panels=[("lr", "learning rate", True)])
    rows = (tmp_path / "x.csv").read_text().splitlines()
    assert rows[0] == "variant,seed_index,final,steps_to_solved,lr_median,lr_min,lr_max"
    assert (tmp_path / "x.png").stat().st_size > 0


def test_swapped_puts_the_original_back_even_after_an_error():
    before = common.gae
    with pytest.raises(RuntimeError):
        with lab.swapped([(common, "gae", lambda *a: None)]):
            assert common.gae is not before
            raise RuntimeError
    assert common.gae is before


@pytest.mark.parametrize("name", [e for e in EXPERIMENTS if e != "advantage_normalization"])
def test_each_experiment_runs_in_quick_mode_and_leaves_nothing(name, tmp_path, monkeypatch,
                                                               capsys):
    """--quick, a smoke test, draws its figure aside and removes it: no runs/ where it ran,
    no folder of ours left in the temporary folder (torch keeps its own cache there,
    torchinductor_<user>). (advantage_normalization: see tiny() below.) The first runs as the
    command line does, in a process of its own with a worker per core; the others run in this
    process, one run at a time (what differs between them is their variants, not the path)."""
    import runpy
    import tempfile

    temp = tmp_path / "temp"
    temp.mkdir()
    if name == EXPERIMENTS[0]:
        p = run_script(f"experiments/{name}.py", "--quick", timeout=300, cwd=tmp_path,
                       env={"TMPDIR": str(temp)})
        assert p.returncode == 0, p.stderr
        out = p.stdout
    else:
        monkeypatch.chdir(tmp_path)
        monkeypatch.setattr(tempfile, "tempdir", str(temp))
        monkeypatch.setattr(sys, "argv", [f"{name}.py", "--quick", "--workers", "1"])
        try:
            runpy.run_path(str(ROOT / "experiments" / f"{name}.py"), run_name="__main__")
        except SystemExit as e:
            assert e.code in (0, None), e.code
        out = capsys.readouterr().out
    lines = out.splitlines()
    assert any(line.startswith("original") for line in lines)
    assert any(line.startswith("variant") for line in lines)
    assert not (tmp_path / "runs").exists() and not list(temp.glob("experiment_*"))


def test_median_steps_count_the_seeds_that_never_got_there():
    """A seed that never reached the level is later than all: the median is over every seed."""
    assert lab.steps_median_and_range([53760, 24576, None, 21504, 21504]) == "24576 [21504, never]"
    assert lab.steps_median_and_range([None, 56832, None, None, None]) == "never [56832, never]"
    assert lab.steps_median_and_range([3, 1, 2]) == "2 [1, 3]"


@pytest.mark.quick
def test_help_prints_the_question_and_a_bad_argument_is_one_line(monkeypatch, capsys):
    """--help must not start the experiment's runs; a typo is one line and exit 2. The file
    runs as `python experiments/clip_or_penalty.py ...` runs it, in this process."""
    import runpy

    def command(*args):
        monkeypatch.setattr(sys, "argv", ["experiments/clip_or_penalty.py", *args])
        with pytest.raises(SystemExit) as stop:
            runpy.run_path(str(ROOT / "experiments" / "clip_or_penalty.py"), run_name="__main__")
        out, err = capsys.readouterr()
        return stop.value.code or 0, out, err

    code, out, err = command("--help")
    assert code == 0 and out.startswith("Question:"), err
    code, out, err = command("--qick")
    assert code == 2 and out == ""
    assert err.strip().splitlines() == [
        "error: unknown argument --qick (did you mean --quick?); the options are --quick, "
        "--docs, --workers N (N >= 1) and --cluster FOLDER [--partition NAME] (see --help)"]


OPTIONS = ("the options are --quick, --docs, --workers N (N >= 1) and --cluster FOLDER "
           "[--partition NAME] (see --help)")


@pytest.mark.quick
@pytest.mark.parametrize("args, message", [
    (["--workers", "0"], "--workers 0: N, the runs at once, must be a whole number, 1 or more"),
    (["--workers=0"], "--workers 0: N, the runs at once, must be a whole number, 1 or more"),
    (["--workers", "-2"], "--workers -2: N, the runs at once, must be a whole number, 1 or more"),
    (["--quick", "--workers", "two"],
     "--workers two: N, the runs at once, must be a whole number, 1 or more"),
    (["--workers", "1.5"], "--workers 1.5: N, the runs at once, must be a whole number, 1 or more"),
    (["--workers"], "--workers needs a value: --workers N"),
    (["--workers", "--quick"], "--workers needs a value: --workers N"),
    (["--cluster"], "--cluster needs a value: --cluster FOLDER"),
    (["--quick=yes"], "--quick takes no value"),
    (["--partition", "cpu"], "--partition NAME goes with --cluster FOLDER"),
    (["--quick", "--quick"], "--quick given twice"),
    (["--worker", "2"], f"unknown argument --worker (did you mean --workers?); {OPTIONS}"),
    (["--cluser", "jobs"], f"unknown argument --cluser (did you mean --cluster?); {OPTIONS}"),
    (["quick"], f"unknown argument quick (did you mean --quick?); {OPTIONS}"),
    (["--total-timesteps", "1000"], f"unknown argument --total-timesteps; {OPTIONS}"),
])
def test_a_bad_value_is_named_as_such_and_a_typo_gets_did_you_mean(args, message, capsys):
    """The value is wrong, not the flag: say which; a flag close to one we have: name it."""
    with pytest.raises(SystemExit) as stop:
        lab.options(args)
    assert stop.value.code == 2
    out, err = capsys.readouterr()
    assert out == "" and err.splitlines() == [f"error: {message}"]


@pytest.mark.quick
def test_the_options_that_are_right():
    assert lab.options([]) == dict(quick=False, docs=False, workers=None, cluster=None)
    assert lab.options(["--quick", "--workers", "3"]) == dict(quick=True, docs=False, workers=3,
                                                              cluster=None)
    assert lab.options(["--docs", "--cluster=jobs", "--partition", "cpu"]) == dict(
        quick=False, docs=True, workers=None, cluster={"folder": "jobs", "partition": "cpu"})


def tiny(folder, seeds, budget, name="tiny", saying=False, preempted=False):
    """An experiment file of our own in `folder`: advantage_normalization's two variants,
    `seeds` and `budget` of our choice (a real one's full run takes minutes). saying: each
    update of a run prints "update done" (to the real stdout: the runs' own is silenced), so
    that a test can tell when a run is inside its training loop; and after the table and the
    figure, the experiment prints "writing more" and waits there for a Ctrl-C. preempted: a
    cluster whose jobs have 5 minutes, where the first run to reach an update is signalled as
    Slurm signals a job at its time limit (it leaves the file "preempted" in `folder`)."""
    script = folder / f"{name}.py"
    script.write_text(
        f'''"""Question: a tiny experiment, for the tests."""
import os
import signal
import sys
import time
sys.path.insert(0, {str(ROOT / "experiments")!r})
import lab
import advantage_normalization
import ppo_cartpole

UPDATE = ppo_cartpole.ppo_update


def ppo_update_saying_so(*args):
    stats = UPDATE(*args)
    print("update done", file=sys.__stdout__, flush=True)
    return stats


def more_until_ctrl_c(curves, folder, settings):
    print("writing more", flush=True)
    while True:
        time.sleep(0.01)


def ppo_update_timed_out_once(*args):
    try:  # the first run here, once: submitit's signal (SIGUSR2) of a job at its time limit
        os.close(os.open({str(folder / "preempted")!r}, os.O_CREAT | os.O_EXCL))
        signal.raise_signal(signal.SIGUSR2)
    except FileExistsError:
        pass
    return UPDATE(*args)


VARIANTS, MORE = advantage_normalization.VARIANTS, None
if {saying!r}:
    VARIANTS = {{name: {{**variant, "swap": [(ppo_cartpole, "ppo_update", ppo_update_saying_so)]}}
                for name, variant in VARIANTS.items()}}
    MORE = more_until_ctrl_c
if {preempted!r}:  # up to 10 minutes, submitit counts a signal as the time limit's
    lab.JOB_MINUTES = 5
    VARIANTS = {{name: {{**variant, "swap": [(ppo_cartpole, "ppo_update",
                                             ppo_update_timed_out_once)]}}
                for name, variant in VARIANTS.items()}}
lab.main({name!r}, ppo_cartpole, VARIANTS, seeds={tuple(seeds)!r}, budget={budget}, more=MORE)
''')
    return script


def test_two_workers_give_the_same_csvs_byte_for_byte_as_one(tmp_path):
    """lab.run with --workers 2 runs each (variant, seed) in its own process: the numbers must
    be those of the runs one after another in one process."""
    script, written = tiny(tmp_path, (0,), 512), {}  # two runs: one per worker
    for workers in (1, 2):
        where = tmp_path / f"workers{workers}"
        where.mkdir()
        p = run_script(script, "--workers", workers, timeout=300, cwd=where)
        assert p.returncode == 0, p.stderr
        assert f"with {workers} worker(s)" in p.stdout
        lines = p.stdout.splitlines()
        assert sum(line.startswith("original:") for line in lines) == 1 + 1  # run, table
        assert sum(line.startswith("variant:") for line in lines) == 1 + 1
        written[workers] = (where / "runs" / "experiments" / "tiny.csv").read_bytes()
    assert written[1] == written[2]


def test_the_cluster_path_gives_the_same_csvs_through_submitits_local_executor(tmp_path):
    """--cluster hands each run to submitit (Slurm where there is one; here its local
    executor, a process per job): the same numbers as the runs in this process."""
    pytest.importorskip("submitit", reason="the cluster path needs submitit (optional)")
    script, written = tiny(tmp_path, (0,), 512), {}
    for how in (["--workers", "1"], ["--cluster", tmp_path / "jobs"]):
        where = tmp_path / how[0].strip("-")
        where.mkdir()
        p = run_script(script, *how, timeout=300, cwd=where)
        assert p.returncode == 0, p.stderr
        written[how[0]] = (where / "runs" / "experiments" / "tiny.csv").read_bytes()
    assert "2 jobs on local" in p.stdout
    assert written["--workers"] == written["--cluster"]


def test_a_cluster_job_stopped_at_its_time_limit_runs_again_and_gives_the_same_csv(tmp_path):
    """On a cluster a job is signalled at its time limit or when preempted (submitit: SIGUSR2)
    and queued again with what its `checkpoint` returns: the same run, from its start (its
    log is the experiment's only once it ends). Here one job is signalled in its first update,
    through submitit's local executor: the experiment still gives the CSV of the runs in one
    process."""
    pytest.importorskip("submitit", reason="the cluster path needs submitit (optional)")
    script, written = tiny(tmp_path, (0,), 512, preempted=True), {}
    for how in (["--workers", "1"], ["--cluster", tmp_path / "jobs"]):
        where = tmp_path / how[0].strip("-")
        where.mkdir()
        if how[0] == "--workers":  # in this process no run is signalled: as if done already
            (tmp_path / "preempted").touch()
        else:
            (tmp_path / "preempted").unlink()
        p = run_script(script, *how, timeout=300, cwd=where)
        assert p.returncode == 0, p.stderr
        written[how[0]] = (where / "runs" / "experiments" / "tiny.csv").read_bytes()
    assert (tmp_path / "preempted").exists()  # one job was signalled
    logs = "".join(log.read_text() for log in (tmp_path / "jobs").rglob("*.out"))
    assert "this job is timed-out" in logs and "Requeued job" in logs, logs
    assert written["--workers"] == written["--cluster"]


def test_an_experiment_writes_to_runs_experiments_where_it_is_run(tmp_path, monkeypatch):
    """As the scripts' runs/: the folder the command runs in, not the repository's."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(sys, "argv", ["elsewhere.py"])
    name = "written_where_it_is_run"
    lab.main(name, ppo_cartpole, {"original": {}}, seeds=(0,), budget=512)
    out = tmp_path / "runs" / "experiments"
    assert sorted(p.name for p in out.iterdir()) == [f"{name}.csv", f"{name}.png", f"{name}_runs"]
    assert (out / f"{name}_runs" / "original__seed0" / "progress.csv").exists()
    assert not (ROOT / "runs" / "experiments" / f"{name}.csv").exists()


def test_the_workers_are_deaf_to_ctrl_c_from_the_first_to_the_last():
    """A terminal's Ctrl-C reaches the workers too: each, the first ones and those the pool
    forks later (from its own thread, one per run), has SIGINT blocked, so that the experiment
    alone answers it; the experiment's own thread has it back. SIGTERM, which the experiment
    turns into a Ctrl-C, ends a worker as by default (the pool ends its workers with it)."""
    code = f"""
import signal, sys
sys.path.insert(0, {str(ROOT / "experiments")!r})
import common
import lab


def blocked(_):
    mask = signal.pthread_sigmask(signal.SIG_BLOCK, [])
    return (signal.SIGINT in mask, signal.SIGTERM in mask,
            signal.getsignal(signal.SIGTERM) == signal.SIG_DFL)


with common.sigterm_as_ctrl_c(), lab.pool_deaf_to_ctrl_c(1) as pool:
    print(pool.map(blocked, range(3), chunksize=1))  # three workers: one run each
    print(blocked(None))
"""
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stderr
    assert p.stdout.splitlines() == ["[(True, False, True), (True, False, True), "
                                     "(True, False, True)]", "(False, False, False)"]


# Ctrl-C, and SIGTERM (Slurm's, to every process of the job): (signal, exit code, its name)
CTRL_C = (signal.SIGINT, 130, "Ctrl-C")
SIGTERM = (signal.SIGTERM, 143, "SIGTERM")


@pytest.mark.parametrize("workers,sent", [(1, CTRL_C), (2, CTRL_C), (2, SIGTERM)],
                         ids=["1-ctrl_c", "2-ctrl_c", "2-sigterm"])
def test_ctrl_c_keeps_the_finished_runs_says_so_in_one_line_and_leaves_nothing_else(
        workers, sent, tmp_path):
    """Ctrl-C, as a terminal sends it (to the workers too), once a run has been kept and
    another is inside its training loop: exit 130, one line that says how many runs are kept
    and how to go on; each kept run whole, the runs cut short not kept, no *.tmp, no
    temporary folder of ours, no worker process left. SIGTERM the same, exit 143."""
    how, exit_code, name = sent
    script, temp = tiny(tmp_path, range(50), 512, saying=True), tmp_path / "temp"
    temp.mkdir()
    code, out, err, left = interrupt_in_a_terminal(script, "--workers", workers,
                                                   after=("original", "update done"),
                                                   cwd=tmp_path, env={"TMPDIR": str(temp)},
                                                   signal=how)
    assert code == exit_code, (out, err)
    assert not left  # no worker process outlives the experiment
    record = tmp_path / "runs" / "experiments" / "tiny_runs"
    kept = sorted(record.iterdir())
    assert 1 <= len(kept) < 100
    assert err.strip().splitlines() == [
        f"interrupted ({name}): {len(kept)} of 100 runs kept in "
        f"{Path('runs', 'experiments', 'tiny_runs')}; the same command again goes on from there"]
    for run in kept:  # each whole: 512 steps are two updates of 256, two rows
        assert [p.name for p in run.iterdir()] == ["progress.csv"]
        assert len((run / "progress.csv").read_text().splitlines()) == 1 + 2, run
    assert not list(tmp_path.rglob("*.tmp*")) and not list(temp.glob("experiment_*"))
    assert not (tmp_path / "runs" / "experiments" / "tiny.csv").exists()


def test_each_run_is_kept_as_it_ends_and_not_run_again(tmp_path, monkeypatch):
    """With a record folder, a run's log is kept the moment the run ends; a second call reads
    it back (the same curves, value for value) instead of training again: an experiment cut
    short goes on where it stopped."""
    variants = {"original": {}, "variant: no norm": {"config": {"norm_adv": False}}}
    first = lab.run(ppo_cartpole, variants, (0, 1), 512, ["approx_kl"], record=tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "original__seed0", "original__seed1", "variant_no_norm__seed0", "variant_no_norm__seed1"]
    (tmp_path / "original__seed1" / "progress.csv").unlink()  # as if cut short before it
    ran = []
    real = lab.one_run
    monkeypatch.setattr(lab, "one_run", lambda task, job: (ran.append(job), real(task, job))[1])
    again = lab.run(ppo_cartpole, variants, (0, 1), 512, ["approx_kl"], record=tmp_path)
    assert ran == [("original", 1)]  # only the run whose log was missing
    for name in variants:
        for (s1, v1, k1), (s2, v2, k2) in zip(first[name], again[name]):
            np.testing.assert_array_equal(s1, s2)
            np.testing.assert_array_equal(v1, v2)
            np.testing.assert_array_equal(k1["approx_kl"][1], k2["approx_kl"][1])


def test_td3_fixes_variants_turn_off_exactly_one_fix_each():
    """Each single-fix variant keeps one fix and turns the other two off; the first none."""
    import td3_walker

    on = {}
    for name, variant in td3_fixes.VARIANTS.items():
        cfg = {**variant.get("config", {})}
        on[name] = (not variant.get("swap"), cfg.get("policy_delay", 2) > 1,
                    cfg.get("target_noise", 0.2) > 0)
    assert list(on.values()) == [(False, False, False), (True, False, False),
                                 (False, True, False), (False, False, True), (True, True, True)]
    r, nd = torch.tensor([1.0, 2.0]), torch.tensor([1.0, 0.0])
    q1, q2 = torch.tensor([5.0, 5.0]), torch.tensor([3.0, 9.0])
    assert td3_fixes.td_target_of_q1_alone(r, nd, q1, q2, 0.5).tolist() == [3.5, 2.0]
    assert td3_walker.td_target(r, nd, q1, q2, 0.5).tolist() == [2.5, 2.0]


@pytest.mark.parametrize("sent", [CTRL_C, SIGTERM], ids=["ctrl_c", "sigterm"])
def test_ctrl_c_after_the_last_run_says_all_are_kept(tmp_path, sent):
    """Ctrl-C (or SIGTERM) once every run is kept (here: while the experiment writes what it
    adds to its table and figure): one line that says so and how to get the rest, exit 130
    (143)."""
    how, exit_code, name = sent
    script = tiny(tmp_path, (0,), 256, saying=True)
    code, out, err, left = interrupt_in_a_terminal(script, "--workers", 1, after="writing more",
                                                   cwd=tmp_path, signal=how)
    assert code == exit_code and not left, (out, err)
    assert err.strip().splitlines() == [
        f"interrupted ({name}): all 2 runs kept in {Path('runs', 'experiments', 'tiny_runs')}; "
        "the same command again draws the table and the figure from them"]
    assert not list(tmp_path.rglob("*.tmp*"))


def test_td3_fixes_writes_every_evaluation_and_the_gap_after_its_runs_warm_up(tmp_path):
    """The gap is drawn from the evaluations after the warm-up of the runs as they were run
    (--quick's is 1000 steps, not 10,000: its one evaluation, at 2500, is after it)."""
    steps = np.array([2500.0])
    one = (steps, np.array([100.0]), {"q_estimate": (steps, np.array([5.0])),
                                      "discounted_return": (steps, np.array([3.0]))})
    curves = {name: [one] for name in td3_fixes.VARIANTS}
    table, gap = td3_fixes.more(curves, tmp_path, {"start_steps": 1000})
    assert table.read_text().splitlines()[1] == "DDPG: no fix,0,2500,100,5,3,2"  # gap: 5 - 3
    assert gap.stat().st_size > 0 and not list(tmp_path.glob("*.tmp*"))


def test_sac_temperature_variants_are_only_the_alpha_flag():
    """Learned (the script's default, alpha None) against --alpha 0.2, nothing else."""
    import sac_walker

    assert sac_walker.Config().alpha is None
    assert [v.get("config", {}) for v in sac_temperature.VARIANTS.values()] == [
        {}, {"alpha": 0.2}]
    assert not any("swap" in v for v in sac_temperature.VARIANTS.values())


def test_dqn_variants_are_only_the_double_flag_and_the_target_period():
    """double_dqn: the default against --double; dqn_target_period: --target-update-interval
    16, the default (64) and 512; nothing else, no swapped code."""
    import dqn_cartpole

    assert dqn_cartpole.Config().double is False
    assert dqn_cartpole.Config().target_update_interval == 64
    assert [v.get("config", {}) for v in double_dqn.VARIANTS.values()] == [{}, {"double": True}]
    assert [v.get("config", {}) for v in dqn_target_period.VARIANTS.values()] == [
        {"target_update_interval": 16}, {}, {"target_update_interval": 512}]
    assert not any("swap" in v for v in [*double_dqn.VARIANTS.values(),
                                         *dqn_target_period.VARIANTS.values()])


def test_double_dqn_writes_each_check_of_q_against_the_return_and_its_gap(tmp_path, capsys):
    """Only the phases where Q was checked (the others are nan in progress.csv) make a row."""
    steps = np.array([256.0, 512.0, 768.0])
    one = (steps, np.array([10.0, 20.0, 30.0]),
           {"q_greedy": (steps, np.array([np.nan, 50.0, 90.0])),
            "mc_return": (steps, np.array([np.nan, 40.0, 95.0]))})
    curves = {name: [one] for name in double_dqn.VARIANTS}
    (table,) = double_dqn.more(curves, tmp_path, {})
    import csv

    rows = list(csv.reader(table.read_text().splitlines()))
    default = "original: DQN, max_a Q'(s', a) (the default)"
    assert rows[1:3] == [[default, "0", "512", "50", "40", "10"],
                         [default, "0", "768", "90", "95", "-5"]]
    assert len(rows) == 5 and "+2.50 [+2.50, +2.50]" in capsys.readouterr().out  # median(10, -5)


@pytest.mark.parametrize("signum, code, name", [(signal.SIGINT, 130, "Ctrl-C"),
                                                (signal.SIGTERM, 143, "SIGTERM")])
def test_the_tabular_experiment_stops_on_sigterm_as_on_ctrl_c(signum, code, name, monkeypatch,
                                                              capsys, tmp_path):
    """sarsa_vs_q_learning.py runs its own loop (not lab.main's): a SIGTERM in its first run
    ends it as a Ctrl-C does, in one line, with its own exit code."""
    real = sarsa_vs_q_learning.tabular.train

    def stopped(cfg):
        signal.raise_signal(signum)  # as `kill PID` (or Ctrl-C) would, inside the run
        return real(cfg)
    def unhandled(signum, frame):  # where the experiment leaves SIGTERM as it was
        raise AssertionError("SIGTERM reached the handler the experiment started with")
    monkeypatch.setattr(sarsa_vs_q_learning.tabular, "train", stopped)
    monkeypatch.setattr(sys, "argv", ["sarsa_vs_q_learning.py", "--quick"])
    before = signal.signal(signal.SIGTERM, unhandled)  # not this test process's death
    restore = lambda: signal.signal(signal.SIGTERM, before)  # noqa: E731
    monkeypatch.chdir(tmp_path)
    try:
        with pytest.raises(SystemExit) as exit_:
            sarsa_vs_q_learning.main()
    finally:
        restore()
    err = capsys.readouterr().err.strip().splitlines()
    assert exit_.value.code == code and len(err) == 1 and f"interrupted ({name})" in err[0], err
