"""The checks of exercises/sarsa_update.py, Sarsa's update of a Q table (the next action taken) and
its TD error: its worked cases, its named mistakes and its runs."""

from checking import tr
import runs
from cases._td_control import check_td_control

SCRIPT = "q_learning_cliffwalking"
FUNCTION = "sarsa_update"
ORDER = 21  # its row in docs/exercises.md's table
RUN = runs.CLIFF
LOOP = runs.TABULAR_LOOP
LEARN = runs.TABULAR_LEARN


def loop_hint():
    return tr(
        "Sarsa's table is updated by your function at every step: its columns "
        "(sarsa_*) differ first, at the first\n  episode where the table differs "
        "(Q-learning's columns stay the script's own).",
        "Sarsa 的表每一步都由你的函数更新：它的那几列（sarsa_*）最先不同，就在表第一次不同的"
        "\n  那个回合（Q 学习的那几列还是脚本自己的）。")


def worked_cases(fn):
    return check_td_control(fn, sarsa=True)


def learned(result):
    runs.cliff_walked("sarsa", result)
