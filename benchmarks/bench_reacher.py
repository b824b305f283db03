"""ppo_reacher.py against Stable-Baselines3's PPO with rl-baselines3-zoo's Reacher settings.

Both side by side, one process each, each at one torch thread: seed k of ours beside seed k of
SB3, seeds 0-4, 1M env steps. Both are measured alike: the mean return of 10 episodes of the
deterministic action (the mean, clipped to the box), eval env seeded 10000 (our evaluation,
common.evaluate), at 200k, 500k and 1M env steps, and the seconds from the start of the
process to each: wall-clock, and the CPU time the process had (on a busy machine the fairer
measure of the two: it does not count the time another process held the core). SB3's evaluation normalizes the obs with its VecNormalize statistics,
frozen, as zoo's enjoy does. Our steps count the autoreset steps (one in 51 on Reacher);
SB3's do not. Each pair's row goes to the record as it ends; run again, it goes on with the
seeds the record lacks.

    pip install -r benchmarks/requirements.txt
    python benchmarks/bench_reacher.py                 # seeds 0-4: ~1 hour on 2 cores
    python benchmarks/bench_reacher.py --sb3 --seed 0  # one SB3 run, its lines
    python benchmarks/bench_reacher.py --table benchmarks/results/ppo_reacher.json
"""

import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

START = time.time()
ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(Path(__file__).resolve().parent))
import settings  # noqa: E402  our settings, written out
RECORD = ROOT / "benchmarks" / "results" / "ppo_reacher.json"
AT = (200_000, 500_000, 1_000_000)
EVAL = dict(episodes=10, seed=10_000)
# rl-baselines3-zoo, hyperparams/ppo.yml, Reacher (v2 there; the same task in v5): normalize
# (VecNormalize, obs and reward, its gamma the algorithm's), one env, 1M steps.
ZOO = dict(n_steps=512, batch_size=32, gamma=0.9, learning_rate=0.000104019,
           ent_coef=7.52585e-08, clip_range=0.3, n_epochs=5, gae_lambda=1.0, max_grad_norm=0.9,
           vf_coef=0.950368)
LINE = re.compile(r"^evaluation at step (\d+): (-?[\d.]+)")


def sb3(seed, out):
    """One SB3 run; prints `evaluation at step N: mean` lines as ours does, at AT."""
    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.callbacks import BaseCallback
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.vec_env import VecNormalize

    sys.path.insert(0, str(ROOT))
    import common

    torch.set_num_threads(1)
    env = VecNormalize(make_vec_env("Reacher-v5", n_envs=1, seed=seed), gamma=ZOO["gamma"])
    model = PPO("MlpPolicy", env, seed=seed, device="cpu", **ZOO)
    rows = []

    class Evaluate(BaseCallback):
        def _on_step(self):
            if self.num_timesteps in AT:
                def act(obs):
                    return model.predict(env.normalize_obs(obs), deterministic=True)[0]
                returns = common.evaluate("Reacher-v5", act, EVAL["episodes"], EVAL["seed"])
                rows.append(dict(step=self.num_timesteps, mean=statistics.mean(returns),
                                 seconds=time.time() - START, cpu=time.process_time()))
                print(f"evaluation at step {self.num_timesteps}: {rows[-1]['mean']:.2f}",
                      flush=True)
            return True

    model.learn(total_timesteps=AT[-1], callback=Evaluate())
    Path(out).write_text(json.dumps(rows))


# Ours: ppo_reacher.py's settings (tutorial 002's update with Spinning Up's defaults), written
# out rather than left to the script's defaults (benchmarks/settings.py)
OURS = settings.flags(
    env_id="Reacher-v5", total_timesteps=AT[-1], eval_every=100_000, num_envs=1, num_steps=4000,
    gamma=0.99, lam=0.97, update="full_batch", train_pi_iters=80, train_v_iters=80,
    target_kl=0.01, kl_stop_factor=1.5, clip_ratio=0.2, pi_lr=3e-4, vf_lr=1e-3, update_epochs=10,
    num_minibatches=32, max_grad_norm=0.0, anneal_lr=False, hidden=64, log_std_init=-0.5,
    norm_obs=True, norm_reward=False)


