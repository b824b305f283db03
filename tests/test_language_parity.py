"""The Chinese reader gets what the English reader gets: every docs page in both languages,
with the same sections, commands and numbers; both READMEs list the same scripts (found by
their `def train(`, so a new script needs its Chinese lines too) and the same commands; every
Chinese page links the Chinese page where there is one; and one glossary (README.zh-CN.md's
术语对照) is used by every Chinese page and by the Chinese text in the code."""

import dataclasses
import importlib
import re

import pytest
from pathlib import Path

import help_zh

pytestmark = pytest.mark.quick

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs"
EN_README, ZH_README = ROOT / "README.md", ROOT / "README.zh-CN.md"

# A docs page that stays English, with the reason a Chinese reader is given for it.
ENGLISH_ONLY = {}

# Numbers a Chinese page may quote without its English page: {page name: {number: why}}.
ZH_ONLY_NUMBERS = {
    "README.zh-CN.md": {195: "CartPole-v0's solved return, named where tutorial 004's env is"},
}

# The glossary's word for a term, and the words it replaces on every Chinese page and in the
# Chinese text of the code (README.zh-CN.md's 术语对照 names each kept word).
GLOSSARY = {
    "比值": ("比率",),
    "熵正则项": ("熵奖励",),
    "PPO-penalty": ("PPO 惩罚版", "PPO惩罚版"),
    "早停": ("提前停止",),
    "验证器": (),
    "检查程序": (),
    "题目": ("提示词",),
    "统计口径": ("量法",),
    "隐式奖励": ("隐含奖励",),
    "标准误差": (),  # not 标准误 alone: checked below, as it is a part of 标准误差
    "监督学习": ("监督训练", "有监督训练"),
    "奖励模型": ("回报模型",),
    "偏好对": ("成对比较", "成对的比较", "成对偏好"),
    "评审": ("裁判",),
    "过度优化": ("过优化", "奖励黑客", "钻空子", "钻了空子"),
    "参考策略": ("参考模型",),
    "拒绝采样微调": ("拒绝抽样",),
}
GRPO_TEXTS = ("docs/ppo_to_grpo.zh-CN.md", "grpo_addition.py")  # verifier and prompt live here


def english_pages():
    return sorted(p for p in DOCS.glob("*.md") if not p.name.endswith(".zh-CN.md"))


def chinese_of(page):
    return page.with_name(page.stem + ".zh-CN.md")


def pairs():
    """(English page, its Chinese page) for every docs page that has both."""
    return [(p, chinese_of(p)) for p in english_pages() if chinese_of(p).is_file()]


def split_code(text):
    """(lines inside ``` fences, lines outside them)."""
    inside, outside, in_code = [], [], False
    for line in text.splitlines():
        if line.lstrip().startswith("```"):
            in_code = not in_code
        else:
            (inside if in_code else outside).append(line)
    return inside, outside


def prose(text):
    """A page's running text: no code blocks, inline code, display math or link targets."""
    text = "\n".join(split_code(text)[1])
    text = re.sub(r"`[^`]*`", "", text)
    text = re.sub(r"\$\$.*?\$\$", "", text, flags=re.S)
    return re.sub(r"\]\([^)]*\)", "]", text)


NUMBER = re.compile(r"(?<![\w.])(\d+(?:,\d{3})*(?:\.\d+)?)(?:\s*([kM万])(?![A-Za-z]))?")
SCALE = {None: 1, "k": 1_000, "M": 1_000_000, "万": 10_000}


def quoted(text):
    """(value, where) for each number in `text`: 25,000 = 25k = 2.5 万 = 25000. A Chinese
    date's month (11 月) is left out: the English page spells it (November)."""
    text = re.sub(r"\d+\s*月", "", text)
    return [(round(float(m.group(1).replace(",", "")) * SCALE[m.group(2)], 6),
             text[max(0, m.start() - 40):m.end() + 20].replace("\n", " "))
            for m in NUMBER.finditer(text)]


def numbers(text):
    return {value for value, _ in quoted(text)}


