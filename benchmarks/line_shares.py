"""How much of each script is algorithm? Counts non-blank lines in three kinds:

    algorithm        networks, buffer, losses, update, and in train() the setup (seeds, envs,
                     networks, optimizers) and the loop's act/collect/store/learn lines, with
                     their comments and docstrings; the module docstring (what the loop does)
    hyperparameters  the fields of the script's Config
    plumbing         the rest: imports, section banners, Config.__post_init__ (flag checks),
                     train()'s docstring and every statement in it that calls the run's log or
                     the tools (runlog, report, checkpoints, cli), with what it holds (e.g. the
                     solved stop's break), main()

    python benchmarks/line_shares.py            # the four scripts
"""

import ast
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SCRIPTS = ("ppo_cartpole.py", "ppo_kl_cartpole.py", "actor_critic_cartpole.py", "ddpg_walker.py",
           "td3_walker.py", "grpo_addition.py", "rlhf_addition.py")
ALGORITHM_DEFS = ("layer_init", "PolicyNetwork", "ValueNetwork", "ActorCritic", "Actor", "Critic",
                  "RolloutBuffer", "ReplayBuffer", "compute_loss_pi", "compute_loss_v", "approx_kl",
                  "adapt_beta", "ppo_update", "a2c_targets", "a2c_loss", "soft_update", "td_target",
                  "compute_loss_actor", "ddpg_update", "build", "update_critics",
                  "update_actor_and_targets", "encode", "decode", "Block", "TinyGPT", "prompt_of",
                  "answer_of", "reward", "split_pairs", "sample", "completion_mask", "token_logp",
                  "group_advantages", "grpo_loss", "sft_loss", "evaluate", "with_scalar_head",
                  "label_of", "true_score", "scores_of", "preference_pairs", "sequence_score",
                  "bradley_terry_loss", "answer_logp", "dpo_loss", "per_token_rewards",
                  "token_advantages", "ppo_token_loss", "fit_on_pairs", "supervised_batch")
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
        if node.name in ALGORITHM_DEFS:
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
    return len(lines), counts, train.end_lineno - train.lineno + 1


def main():
    if {"-h", "--help"} & set(sys.argv[1:]):
        print(__doc__.strip())
        return
    print(f"{'script':26} {'lines':>5} {'non-blank':>9} {'algorithm':>10} {'hyperparams':>11} "
          f"{'plumbing':>9} {'train()':>8}")
    for name in sys.argv[1:] or SCRIPTS:
        total, c, train = shares(ROOT / name)
        n = sum(c.values())
        algorithm, hyper, plumbing = (c[k] / n for k in ("algorithm", "hyperparameters", "plumbing"))
        print(f"{name:26} {total:5} {n:9} {algorithm:9.1%} {hyper:11.1%} {plumbing:9.1%} {train:8}")


if __name__ == "__main__":
    main()
