"""An answer that raises gets one line, in the learner's language: where (the exercise's file
and line), the likely cause (a shape, an in-place operation, a dtype, a device) or, for any
other error, what Python raised there; never a traceback."""

import sys
import textwrap

import pytest

from conftest import ROOT

sys.path.insert(0, str(ROOT / "exercises"))
import check  # noqa: E402
import checking  # noqa: E402
from test_exercises import HEADER, english, run  # noqa: E402, F401

TD = "def td_target(reward, not_done, next_q, gamma):\n    return {}\n"

# (exercise, answer, words its one line must hold: the file's line, then the cause)
RAISING = {
    "shape": ("grpo_loss", """def grpo_loss(logp, logp_old, logp_ref, adv, mask, cfg):
    ratio, eps = torch.exp(logp - logp_old), cfg.clip_coef
    surrogate = torch.min(ratio * adv, torch.clamp(ratio, 1 - eps, 1 + eps) * adv)  # adv: (B,)
    return -surrogate.mean(), {}
""", "line 3 (surrogate = torch.min(ratio * adv,", "a shape error: two tensors whose shapes"),
    "in-place": ("clipped_surrogate", """def compute_loss_pi(policy, data, clip_coef):
    dist = Categorical(logits=policy(data["obs"]))
    ratio = torch.exp(dist.log_prob(data["act"]) - data["logp"])
    clipped = torch.clamp(ratio, 1 - clip_coef, 1 + clip_coef) * data["adv"]
    ratio *= data["adv"]  # in place: exp's backward needs its output
    return -torch.min(ratio, clipped).mean(), dist.entropy().mean(), {}
""", "in the gradient of what clipped_surrogate.py returned", "an in-place operation (+="),
    "dtype": ("td_target", """def td_target(reward, not_done, next_q, gamma):
    y = torch.zeros_like(reward, dtype=torch.long)  # a float result cannot go into it
    y += reward + gamma * not_done * next_q
    return y
""", "line 3 (y += reward", "a dtype error: tensors of different types"),
    "device": ("td_target", TD.format("reward + gamma * not_done * next_q.to('meta')"),
               "line 2 (return reward", "a device error: tensors on different devices"),
    "none": ("td_target", TD.format("reward + None * not_done * next_q"),
             "line 2 (return reward", "a None where a number belongs"),
    "twice": ("td_target", TD.format("(lambda y: (y.sum().backward(), y.sum().backward(), y)[2])"
                                     "(reward.detach().requires_grad_().exp())"),
              "line 2 (return (lambda y", "a graph backpropagated twice"),
    "or": ("td_target", TD.format("reward + gamma * (not_done or next_q)"),
           "line 2 (return reward", "where Python wants one truth value"),
    "if": ("td_target", TD.format("reward + gamma * next_q if not_done else reward"),
           "line 2 (return reward", "torch.where(cond, a, b) for an `if`"),
    "name": ("td_target", TD.format("rewrad + gamma * not_done * next_q"),
             "your code raised NameError at td_target.py line 2 (return rewrad",
             "name 'rewrad' is not defined"),
    "type": ("td_target", TD.format("reward + gamma * not_done * next_q(0)"),
             "your code raised TypeError at td_target.py line 2 (return reward",
             "'Tensor' object is not callable"),
    "index": ("td_target", TD.format("reward + gamma * not_done * next_q[len(next_q)]"),
              "line 2 (return reward", "an index past the end"),
    # torch's own NotImplementedError is the answer's error, not the blank's "not written yet"
    "not-implemented": ("td_target", TD.format(
        "reward + gamma * not_done * kl_divergence(next_q, next_q)"),
        "your code raised NotImplementedError at td_target.py line 2", "No KL(p || q)"),
}


def load(tmp_path, name, source):
    """The answer as the learner's file would hold it, loaded as the checker loads one."""
    path = tmp_path / f"{name}.py"
    path.write_text(HEADER + textwrap.dedent(source))
    return check.load(name, path), HEADER.count("\n")


@pytest.mark.quick
@pytest.mark.parametrize("cause", RAISING)
def test_an_answer_that_raises_gets_one_line_naming_the_cause(cause, tmp_path):
    name, source, where, words = RAISING[cause]
    fn, offset = load(tmp_path, name, source)
    passed, lines = run(name, fn)
    assert not passed, lines
    where = where.replace("line 2", f"line {2 + offset}").replace("line 3", f"line {3 + offset}")
    last = lines[-1]
    assert where in last and words in last, last
    assert "Traceback" not in last and 'File "' not in last, last
    assert "\n" not in last.split("\n  ")[-1], last  # the error's own line is one line


@pytest.mark.quick
def test_the_cause_in_chinese(tmp_path):
    checking.LANG = "zh"
    name, source, _, _ = RAISING["shape"]
    fn, offset = load(tmp_path, name, source)
    passed, lines = run(name, fn)
    assert f"你的代码抛出了 RuntimeError（grpo_loss.py 第 {3 + offset} 行：" in lines[-1], lines
    assert "形状错误" in lines[-1], lines


@pytest.mark.quick
def test_a_passing_learning_stage_ends_in_one_line(monkeypatch):
    """Stage (c)'s verdict is one line: train()'s result is not printed."""
    monkeypatch.setattr(check, "real_loop", lambda ex, fn: None)
    monkeypatch.setattr(check, "learns", lambda ex, fn: {"returns": [500.0] * 20, "run_dir": "x"})
    ex = check.EXERCISES["td_target"]
    lines = []
    assert check.check("td_target", fn=getattr(ex.owner(), ex.function), say=lines.append)
    assert len(lines) == 3 and lines[-1].startswith("td_target: (c) learning: pass (")
    assert lines[-1].endswith(" s)") and "\n" not in lines[-1], lines


@pytest.mark.quick
def test_a_run_that_fell_short_by_rounding_passes_in_one_line(monkeypatch):
    """Where the learner's run fell short but matched the script's own at every call, stage
    (c) passes with a note, still on one line."""
    monkeypatch.setattr(check, "real_loop", lambda ex, fn: None)
    runs_of = iter([check.Failed("the last 2 evaluations are 85, 135, not all 1000\nmore"),
                    None])

    def learning_run(ex, fn):
        outcome = next(runs_of)
        if outcome is not None:
            raise outcome
        return {}
    monkeypatch.setattr(check, "learning_run", learning_run)
    ex = check.EXERCISES["td_target"]
    lines = []
    assert check.check("td_target", fn=getattr(ex.owner(), ex.function), say=lines.append)
    assert lines[-1].startswith("td_target: (c) learning: pass (") and "fell short" in lines[-1]
    assert "\n" not in lines[-1], lines[-1]