def commands(text):
    """The command lines of a page's code blocks, a trailing `  # comment` removed."""
    lines = (re.sub(r"\s+#.*$", "", line).strip() for line in split_code(text)[0])
    return {line for line in lines if line.split(" ")[0] in ("python", "pip", "pytest",
                                                               "tensorboard")}


def headings(text):
    """The level of each ## and ### heading, in order."""
    return [line.split(" ")[0] for line in split_code(text)[1] if re.match(r"#{2,3} ", line)]


def anchors(text):
    """The #anchors GitHub gives a page's headings (Chinese characters are kept)."""
    found = re.findall(r"^#+ (.+)$", "\n".join(split_code(text)[1]), re.MULTILINE)
    return {re.sub(r"[^\w\- ]", "", h.strip().lower()).replace(" ", "-") for h in found}


def read(path):
    return path.read_text(encoding="utf-8")


def chinese_texts():
    """{name: Chinese text} for every Chinese page, and the lines with Chinese in the code."""
    readme = read(ZH_README)  # less its glossary, which names the words it replaces
    texts = {ZH_README.name: readme.replace(glossary(), "")}
    texts.update({f"docs/{p.name}": read(p) for p in DOCS.glob("*.zh-CN.md")})
    for locale in (help_zh.HELP_ZH, help_zh.OUTPUT_ZH):  # --help-zh's lines, --lang zh's
        texts[str(locale.relative_to(ROOT))] = read(locale)
    for path in [*ROOT.glob("*.py"), *ROOT.glob("exercises/*.py"), *ROOT.glob("experiments/*.py")]:
        lines = [l for l in read(path).splitlines() if re.search(r"[\u4e00-\u9fff]", l)]
        if lines:
            texts[str(path.relative_to(ROOT))] = "\n".join(lines)
    return texts


def training_scripts():
    """The top-level scripts with a `def train(`: the algorithm scripts."""
    return sorted(p.name for p in ROOT.glob("*.py")
                  if re.search(r"^def train\(", read(p), re.MULTILINE))


def listed_scripts(text):
    """The scripts a README lists: each table row whose first cell is a `script.py`."""
    return set(re.findall(r"^\| `(\w+\.py)` \|", text, re.MULTILINE))


def test_every_docs_page_has_its_chinese_page():
    for page in english_pages():
        if page.name in ENGLISH_ONLY:
            assert ENGLISH_ONLY[page.name].strip(), f"say why docs/{page.name} stays English"
            continue
        assert chinese_of(page).is_file(), (
            f"docs/{page.name} has no Chinese page: write docs/{chinese_of(page).name}, or list "
            f"it in ENGLISH_ONLY with the reason")
    for page in DOCS.glob("*.zh-CN.md"):
        assert page.with_name(page.name.replace(".zh-CN", "")).is_file(), \
            f"docs/{page.name} has no English page"


@pytest.mark.parametrize("en", english_pages(), ids=lambda p: p.name)
def test_each_chinese_page_has_the_english_pages_sections_and_commands(en):
    zh = chinese_of(en)
    if not zh.is_file():
        pytest.skip(f"{en.name}: English only")
    assert headings(read(zh)) == headings(read(en)), (
        f"docs/{zh.name}'s ## and ### headings {headings(read(zh))} differ from "
        f"docs/{en.name}'s {headings(read(en))}: a section is in one language only")
    missing, extra = commands(read(en)) - commands(read(zh)), commands(read(zh)) - commands(read(en))
    assert not missing, f"commands of docs/{en.name} missing from docs/{zh.name}: {missing}"
    assert not extra, f"commands only in docs/{zh.name}: {extra}"


def sections(text):
    """A page cut at its ## and ### headings (outside code blocks): the text before the first
    heading, then each section with its heading."""
    parts, in_code = [[]], False
    for line in text.splitlines():
        if line.lstrip().startswith("```"):
            in_code = not in_code
        if not in_code and re.match(r"#{2,3} ", line):
            parts.append([])
        parts[-1].append(line)
    return ["\n".join(part) for part in parts]


