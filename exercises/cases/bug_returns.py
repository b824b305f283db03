"""The planted bug of exercises/bug_returns.py: checked as the discounted_returns exercise is
(cases/discounted_returns.py)."""

BUG_IN = "discounted_returns"
