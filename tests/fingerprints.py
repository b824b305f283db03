"""Each script's numbers, recorded in tests/fingerprints.json so that a change which moves them
fails the quick layer and says so: its Config's defaults (every field), and the first rows of
each log its SMOKE run writes, the very run the quick layer trains (tests/test_every_script.py
compares both). A change meant to move them (a new default, another network or vocabulary)
records them anew:

    python tests/fingerprints.py --accept reinforce_cartpole   # rerun its SMOKE run, record it
    python tests/fingerprints.py --accept                      # every script's
    python tests/fingerprints.py                               # say what moved; record nothing

A script with no record yet (a new one) passes, with a warning; `--accept NAME` records it.
"""

import argparse
import contextlib
import csv
import dataclasses
import importlib
import io
import json
import math
import sys
import tempfile
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
RECORD = Path(__file__).resolve().parent / "fingerprints.json"
SCRIPTS = sorted(p.stem for p in ROOT.glob("*.py") if "\ndef train(" in p.read_text("utf-8"))
LOGS = ("progress.csv", "evaluations.csv", "episodes.csv")
# The first two rows: their numbers come from the initial networks and the first updates, so a
# shifted initialisation, seed or default moves them, while another machine's float order has
# not had the time to grow (it flips a sampled action, then the run's whole course, later).
ROWS = 2
# A logged float may differ by this share of itself, or of its column's largest recorded value
# (a mean of normalized advantages, 3e-05, is mostly cancellation: its noise is the column's).
RTOL = 1e-3
# The libraries whose releases may change the logged numbers (an env's dynamics, an init, a
# kernel): the logs are compared only where these are the versions they were recorded with.
LIBRARIES = ("torch", "numpy", "gymnasium", "mujoco")


def smoke(module, run_dir, **more):
    """The Config of `module`'s SMOKE run: files under run_dir, no progress lines."""
    assert hasattr(module, "SMOKE"), (f"{module.__name__}.py declares no SMOKE: the Config "
                                      "overrides of a run of seconds that writes every file")
    return module.Config(**{**module.SMOKE, "run_dir": str(run_dir), "print_every": 10**6,
                            **more})


def quick_smoke(module, run_dir):
    """The SMOKE run as the quick layer trains it, and as its numbers are recorded: no GIFs."""
    no_gifs = {} if "gifs" in getattr(module.Config, "UNUSED_FLAGS", ()) else {"gifs": False}
    return smoke(module, run_dir, **no_gifs)


def defaults(module):
    """Every field of the script's Config and its default, as JSON has them."""
    return json.loads(json.dumps(dataclasses.asdict(module.Config()), default=repr))


def logged(run):
    """The header and the first ROWS rows of each log the run wrote, as written."""
    return {name: (run / name).read_text("utf-8").splitlines()[:1 + ROWS]
            for name in LOGS if (run / name).exists()}


def recorded(name):
    return json.loads(RECORD.read_text("utf-8")).get(name) if RECORD.exists() else None


def versions():
    """{library: version} of LIBRARIES, as installed here."""
    from importlib.metadata import PackageNotFoundError, version

    def of(library):
        try:
            return version(library)
        except PackageNotFoundError:
            return None
    return {library: of(library) for library in LIBRARIES}


def moved(name, part, now):
    """What differs in `part` of script `name` ("defaults": defaults(); "smoke": logged()) from
    the record, one line each; [] where nothing does, or where nothing is recorded (a warning)."""
    record = recorded(name)
    if record is None:
        warnings.warn(f"{name}: no numbers recorded in tests/fingerprints.json yet; "
                      f"python tests/fingerprints.py --accept {name} records them", stacklevel=2)
        return []
    if part == "defaults":
        return moved_defaults(record["defaults"], now)
    was = json.loads(RECORD.read_text("utf-8")).get("_versions")
    if was is not None and was != versions():  # another release may move them: not compared
        warnings.warn(f"{name}: its logged numbers were recorded with {was}, this is "
                      f"{versions()}: not compared (the defaults are)", stacklevel=2)
        return []
    return [line for log, rows in record["smoke"].items()
            for line in moved_rows(log, rows, now.get(log))]


