"""How the project's modules hang together: common.py is the ground floor, no two modules
import each other (directly or round a longer circle), and importing any of them, in any
order, changes nothing in the process (no signal handler, no environment variable)."""

import ast
import os
import subprocess
import sys

import pytest

from conftest import ROOT

TOOLS = ("common", "cli", "runlog", "checkpoints", "report", "plots")
SCRIPTS = ("ppo_cartpole", "ppo_kl_cartpole", "actor_critic_cartpole", "ddpg_walker",
           "td3_walker", "sac_walker")
MODULES = TOOLS + SCRIPTS


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
    assert not any(graph[tool] & set(SCRIPTS) for tool in TOOLS)  # no tool knows a script


CHECK = """
import os, signal, sys
import gymnasium, numpy, torch  # what they do on import themselves is theirs
before = (signal.getsignal(signal.SIGINT), dict(os.environ))
for name in sys.argv[1:]:
    __import__(name)
after = (signal.getsignal(signal.SIGINT), dict(os.environ))
print("same" if after == before else f"changed: {after[0]} {set(after[1].items()) ^ set(before[1].items())}")
"""


@pytest.mark.quick
@pytest.mark.parametrize("order", [MODULES, MODULES[::-1], ("report", "ppo_cartpole", "common"),
                                   ("ddpg_walker", "cli"), ("td3_walker",),
                                   ("sac_walker",)])
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
