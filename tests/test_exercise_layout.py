"""The exercises' checker is laid out as docs/exercises.md's maintainer section says: each
exercise's checks in exercises/cases/<name>.py, a runner that names no exercise and no script,
and the checks' Chinese held to the glossary as the rest of the code is."""

import re
import sys

import pytest

from conftest import ROOT

sys.path.insert(0, str(ROOT / "exercises"))
import check  # noqa: E402

RUNNER = (ROOT / "exercises" / "check.py").read_text(encoding="utf-8")


@pytest.mark.quick
def test_the_runner_is_small_and_names_no_exercise_and_no_script():
    """A new exercise is one new file in exercises/cases/: the runner has no branch, table or
    string for any one exercise or script (a planted name fails here)."""
    assert len(RUNNER.splitlines()) <= 500
    code = RUNNER.split('"""', 2)[2]  # its docstring may show a command
    scripts = {ex.script for ex in check.EXERCISES.values()}
    for name in [*check.EXERCISES, *scripts]:
        assert not re.search(rf"\b{name}\b", code), f"exercises/check.py names {name}"


@pytest.mark.quick
def test_every_exercise_has_its_checks_and_its_row_in_the_docs():
    """Each exercises/<name>.py that is an exercise has exercises/cases/<name>.py, and the
    table of docs/exercises.md lists them in the order of their ORDER."""
    learners = {p.stem for p in (ROOT / "exercises").glob("*.py")} - {
        "check", "checking", "runs", "draw_bugs"}
    assert learners == set(check.EXERCISES)
    rows = re.findall(r"^\| (\d+) \| `(\w+)` \|", (ROOT / "docs" / "exercises.md").read_text(
        encoding="utf-8"), re.MULTILINE)
    assert [(int(n), name) for n, name in rows] == [
        (ex.order, name) for name, ex in check.EXERCISES.items() if name not in check.BUGS]


def test_the_checks_chinese_follows_the_glossary():
    """tests/test_language_parity.py holds the glossary to exercises/*.py; the same words
    here, for the messages that moved into exercises/cases/."""
    from test_language_parity import GLOSSARY
    for path in sorted((ROOT / "exercises" / "cases").glob("*.py")):
        for line in path.read_text(encoding="utf-8").splitlines():
            if not re.search(r"[\u4e00-\u9fff]", line):
                continue
            for word, others in GLOSSARY.items():
                for other in others:
                    assert other not in line, f"{path.name} says {other} where the glossary's " \
                                              f"word is {word}: «{line.strip()[:120]}»"
