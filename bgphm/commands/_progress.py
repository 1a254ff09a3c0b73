"""Progress lines on stderr, and the progress callbacks the library's long runs call."""

from __future__ import annotations

import math
import sys
import time

__all__ = ["Progress", "filter_progress", "fleet_progress"]


class Progress:
    """Progress lines on stderr (nothing with ``quiet``)."""

    def __init__(self, quiet: bool):
        self.quiet = quiet
        self.start = time.perf_counter()

    def __call__(self, message: str) -> None:
        if not self.quiet:
            print(f"[{time.perf_counter() - self.start:6.1f} s] {message}", file=sys.stderr, flush=True)


def filter_progress(progress: Progress, every: float = 2.0):
    """The ``progress`` callback of :meth:`~prognosis.health_monitor.HealthMonitor.run` for a command.

    It prints a line at the first report, then at most every ``every`` seconds, and at the last step;
    None with ``--quiet``, so that the monitor makes no calls at all.
    """
    if progress.quiet:
        return None
    start = time.perf_counter()
    printed = -math.inf

    def report(done: int, total: int, t: float) -> None:
        nonlocal printed
        now = time.perf_counter()
        if done == total or now - printed >= every:
            printed = now
            progress(f"filter: {100 * done / total:.0f} % of {total} steps (t = {t:.4g} s), "
                     f"{now - start:.1f} s elapsed")

    return report


def fleet_progress(progress: Progress, every: float = 2.0):
    """The ``progress`` callback of :func:`bgphm.fleet.run_fleet`: assets done, at most every ``every`` s."""
    if progress.quiet:
        return None
    printed = -math.inf

    def report(done: int, total: int) -> None:
        nonlocal printed
        now = time.perf_counter()
        if done == total or now - printed >= every:
            printed = now
            progress(f"fleet: {done} of {total} assets ({100 * done / total:.0f} %)")

    return report
