"""A recorded benchmark's settings, written out: the flags a benchmark hands a script set every
learning setting of that script (each field of its Config but the shared output flags and the
seed), never leaving one to the default. A default changed later then changes no rerun of a
record, and the record says what it ran. tests/test_benchmark_settings.py checks each
benchmark's SETTINGS against the scripts' Configs.

    flags(gamma=0.99, norm_obs=True, target_kl=None) -> ["--gamma", "0.99", "--norm-obs",
                                                           "--target-kl", "none"]
"""

import dataclasses
import importlib
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def flags(**settings):
    """The command-line flags of `settings` (a bool as --name / --no-name, None as none)."""
    out = []
    for name, value in settings.items():
        flag = "--" + name.replace("_", "-")
        if isinstance(value, bool):
            out.append(flag if value else "--no-" + flag[2:])
        else:
            out += [flag, "none" if value is None else str(value)]
    return out


def learning_fields(script):
    """The fields of `script`'s Config that a record's flags must set: its own, less those its
    bases share with every script (output, evaluation, checkpoints) and the seed (a benchmark
    gives each run its own)."""
    sys.path.insert(0, str(ROOT))
    config = importlib.import_module(script).Config
    shared = {f.name for base in config.__mro__[1:] if dataclasses.is_dataclass(base)
              for f in dataclasses.fields(base)}
    return {f.name for f in dataclasses.fields(config)} - shared - {"seed"}


def left_to_default(script, given):
    """The learning fields of `script` that the flags `given` do not set."""
    named = {arg[2:].removeprefix("no-").replace("-", "_") for arg in given
             if arg.startswith("--")}
    return learning_fields(script) - named
