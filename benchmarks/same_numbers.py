"""Same numbers? Run the scripts at fixed seeds and short budgets twice, once from a given
git revision and once from the working tree as it is now, and compare the logs they write
(progress.csv, episodes.csv, evaluations.csv) byte for byte.

A change that only moves code around (a refactor, a comment, a rename) must print SAME for
every file. A log may gain columns at its end: the old columns must then be the same, value
for value, and the line names the new ones. Runs are serial, on the CPU, with one torch thread: same seed, same machine =>
same bytes. A case whose flags one of the two revisions lacks is skipped, with a line.

    python benchmarks/same_numbers.py                  # against HEAD (about 20 min on 2 cores)
    python benchmarks/same_numbers.py 070180b          # against any commit, tag or branch
    python benchmarks/same_numbers.py HEAD~3 --only ppo   # only the cases whose name has "ppo"
    python benchmarks/same_numbers.py /tmp/before      # against a copy of the scripts' folder

Prints SAME or DIFFERENT per file, and exits 1 if any file differs or is missing on one side.
"""

import argparse
import csv
import filecmp
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
LOGS = ("progress.csv", "episodes.csv", "evaluations.csv")
CARTPOLE = ["--total-timesteps", "20000", "--eval-episodes", "3", "--no-gifs", "--no-curves"]
# name: (script, flags). The CartPole budget is about where PPO solves: the solved check runs.
CASES = {
    **{f"{script}_seed{seed}": (f"{script}.py", ["--seed", str(seed), *CARTPOLE])
       for script in ("ppo_cartpole", "ppo_kl_cartpole", "actor_critic_cartpole")
       for seed in (0, 1, 2)},
    "ppo_cartpole_target_kl": ("ppo_cartpole.py", ["--seed", "0", "--target-kl", "0.01",
                                                   *CARTPOLE]),
    "ddpg_walker_pendulum": ("ddpg_walker.py", [
        "--env-id", "InvertedPendulum-v5", "--total-timesteps", "3000", "--start-steps", "1000",
        "--eval-every", "1000", "--eval-episodes", "2", "--no-gifs", "--no-cuda"]),
    # Walker2d past the 25k-step warm-up: 5000 steps of learning, evaluated at 5k and 30k
    "ddpg_walker_walker2d": ("ddpg_walker.py", [
        "--total-timesteps", "30000", "--eval-episodes", "2", "--no-gifs", "--no-cuda"]),
    # TD3 the same way: its 1M runs go on from a frozen commit, valid while these stay SAME
    "td3_walker_pendulum": ("td3_walker.py", [
        "--env-id", "InvertedPendulum-v5", "--total-timesteps", "3000", "--start-steps", "1000",
        "--eval-every", "1000", "--eval-episodes", "2", "--no-gifs", "--no-cuda"]),
    "td3_walker_walker2d": ("td3_walker.py", [
        "--total-timesteps", "30000", "--eval-episodes", "2", "--no-gifs", "--no-cuda"]),
    # DQN past its warm-up: learning phases, Q checks and the target's copies, both targets
    **{f"dqn_cartpole{flag}": ("dqn_cartpole.py", [
        "--seed", "0", "--total-timesteps", "6000", *([flag] if flag else []),
        "--eval-episodes", "3", "--no-gifs", "--no-curves"]) for flag in ("", "--double")},
    # where the path begins: REINFORCE with and without its baseline, both tabular agents
    **{f"reinforce_cartpole{flag}": ("reinforce_cartpole.py", ["--seed", "0", *CARTPOLE,
                                                               *([flag] if flag else [])])
       for flag in ("", "--no-baseline")},
    "q_learning_cliffwalking": ("q_learning_cliffwalking.py", [
        "--seed", "0", "--total-episodes", "200", "--no-gifs", "--no-curves"]),
    # the language-model scripts: every phase, a few steps each
    "grpo_addition_short": ("grpo_addition.py", [
        "--digits", "1", "--sft-steps", "30", "--grpo-steps", "10", "--eval-prompts", "50",
        "--no-curves"]),
    "rlhf_addition_short": ("rlhf_addition.py", [
        "--digits", "1", "--sft-steps", "30", "--rm-epochs", "1", "--ppo-steps", "4",
        "--eval-prompts", "50", "--no-curves"]),
    # SAC the same way: its long runs go on from a frozen commit too
    "sac_walker_pendulum": ("sac_walker.py", [
        "--env-id", "InvertedPendulum-v5", "--total-timesteps", "3000", "--start-steps", "1000",
        "--eval-every", "1000", "--eval-episodes", "2", "--no-gifs", "--no-cuda"]),
    "sac_walker_walker2d": ("sac_walker.py", [
        "--total-timesteps", "30000", "--eval-episodes", "2", "--no-gifs", "--no-cuda"]),
}


