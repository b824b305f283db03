"""How much of each script is algorithm? Counts non-blank lines in three kinds:

    algorithm        networks, buffer, losses, update, and in train() the setup (seeds, envs,
                     networks, optimizers) and the loop's act/collect/store/learn lines, with
                     their comments and docstrings; the module docstring (what the loop does)
    hyperparameters  the fields of the script's Config
    plumbing         the rest: imports, section banners, Config.__post_init__ (flag checks),
                     train()'s docstring and every statement in it that calls the run's log or
                     the tools (runlog, report, checkpoints, cli), with what it holds (e.g. the
                     solved stop's break), main()

    python benchmarks/line_shares.py            # every script (a top-level *.py with a train())
    python benchmarks/line_shares.py sac_walker.py   # one
    python benchmarks/line_shares.py --show dqn_cartpole.py   # each line marked a, h or p
"""

import ast
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
# The scripts, found as the tests find them: every top-level *.py with a train().
SCRIPTS = sorted(p.name for p in ROOT.glob("*.py") if "\ndef train(" in p.read_text("utf-8"))
# A script's top-level functions and classes are algorithm, but: main (the command line),
# train (classified line by line), Config (its fields are the hyperparameters), and those
# that draw or log (a def that calls the run's log, a tool or matplotlib, or is named so).
NOT_ALGORITHM = ("main", "pictures", "draw")
DRAWS_OR_LOGS = r"\b(run|plt|fig|ax)\b\.|\b(runlog|report|checkpoints|cli|plots)\."
# In train(), a statement is plumbing when it calls the run's log or plumbing (a compound one:
# when its first line does, and then all it holds); comment lines that name them are too.
PLUMBING_IN_TRAIN = re.compile(r"\b(run|ctrl_c|in_checkpoint)\b|\b(runlog|report|checkpoints|cli)\."
                               r"|envs?\.close\(\)")


def train_kinds(train, lines, kind):
    """Mark the lines of train() as algorithm or plumbing, statement by statement."""
    body_start = train.body[0].end_lineno  # after the docstring
    for i in range(train.lineno - 1, train.end_lineno):
        plumbing = i < body_start or PLUMBING_IN_TRAIN.search(lines[i])
        kind[i] = "plumbing" if plumbing else "algorithm"

    def visit(statements, inside_plumbing):
        for node in statements:
            compound = hasattr(node, "body")
            head = node.lineno - 1
            last = (node.body[0].lineno - 2) if compound else node.end_lineno - 1
            text = "\n".join(lines[head:last + 1])
            plumbing = inside_plumbing or bool(PLUMBING_IN_TRAIN.search(text))
            for i in range(head, last + 1):
                kind[i] = "plumbing" if plumbing else "algorithm"
            if compound:
                visit(node.body, plumbing and not isinstance(node, ast.With))
                visit(getattr(node, "orelse", []), plumbing)

    visit(train.body[1:], False)


def shares(path):
    lines = path.read_text(encoding="utf-8").splitlines()
    kind = ["plumbing"] * len(lines)
    tree = ast.parse("\n".join(lines))
    doc = tree.body[0]
    for i in range(doc.lineno - 1, doc.end_lineno):
        kind[i] = "algorithm"
    for node in tree.body:
        if not isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            continue
        span = range(node.lineno - 1 - len(node.decorator_list), node.end_lineno)
        source = "\n".join(lines[node.lineno - 1:node.end_lineno])
        if node.name not in NOT_ALGORITHM + ("Config", "train") and not (
                isinstance(node, ast.FunctionDef) and re.search(DRAWS_OR_LOGS, source)):
            for i in span:
                kind[i] = "algorithm"
        elif node.name == "Config":
            post = next(n for n in node.body if getattr(n, "name", "") == "__post_init__")
            for i in span:
                kind[i] = "plumbing" if i >= post.lineno - 1 else "hyperparameters"
        elif node.name == "train":
            train_kinds(node, lines, kind)
    counts = {"algorithm": 0, "hyperparameters": 0, "plumbing": 0}
    for line, k in zip(lines, kind):
        if line.strip():
            counts[k] += 1
    train = next(n for n in tree.body if getattr(n, "name", "") == "train")
    return len(lines), counts, train.end_lineno - train.lineno + 1, kind


def main():
    if {"-h", "--help"} & set(sys.argv[1:]):
        print(__doc__.strip())
        return
    print(f"{'script':26} {'lines':>5} {'non-blank':>9} {'algorithm':>10} {'hyperparams':>11} "
          f"{'plumbing':>9} {'train()':>8}")
    show = "--show" in sys.argv
    for name in [a for a in sys.argv[1:] if a != "--show"] or SCRIPTS:
        total, c, train, kind = shares(ROOT / name)
        if show:  # each line with its kind's initial (a, h or p), to see what is counted how
            text = (ROOT / name).read_text(encoding="utf-8").splitlines()
            for i, (line, k) in enumerate(zip(text, kind), 1):
                print(f"{k[0] if line.strip() else ' '} {i:4} {line}")
        n = sum(c.values())
        algorithm, hyper, plumbing = (c[k] / n for k in ("algorithm", "hyperparameters", "plumbing"))
        print(f"{name:26} {total:5} {n:9} {algorithm:9.1%} {hyper:11.1%} {plumbing:9.1%} {train:8}")


if __name__ == "__main__":
    main()