def ours(seed):
    return [sys.executable, str(ROOT / "ppo_reacher.py"), "--seed", str(seed), *OURS,
            "--no-gifs", "--print-every", "100000", "--threads", "1"]


def cpu_seconds(pid):
    """The CPU time (user + system) process `pid` has had so far (Linux: /proc), or None."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    except (OSError, ValueError, IndexError):
        return None


def watch(proc, rows, start):
    """Read a run's lines as they come: (step, mean, seconds, cpu) at AT."""
    for line in proc.stdout:
        m = LINE.match(line)
        if m and int(m[1]) in AT:
            rows.append(dict(step=int(m[1]), mean=float(m[2]), seconds=time.time() - start,
                             cpu=cpu_seconds(proc.pid)))


def pair(seed, tmp):
    """Seed `seed` of ours and of SB3, at once, each on its own core."""
    env = dict(os.environ, OMP_NUM_THREADS="1", CUDA_VISIBLE_DEVICES="")
    out = Path(tmp) / f"sb3_{seed}.json"
    start = time.time()
    theirs = subprocess.Popen([sys.executable, __file__, "--sb3", "--seed", str(seed), "--out",
                               str(out)], env=env, stdout=subprocess.DEVNULL)
    mine = subprocess.Popen(ours(seed) + ["--run-dir", str(Path(tmp) / "runs")], env=env,
                            stdout=subprocess.PIPE, text=True, cwd=tmp)
    rows = []
    watch(mine, rows, start)
    if mine.wait() or theirs.wait():
        sys.exit(f"seed {seed}: a run failed")
    return dict(seed=seed, ours=rows, sb3=json.loads(out.read_text()))


def table(record):
    """Markdown: per step count, the median [min, max] over seeds of each, and seconds. One
    decimal: our runs' progress lines give their means so (the evaluation's line)."""
    runs = record["runs"]
    lines = ["| Reacher-v5 | steps | mean return, median [min, max] | seconds, median | "
             "CPU seconds, median |", "|---|---|---|---|---|"]
    for who, name in (("ours", "ppo_reacher.py"), ("sb3", "SB3 PPO, rl-zoo settings")):
        for step in AT:
            got = [r for run in runs for r in run[who] if r["step"] == step]
            means, secs = [r["mean"] for r in got], [r["seconds"] for r in got]
            cpus = [r["cpu"] for r in got if r.get("cpu") is not None]
            cpu = f"{statistics.median(cpus):.0f} ({len(cpus)} seeds)" if cpus else "-"
            lines.append(f"| {name} ({len(got)} seeds) | {step:,} | "
                         f"{statistics.median(means):.1f} [{min(means):.1f}, {max(means):.1f}]"
                         f" | {statistics.median(secs):.0f} | {cpu} |")
    return "\n".join(lines)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3, 4])
    parser.add_argument("--sb3", action="store_true", help="one SB3 run (--seed)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", default=None)
    parser.add_argument("--table", default=None, help="print a record's table")
    args = parser.parse_args()
    if args.table:
        print(table(json.loads(Path(args.table).read_text())))
        return
    if args.sb3:
        sb3(args.seed, args.out or os.devnull)
        return
    settings = dict(zoo=ZOO, ours=ours("K")[2:], at=AT, evaluation=EVAL)
    record = json.loads(RECORD.read_text()) if RECORD.exists() else dict(settings=settings,
                                                                         runs=[])
    if record["settings"] != json.loads(json.dumps(settings)):
        sys.exit(f"{RECORD} was measured with other settings: move it away to start anew")
    done = {run["seed"] for run in record["runs"]}  # a stopped benchmark goes on from there
    with tempfile.TemporaryDirectory() as tmp:
        for seed in [s for s in args.seeds if s not in done]:
            record["runs"].append(pair(seed, tmp))
            RECORD.write_text(json.dumps(record, indent=1) + "\n")  # as each pair ends
            print(json.dumps(record["runs"][-1]), flush=True)
    print(table(record))


if __name__ == "__main__":
    main()
