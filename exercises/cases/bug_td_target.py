"""The planted bug of exercises/bug_td_target.py: checked as the td_target exercise is
(cases/td_target.py)."""

BUG_IN = "td_target"
