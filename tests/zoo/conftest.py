"""The zoo's check scripts (``python -m tests.zoo.check``) are tools, not tests: their examples simulate records."""

collect_ignore = ["check.py", "check_b.py"]
