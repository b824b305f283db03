"""Chinese for the reader. --help in Chinese: `--help-zh` (or --help in a Chinese locale) puts
a Chinese line under each flag's English help, read from locale/flags.zh-CN.md, and the
script's 中文导读 under its English description. The output in Chinese: `--lang zh` (or a
Chinese locale) prints each line the code prints in English in its Chinese from
locale/output.zh-CN.md, so the code keeps its English sentences, and plots.py draws the
pictures' words in Chinese from the same file (output_entries). cli.parse_config asks it;
nothing here knows a script."""

import argparse
import ast
import dataclasses
import importlib
import inspect
import os
import re
import sys
import textwrap
from pathlib import Path

HELP_ZH = Path(__file__).resolve().parent / "locale" / "flags.zh-CN.md"
OUTPUT_ZH = HELP_ZH.with_name("output.zh-CN.md")
HINT = "--help-zh: a Chinese line under each flag (每个参数下面加一行中文说明)"  # --help ends so
EPILOG = HINT  # what --help ends with
LANG_HELP = ("the output's language: zh (Chinese) or en (default: the locale's, as for --help)",
             "输出的语言：zh 中文，en 英文（不写时按系统语言，和 --help 一样）")  # --lang, in --help


def wanted(argv):
    """(argv with --help-zh read as --help and --lang taken out, whether to add the Chinese
    lines (--help-zh; --help with --lang zh or, without --lang, a Chinese locale), whether the
    output is in Chinese: --lang zh|en, else the locale)."""
    argv, lang = list(argv), None
    for i, arg in enumerate(argv):
        if arg.startswith("--lang="):
            argv[i:i + 1], lang = [], arg.split("=", 1)[1]
        elif arg == "--lang" and i + 1 < len(argv):
            argv[i:i + 2], lang = [], argv[i + 1]
        if lang is not None:
            break
    if lang not in (None, "zh", "en"):
        argv.append(f"--lang={lang}")  # refused by argparse, as an unknown flag is
    chinese = lang == "zh" or lang is None and chinese_locale()
    zh = "--help-zh" in argv or bool({"-h", "--help"} & set(argv) and chinese)  # --lang zh too
    return ["--help" if arg == "--help-zh" else arg for arg in argv], zh, chinese


def chinese_locale():
    """Whether the locale (LC_ALL, else LC_MESSAGES, else LANG: the first one set) is Chinese
    (zh_CN.UTF-8 and the like, in either case). exercises/check.py asks it too."""
    env = os.environ
    return (env.get("LC_ALL") or env.get("LC_MESSAGES") or env.get("LANG", "")).lower().startswith(
        "zh")


def flags(script, module=None):
    """{field: its Chinese line} for `script` (its name), read from HELP_ZH's tables: a section
    whose heading names fewer scripts, `script` among them, wins over one naming more, and
    every section wins over 所有脚本 (all scripts). A script that no heading names (a new one,
    or a copy) takes a flag's line from a named script whose English help of that flag is its
    own (a Chinese line translates an English one), the nearest such script first (the one
    with the most flags like it); the script's own FLAGS_ZH ({field: line}, if it has one: a
    new script needs no other file) wins over them all."""
    sections = []  # (the scripts a heading names, {field: Chinese line}), HELP_ZH read once
    for line in HELP_ZH.read_text(encoding="utf-8").splitlines():
        if line.startswith("## "):
            sections.append((re.findall(r"`(\w+)\.py`", line), {}))
        elif sections and (row := re.match(r"\| `--([\w-]+)` \| (.+) \|$", line)):
            sections[-1][1][row[1].replace("-", "_")] = row[2]

    def listed(name):  # the lines of the sections naming `name`, and 所有脚本's
        lines = {}
        for names, rows in sorted(sections, key=lambda s: (bool(s[0]), -len(s[0]))):
            if not names or name in names:
                lines.update(rows)
        return lines

    found = listed(script)
    module = module or importlib.import_module(script)  # a script run as __main__: given
    named = {name for names, _ in sections for name in names}
    if script not in named:
        mine = english(module.Config)
        theirs = {name: english(importlib.import_module(name).Config) for name in sorted(named)}
        alike = {name: {f for f, e in mine.items() if theirs[name].get(f) == e} for name in theirs}
        for name in sorted(theirs, key=lambda name: len(alike[name])):  # the nearest last: wins
            found.update({f: line for f, line in listed(name).items() if f in alike[name]})
    return {**found, **getattr(module, "FLAGS_ZH", {})}


