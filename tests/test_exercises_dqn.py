"""The exercise of dqn_cartpole.py's loss (exercises/dqn_loss.py): typical wrong answers each fail
stage (a) with their mistake named, right answers written otherwise pass (a) and (b), and stage
(b)'s loop has TD errors past 1, so that it tells the halved squared error from the Huber loss
on real data. The blank and the script's own function through (a) and (b) are
tests/test_exercises.py's, which finds every exercise."""

import sys
import textwrap

import pytest

from conftest import ROOT

sys.path.insert(0, str(ROOT / "exercises"))
import check  # noqa: E402
import checking  # noqa: E402
from test_exercises import english, run  # noqa: E402,F401  (english: an autouse fixture)

HEADER = """
import torch
import torch.nn.functional as F
"""
Q = "q = q_net(obs).gather(-1, action[:, None]).squeeze(-1)"


def answer(loss, q=Q):
    """compute_loss_q with `q` (Q(s, a)) and `loss` written where the blank is."""
    namespace = {}
    body = f"{q}\nreturn {loss}, q\n"
    exec(HEADER + "def compute_loss_q(q_net, obs, action, y):\n" + textwrap.indent(body, "    "),
         namespace)
    return namespace["compute_loss_q"]


EXACTLY = "this is exactly what this mistake gives: "
HUBER = "torch.where((q - y).abs() <= 1, {}, {}).mean()"
WRONG = [  # (loss, q, words the stage (a) message must hold)
    ("F.mse_loss(q, y)", Q, EXACTLY + "the squared error (MSE, F.mse_loss)"),
    ("0.5 * ((q - y) ** 2).mean()", Q, EXACTLY + "the halved squared error 0.5 x^2 everywhere"),
    (HUBER.format("(q - y) ** 2", "(q - y).abs() - 0.5"), Q,
     EXACTLY + "Huber's quadratic part without its 1/2"),
    (HUBER.format("0.5 * (q - y) ** 2", "(q - y).abs()"), Q,
     EXACTLY + "Huber's linear part without its - 0.5"),
    ("F.l1_loss(q, y)", Q, EXACTLY + "the absolute error |x| (L1, F.l1_loss)"),
    ("(0.5 * (q - y).clamp(-1, 1) ** 2).mean()", Q,
     EXACTLY + "the error clipped, not its gradient: 0.5 * clamp"),
    ("((q - y).clamp(-1, 1) ** 2).mean()", Q,
     EXACTLY + "the error clipped, not its gradient, and not halved"),
    ("F.smooth_l1_loss(q, y, reduction='sum')", Q, EXACTLY + "a sum over the batch"),
    ("F.smooth_l1_loss(q, y)", "q = q_net(obs).gather(-1, action[:, None])",
     EXACTLY + "Q(s, a) as (B, 1)"),
    ("F.smooth_l1_loss(q, y[:, None])", Q, EXACTLY + "Q(s, a) as (B, 1)"),
    ("F.smooth_l1_loss(q, y)", "q = q_net(obs).max(-1).values",
     EXACTLY + "max_a Q(s, a) where Q(s, a) of the action taken belongs"),
    ("F.smooth_l1_loss(q, y)", Q + ".detach()", "this is exactly what this mistake does: Q(s, a) "
                                                "computed without a gradient"),
    ("F.smooth_l1_loss(q, y)", "q = q_net(obs).gather(-1, action)",
     "this is exactly what this mistake raises: gather(-1, action) with action (B,)"),
]


@pytest.mark.quick
@pytest.mark.parametrize("index", range(len(WRONG)))
def test_a_wrong_answer_fails_stage_a_and_its_mistake_is_named(index):
    loss, q, needle = WRONG[index]
    passed, lines = run("dqn_loss", answer(loss, q))
    assert not passed and lines[-1].startswith("dqn_loss: (a)"), lines
    assert needle in lines[-1], lines[-1]


RIGHT = [  # right answers written otherwise than the script: (a) and (b) pass
    "F.huber_loss(q, y)",
    "F.smooth_l1_loss(y, q)",
    HUBER.format("0.5 * (q - y) ** 2", "(q - y).abs() - 0.5"),
]


@pytest.mark.parametrize("loss", RIGHT)
def test_a_right_answer_written_otherwise_passes_a_and_b(loss):
    passed, lines = run("dqn_loss", answer(loss))
    assert passed, lines


def test_stage_b_tells_the_halved_square_from_the_huber_loss():
    """The loop's first gradient step already has TD errors past 1: the halved squared error,
    past stage (a) unseen, differs there."""
    with pytest.raises(checking.Failed, match="first differ at gradient step 1, in loss"):
        check.real_loop(check.EXERCISES["dqn_loss"], answer("0.5 * ((q - y) ** 2).mean()"))
