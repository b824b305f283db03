"""The checks of exercises/q_learning_update.py, Q-learning's update of a Q table (the best next
action) and its TD error: its worked cases, its named mistakes and its runs."""

from checking import tr
import runs
from cases._td_control import check_td_control

SCRIPT = "q_learning_cliffwalking"
FUNCTION = "q_learning_update"
ORDER = 22  # its row in docs/exercises.md's table
RUN = runs.CLIFF
LOOP = runs.TABULAR_LOOP
LEARN = runs.TABULAR_LEARN


def loop_hint():
    return tr(
        "Q-learning's table is updated by your function at every step: its columns "
        "(q_learning_*) differ first, at the\n  first episode where the table differs "
        "(Sarsa's columns stay the script's own).",
        "Q 学习的表每一步都由你的函数更新：它的那几列（q_learning_*）最先不同，就在表第一次"
        "不同的\n  那个回合（Sarsa 的那几列还是脚本自己的）。")


def worked_cases(fn):
    return check_td_control(fn, sarsa=False)


def learned(result):
    runs.cliff_walked("q_learning", result)