def moved_defaults(was, now):
    lines = [f"Config.{k}: {was[k]!r} recorded, {now[k]!r} now" for k in was
             if k in now and now[k] != was[k]]
    lines += [f"Config.{k}: {was[k]!r} recorded, no such field now" for k in was if k not in now]
    return lines + [f"Config.{k}: {now[k]!r} now, not recorded" for k in now if k not in was]


def moved_rows(log, was, now):
    """Integers and words compare exactly; floats within RTOL (see above); nan equals nan."""
    if now is None:
        return [f"{log}: not written now"]
    (columns, *was), (header, *now) = csv.reader(was), csv.reader(now)
    lines = [f"{log}: column {c} recorded, not written now" for c in columns if c not in header]
    scale = {c: max([abs(x) for x in map(number, column) if x is not None and math.isfinite(x)],
                    default=0.0) for c, column in zip(columns, zip(*was))}
    for i, row in enumerate(was):
        if i >= len(now):
            lines.append(f"{log} row {i + 1}: recorded, not written now")
            continue
        got = dict(zip(header, now[i]))
        for c, old in zip(columns, row):
            new = got.get(c)
            if new is not None and not same(old, new, scale[c]):
                lines.append(f"{log} row {i + 1} ({columns[0]} {row[0]}), {c}: "
                             f"{old} recorded, {new} now")
    return lines


def number(text):
    try:
        return float(text)
    except ValueError:
        return None


def same(old, new, scale):
    a, b = number(old), number(new)
    if a is None or b is None or old.lstrip("-").isdigit() and new.lstrip("-").isdigit():
        return old == new  # words, or integers (a step, a count, a CartPole return)
    if math.isnan(a) or math.isnan(b):
        return math.isnan(a) and math.isnan(b)
    return abs(a - b) <= RTOL * max(abs(a), abs(b), scale)


def message(name, lines, most=8):
    """The failure: the script, what moved, and the command that records the new numbers."""
    more = [f"... and {len(lines) - most} more"] if len(lines) > most else []
    return "\n  ".join([f"{name}: numbers moved from those recorded in tests/fingerprints.json:",
                        *lines[:most], *more,
                        f"If the change is meant to move them: python tests/fingerprints.py "
                        f"--accept {name}"])


def fingerprint(name):
    """{"defaults": ..., "smoke": ...} of script `name`, from a SMOKE run trained now."""
    module = importlib.import_module(name)
    with tempfile.TemporaryDirectory() as tmp, contextlib.redirect_stdout(io.StringIO()):
        run = module.train(quick_smoke(module, tmp))["run_dir"]
        return {"defaults": defaults(module), "smoke": logged(run)}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--accept", action="store_true",
                        help="record the numbers the scripts give now")
    parser.add_argument("names", nargs="*", metavar="SCRIPT", help="(default: every script)")
    args = parser.parse_args(argv)
    names = [n.removesuffix(".py") for n in args.names] or SCRIPTS
    unknown = sorted(set(names) - set(SCRIPTS))
    if unknown:
        parser.error(f"not a script: {', '.join(unknown)} (the scripts: {', '.join(SCRIPTS)})")
    sys.path.insert(0, str(ROOT))
    record = json.loads(RECORD.read_text("utf-8")) if RECORD.exists() and args.names else {}
    any_moved = False
    for name in names:
        now = fingerprint(name)
        with warnings.catch_warnings(record=True):  # no record yet: a new script
            lines = moved(name, "defaults", now["defaults"]) + moved(name, "smoke", now["smoke"])
        any_moved |= bool(lines)
        if args.accept:
            print("\n  ".join([f"{name}: recorded" + (", what moved:" if lines else ""), *lines]))
        elif lines:
            print(message(name, lines, most=len(lines)))
        else:
            print(f"{name}: as recorded" if recorded(name) else f"{name}: not recorded yet")
        record[name] = now
    if args.accept:
        record["_versions"] = versions()
        RECORD.write_text(json.dumps(dict(sorted(record.items())), indent=1) + "\n", "utf-8")
        print(f"written: {RECORD.relative_to(ROOT)}")
    return 1 if any_moved and not args.accept else 0


if __name__ == "__main__":
    sys.exit(main())