def number_pairs(zh):
    """(Chinese text, the numbers it may quote), section by section for a docs page (its
    sections are the English page's, in order); for README.zh-CN.md, a guide longer than
    README.md, the whole page against the English README, every English docs page and the
    scripts' source (their Config's help texts)."""
    if zh == ZH_README:
        sources = [EN_README, *english_pages(), *ROOT.glob("*.py")]
        return [(read(zh), set().union(*(numbers(read(p)) for p in sources)))]
    en = read(zh.with_name(zh.name.replace(".zh-CN", "")))
    return [(z, numbers(e)) for z, e in zip(sections(read(zh)), sections(en))]


@pytest.mark.parametrize("zh", [ZH_README, *sorted(DOCS.glob("*.zh-CN.md"))],
                         ids=lambda p: p.name)
def test_every_number_a_chinese_page_quotes_is_on_its_english_page(zh):
    """Each number of a Chinese section is in the same section of the English page (code
    blocks included there). Small counts (0 to 10) are exempt: English spells them out (two
    workers, zero). A number changed on the English page alone is caught when the Chinese
    section quotes it and the English section has it nowhere else."""
    stray = {}
    for text, allowed in number_pairs(zh):
        allowed = allowed | set(ZH_ONLY_NUMBERS.get(zh.name, {}))
        for value, where in quoted(prose(text)):
            if value not in allowed and not (value == int(value) and 0 <= value <= 10):
                stray.setdefault(value, where.strip())
    assert not stray, f"{zh.name} quotes numbers its English page lacks: " + "; ".join(
        f"{v:g} in «{line}»" for v, line in sorted(stray.items()))


def test_both_readmes_list_the_same_scripts_with_a_command_each():
    """Both READMEs list the same scripts, each with a command, and no script that is gone. A
    script that neither lists yet (a new file) fails nothing here: its rows are documentation,
    added with it in both languages, not something the script needs in order to run and be
    tested (tests/test_every_script.py finds it by itself)."""
    scripts = training_scripts()
    en, zh = read(EN_README), read(ZH_README)
    listed = listed_scripts(en) | listed_scripts(zh)
    assert len(listed) >= 9 and listed <= set(scripts), (listed, scripts)
    for name, text in (("README.md", en), ("README.zh-CN.md", zh)):
        missing = listed - listed_scripts(text)
        assert not missing, f"{name}'s table of scripts lacks {sorted(missing)}"
        run = {s for s in listed if any(c.startswith(f"python {s}") for c in commands(text))}
        assert run == listed, f"{name} shows no command for {sorted(listed - run)}"
    assert listed_scripts(en) == listed_scripts(zh), (
        f"listed only in README.md: {sorted(listed_scripts(en) - listed_scripts(zh))}; "
        f"only in README.zh-CN.md: {sorted(listed_scripts(zh) - listed_scripts(en))}")
    assert commands(en) <= commands(zh), \
        f"commands of README.md missing from README.zh-CN.md: {commands(en) - commands(zh)}"


def test_chinese_pages_link_the_chinese_page_where_there_is_one():
    """A Chinese page links docs/X.zh-CN.md, not docs/X.md, once X has a Chinese page (its own
    English original, linked at its top, excepted), and every #anchor it links exists."""
    for zh in [ZH_README, *DOCS.glob("*.zh-CN.md")]:
        for name, anchor in re.findall(r"\]\(([^)#\s:]+\.md)(?:#([^)]*))?\)", read(zh)):
            target = (zh.parent / name).resolve()
            where = zh.relative_to(ROOT)
            assert target.is_file(), f"{where} links {name}, which does not exist"
            own = target == zh.with_name(zh.name.replace(".zh-CN", "")).resolve()
            if not target.name.endswith(".zh-CN.md") and not own and target != EN_README:
                assert not chinese_of(target).is_file(), \
                    f"{where} links {name}: link its Chinese page {chinese_of(target).name}"
            if anchor:
                assert anchor in anchors(read(target)), f"{where} links {name}#{anchor}"
        for shown, name in re.findall(r"\[([^\]\s]+\.md)\]\(([^)#\s:]+\.md)", read(zh)):
            assert Path(shown).name == Path(name).name, \
                f"{zh.relative_to(ROOT)}: the link [{shown}] goes to {name}: name what it links"


