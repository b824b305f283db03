"""What inside.png and its logged numbers cost: the same runs from a git revision without them
and from the working tree, interleaved (old, new, old, new, ...) so that both see the same
machine, compared by their medians.

    python benchmarks/inside_cost.py a540a5d            # the revision before inside.png
    python benchmarks/inside_cost.py a540a5d --pairs 7

Measured: the wall time of a default `python ppo_cartpole.py` and `python
actor_critic_cartpole.py` (imports, training, evaluation, GIFs, pictures: what a user waits),
and DDPG's learning-phase steps/s (its own report, evaluations included) on a short
InvertedPendulum run that evaluates every 2000 steps, more often than the default 5000.
"""

import argparse
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
CASES = {
    "ppo_cartpole (s)": ["ppo_cartpole.py"],
    "actor_critic_cartpole (s)": ["actor_critic_cartpole.py"],
    "ddpg_walker InvertedPendulum (steps/s)": [
        "ddpg_walker.py", "--env-id", "InvertedPendulum-v5", "--total-timesteps", "10000",
        "--start-steps", "1000", "--eval-every", "2000", "--no-gifs"],
}


def run(tree, args, out):
    """Seconds of the whole process, or DDPG's learning steps/s."""
    started = time.time()
    done = subprocess.run([sys.executable, *args, "--run-dir", str(out)], cwd=tree,
                          capture_output=True, text=True, check=True)
    seconds = time.time() - started
    rate = re.search(r"learning phase: \d+ steps at ([\d.]+) steps/s", done.stdout)
    return float(rate.group(1)) if rate else seconds


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("rev", help="the revision to compare with (before inside.png)")
    parser.add_argument("--pairs", type=int, default=5, help="interleaved runs of each side")
    parser.add_argument("--only", default="", help="only the cases whose name has this")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="inside_cost_") as tmp:
        old_tree = Path(tmp) / "old_tree"
        subprocess.run(["git", "worktree", "add", "--detach", "-q", str(old_tree), args.rev],
                       cwd=ROOT, check=True)
        try:
            for name, case in CASES.items():
                if args.only not in name:
                    continue
                old, new = [], []
                for i in range(args.pairs):
                    old.append(run(old_tree, case, Path(tmp) / f"o{name}{i}"))
                    new.append(run(ROOT, case, Path(tmp) / f"n{name}{i}"))
                a, b = statistics.median(old), statistics.median(new)
                cost = (b / a - 1) if name.endswith("(s)") else (a / b - 1)
                print(f"{name:40} before {a:8.2f}  now {b:8.2f}  cost {cost:+.1%}  "
                      f"(medians of {args.pairs}; before {sorted(old)}, now {sorted(new)})",
                      flush=True)
        finally:
            subprocess.run(["git", "worktree", "remove", "--force", str(old_tree)], cwd=ROOT)


if __name__ == "__main__":
    main()
