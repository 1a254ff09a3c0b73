"""Long runs from scripts: one job per seed in worker processes, progress on stderr, a clean Ctrl-C.

The examples' multi-seed runs and sweeps use :func:`over_seeds` for their loops and :func:`run_main` for
their entry point, so an interrupt stops every worker at once and ends with one line, ``interrupted``,
and exit code 1, as ``bgphm`` does.

Examples
--------
>>> over_seeds(pow, [(2, 3), (3, 2), (10, 0)], workers=2)
[8, 9, 1]
"""

from __future__ import annotations

import functools
import multiprocessing
import signal
import sys
from collections.abc import Callable, Sequence

__all__ = ["over_seeds", "progress_line", "run_main"]


def over_seeds(function: Callable, arguments: Sequence[tuple], *, workers: int = 1,
               progress: Callable[[int, int], None] | None = None) -> list:
    """``[function(*a) for a in arguments]``, in order, in ``workers`` processes.

    ``progress(done, total)`` is called after each result, in order.  The workers ignore SIGINT, so a
    Ctrl-C reaches only this process, which then terminates the pool at once (pending jobs are dropped,
    running ones killed) and lets ``KeyboardInterrupt`` propagate.  An exception in a job propagates
    the same way.  ``function`` must be picklable (a module-level function).

    Examples
    --------
    >>> seen = []
    >>> over_seeds(divmod, [(7, 2), (9, 4)], progress=lambda done, total: seen.append((done, total)))
    [(3, 1), (2, 1)]
    >>> seen
    [(1, 2), (2, 2)]
    """
    arguments = [tuple(a) for a in arguments]
    total = len(arguments)
    if isinstance(workers, bool) or int(workers) != workers or workers < 1:
        raise ValueError(f"workers must be a positive integer, got {workers!r}")
    results = []
    if workers == 1 or total <= 1:
        for args in arguments:
            results.append(function(*args))
            if progress is not None:
                progress(len(results), total)
        return results
    methods = multiprocessing.get_all_start_methods()
    context = multiprocessing.get_context("fork" if "fork" in methods else "spawn")
    with context.Pool(min(int(workers), total), initializer=_ignore_interrupt) as pool:  # exit: terminate()
        for result in pool.imap(functools.partial(_call, function), arguments):
            results.append(result)
            if progress is not None:
                progress(len(results), total)
    return results


def progress_line(quiet: bool, what: str = "seed") -> Callable[[int, int], None] | None:
    """A ``progress(done, total)`` printing ``  seed 3/10 done`` on stderr, or None when ``quiet``.

    >>> progress_line(True) is None
    True
    """
    if quiet:
        return None

    def report(done: int, total: int) -> None:
        print(f"  {what} {done}/{total} done", file=sys.stderr, flush=True)

    return report


def run_main(main: Callable[[], object]) -> None:
    """Run a script's ``main()``; on Ctrl-C print ``interrupted`` on stderr and exit with code 1."""
    try:
        main()
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr, flush=True)
        raise SystemExit(1) from None


def _call(function: Callable, args: tuple):
    return function(*args)


def _ignore_interrupt() -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)
