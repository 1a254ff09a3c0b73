"""Ranking methods compared on the same runs by a score, with ties where the runs do not tell them apart.

:func:`rank_with_ties` groups methods whose paired scores differ by less than a relative tolerance or
that a paired test does not resolve; :func:`format_ranking` prints the groups (``"A = B < C"``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from numpy.typing import ArrayLike
from scipy import stats

from .errors import PrognosisError

__all__ = ["format_ranking", "rank_with_ties"]


def rank_with_ties(scores: Mapping[str, ArrayLike], *, rtol: float = 1e-3,
                   confidence: float = 0.95) -> list[list[str]]:
    """Order methods by their mean score, lowest first, in groups of methods the runs do not tell apart.

    The methods are scored on the same runs (seeds), so run ``i`` of every method saw the same
    data and two methods are compared by their paired differences ``d_i = b_i - a_i``.  Two
    neighbours in the order are told apart only when the mean difference exceeds both

    * the half-width of the paired t-interval, ``t_{(1 + confidence)/2, n-1} std(d) / sqrt(n)``:
      the runs resolve it (not checked with a single run);
    * ``rtol`` times the larger of the two mean scores: a resolution below which a difference does
      not matter, however consistently the runs show it (filters that linearize one nearly linear
      step differently differ by 1e-9 in every seed).

    Ties chain: a method joins its predecessor's group when the two are not told apart, so ``<``
    separates only neighbours that are, and ``=`` may join methods that differ end to end.

    Parameters
    ----------
    scores : mapping of str to array (n,) or float
        Each method's score on each of the same ``n`` runs, lower is better (an MAE, say).
    rtol : float
        Relative resolution (default 0.1 %, below the digits a table of such scores shows).
    confidence : float
        Level of the paired t-interval, in (0, 1).

    Returns
    -------
    list of list of str
        The groups, best first; each group in the order of its mean scores.

    Raises
    ------
    PrognosisError
        No methods, a method with no or non-finite scores or another number of runs, or ``rtol`` or
        ``confidence`` out of range.

    Examples
    --------
    Two filters 1e-9 apart in every run tie, and both beat a third:

    >>> runs = {"EKF": [0.150, 0.146, 0.148], "STUKF": [0.0300, 0.0270, 0.0285],
    ...         "STSCKF": [0.0300 - 1e-9, 0.0270 - 1e-9, 0.0285 - 1e-9]}
    >>> rank_with_ties(runs)
    [['STSCKF', 'STUKF'], ['EKF']]

    A 2 % difference in the mean that the runs do not resolve (it changes sign between them) is a
    tie too, and one the runs resolve is not:

    >>> rank_with_ties({"A": [1.0, 2.0, 3.0], "B": [1.2, 1.9, 3.02]})
    [['A', 'B']]
    >>> rank_with_ties({"A": [1.0, 2.0, 3.0], "B": [1.04, 2.04, 3.05]})
    [['A'], ['B']]
    """
    if not 0.0 < confidence < 1.0:
        raise PrognosisError(f"confidence must be in (0, 1), got {confidence!r}")
    if not rtol >= 0.0:
        raise PrognosisError(f"rtol must be non-negative, got {rtol!r}")
    runs = _paired_runs(scores)
    order = sorted(runs, key=lambda name: runs[name].mean())
    groups = [[order[0]]]
    for previous, name in zip(order, order[1:]):
        if _told_apart(runs[previous], runs[name], rtol, confidence):
            groups.append([name])
        else:
            groups[-1].append(name)
    return groups


def _paired_runs(scores: Mapping[str, ArrayLike]) -> dict[str, np.ndarray]:
    """Each method's scores as a finite 1-D array, all of one length."""
    if not scores:
        raise PrognosisError("scores: no methods to rank")
    runs = {name: np.atleast_1d(np.asarray(values, float)).reshape(-1) for name, values in scores.items()}
    first = next(iter(runs))
    for name, values in runs.items():
        if values.size == 0 or not np.all(np.isfinite(values)):
            raise PrognosisError(f"scores of {name!r}: need finite values, got {values.tolist()}")
        if values.size != runs[first].size:
            raise PrognosisError(f"scores of {name!r}: {values.size} runs, but {runs[first].size} for {first!r}; "
                                 "methods are compared run by run")
    return runs


def _told_apart(a: np.ndarray, b: np.ndarray, rtol: float, confidence: float) -> bool:
    """Whether ``b``'s mean exceeds ``a``'s by more than the resolution and the paired t-interval."""
    difference = b - a
    threshold = rtol * max(abs(a.mean()), abs(b.mean()))
    if difference.size > 1:
        t = stats.t.ppf(0.5 + 0.5 * confidence, difference.size - 1)
        threshold = max(threshold, t * difference.std(ddof=1) / np.sqrt(difference.size))
    return bool(difference.mean() > threshold)


def format_ranking(groups: Sequence[Sequence[str]]) -> str:
    """``"A = B < C"`` from the groups of :func:`rank_with_ties`.

    Parameters
    ----------
    groups : sequence of sequences of str
        Best group first; the members of a group are tied.

    Returns
    -------
    str

    Examples
    --------
    >>> format_ranking([["STSCKF", "STUKF"], ["EKF"]])
    'STSCKF = STUKF < EKF'
    >>> format_ranking(rank_with_ties({"A": [1.0, 2.0], "B": [1.0, 2.0]}))   # equal scores are tied
    'A = B'
    """
    return " < ".join(" = ".join(group) for group in groups)
