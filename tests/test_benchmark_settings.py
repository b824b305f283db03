"""A recorded benchmark writes out the settings it runs a script with (benchmarks/settings.py):
no learning setting is left to the script's default, so a default changed later changes no
rerun of a record."""

import importlib.util
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
pytestmark = pytest.mark.quick


def benchmark(name):
    spec = importlib.util.spec_from_file_location(name, ROOT / "benchmarks" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_flags_write_bools_and_none_as_the_command_line_takes_them():
    settings = benchmark("settings")
    assert settings.flags(gamma=0.99, norm_obs=True, anneal_lr=False, target_kl=None) == [
        "--gamma", "0.99", "--norm-obs", "--no-anneal-lr", "--target-kl", "none"]
    assert settings.left_to_default("ppo_reacher", ["--no-norm-obs", "--gamma", "1"]) >= {
        "lam", "clip_ratio"}
    assert not {"gamma", "norm_obs", "seed", "print_every"} & settings.left_to_default(
        "ppo_reacher", ["--no-norm-obs", "--gamma", "1"])  # seed, output flags: not settings


@pytest.mark.parametrize("name,runs", [
    ("ddpg_walker_1m", lambda m: m.FLAGS.items()),  # the walkers' 1M records, PPO's too
    ("bench_reacher", lambda m: [("ppo_reacher", m.OURS)]),  # ours beside SB3 on Reacher
])
def test_every_recorded_run_sets_every_learning_setting(name, runs):
    settings = benchmark("settings")
    for script, flags in runs(benchmark(name)):
        assert not settings.left_to_default(script, flags), (
            f"benchmarks/{name}.py leaves {script}'s "
            f"{sorted(settings.left_to_default(script, flags))} to the defaults: write them out")