def english(cls):
    """{field: its English help} of a Config, its bases' fields included."""
    docs = {}
    for klass in reversed(cls.__mro__[:-1]):  # the string under each field; subclasses win
        docs.update(field_docs(klass))
    return {f.name: docs[f.name] for f in dataclasses.fields(cls) if docs.get(f.name)}


def field_docs(klass):
    """{field: the string under it} of one dataclass, read from its source."""
    if "__dataclass_fields__" not in vars(klass):
        return {}
    body = ast.parse(textwrap.dedent(inspect.getsource(klass))).body[0].body
    return {node.target.id: " ".join(str(nxt.value.value).split())
            for node, nxt in zip(body, body[1:]) if isinstance(node, ast.AnnAssign)
            and isinstance(nxt, ast.Expr) and isinstance(nxt.value, ast.Constant)}



def overview(cls, description):
    """`description`, then the 中文导读 paragraph of the module that defines `cls`."""
    doc = sys.modules[cls.__module__].__doc__ or ""
    return "\n\n".join([description or "", *(p for p in doc.split("\n\n")
                                             if p.startswith("中文导读"))])


class HelpFormatter(argparse.ArgumentDefaultsHelpFormatter):
    """--help with each flag's default; a Chinese line (--help-zh) stays on a line of its own,
    after the English line and its default, wrapped by columns (a Chinese character takes two)."""

    def _get_help_string(self, action):
        english, _, chinese = super()._get_help_string(action).partition("\n")
        default = " (default: %(default)s)"
        if chinese.endswith(default):
            english, chinese = english + default, chinese[:-len(default)]
        return english + (f"\n{chinese}" if chinese else "")

    def _split_lines(self, text, width):
        split = super()._split_lines
        return [piece for line in text.split("\n")
                for piece in (_wrap_wide(line, width) if WIDE.search(line) else split(line, width))]

    def _fill_text(self, text, width, indent):
        fill = super()._fill_text
        return "\n\n".join("\n".join(indent + line for line in _wrap_wide(part, width))
                           if WIDE.search(part) else fill(part, width, indent)
                           for part in text.split("\n\n"))


class HelpFormatterZh(HelpFormatter):
    """HelpFormatter for --help-zh: argparse's own -h, --help gets its Chinese line too."""

    def _get_help_string(self, action):
        text = super()._get_help_string(action)
        return text + "\n显示本帮助并退出" if action.dest == "help" else text


WIDE = re.compile(r"[\u3000-\u303f\u4e00-\u9fff\uff00-\uffef]")  # two columns each
TOKEN = re.compile(r"[\u3000-\u303f\u4e00-\u9fff\uff00-\uffef]|[^\s\u3000-\u303f\u4e00-\u9fff"
                   r"\uff00-\uffef]+|\s+")  # a Chinese character, a word or a space
OPEN, CLOSE = "（《“", "，。；：、）》”"  # no line ends with the first nor starts with the second


def columns(text):
    return len(text) + len(WIDE.findall(text))


def _join(text):
    """The lines of `text` as one, as Chinese is written: no space where two Chinese characters
    meet or where full-width punctuation (，（) touches the break; a space between Chinese and
    Latin text (读 DDPG, 用 n 步) and between two Latin words."""
    def glue(m):  # m[1] ends a line, m[2] starts the next (looked at, not replaced)
        tight = PUNCT.match(m[1]) or PUNCT.match(m[2]) or HAN.match(m[1]) and HAN.match(m[2])
        return m[1] + ("" if tight else " ")
    return re.sub(r"(\S)[ \t]*\n\s*(?=(\S))", glue, text)


HAN = re.compile(r"[\u4e00-\u9fff]")  # a Chinese character
PUNCT = re.compile(r"[\u3000-\u303f\uff00-\uffef]")  # full-width punctuation


