"""The two READMEs: the same commands, the Chinese one mostly Chinese, and its code
references (`file.py:LINE` `name`) still pointing at the line that holds the name."""

import re
import string
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
EN, ZH = ROOT / "README.md", ROOT / "README.zh-CN.md"
SCRIPTS = ("ppo_cartpole.py", "ppo_kl_cartpole.py", "actor_critic_cartpole.py", "ddpg_walker.py")
TUTORIAL_TITLES = (
    "PPO近段策略优化玩cartpole游戏",  # 000
    "强化学习PPO从理论到代码详解(2)---PPO1和PPO2",  # 001
    "损失函数", "强化学习PPO从理论到代码详解",  # 002: no title line of its own
    "【PyTorch深度强化学习】DDPG算法的讲解及实战(超详细 附源码)",  # 003
    "使用 actor-critic 方法来控制 CartPole-V0 游戏",  # 004
)


def split_code(path):
    """(lines inside ``` fences, lines outside them) of a markdown file."""
    inside, outside, in_code = [], [], False
    for line in path.read_text(encoding="utf-8").splitlines():
        if line.lstrip().startswith("```"):
            in_code = not in_code
        else:
            (inside if in_code else outside).append(line)
    return inside, outside


def commands(path):
    """The command lines of a markdown file's code blocks, trailing `  # comment` removed."""
    lines = (re.sub(r"\s+#.*$", "", line).strip() for line in split_code(path)[0])
    return {line for line in lines if line.split(" ")[0] in ("python", "pip", "pytest", "tensorboard")}


def test_both_readmes_show_the_same_commands():
    zh = commands(ZH)
    assert commands(EN) == zh
    assert {"pip install -r requirements.txt", "python ppo_cartpole.py", "pytest"} <= zh


def test_zh_readme_is_mostly_chinese():
    prose = re.sub(r"`[^`]*`", "", "\n".join(split_code(ZH)[1]))
    counted = [c for c in prose if not c.isspace() and c not in string.punctuation]
    cjk = [c for c in counted if re.match(r"[\u3000-\u303f\u4e00-\u9fff\uff00-\uffef]", c)]
    assert len(cjk) / len(counted) > 0.5, f"{len(cjk)} CJK of {len(counted)} characters"
    text = ZH.read_text(encoding="utf-8")
    for name in SCRIPTS + TUTORIAL_TITLES:
        assert name in text, name


def test_readmes_link_each_other():
    assert "README.zh-CN.md" in EN.read_text(encoding="utf-8")
    assert "README.md" in ZH.read_text(encoding="utf-8")


def test_code_references_point_at_their_names():
    checked = 0
    for line in ZH.read_text(encoding="utf-8").splitlines():
        for ref in re.finditer(r"`(\w+\.py):(\d+)`", line):
            # The name: the next backticked span, in the same table row or within 60 characters.
            after = line[ref.end():] if line.startswith("|") else line[ref.end():ref.end() + 60]
            name = re.search(r"`([^`]+)`", after)
            assert name and ":" not in name.group(1), f"no name after {ref.group(0)}: {line}"
            source = (ROOT / ref.group(1)).read_text(encoding="utf-8").splitlines()
            number = int(ref.group(2))
            assert number <= len(source) and name.group(1) in source[number - 1], \
                f"{ref.group(1)}:{number} does not contain {name.group(1)!r}"
            checked += 1
    assert checked >= 20
