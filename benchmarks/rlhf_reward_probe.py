"""What did the reward model learn? Its scores of hand-made answers to the 500 held-out sums
(docs/ppo_to_rlhf.md, "Reward hacking"): the right sum, the sum with its carry wrong (what
the supervised model gets wrong, so what the preference pairs show), and the sum with its
ones digit one off (an error the supervised model hardly makes, so the pairs hardly show).
The judge scores the ones digit off 0.75 on every sum, the carry wrong 0.75 on most and 0.5
where the carry also reaches the hundreds digit (55+48=093.; 53 of the 500 held-out sums).

    python benchmarks/rlhf_reward_probe.py RUN_DIR     # a finished rlhf_addition.py run
"""

import sys
from pathlib import Path

import numpy as np
import torch

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
import checkpoints  # noqa: E402
import rlhf_addition as rlhf  # noqa: E402


def main():
    run = sys.argv[1]
    saved = checkpoints.load_checkpoint(run, script=rlhf.SCRIPT, required=("reward_model",))
    c = rlhf.Config(**{**saved["config"], "eval": None})
    rm = rlhf.with_scalar_head(rlhf.TinyGPT(c.n_layer, c.d_model, c.n_head, 3 * c.digits + 4),
                               c.d_model)
    rm.load_state_dict(saved["reward_model"])
    _, held = rlhf.split_pairs(c.digits, c.eval_prompts, np.random.default_rng(c.seed))

    def score(answer):
        seqs = torch.tensor([rlhf.encode(rlhf.prompt_of(a, b, c.digits) + answer(a, b))
                             for a, b in held])
        with torch.no_grad():
            return rlhf.sequence_score(rm, seqs, 2 * c.digits + 2)

    def ones_off(d):
        return lambda a, b: (lambda s: s[:-2] + str((int(s[-2]) + d) % 10) + ".")(
            rlhf.label_of(a, b, c.digits))

    right = score(lambda a, b: rlhf.label_of(a, b, c.digits))
    carry = score(lambda a, b: rlhf.label_of(a, b, c.digits, wrong=True))
    plus, minus = score(ones_off(1)), score(ones_off(-1))
    print(f"{run}, seed {c.seed}, {len(held)} held-out sums: the share of sums on which the "
          "reward model scores")
    for name, a, b in (("the right sum above its carry-wrong answer", right, carry),
                       ("the right sum above the ones digit + 1", right, plus),
                       ("the right sum above the ones digit - 1", right, minus)):
        print(f"  {name}: {(a > b).float().mean().item():.3f}")


if __name__ == "__main__":
    main()
