"""Learning-speed benchmark of the CartPole scripts against their peers.

The criterion (also in the README): a run is solved at the first
finished training episode after which the mean return of the last 20 finished
episodes (all envs together) is >= 475. Steps to solve are the env steps of
all envs up to that episode; seconds to solve are the wall time of the whole
process from launch (python and torch imports included) to that episode,
measured here from the moment the process is started to the moment its
`solved:` line is read. Runs are serial, seeds interleaved across runners, so
that drift of the machine hits every runner alike.

    pip install -r benchmarks/requirements.txt     # adds stable-baselines3
    python benchmarks/bench_cartpole.py ppo_cartpole sb3_ppo
    python benchmarks/bench_cartpole.py --all       # every runner below, seeds 0-9
    python benchmarks/bench_cartpole.py reinforce_cartpole reinforce_no_baseline \
        actor_critic_cartpole ppo_cartpole --seeds 5 --out benchmarks/results/reinforce_cartpole.json

The targets the project holds itself to are checked at the end and printed as
PASS/FAIL lines; results are also written as JSON to benchmarks/results/.
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

ROOT = Path(__file__).resolve().parent.parent
PY = sys.executable
REINFORCE = ["--episodes-per-update", "4", "--learning-rate", "0.01", "--vf-learning-rate", "0.01",
             "--gamma", "0.99", "--hidden", "128"]
# Each runner: the command for one seed. Our scripts skip the GIFs and the curve and evaluate
# one episode: all of it comes after the solved line and never counts in the timing.
RUNNERS = {
    "ppo_cartpole": lambda seed, out: [PY, str(ROOT / "ppo_cartpole.py"), "--seed", str(seed), "--run-dir", out,
                                       "--no-gifs", "--no-curves", "--eval-episodes", "1"],
    "ppo_kl_cartpole": lambda seed, out: [PY, str(ROOT / "ppo_kl_cartpole.py"), "--seed", str(seed), "--run-dir", out,
                                          "--no-gifs", "--no-curves", "--eval-episodes", "1"],
    "actor_critic_cartpole": lambda seed, out: [PY, str(ROOT / "actor_critic_cartpole.py"), "--seed", str(seed),
                                                "--run-dir", out, "--no-gifs", "--no-curves", "--eval-episodes", "1"],
    # REINFORCE's defaults written out (one env, 4 whole episodes a step, Adam 0.01 for pi and
    # V, gamma 0.99, 128 units), so that the record does not lean on them
    "reinforce_cartpole": lambda seed, out: [PY, str(ROOT / "reinforce_cartpole.py"), "--seed", str(seed),
                                             "--run-dir", out, "--no-gifs", "--no-curves", "--eval-episodes", "1",
                                             *REINFORCE, "--baseline"],
    "reinforce_no_baseline": lambda seed, out: [PY, str(ROOT / "reinforce_cartpole.py"), "--seed", str(seed),
                                                "--run-dir", out, "--no-gifs", "--no-curves", "--eval-episodes",
                                                "1", *REINFORCE, "--no-baseline"],
    "episodic_ac": lambda seed, out: [PY, str(ROOT / "benchmarks" / "episodic_ac_cartpole.py"), "--seed", str(seed)],
    "sb3_ppo": lambda seed, out: [PY, str(ROOT / "benchmarks" / "sb3_cartpole.py"), "--algo", "ppo", "--seed", str(seed)],
    "sb3_a2c": lambda seed, out: [PY, str(ROOT / "benchmarks" / "sb3_cartpole.py"), "--algo", "a2c", "--seed", str(seed)],
}
OURS = ("ppo_cartpole", "ppo_kl_cartpole", "actor_critic_cartpole", "reinforce_cartpole",
        "reinforce_no_baseline")
# The targets: (runner, what, limit, relative to). Seconds include torch.optim's one-time
# import of torch._dynamo on the first Adam (1-2 s here), which SB3 pays too.
TARGETS = [
    ("ppo_cartpole", "solved", 10, None),
    ("ppo_cartpole", "median_steps", 16_000, None),
    ("ppo_cartpole", "median_seconds", 0.8, "sb3_ppo"),
    ("ppo_kl_cartpole", "solved", 10, None),
    ("ppo_kl_cartpole", "median_seconds", 0.85, "sb3_ppo"),
    ("actor_critic_cartpole", "solved", 10, None),
    ("actor_critic_cartpole", "median_steps", 40_000, None),
    ("actor_critic_cartpole", "median_seconds", 0.6, "sb3_a2c"),
    ("actor_critic_cartpole", "median_seconds", 1.0, "episodic_ac"),
    ("reinforce_cartpole", "solved", 10, None),
    ("reinforce_no_baseline", "solved", 10, None),
]
SOLVED = re.compile(r"^solved: .* at step (\d+)")


def run_one(cmd, timeout):
    """Run cmd; return (steps, seconds) at its solved line, or (None, None)."""
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    start = time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env, cwd=ROOT)
    steps = seconds = None
    tail = []
    try:
        for line in proc.stdout:
            match = SOLVED.match(line)
            if match and steps is None:
                seconds = time.perf_counter() - start
                steps = int(match.group(1))
            tail = (tail + [line])[-5:]
            if time.perf_counter() - start > timeout:
                proc.kill()
                break
    finally:
        proc.wait()
    if proc.returncode not in (0, None) and steps is None:
        print("".join(tail), file=sys.stderr)
    return steps, seconds


def summarize(runs):
    solved = [r for r in runs if r["steps"] is not None]
    if not solved:
        return dict(solved=0, seeds=len(runs))
    return dict(
        seeds=len(runs), solved=len(solved),
        median_steps=statistics.median(r["steps"] for r in solved),
        worst_steps=max(r["steps"] for r in solved),
        median_seconds=statistics.median(r["seconds"] for r in solved),
        worst_seconds=max(r["seconds"] for r in solved),
    )


def table(path):
    """The rows a results page shows of a committed record (`--table FILE`): per runner, the
    seeds solved, the steps and the seconds to solve as median [min, max]."""
    runs = json.loads((ROOT / path).read_text())["runs"]
    rows = ["| runner | solved | steps to solve, median [min, max] | seconds, median [min, max] |",
            "|---|---|---|---|"]
    for name, seeds in runs.items():
        done = [r for r in seeds if r["steps"] is not None]
        steps, secs = [r["steps"] for r in done], [r["seconds"] for r in done]
        rows.append(f"| {name} | {len(done)}/{len(seeds)} | {statistics.median(steps):,.0f} "
                    f"[{min(steps):,}, {max(steps):,}] | {statistics.median(secs):.1f} "
                    f"[{min(secs):.1f}, {max(secs):.1f}] |" if done else
                    f"| {name} | 0/{len(seeds)} | - | - |")
    return rows


def main():
    if sys.argv[1:2] == ["--table"]:  # python benchmarks/bench_cartpole.py --table FILE
        print("\n".join(table(sys.argv[2])))
        return
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("runners", nargs="*", choices=[[]] + sorted(RUNNERS), help="which runners (default: --all)")
    parser.add_argument("--all", action="store_true", help="every runner")
    parser.add_argument("--seeds", type=int, default=10, help="seeds 0 .. N-1")
    parser.add_argument("--timeout", type=float, default=300, help="seconds before a run counts as unsolved")
    parser.add_argument("--args", default="", help="extra flags for our scripts, e.g. '--num-envs 16'")
    parser.add_argument("--out", default="benchmarks/results/cartpole.json",
                        help="JSON file for the results, relative to the repository")
    args = parser.parse_args()
    names = sorted(RUNNERS) if args.all or not args.runners else args.runners

    results = {name: [] for name in names}
    with tempfile.TemporaryDirectory() as tmp:
        for seed in range(args.seeds):
            for name in names:
                cmd = RUNNERS[name](seed, tmp) + (args.args.split() if name in OURS else [])
                steps, seconds = run_one(cmd, args.timeout)
                results[name].append(dict(seed=seed, steps=steps, seconds=seconds))
                shown = f"{steps} steps, {seconds:.2f}s" if steps else "not solved"
                print(f"seed {seed}  {name:<22} {shown}", flush=True)

    summary = {name: summarize(runs) for name, runs in results.items()}
    print("\n| runner | solved | median steps | worst steps | median s | worst s |\n|---|---|---|---|---|---|")
    for name, s in summary.items():
        if s["solved"]:
            print(f"| {name} | {s['solved']}/{s['seeds']} | {s['median_steps']:,.0f} | {s['worst_steps']:,} "
                  f"| {s['median_seconds']:.2f} | {s['worst_seconds']:.2f} |")
        else:
            print(f"| {name} | 0/{s['seeds']} | - | - | - | - |")

    verdicts = []
    for name, what, limit, peer in TARGETS:
        if name not in summary or (peer and peer not in summary):
            continue
        value = summary[name].get(what)
        if peer:
            base = summary[peer].get(what)
            ratio = value / base if value and base else None
            ok = ratio is not None and ratio <= limit
            text = f"{name} {what} / {peer} = {ratio:.2f} (target <= {limit})" if ratio else f"{name} vs {peer}: n/a"
        elif what == "solved":
            ok = value == limit * args.seeds / 10
            text = f"{name} solved {value}/{args.seeds}"
        else:
            ok = value is not None and value <= limit
            text = f"{name} {what} = {value} (target <= {limit:,})"
        verdicts.append(dict(text=text, ok=ok))
        print(("PASS " if ok else "FAIL ") + text)

    (ROOT / args.out).parent.mkdir(parents=True, exist_ok=True)
    (ROOT / args.out).write_text(json.dumps(dict(runs=results, summary=summary, verdicts=verdicts,
                                              python=sys.version.split()[0], cpus=os.cpu_count()), indent=1))
    print(f"\nwritten: {args.out}")


if __name__ == "__main__":
    main()
