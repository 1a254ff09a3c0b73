"""The text files the commands write: columns of numbers as CSV.

The counterpart of :func:`diagnosis.signals.read_csv`: what ``bgphm simulate`` and ``bgphm demo``
write reads back as the same record.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from numpy.typing import ArrayLike


def csv_text(columns: Mapping[str, ArrayLike]) -> str:
    """CSV text of equally long columns: a header row of the names, one row per sample.

    Values are written with ``repr`` so that they read back exactly; NaN and infinities are
    written as empty cells, which :func:`~diagnosis.signals.read_csv` reads as gaps.

    Parameters
    ----------
    columns : mapping of str to array_like
        Column name -> values, in the order of the columns.

    Returns
    -------
    str
        The CSV text, ending with a newline.

    Examples
    --------
    >>> print(csv_text({"t": [0.0, 0.1], "x": [1.5, float("nan")]}), end="")
    t,x
    0.0,1.5
    0.1,
    """
    names = list(columns)
    data = np.column_stack([np.asarray(columns[n], float) for n in names])
    lines = [",".join(names)]
    lines += [",".join("" if not np.isfinite(v) else repr(float(v)) for v in row) for row in data]
    return "\n".join(lines) + "\n"