def glossary():
    """README.zh-CN.md's 术语对照 section."""
    return read(ZH_README).split("\n## 术语对照\n", 1)[1].split("\n## ", 1)[0]


def test_one_glossary_for_every_chinese_text():
    table = glossary()
    for word in GLOSSARY:
        assert word in table, f"README.zh-CN.md's 术语对照 lacks {word}"
    for name, text in chinese_texts().items():
        for line in text.splitlines():
            for word, others in GLOSSARY.items():
                for other in others:
                    if other in line:
                        pytest.fail(f"{name} says {other} where the glossary's word is {word}: "
                                    f"«{line.strip()[:120]}»")
        for line in text.splitlines():
            if re.search(r"标准误(?!差)", line):
                pytest.fail(f"{name} says 标准误 where the glossary's word is 标准误差: "
                            f"«{line.strip()[:120]}»")
        for line in prose(text).splitlines():  # 截断 is the time limit's, and nothing else's
            if "截断" in line:
                assert "时间截断" in line or "truncated" in line, \
                    f"{name}: 截断 is only the time limit (时间截断): «{line.strip()[:120]}»"
    for name in GRPO_TEXTS:  # GRPO's reward is the verifier, its input a 题目
        text = chinese_texts()[name]
        assert "检查程序" not in text, f"{name}: GRPO's verifier is 验证器 (检查程序 is check.py)"
        assert "提示" not in re.sub(r"<summary>提示", "", text), f"{name}: a prompt is 题目"
        assert "题目" in text, name
    assert "验证器" in chinese_texts()[GRPO_TEXTS[0]]


# --help-zh: a Chinese line under each flag (locale/flags.zh-CN.md), for every script.

def shown_flags(script):
    """{field: English help} of the flags `python script --help` shows."""
    module = importlib.import_module(script[:-3])
    docs = help_zh.english(module.Config)
    unused = getattr(module.Config, "UNUSED_FLAGS", ())
    return {f.name: f"{docs.get(f.name, '')} {f.default}" for f in dataclasses.fields(module.Config)
            if f.name not in unused}



@pytest.mark.parametrize("script", training_scripts())
def test_every_flag_has_a_chinese_line_with_the_english_lines_numbers(script):
    chinese = help_zh.flags(script[:-3])
    for name, english in shown_flags(script).items():
        flag = "--" + name.replace("_", "-")
        if name not in chinese:
            pytest.fail(f"{script} {flag} has no Chinese line: in the script's FLAGS_ZH or in "
                        f"{help_zh.HELP_ZH.relative_to(ROOT)}")
        stray = {v for v in numbers(chinese[name]) - numbers(english) if not v == int(v) <= 10}
        assert not stray, (f"{script} {flag}: the Chinese line quotes {sorted(stray)}, which its "
                           f"English help and default do not: «{chinese[name]}»")


def help_text(capsys, argv, module="ppo_cartpole"):
    import cli
    with pytest.raises(SystemExit) as stop:
        cli.parse_config(importlib.import_module(module).Config, argv, description="English.")
    assert stop.value.code == 0
    return capsys.readouterr().out


def columns(line):
    return len(line) + len(help_zh.WIDE.findall(line))


def test_help_zh_puts_each_chinese_line_under_its_english_one_within_the_width(capsys, monkeypatch):
    monkeypatch.setenv("COLUMNS", "80")
    monkeypatch.setenv("LANG", "C.UTF-8")
    for key in ("LC_ALL", "LC_MESSAGES"):
        monkeypatch.delenv(key, raising=False)
    out = help_text(capsys, ["--help-zh"])
    lines = out.splitlines()
    at = next(i for i, line in enumerate(lines) if line.lstrip().startswith("--gamma"))
    assert lines[at + 1].strip().endswith("(default: 0.99)"), lines[at:at + 3]  # English first
    assert lines[at + 2].strip() == "折扣因子（0.98 到 0.999）；0.99 大约往前看 100 步", lines[at:at + 3]
    assert "中文导读：PPO-clip" in out and out.rstrip().endswith(help_zh.HINT)
    at = next(i for i, line in enumerate(lines) if line.lstrip().startswith("-h, --help"))
    assert lines[at + 1].strip() == "显示本帮助并退出", lines[at:at + 2]  # argparse's own flag too
    too_wide = [line for line in lines if columns(line) > 80]
    assert not too_wide, too_wide
    monkeypatch.setenv("LANG", "zh_CN.UTF-8")  # a Chinese locale: plain --help has them too
    assert help_text(capsys, ["--help"]) == out
    monkeypatch.setenv("LANG", "en_US.UTF-8")
    plain = help_text(capsys, ["--help"])
    assert not help_zh.WIDE.search(plain.replace(help_zh.HINT, "")), "Chinese in English --help"


