"""The guides' code references, `file.py:LINE` `name` (README.zh-CN.md, docs/ppo_to_grpo*.md,
docs/ppo_to_rlhf*.md), kept true by a program: each
LINE is made the line of `name` in that file nearest to the LINE written, so an edit that
moves a script's lines moves its references with it. A name written as a call, `name(`, is
a call: never the line that defines it.

    python tests/line_refs.py          # rewrite the guides' line numbers; say which moved
    python tests/line_refs.py --check  # exit 1 if any is off (tests/test_readmes.py runs this)
"""

import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
GUIDES = [ROOT / "README.zh-CN.md", ROOT / "docs" / "ppo_to_grpo.md",
          ROOT / "docs" / "ppo_to_grpo.zh-CN.md", ROOT / "docs" / "ppo_to_rlhf.md",
          ROOT / "docs" / "ppo_to_rlhf.zh-CN.md"]
REF = re.compile(r"`(\w+\.py):(\d+)`")


def name_after(line, ref):
    """The name a reference points at: the next backticked span, in the same table row or
    within 60 characters."""
    after = line[ref.end():] if line.startswith("|") else line[ref.end():ref.end() + 60]
    name = re.search(r"`([^`]+)`", after)
    return name.group(1) if name and ":" not in name.group(1) else None


def prose_lines(path):
    """The line numbers of a Python file's docstrings and comment-only lines: a name is looked
    for in the code first (the word `ratio` in a docstring is not the line that computes it)."""
    import ast

    source = path.read_text(encoding="utf-8")
    lines = {i + 1 for i, s in enumerate(source.splitlines()) if s.lstrip().startswith("#")}
    for node in ast.walk(ast.parse(source)):
        body = getattr(node, "body", None)
        first = body[0] if isinstance(body, list) and body else None
        if (isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant)
                and isinstance(first.value.value, str)):
            lines |= set(range(first.lineno, first.end_lineno + 1))
    return lines


def refreshed(text):
    """(the guide with each LINE moved to its name's nearest line, [(old ref, new ref) moved],
    [problems: a reference without a name, or a name the file does not hold])."""
    moved, problems, out = [], [], []
    for line in text.splitlines(keepends=True):
        def fix(ref, line=line):
            file, number, name = ref.group(1), int(ref.group(2)), name_after(line, ref)
            if name is None:
                problems.append(f"no name after {ref.group(0)}")
                return ref.group(0)
            source = (ROOT / file).read_text(encoding="utf-8").splitlines()
            prose = prose_lines(ROOT / file)
            word = re.compile((r"(?<!\w)" if name[0].isalnum() or name[0] == "_" else "")
                              + re.escape(name) + (r"(?!\w)" if name[-1].isalnum() else ""))
            hits = [i + 1 for i, s in enumerate(source) if word.search(s) and i + 1 not in prose
                    and not (name.endswith("(") and re.match(r"\s*(def|class) ", s))]  # a call
            hits = hits or [i + 1 for i, s in enumerate(source) if word.search(s)]  # a comment
            if not hits:
                problems.append(f"{file} holds no {name!r} ({ref.group(0)})")
                return ref.group(0)
            best = min(hits, key=lambda i: abs(i - number))
            if best != number:
                moved.append((f"{file}:{number}", f"{file}:{best} {name}"))
            return f"`{file}:{best}`"
        out.append(REF.sub(fix, line))
    return "".join(out), moved, problems


def main(argv):
    code = 0
    for guide in GUIDES:
        new, moved, problems = refreshed(guide.read_text(encoding="utf-8"))
        for old, now in moved:
            print(f"{guide.name}: {old} -> {now}")
        for problem in problems:
            print(f"error: {guide.name}: {problem}", file=sys.stderr)
        if "--check" in argv or problems:  # a problem: nothing is rewritten
            code = max(code, 1 if moved or problems else 0)
            continue
        guide.write_text(new, encoding="utf-8")
    return code


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
