"""The planted bug of exercises/bug_gae.py: checked as the gae exercise is
(cases/gae.py)."""

BUG_IN = "gae"
