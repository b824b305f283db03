"""Each exercise's checks, one file each, named as its exercise (exercises/check.py finds them)."""
