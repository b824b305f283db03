"""A wrong answer that no listed mistake gives is still named where its numbers alone say what it
is: the right values in another shape or in reverse time order, a (B, 1) broadcast against a
(B,), the right result with its sign flipped or times a whole number (or one over one); and a
gradient that is cut or sent where none belongs says which input. Each is a fact about the
answer's numbers, so it never names another mistake; a number that is merely wrong gets none."""

import sys

import pytest
import torch

from conftest import ROOT

sys.path.insert(0, str(ROOT / "exercises"))
import checking  # noqa: E402
from test_exercises import compile_answer, english, run  # noqa: E402, F401

EXPECTED = torch.tensor([[1.5, 2.0], [1.0, -3.0], [0.5, 4.0]])


@pytest.mark.quick
@pytest.mark.parametrize("got,words", [
    (EXPECTED.reshape(2, 3), "the right values in the shape (2, 3): flatten"),
    (EXPECTED.flip(0), "reverse order along the first axis (time)"),
    (-EXPECTED, "the right result with its sign flipped"),
    (EXPECTED / 3, "1/3 times the right result everywhere"),
    (EXPECTED * 2, "2 times the right result everywhere"),
])
def test_an_effect_plain_from_the_numbers_is_named(got, words):
    assert words in checking.effect(got, EXPECTED)


@pytest.mark.quick
def test_a_broadcast_to_b_by_b_is_named_and_a_number_merely_wrong_is_not():
    y = torch.tensor([1.0, 2.0, 3.0])
    assert "broadcast to (B, B)" in checking.effect(y[:, None] + y, y)
    wrong = EXPECTED.clone()
    wrong[1, 1] = 7.0  # one entry off: no pattern
    assert checking.effect(wrong, EXPECTED) == ""
    assert checking.effect(torch.tensor(0.7), torch.tensor(0.3)) == ""  # any factor: not said
    assert checking.effect(torch.tensor(0.6), torch.tensor(0.3)) != ""  # 2 exactly: said
    assert checking.effect(EXPECTED + 0.25, EXPECTED) == ""  # a shift: swapped terms give one


@pytest.mark.quick
@pytest.mark.parametrize("name,source,words", [
    ("a2c_targets", """def a2c_targets(model, rollout, next_obs, cfg):  # V with its graph
    _, values = model(rollout["obs"])
    _, last = model(torch.as_tensor(next_obs, dtype=torch.float32))
    next_values = torch.cat([values[1:], last[None]])
    if cfg.lam is None:
        returns = common.discounted_returns(rollout["rewards"], next_values,
                                            rollout["terminated"], rollout["truncated"],
                                            cfg.gamma)
        return returns, returns - values
    advantages = common.gae(rollout["rewards"], values, next_values, rollout["terminated"],
                            rollout["truncated"], cfg.gamma, cfg.lam)
    return advantages + values, advantages
""", "V computed with its graph"),
    ("gae", """def gae(rewards, values, next_values, terminated, truncated, gamma, lam):
    not_done = 1.0 - terminated.float()
    cut = 1.0 - (terminated | truncated).float()
    delta = rewards + gamma * next_values * not_done - values
    adv, running = torch.zeros_like(rewards), torch.zeros_like(rewards[0])
    for t in range(len(rewards)):  # forward: the wrong way round
        running = delta[t] + gamma * lam * cut[t] * running
        adv[t] = running
    return adv
""", "this is exactly what this mistake gives"),
])
def test_a_wrong_answer_named_by_its_effect(name, source, words):
    passed, lines = run(name, compile_answer("import common\n" + source, name))
    assert not passed and words in lines[-1], lines[-1]
    assert "Traceback" not in "\n".join(lines)
