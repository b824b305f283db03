"""The experiments: each variant differs from the original only as its docstring says, the
code it replaces is put back after its runs, and each file runs in its quick mode."""

import sys

import numpy as np
import pytest
import torch

import common
import ppo_cartpole
from conftest import ROOT, run_script

sys.path.insert(0, str(ROOT / "experiments"))
import advantage_normalization  # noqa: E402
import autoreset_not_masked  # noqa: E402
import critic_output_shape  # noqa: E402
import gae_lambda  # noqa: E402
import lab  # noqa: E402
import truncation_as_termination  # noqa: E402

EXPERIMENTS = ("truncation_as_termination", "autoreset_not_masked", "advantage_normalization",
               "gae_lambda", "critic_output_shape")


def rollout(truncate_at=None):
    torch.manual_seed(0)
    T, N = 12, 3
    r, v, nv = torch.rand(T, N), torch.rand(T, N), torch.rand(T, N)
    term = torch.zeros(T, N, dtype=torch.bool)
    term[4, 0] = True
    trunc = torch.zeros(T, N, dtype=torch.bool)
    if truncate_at is not None:
        trunc[truncate_at, 1] = True
    return r, v, nv, term, trunc


def test_gae_variant_equals_common_gae_without_truncations_and_differs_with_one():
    variant = truncation_as_termination.gae_truncation_as_termination
    args = rollout()
    assert torch.equal(variant(*args, 0.99, 0.95), common.gae(*args, 0.99, 0.95))
    args = rollout(truncate_at=6)
    got, want = variant(*args, 0.99, 0.95), common.gae(*args, 0.99, 0.95)
    differs = (got != want).any(0)
    assert differs.tolist() == [False, True, False]  # only the truncated env's column
    # there, exactly the bootstrap is gone: gamma * V(final obs) at the truncated step
    assert got[6, 1] == pytest.approx((want[6, 1] - 0.99 * args[2][6, 1]).item(), rel=1e-6)


def test_store_variant_keeps_the_autoreset_steps_and_nothing_else_changes():
    original, variant = ppo_cartpole.RolloutBuffer(2, 3, 4), ppo_cartpole.RolloutBuffer(2, 3, 4)
    valid = np.array([True, False, True])
    args = (0, np.ones((3, 4)), np.array([0, 1, 0]), np.ones(3), np.zeros(3, bool),
            np.zeros(3, bool))
    original.store(*args, valid=valid)
    autoreset_not_masked.store_without_mask(variant, *args, valid=valid)
    assert original.valid[0].tolist() == [True, False, True]
    assert variant.valid[0].tolist() == [True, True, True]
    for name in ("obs", "actions", "rewards", "terminated", "truncated"):
        assert np.array_equal(getattr(original, name), getattr(variant, name))


def test_advantage_variant_is_only_the_flag():
    (original, variant) = advantage_normalization.VARIANTS.values()
    assert original == {} and variant == {"config": {"norm_adv": False}}


def test_gae_lambda_variants_are_only_the_setting_and_its_ends_are_td_and_returns():
    assert [v.get("config", {}) for v in gae_lambda.VARIANTS.values()] == [
        {}, {"lam": 0.0}, {"lam": 1.0}]
    r, v, last, term, trunc = rollout(truncate_at=6)
    nv = torch.cat([v[1:], last[:1]])  # V(s_{t+1}): the next stored obs's value, as in train()
    delta = r + 0.99 * nv * (~term) - v  # lam = 0: the one-step TD error
    assert torch.allclose(common.gae(r, v, nv, term, trunc, 0.99, 0.0), delta)
    ret = common.discounted_returns(r, nv, term, trunc, 0.99)  # lam = 1: return minus V
    assert torch.allclose(common.gae(r, v, nv, term, trunc, 0.99, 1.0), ret - v, atol=1e-6)


def test_critic_variant_is_the_same_q_with_its_last_dimension_kept():
    """Spinning Up's planted bug: the same numbers, shaped (B, 1); against (B,) targets the
    TD target and the loss broadcast to (B, B)."""
    import ddpg_walker

    torch.manual_seed(0)
    critic = ddpg_walker.Critic(3, 2, 16)
    obs, action = torch.randn(5, 3), torch.randn(5, 2)
    q = critic(obs, action)
    q_variant = critic_output_shape.forward_keeping_its_dimension(critic, obs, action)
    assert q.shape == (5,) and q_variant.shape == (5, 1)
    assert torch.equal(q_variant.squeeze(-1), q)
    y = ddpg_walker.td_target(torch.zeros(5), torch.ones(5), q_variant, 0.99)
    assert y.shape == (5, 5)  # what the variant's critic is then trained toward


def test_swapped_puts_the_original_back_even_after_an_error():
    before = common.gae
    with pytest.raises(RuntimeError):
        with lab.swapped([(common, "gae", lambda *a: None)]):
            assert common.gae is not before
            raise RuntimeError
    assert common.gae is before


@pytest.mark.parametrize("name", EXPERIMENTS)
def test_each_experiment_runs_in_quick_mode(name):
    p = run_script(f"experiments/{name}.py", "--quick", timeout=300)
    assert p.returncode == 0, p.stderr
    lines = p.stdout.splitlines()
    assert any(line.startswith("original") for line in lines)
    assert any(line.startswith("variant") for line in lines)