def test_chinese_lines_wrap_by_columns_and_keep_punctuation_with_its_word():
    """A Chinese character takes two columns; no line starts with ，or ends with （."""
    assert help_zh._wrap_wide("一二三四五，六七", 10) == ["一二三四", "五，六七"]
    assert help_zh._wrap_wide("一二三四（五六", 10) == ["一二三四", "（五六"]
    assert help_zh._wrap_wide("用 Adam\n学习率，和\n中文", 12) == ["用 Adam 学习", "率，和中文"]
    # a source line break: a space between Chinese and Latin text, none at full-width punctuation
    assert help_zh._join("先读\nDDPG 和 TD3\n（教程 003\n和它；\nmin(Q)\n加") == \
        "先读 DDPG 和 TD3（教程 003 和它；min(Q) 加"


@pytest.mark.quick
def test_a_copy_of_a_script_takes_the_chinese_lines_of_the_english_it_kept(tmp_path, monkeypatch):
    """A new script that no heading of locale/flags.zh-CN.md names (here a copy of
    ppo_cartpole.py on another env, and with its own words for --gamma) gets a flag's Chinese
    line where its English help is a named script's (the env's default changed, its help did
    not); where the help is its own, none: a line written for other words would say something
    else (FLAGS_ZH in the script gives it one)."""
    import sys

    source = (ROOT / "ppo_cartpole.py").read_text(encoding="utf-8")
    changed = source.replace('env_id: str = "CartPole-v1"', 'env_id: str = "Acrobot-v1"')
    gamma = re.search(r'    gamma: float = .*\n    """(.*)"""', changed)[1]
    changed = changed.replace(gamma, "the discount factor of Acrobot's returns")
    assert changed.count("Acrobot") == 2
    (tmp_path / "ppo_copy.py").write_text(changed, encoding="utf-8")
    monkeypatch.syspath_prepend(str(tmp_path))
    try:
        copy = help_zh.flags("ppo_copy", importlib.import_module("ppo_copy"))
    finally:
        sys.modules.pop("ppo_copy", None)
    original = help_zh.flags("ppo_cartpole")
    for field in ("env_id", "hidden", "seed", "eval_episodes", "clip_coef", "solved_window"):
        assert copy[field] == original[field], field
    assert "gamma" not in copy


def test_every_ctrl_c_line_of_report_is_in_chinese():
    """The last line of a Ctrl-C at each point report.py knows (during training, after it,
    while the GIFs are recorded) is Chinese from the catalogue, its `when` and `then` too:
    those lines come only from a Ctrl-C at the right moment, which the smoke runs rarely hit."""
    import ast
    from test_every_script import english_sentences
    tree = ast.parse((ROOT / "report.py").read_text(encoding="utf-8"))
    calls = [node for node in ast.walk(tree) if isinstance(node, ast.Call)
             and getattr(node.func, "id", None) == "interrupted_at"]
    assert len(calls) >= 4
    entries = help_zh.catalogue()
    for call in calls:
        then = call.args[2].value
        when = "".join(part.value for part in ast.walk(call.args[3])
                       if isinstance(part, ast.Constant)) if len(call.args) > 3 else ""
        line = (f"interrupted at step 120{when}: runs/x holds model.pt, progress.csv "
                f"({then}: python ppo_cartpole.py --eval runs/x)")
        chinese = help_zh.translate(line, entries)
        assert chinese != line and not english_sentences(chinese), (line, chinese)
