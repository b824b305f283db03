"""The Chinese guide's code references, `file.py:LINE` `name`, kept true by a program: each
LINE is made the line of `name` in that file nearest to the LINE written, so an edit that
moves a script's lines moves its references with it.

    python tests/line_refs.py          # rewrite README.zh-CN.md's line numbers; say which moved
    python tests/line_refs.py --check  # exit 1 if any is off (tests/test_readmes.py runs this)
"""

import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
GUIDE = ROOT / "README.zh-CN.md"
REF = re.compile(r"`(\w+\.py):(\d+)`")


def name_after(line, ref):
    """The name a reference points at: the next backticked span, in the same table row or
    within 60 characters."""
    after = line[ref.end():] if line.startswith("|") else line[ref.end():ref.end() + 60]
    name = re.search(r"`([^`]+)`", after)
    return name.group(1) if name and ":" not in name.group(1) else None


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
            hits = [i + 1 for i, s in enumerate(source) if name in s]
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
    text = GUIDE.read_text(encoding="utf-8")
    new, moved, problems = refreshed(text)
    for old, now in moved:
        print(f"{old} -> {now}")
    for problem in problems:
        print(f"error: {problem}", file=sys.stderr)
    if "--check" in argv:
        return 1 if moved or problems else 0
    GUIDE.write_text(new, encoding="utf-8")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
