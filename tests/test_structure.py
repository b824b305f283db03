"""How the project's modules hang together: common.py is the ground floor, no two modules
import each other (directly or round a longer circle), and importing any of them, in any
order, changes nothing in the process (no signal handler, no environment variable)."""

import ast
import dataclasses
import importlib
import io
import os
import re
import subprocess
import sys
import tokenize
from collections import Counter

import pytest

from conftest import ROOT
from test_every_script import SCRIPTS

TOOLS = ("common", "cli", "runlog", "checkpoints", "report", "plots")
ENV_HELPERS = ("cartpole_env", "mujoco_env")  # what belongs to an env, named for it
SCRIPTS = tuple(SCRIPTS)  # found by themselves: every top-level *.py with a train()
MODULES = TOOLS + ENV_HELPERS + SCRIPTS


def project_imports(name):
    """The project modules that module `name` imports, anywhere in its file."""
    tree = ast.parse((ROOT / f"{name}.py").read_text(encoding="utf-8"))
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module:
            found.add(node.module)
    return found & set(MODULES)


@pytest.mark.quick
def test_common_is_the_ground_floor_and_there_is_no_import_circle():
    graph = {name: project_imports(name) for name in MODULES}
    assert graph["common"] == set() and graph["plots"] == set()
    for name in MODULES:  # follow the imports from each module: it never comes back to itself
        seen, todo = set(), list(graph[name])
        while todo:
            other = todo.pop()
            assert other != name, f"{name} imports itself, through {sorted(seen)}"
            if other not in seen:
                seen.add(other)
                todo += graph[other]
    assert not any(graph[tool] & set(SCRIPTS + ENV_HELPERS) for tool in TOOLS)  # nor an env


def script_only(kind):
    """The names of `kind` ("fields": a Config's own fields; "columns": its declared LOGGED
    columns) that exactly one script has."""
    counts = Counter()
    for name in SCRIPTS:
        module = importlib.import_module(name)
        if kind == "fields":
            shared = {f.name for base in module.Config.__mro__[1:] if dataclasses.is_dataclass(base)
                      for f in dataclasses.fields(base)}
            counts.update({f.name for f in dataclasses.fields(module.Config)} - shared)
        else:
            counts.update(set(getattr(module, "LOGGED", {})))
    import common  # ratio_stats' columns are common's own, whoever logs them
    return {name for name, n in counts.items() if n == 1} - set(common.RATIO_COLUMNS)


def words(tool):
    """A tool's code as (attribute names, string literals, every word of its text)."""
    text = (ROOT / f"{tool}.py").read_text(encoding="utf-8")
    tokens = list(tokenize.generate_tokens(io.StringIO(text).readline))
    attributes = {c.string for a, b, c in zip(tokens, tokens[1:], tokens[2:])  # cfg.<field>
                  if a.string in ("cfg", "config") and b.string == "." and c.type == tokenize.NAME}
    strings = {t.string.strip("'\"rbf") for t in tokens if t.type == tokenize.STRING}
    return attributes, strings, text


@pytest.mark.quick
def test_no_tool_names_a_script_an_env_or_what_only_one_script_has():
    """The tools take data and functions from the scripts: no script's name, no env id, no
    field of one script's Config read as cfg.<field>, no column that only one script logs."""
    fields, columns = script_only("fields"), script_only("columns")
    assert fields and columns  # the check sees some (unnamed: a new script may share one)
    for tool in TOOLS:
        attributes, strings, text = words(tool)
        named = [s for s in SCRIPTS if re.search(rf"\b{s}\b", text)]
        assert not named, f"{tool}.py names the script(s) {named}"
        envs = re.findall(r"\b[A-Z][A-Za-z0-9]*-v\d+\b", text)
        assert not envs, f"{tool}.py names env ids {envs}"
        assert not attributes & fields, f"{tool}.py reads {sorted(attributes & fields)}"
        assert not strings & columns, f"{tool}.py names the columns {sorted(strings & columns)}"
        assert not strings & fields, f"{tool}.py names the fields {sorted(strings & fields)}"


CHECK = """
import os, signal, sys
import gymnasium, numpy, torch  # what they do on import themselves is theirs
before = (signal.getsignal(signal.SIGINT), dict(os.environ))
for name in sys.argv[1:]:
    __import__(name)
after = (signal.getsignal(signal.SIGINT), dict(os.environ))
print("same" if after == before else f"changed: {after[0]} {set(after[1].items()) ^ set(before[1].items())}")
"""


@pytest.mark.parametrize("order", [  # every module at once in the quick layer; the orders after
    pytest.param(MODULES, marks=pytest.mark.quick),  # it in the default one
    MODULES[::-1], ("report", "ppo_cartpole", "common"), ("ddpg_walker", "cli"), ("td3_walker",)])
def test_importing_in_any_order_changes_nothing(order):
    """No import-order rule: whatever is imported first, SIGINT keeps Python's handler and
    the environment variables stay as they were (headless defaults are set where an env is
    made, not on import)."""
    env = {k: v for k, v in os.environ.items() if k not in ("SDL_VIDEODRIVER", "MUJOCO_GL")}
    p = subprocess.run([sys.executable, "-c", CHECK, *order], capture_output=True, text=True,
                       cwd=ROOT, env={**env, "PYTHONPATH": str(ROOT)}, timeout=120)
    assert p.returncode == 0, p.stderr
    assert p.stdout.strip() == "same", p.stdout


@pytest.mark.quick
def test_each_module_says_what_it_holds_in_its_first_line():
    for name in TOOLS:
        doc = ast.get_docstring(ast.parse((ROOT / f"{name}.py").read_text(encoding="utf-8")))
        assert doc and len(doc.splitlines()[0]) > 30, name


@pytest.mark.quick
def test_no_tool_asks_what_a_network_returns():
    """The scripts hand over functions (obs -> logits, obs -> V) and constructors: no tool
    looks inside a network's output or guesses a constructor from a checkpoint's keys."""
    for name in TOOLS:
        text = (ROOT / f"{name}.py").read_text(encoding="utf-8")
        assert "isinstance(out" not in text and "isinstance(logits" not in text, name
        assert '"act_dim" in' not in text, name


@pytest.mark.quick
def test_every_line_fits_a_split_pane():
    """At most 100 characters a line in every top-level *.py (scripts, tools, env helpers):
    the script beside the tutorial, in half a screen. A line joined to stay within a script's
    line budget fails here."""
    long = [f"{p.name}:{i}" for p in sorted(ROOT.glob("*.py"))
            for i, line in enumerate(p.read_text(encoding="utf-8").splitlines(), 1)
            if len(line) > 100]
    assert not long, f"lines over 100 characters: {long}"