def flags_known(tree, script, flags):
    """Does `script` in `tree` take every --flag in `flags` (read from its --help)?"""
    help_text = subprocess.run([sys.executable, script, "--help"], cwd=tree,
                               capture_output=True, text=True).stdout
    return all(f in help_text for f in flags if f.startswith("--"))


def run(tree, script, flags, out):
    """Run `script` from `tree` with its run folders under `out`; return the run folder."""
    done = subprocess.run([sys.executable, script, *flags, "--run-dir", str(out)], cwd=tree,
                          capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit(f"{script} {' '.join(flags)} failed in {tree}:\n{done.stderr[-2000:]}")
    (run_dir,) = Path(out).iterdir()  # one run, one folder
    return run_dir


# Columns renamed since (old name: new name): the same values under a name that says what
# they hold (the solved rule's window is a setting, no longer always 20).
RENAMED = {"return_mean20": "recent_return"}


def same_old_columns(a, b):
    """(same, new columns): every column of the older log `a` is in `b` (under its RENAMED
    name) with the same values, row for row; columns that only `b` has are new."""
    rows_a, rows_b = (list(csv.DictReader(open(path))) for path in (a, b))
    rows_a = [{RENAMED.get(k, k): v for k, v in row.items()} for row in rows_a]
    header_a = list(rows_a[0]) if rows_a else []
    header_b = list(rows_b[0]) if rows_b else []
    same = (len(rows_a) == len(rows_b) and header_b[:len(header_a)] == header_a
            and all(x[k] == y[k] for x, y in zip(rows_a, rows_b) for k in header_a))
    return same, header_b[len(header_a):]


def columns_that_differ(a, b):
    """Which columns of two CSV logs differ: a few words for the DIFFERENT line."""
    rows_a, rows_b = (list(csv.DictReader(open(path))) for path in (a, b))
    if len(rows_a) != len(rows_b) or rows_a and list(rows_a[0]) != list(rows_b[0]):
        return "rows or columns differ"
    header = list(rows_a[0]) if rows_a else []
    changed = [k for k in header if any(x[k] != y[k] for x, y in zip(rows_a, rows_b))]
    return "columns: " + ", ".join(changed)


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("rev", nargs="?", default="HEAD",
                        help="the git revision to compare with, or a folder holding the scripts")
    parser.add_argument("--only", default="", help="only the cases whose name contains this")
    args = parser.parse_args()
    differ, folder = 0, Path(args.rev).is_dir()
    with tempfile.TemporaryDirectory(prefix="same_numbers_") as tmp:
        if folder:
            old_tree = commit = Path(args.rev).resolve()
        else:  # a temporary checkout of the revision, removed at the end
            commit = subprocess.run(["git", "rev-parse", "--short", args.rev], cwd=ROOT,
                                    text=True, capture_output=True, check=True).stdout.strip()
            old_tree = Path(tmp) / "old_tree"
            subprocess.run(["git", "worktree", "add", "--detach", "-q", str(old_tree), commit],
                           cwd=ROOT, check=True)
        try:
            for name, (script, flags) in CASES.items():
                if args.only not in name:
                    continue
                if not all(flags_known(tree, script, flags) for tree in (old_tree, ROOT)):
                    print(f"{name}: skipped, a flag is missing at {commit} or now", flush=True)
                    continue
                old = run(old_tree, script, flags, Path(tmp) / name / "old")
                new = run(ROOT, script, flags, Path(tmp) / name / "new")
                for log in LOGS:
                    a, b = old / log, new / log
                    if not a.exists() and not b.exists():
                        continue
                    same = a.exists() and b.exists() and filecmp.cmp(a, b, shallow=False)
                    added = []
                    if not same and a.exists() and b.exists():  # the same, but for new columns?
                        same, added = same_old_columns(a, b)
                    differ += not same
                    verdict = "SAME" if same else "DIFFERENT"
                    if same and added:
                        verdict += f" (and new columns: {', '.join(added)})"
                    if not same and a.exists() and b.exists():
                        verdict += f" ({columns_that_differ(a, b)})"
                    print(f"{name:28} {log:16} {verdict}", flush=True)
        finally:
            if not folder:
                subprocess.run(["git", "worktree", "remove", "--force", str(old_tree)], cwd=ROOT)
    print(f"{'all SAME' if not differ else f'{differ} DIFFERENT'} (working tree vs {commit})")
    sys.exit(1 if differ else 0)


if __name__ == "__main__":
    main()
