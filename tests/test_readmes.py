"""The two READMEs: the same commands, the Chinese one mostly Chinese, its terms used one
way, and its code references (`file.py:LINE` `name`), variable names and hyperparameter
tables still agreeing with the code; the English one short, its docs pages there, and the
DDPG 1M table in docs/results.md the one the committed records give."""

import dataclasses
import json
import importlib
import importlib.util
import re
import statistics
import string

import pytest
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
EN, ZH = ROOT / "README.md", ROOT / "README.zh-CN.md"
RESULTS = ROOT / "docs" / "results.md"  # the measured results, the DDPG 1M table among them
from test_every_script import SCRIPTS as FOUND  # noqa: E402
SCRIPTS = tuple(f"{name}.py" for name in FOUND)  # every top-level *.py with a train()
TUTORIAL_TITLES = (
    "PPO近段策略优化玩cartpole游戏",  # 000
    "强化学习PPO从理论到代码详解(2)---PPO1和PPO2",  # 001
    "前面两节讲完了critic、actor以及缓冲区的设计",  # 002: no title line; its first sentence,
    "实现机械臂reach某点之PPO算法实现",  # and the series it belongs to (not 001's)
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
    return {line for line in lines
            if line.split(" ")[0] in ("python", "pip", "pytest", "tensorboard")}


def linked_docs():
    """The docs/*.md pages README.md links to, as paths (they may not exist)."""
    names = re.findall(r"\]\((docs/[^)#\s]+\.md)(?:#[^)]*)?\)", EN.read_text(encoding="utf-8"))
    return [ROOT / name for name in dict.fromkeys(names)]


def test_both_readmes_show_the_same_commands():
    en, zh = commands(EN), commands(ZH)
    assert en <= zh, f"missing from README.zh-CN.md: {en - zh}"
    # The Chinese guide is one page, so it also shows commands the English README leaves to
    # its docs pages; beyond those it may add only the PyPI mirror lines a reader in China needs.
    docs = set().union(*(commands(page) for page in linked_docs()))
    extra = {line for line in zh - en - docs if "pypi.tuna.tsinghua.edu.cn" not in line}
    assert not extra, f"commands only in README.zh-CN.md: {extra}"
    assert {"pip install -r requirements.txt", "python ppo_cartpole.py", "pytest"} <= zh


def test_both_readmes_open_with_the_number_of_scripts_there_are():
    """The first paragraph of each README counts the scripts ("Twelve scripts", "十二个脚本"):
    a new script changes the count in both."""
    words = {10: ("Ten", "十"), 11: ("Eleven", "十一"), 12: ("Twelve", "十二"),
             13: ("Thirteen", "十三"), 14: ("Fourteen", "十四"), 15: ("Fifteen", "十五")}
    en, zh = words[len(SCRIPTS)]
    first = {path: path.read_text(encoding="utf-8").split("\n\n")[2] for path in (EN, ZH)}
    assert f"{en} scripts" in first[EN], first[EN][:80]
    assert f"有{zh}个脚本" in first[ZH], first[ZH][:80]


def test_readme_is_short_and_its_docs_links_exist():
    """The README is read in five minutes; what it leaves out is one link away."""
    lines = EN.read_text(encoding="utf-8").splitlines()
    assert len(lines) <= 216, f"README.md has {len(lines)} lines (at most 216)"
    pages = linked_docs()
    assert pages, "README.md links no docs/*.md page"
    for page in pages:
        assert page.is_file(), f"README.md links {page.relative_to(ROOT)}, which does not exist"
    # Every link among them (the README's, each page's to the others and back) resolves,
    # down to its #section.
    for source in [EN, *pages]:
        text = source.read_text(encoding="utf-8")
        for name, anchor in re.findall(r"\]\(([^)#\s:]+\.md)(?:#([^)]*))?\)", text):
            target = source.parent / name
            assert target.is_file(), f"{source.relative_to(ROOT)} links {name}"
            if anchor:
                assert anchor in anchors(target), f"{source.relative_to(ROOT)} links {name}#{anchor}"


def anchors(path):
    """The #anchors GitHub gives the headings of a markdown file."""
    headings = re.findall(r"^#+ (.+)$", "\n".join(split_code(path)[1]), re.MULTILINE)
    return {re.sub(r"[^\w\- ]", "", h.strip().lower()).replace(" ", "-") for h in headings}


def test_zh_readme_is_mostly_chinese():
    prose = re.sub(r"`[^`]*`", "", "\n".join(split_code(ZH)[1]))
    counted = [c for c in prose if not c.isspace() and c not in string.punctuation]
    cjk = [c for c in counted if re.match(r"[\u3000-\u303f\u4e00-\u9fff\uff00-\uffef]", c)]
    assert len(cjk) / len(counted) > 0.5, f"{len(cjk)} CJK of {len(counted)} characters"
    text, english = ZH.read_text(encoding="utf-8"), EN.read_text(encoding="utf-8")
    for name in [s for s in SCRIPTS if s in english] + list(TUTORIAL_TITLES):  # a new script:
        assert name in text, name  # in both READMEs once it is in one


def test_readmes_link_each_other():
    assert "README.zh-CN.md" in EN.read_text(encoding="utf-8")
    assert "README.md" in ZH.read_text(encoding="utf-8")


@pytest.mark.quick
@pytest.mark.parametrize("guide", ["README.zh-CN.md", "docs/ppo_to_grpo.md",
                                   "docs/ppo_to_grpo.zh-CN.md", "docs/ppo_to_rlhf.md",
                                   "docs/ppo_to_rlhf.zh-CN.md"])
def test_code_references_point_at_their_names(guide):
    """Each `file.py:LINE` `name` of a guide is on the line of `name` nearest to it; after an
    edit that moves lines, `python tests/line_refs.py` moves them back."""
    import line_refs

    text = (ROOT / guide).read_text(encoding="utf-8")
    _, moved, problems = line_refs.refreshed(text)
    assert not problems, problems
    assert not moved, f"run python tests/line_refs.py: {moved}"
    assert len(line_refs.REF.findall(text)) >= 20


def test_a_reference_to_a_call_is_not_moved_to_the_definition():
    """`name(` names a call: a guide that gives a function and its call gets two lines."""
    import line_refs

    text = "定义 `ddpg_walker.py:190` `td_target`，调用 `ddpg_walker.py:190` `td_target(`"
    _, moved, _ = line_refs.refreshed(text)
    source = (ROOT / "ddpg_walker.py").read_text(encoding="utf-8").splitlines()
    (define, _), (call, _) = [(int(new.split()[0].split(":")[1]), new) for _, new in moved]
    assert source[define - 1].startswith("def td_target(")
    assert "= td_target(" in source[call - 1], source[call - 1]


def zh_prose():
    """README.zh-CN.md outside its code blocks, as one string."""
    return "\n".join(split_code(ZH)[1])


def test_zh_readme_uses_one_word_per_term():
    prose = zh_prose()
    # The tutorials' other names for our terms are given, so a reader can map them.
    for word in ("情节", "行动者", "评论家", "演员", "评论员", "折扣因子", "近端策略优化", "近段",
                 "clip_param", "clip_ratio", "截断系数"):
        assert word in prose, word
    # First use of a term: the Chinese word, then the English in brackets.
    for zh, en in (("回合", "episode"), ("回报", "return"), ("裁剪", "clip"),
                   ("截断", "truncated"), ("终止", "terminated"), ("折扣因子", "discount factor"),
                   ("自举", "bootstrap"), ("熵", "entropy"), ("奈特", "nat"),
                   ("回放缓冲区", "replay buffer"), ("重要性采样", "importance sampling"),
                   ("广义优势估计", "GAE")):
        first = prose.index(zh) + len(zh)
        assert prose[first:first + len(en) + 1] == f"（{en}", f"first {zh} is not {zh}（{en}"
    # 截断 is truncated only (clip is 裁剪): every line that says it names the time limit.
    for line in prose.splitlines():
        if "截断" in line:
            assert "truncated" in line or "时间截断" in line, line
    assert "nats" not in prose


def table_rows(lines):
    """Cells of each markdown table row in `lines` (a `\\|` inside a cell is not a border)."""
    for line in lines:
        if line.startswith("|") and not line.startswith("|---"):
            yield [cell.strip() for cell in re.split(r"(?<!\\)\|", line)[1:-1]]


def section(title):
    """The lines of README.zh-CN.md's `## title` section."""
    text = ZH.read_text(encoding="utf-8")
    body = text.split(f"\n## {title}\n", 1)[1]
    return body.split("\n## ", 1)[0].splitlines()


def test_zh_variable_names_exist_in_the_script_named():
    rows = [r for r in table_rows(section("术语对照")) if len(r) == 4 and ".py` `" in r[2]]
    assert len(rows) >= 10
    for row in rows:
        script, *names = re.findall(r"`([^`]+)`", row[2])
        source = (ROOT / script).read_text(encoding="utf-8")
        for name in names:
            assert name in source, f"{name!r} is not in {script}"


def test_zh_hyperparameter_tables_match_each_config():
    """Each flag in the guide's tables is a flag of every script its table names, shown once,
    with the default that script's Config has; the flags that stand for a tutorial's variable
    are among them (the rest: each script's --help)."""
    configs = {s: importlib.import_module(s[:-3]).Config for s in SCRIPTS}
    seen = {s: [] for s in SCRIPTS}
    scripts = ()
    for line in section("超参数"):
        if line.startswith("### "):
            scripts = re.findall(r"`(\w+\.py)`", line)
            assert scripts and set(scripts) <= set(SCRIPTS), line
            continue
        row = next(table_rows([line]), None)
        if not row or not row[0].startswith("`--"):
            continue
        flag = re.match(r"`--([\w-]+)`", row[0]).group(1)
        shown = re.search(r"`([^`]*)`", row[2]).group(1)
        for script in scripts:
            fields = {f.name: f.default for f in dataclasses.fields(configs[script])}
            name = flag.replace("-", "_")
            assert name in fields, f"--{flag} is not a flag of {script}"
            assert same(shown, fields[name]), \
                f"{script} --{flag}: the table says {shown}, the Config {fields[name]!r}"
            seen[script].append(name)
    tutorials_variables = {  # clip_param, lam, gamma, tau, ... of tutorials 000-004
        "ppo_cartpole.py": {"gamma", "lam", "clip_coef", "learning_rate", "update_epochs",
                            "target_kl"},
        "ppo_kl_cartpole.py": {"gamma", "lam", "d_targ", "kl_tolerance", "beta_init"},
        "actor_critic_cartpole.py": {"gamma", "learning_rate", "num_steps"},
        "ddpg_walker.py": {"gamma", "tau", "batch_size", "buffer_size", "actor_lr", "critic_lr",
                           "expl_noise"},
        "td3_walker.py": {"policy_delay", "target_noise", "noise_clip"},  # TD3's own flags
        "sac_walker.py": {"alpha", "alpha_lr", "target_entropy"},  # SAC's own flags
        "dqn_cartpole.py": {"double", "target_update_interval", "train_freq", "eps_end"}}  # DQN's
    for script, names in seen.items():
        twice = {name for name in names if names.count(name) > 1}
        assert not twice, f"{script}: twice in the tables {twice}"
        assert tutorials_variables.get(script, set()) <= set(names), \
            f"{script}: not in the tables {tutorials_variables.get(script, set()) - set(names)}"


def same(shown, default):
    """Whether the text of a table's default cell states `default`."""
    if default is None or isinstance(default, bool):
        return shown == str(default)
    if isinstance(default, (int, float)):
        try:
            return float(shown) == default
        except ValueError:
            return False
    return shown == default


def walkers_1m():
    """benchmarks/ddpg_walker_1m.py, loaded fresh (its SCRIPT global is set per test)."""
    spec = importlib.util.spec_from_file_location("walkers_1m",
                                                  ROOT / "benchmarks" / "ddpg_walker_1m.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_readme_ddpg_table_comes_from_the_committed_records(capsys):
    """The DDPG 1M table in docs/results.md and its summary line are what
    `ddpg_walker_1m.py table` prints from the evaluations.csv files in benchmarks/results/ (no
    cell typed by hand, none left stale)."""
    module = walkers_1m()
    module.table()
    out = capsys.readouterr().out
    rows = [line for line in out.splitlines() if line.startswith("| ")]
    page = RESULTS.read_text(encoding="utf-8")
    assert len(rows) == 1 + len(module.SEEDS)
    for row in rows:
        assert row in page.splitlines(), f"docs/results.md lacks the table row {row!r}"
    summaries = [line for line in out.splitlines() if line.startswith("Over the ")]
    assert len(summaries) == 2  # the mean of the last-10 means, and of the highest evaluations
    for summary in summaries:  # with its standard error
        assert summary in " ".join(page.split()), f"docs/results.md lacks {summary!r}"
    # TD3's table, in its own section, from its own records
    module.SCRIPT = "td3_walker"
    module.table()
    td3_out = capsys.readouterr().out.splitlines()
    td3_rows = [line for line in td3_out if line.startswith("| ")]
    td3_section = page.split("## TD3 on Walker2d-v5")[1].split("\n## ")[0]
    assert len(td3_rows) == 1 + len(module.SEEDS)
    for row in td3_rows:
        assert row in td3_section.splitlines(), f"docs/results.md's TD3 section lacks {row!r}"
    for summary in [line for line in td3_out if line.startswith("Over the ")]:
        assert summary in " ".join(td3_section.split()), f"the TD3 section lacks {summary!r}"


SAC_PAGES = [(RESULTS, "## SAC on Walker2d-v5"),
             (ROOT / "docs" / "results.zh-CN.md", "## SAC 在 Walker2d-v5 上")]


def test_the_sac_section_compares_at_equal_steps_from_the_committed_records(capsys):
    """SAC's table on both results pages (DDPG, TD3 and SAC at 300,000 steps) is what
    `ddpg_walker_1m.py at 300000` prints from the committed evaluations.csv files, SAC on at
    least 3 seeds."""
    walkers_1m().at_equal_steps(300_000)
    header, _, *rows = capsys.readouterr().out.splitlines()
    assert [row.split(" | ")[0] for row in rows] == ["| DDPG", "| TD3", "| SAC"]
    assert len(rows[2].split(" | ")[1].split(", ")) >= 3, rows[2]  # SAC's seeds at 300k
    for path, heading in SAC_PAGES:
        page = path.read_text(encoding="utf-8")
        assert heading in page, f"{path.name} lacks its SAC section {heading!r}"
        section = page.split(heading)[1].split("\n## ")[0].splitlines()
        for row in rows + ([header] if path == RESULTS else []):
            assert row in section, f"{path.name}'s SAC section lacks {row!r}"


def dqn_section(path, heading):
    page = path.read_text(encoding="utf-8")
    assert heading in page, f"{path.name} lacks its DQN section {heading!r}"
    return page.split(heading)[1].split("\n## ")[0]


DQN_PAGES = [(RESULTS, "## DQN on CartPole-v1"),
             (ROOT / "docs" / "results.zh-CN.md", "## DQN 在 CartPole-v1 上")]


@pytest.mark.parametrize("path,heading", DQN_PAGES)
def test_results_dqn_figures_come_from_the_committed_records(path, heading):
    """The DQN section of each results page: its per-seed table is the record's rows of the
    defaults' commit (benchmarks/results/dqn_cartpole_seeds.csv), and its side-by-side table
    with SB3's DQN and the summary under it are what `bench_dqn.py --table` prints from
    benchmarks/results/dqn_sb3_cartpole.csv (no cell typed by hand, none left stale)."""
    import csv

    section = dqn_section(path, heading)
    lines = section.splitlines()
    with open(ROOT / "benchmarks" / "results" / "dqn_cartpole_seeds.csv", newline="") as f:
        record = [r for r in csv.DictReader(f) if r["commit"] == "80c09bf"]
    assert len(record) == 5
    for r in record:
        row = f"| {r['seed']} | {int(r['solved_step']):,} | {float(r['solved_seconds']):.1f} |"
        assert row in lines, f"{path.name}'s DQN section lacks {row!r}"
    spec = importlib.util.spec_from_file_location("bench_dqn", ROOT / "benchmarks" / "bench_dqn.py")
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    printed = bench.table(bench.read_rows())
    shown = [line for line in printed if line.startswith("| ")]  # header and seed rows
    for row in shown if path == RESULTS else [r for r in shown if re.match(r"\| \d", r)]:
        assert row in lines, f"{path.name}'s DQN section lacks the table row {row!r}"
    with open(ROOT / "benchmarks" / "results" / "dqn_heldout_seeds.csv", newline="") as f:
        held = {r["seed"]: r for r in csv.DictReader(f)}  # seeds 5-9, no default chosen on them
    assert sorted(held) == ["5", "6", "7", "8", "9"] and all(r["solved_step"] for r in held.values())
    steps = [int(held[s]["solved_step"]) for s in sorted(held)]
    at = section.find("dqn_heldout_seeds.csv")  # the seeds' steps, in order, after its name
    for n in steps + [statistics.median(steps)]:
        assert section.find(f"{n:,.0f}", at) > at, f"{path.name}: no {n:,.0f} for seeds 5-9"
        at = section.find(f"{n:,.0f}", at)
    if path == RESULTS:  # the summary in English; the Chinese page says it in Chinese
        for summary in [line for line in printed if not line.startswith("|")]:
            assert summary in " ".join(section.split()), f"docs/results.md lacks {summary!r}"


@pytest.mark.parametrize("path", [RESULTS, ROOT / "docs" / "results.zh-CN.md"])
def test_results_reinforce_table_comes_from_the_committed_record(path):
    """The REINFORCE table on each results page (seeds 0-4 beside A2C and PPO) is what
    `bench_cartpole.py --table` prints from benchmarks/results/reinforce_cartpole.json."""
    spec = importlib.util.spec_from_file_location("bench_cartpole",
                                                  ROOT / "benchmarks" / "bench_cartpole.py")
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    lines = path.read_text(encoding="utf-8").splitlines()
    rows = bench.table("benchmarks/results/reinforce_cartpole.json")
    for row in rows[2:] if path != RESULTS else rows:  # the Chinese page: its own header
        assert row in lines, f"{path.name} lacks the REINFORCE table row {row!r}"


@pytest.mark.parametrize("path", [RESULTS, ROOT / "docs" / "results.zh-CN.md"])
def test_results_tabular_table_comes_from_the_committed_record(path):
    """The Sarsa / Q-learning table on each results page is what `tabular_cliffwalking.py
    --table` prints from benchmarks/results/tabular_cliffwalking.json."""
    import json

    spec = importlib.util.spec_from_file_location("tabular_bench",
                                                  ROOT / "benchmarks" / "tabular_cliffwalking.py")
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    lines = path.read_text(encoding="utf-8").splitlines()
    rows = bench.summary_rows(json.loads(bench.OUT.read_text()))
    for row in rows[2:] if path != RESULTS else rows:  # the Chinese page: its own header
        assert row in lines, f"{path.name} lacks the Sarsa / Q-learning table row {row!r}"


PPO_PAGES = [(RESULTS, "## PPO on the arm", "## PPO on Walker2d-v5"),
             (ROOT / "docs" / "results.zh-CN.md", "## 机械臂上的 PPO", "## Walker2d-v5 上的 PPO")]


def test_the_ppo_sections_are_their_records(capsys):
    """The PPO-on-Reacher table is what `bench_reacher.py --table` prints from its record
    (the English page word for word; the Chinese page its numbers, row by row), and the
    PPO-on-Walker2d tables what `ddpg_walker_1m.py table` and `at 300000 --script ppo_reacher`
    print from the committed evaluations.csv files, and its tables at equal wall-clock time
    what `walker_rates.py --table` prints from them and the measured rates."""
    spec = importlib.util.spec_from_file_location("bench_reacher",
                                                  ROOT / "benchmarks" / "bench_reacher.py")
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    reacher = bench.table(json.loads(bench.RECORD.read_text())).splitlines()
    module = walkers_1m()
    module.SCRIPT, module.SEEDS = "ppo_reacher", module.SEEDS_OF["ppo_reacher"]
    module.table()
    module.at_equal_steps(300_000, list(module.NAMES))
    spec = importlib.util.spec_from_file_location("walker_rates",
                                                  ROOT / "benchmarks" / "walker_rates.py")
    timed = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(timed)
    rates = json.loads(timed.RECORD.read_text())["rates"]
    for seconds in timed.budgets(rates):
        timed.at_equal_time(rates, seconds)
    walker = [line for line in capsys.readouterr().out.splitlines() if line.startswith("| ")
              and not line.startswith(("| seed |", "| algorithm |"))
              and " minutes | " not in line]  # the rows, not headers
    for path, arm, walk in PPO_PAGES:
        page = path.read_text(encoding="utf-8")
        arm_section = page.split(arm)[1].split("\n## ")[0]
        walk_section = page.split(walk)[1].split("\n## ")[0]
        for row in reacher[2:]:  # numbers, in order, on one line of the section
            cells = re.findall(r"-?[\d,]+(?:\.\d+)?|-(?= \|)", row.split(" | ", 1)[1])
            assert any(re.findall(r"-?[\d,]+(?:\.\d+)?|-(?= \|)", line.split(" | ", 1)[-1])
                       == cells for line in arm_section.splitlines() if line.startswith("| ")), (
                f"{path.name}'s PPO-on-Reacher table lacks the record's row {row!r}")
        for row in walker:
            numbers = row.split(" | ", 1)[1] if " | " in row else row
            assert numbers in walk_section, f"{path.name}'s PPO-on-Walker2d section lacks {row!r}"
