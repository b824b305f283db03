"""The pictures under --lang zh: every word of every script's curve.png and inside.png in
Chinese where a CJK font is found (plots.in_chinese, locale/output.zh-CN.md's section 图里的
文字); without one, English pictures and one line that says so, once; and English runs draw
what they always drew. A new script's pictures are held to this by its smoke run, as its
printed lines are by tests/test_every_script.py's Chinese run."""

import contextlib
import re

import pytest
from matplotlib import font_manager
from matplotlib.text import Text

import plots
from conftest import run_main
from test_every_script import as_flags, script, without_names  # noqa: F401 (script: fixture)

HAN = re.compile(r"[\u4e00-\u9fff]")
# Words a Chinese picture keeps, as the Chinese pages do: the names in formulas (log pi, Var,
# tanh, sqrt, argmax), the ones the glossary leaves untranslated (Huber, Bradley-Terry, Sarsa,
# Double DQN, token, Reacher) and a kept array's name (adv).
SYMBOLS = {"pi", "log", "Var", "tanh", "sqrt", "argmax", "Huber", "Bradley", "Terry", "Sarsa",
           "Double", "token", "Reacher", "adv"}


def saved_figures(monkeypatch):
    """For each figure saved from now on, what plots.in_chinese made of it: {"before": its
    texts before, "made": right after, "drawn": once saved (the tick labels too),
    "fonts_before", "fonts": each text's font families before and after}."""
    saved, original = [], plots.in_chinese

    def texts(fig):
        return [t.get_text() for t in fig.findobj(Text)]

    def fonts(fig):
        return [tuple(t.get_fontfamily()) for t in fig.findobj(Text)]

    @contextlib.contextmanager
    def recorded(fig):
        seen = dict(before=texts(fig), fonts_before=fonts(fig))
        with original(fig):
            seen.update(made=texts(fig), fonts=fonts(fig))
            yield
        saved.append(dict(seen, drawn=texts(fig)))
    monkeypatch.setattr(plots, "in_chinese", recorded)
    return saved


def smoke_run(script, tmp_path, capsys, *lang):
    """The script's SMOKE run from its command line, no GIFs (as the quick layer's), with
    `lang`'s flags."""
    quiet = {} if "gifs" in getattr(script.Config, "UNUSED_FLAGS", ()) else {"gifs": False}
    p = run_main(f"{script.__name__}.py", *as_flags({**script.SMOKE, **quiet}), "--run-dir",
                 tmp_path, *lang, capsys=capsys)
    assert p.returncode == 0, p.stderr
    return p


def english_words(text, names):
    """The English words of a picture's text, once names, numbers, paths and the tick labels'
    $\\mathdefault{...}$ are taken out, and SYMBOLS."""
    text = re.sub(r"\$[^$]*\$", " ", text)
    return [w for line in text.splitlines() for w in re.findall(r"[A-Za-z]{2,}",
                                                                  without_names(line, names))
            if w not in SYMBOLS]


def test_chinese_pictures_hold_no_english_word(script, tmp_path, capsys, monkeypatch):
    """--lang zh with a CJK font: every text of every picture (titles, axis labels, legends,
    colour bars, the tick labels once drawn) is Chinese but for names and symbols, drawn with
    that font behind the figure's own."""
    font = plots.cjk_font()
    if font is None:
        pytest.skip(f"no CJK font here (looked for {', '.join(plots.CJK_FONTS)} and mplfonts): "
                    "pip install mplfonts runs this test")
    saved = saved_figures(monkeypatch)
    p = smoke_run(script, tmp_path, capsys, "--lang", "zh")
    assert "中文字体" not in p.stderr, p.stderr
    assert len(saved) >= 2, "curve.png and inside.png were not both drawn"
    names = [*getattr(script, "LOGGED", {}), "pi"]
    for fig in saved:
        left = {t: english_words(t, names) for t in fig["made"] + fig["drawn"]
                if english_words(t, names)}
        assert not left, f"English left in a picture (add it to locale/output.zh-CN.md): {left}"
        assert any(HAN.search(t) for t in fig["made"]), fig["made"]
        assert all(font in family for family in fig["fonts"]), fig["fonts"]


def test_without_a_cjk_font_the_pictures_stay_english_and_one_line_says_so(
        tmp_path, capsys, monkeypatch):
    """The font search fails (no font of CJK_FONTS known to matplotlib, no mplfonts): the
    pictures are what --lang en draws, and one line, in Chinese, names what was looked for and
    how to get it, once though the run saves two pictures."""
    import ppo_cartpole as script

    saved = saved_figures(monkeypatch)
    smoke_run(script, tmp_path / "en", capsys, "--lang", "en")
    english, chinese = list(saved), saved
    saved.clear()
    monkeypatch.setattr(font_manager.fontManager, "ttflist", [
        f for f in font_manager.fontManager.ttflist if f.name not in plots.CJK_FONTS])
    monkeypatch.setattr(plots, "MPLFONTS", ("no_such_package", plots.MPLFONTS[1]))
    monkeypatch.setattr(plots, "SAID", set())
    assert plots.cjk_font() is None
    p = smoke_run(script, tmp_path / "zh", capsys, "--lang", "zh")
    assert len(chinese) == len(english) >= 2
    for en, zh in zip(english, chinese):
        assert zh["made"] == zh["before"] and zh["fonts"] == en["fonts"]
        assert [t for t in zh["made"] if "__seed" not in t] == [  # but the run folder's name
            t for t in en["made"] if "__seed" not in t]
    said = [line for line in p.stderr.splitlines() if "中文字体" in line]
    assert len(said) == 1, p.stderr
    assert "pip install mplfonts" in said[0] and all(f in said[0] for f in plots.CJK_FONTS)
    assert not HAN.search(" ".join(t for fig in chinese for t in fig["drawn"]))


@pytest.mark.quick
def test_english_pictures_are_drawn_as_before(tmp_path, capsys, monkeypatch):
    """--lang en, in a Chinese locale too: plots.in_chinese leaves every text and font as the
    code wrote it, and a picture saved by plots.draw is, byte for byte, the figure saved
    by matplotlib alone."""
    import ppo_cartpole as script

    monkeypatch.setenv("LANG", "zh_CN.UTF-8")
    saved = saved_figures(monkeypatch)
    smoke_run(script, tmp_path, capsys, "--lang", "en")
    assert len(saved) >= 2
    for fig in saved:
        assert fig["made"] == fig["before"] and fig["fonts"] == fig["fonts_before"]
        assert not HAN.search(" ".join(fig["drawn"]))
    (run,) = [p for p in tmp_path.iterdir() if not p.is_symlink()]
    logs, rows = plots.load_logs(run), [[plots.episode_returns(20, 475)]]
    monkeypatch.undo()  # plots.in_chinese itself
    plots.draw(run, "drawn.png", rows, logs)
    fig = plots.figure(rows, logs, run.name)
    fig.savefig(run / "alone.png", dpi=96)  # plots.draw's
    plots.pyplot().close(fig)
    assert (run / "drawn.png").read_bytes() == (run / "alone.png").read_bytes()