def wrapped(text, width):
    """`text` (Chinese) in lines of at most `width` columns, joined by newlines (_wrap_wide):
    plots.py wraps a translated axis label so."""
    return "\n".join(_wrap_wide(text, width))


def _wrap_wide(text, width):
    """`text` in lines of at most `width` columns, broken between words or Chinese characters;
    lines in the source are joined as Chinese is written (_join)."""
    text = _join(text)
    lines, line = [], []
    for token in TOKEN.findall(" ".join(text.split())):
        if token.isspace():
            line += [" "] if line else []
        elif line and columns("".join(line) + token) > width:
            rest, cut = line + [token], len(line)
            while cut > 1 and (rest[cut] in CLOSE or rest[cut - 1] in OPEN):
                cut -= 1
            lines.append("".join(rest[:cut]).rstrip())
            line = rest[cut:] if rest[cut] != " " else rest[cut + 1:]
        else:
            line.append(token)
    return lines + ["".join(line).rstrip()] if line else lines


# ---- the output in Chinese ---------------------------------------------------------------

def catalogue(path=OUTPUT_ZH):
    """[(the English line as a pattern, its Chinese)] from `path`'s pairs of lines `en: ...`,
    `zh: ...`; {name} in the English stands for any text, put where the Chinese has {name}.
    An English without {name} first (a line that is exactly it takes it: a picture's "policy
    steps" is not "policy {answers}"), then the longest: a line matches the most specific
    entry."""
    pairs, english = [], None
    for line in path.read_text(encoding="utf-8").splitlines():
        if line.startswith("en: "):
            english = line[4:]
        elif line.startswith("zh: ") and english is not None:
            pairs.append((pattern(english), line[4:]))
            english = None
    return sorted(pairs, key=lambda pair: (bool(pair[0].groupindex), -len(pair[0].pattern)))


def pattern(english):
    """'run folder: {dir}' -> a regex that matches the line the code prints, {dir} any text
    that is not blank (its padding kept: 'step {step}' matches 'step     2048')."""
    regex, seen = "", set()
    for text, name in re.findall(r"([^{]*)(?:\{(\w+)\}|$)", english):
        regex += re.escape(text)
        if name:
            regex += f"(?P={name})" if name in seen else f"(?P<{name}>\\s*\\S.*?)"  # not blank
            seen.add(name)
    return re.compile(regex)


def translate(line, entries):
    """`line` in Chinese, where an entry of `entries` (catalogue()) matches the whole of it;
    each field, where it is itself an entry's line, in Chinese too; else `line` as it is."""
    for english, chinese in entries:
        found = english.fullmatch(line)
        if found:
            for name, value in found.groupdict().items():
                chinese = chinese.replace("{" + name + "}", translate(value, entries))
            return chinese
    return line


class Translated:
    """A text stream (sys.stdout, sys.stderr) that writes each whole line translated."""

    def __init__(self, stream, entries):
        self.stream, self.entries, self.pending = stream, entries, ""

    def write(self, text):
        *lines, self.pending = (self.pending + text).split("\n")
        for line in lines:
            self.stream.write(translate(line, self.entries) + "\n")
        return len(text)

    def flush(self):
        if self.pending:  # a line written without its end, e.g. print(..., end="")
            self.stream.write(translate(self.pending, self.entries))
            self.pending = ""
        self.stream.flush()

    def __getattr__(self, name):  # encoding, isatty, fileno: the stream's
        return getattr(self.stream, name)


def print_in_chinese():
    """From now on sys.stdout and sys.stderr print each line in Chinese where the catalogue
    has it (once: a second call changes nothing)."""
    entries = catalogue()
    for name in ("stdout", "stderr"):
        stream = getattr(sys, name)
        if not isinstance(stream, Translated):
            setattr(sys, name, Translated(stream, entries))


def output_entries():
    """The catalogue the output is printed through once print_in_chinese has put it in place
    (--lang zh, or a Chinese locale), else None (English). plots.py asks it: where it is not
    None, the pictures are drawn in Chinese too, from the same catalogue."""
    return sys.stdout.entries if isinstance(sys.stdout, Translated) else None
