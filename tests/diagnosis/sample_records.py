"""Records the records, derivatives, CSV and uniform-grid tests share: a sine at 100 Hz, an uneven time grid."""

import numpy as np

from diagnosis.records import as_record

DT = 0.01
T = np.arange(0.0, 10.0 + DT / 2, DT)


def sine_record(**extra):
    """``x = sin(t)`` over 10 s at 100 Hz (and the ``extra`` columns)."""
    return as_record({"t": T, "x": np.sin(T), **extra}, name="sine")


def uneven_grid(n):
    """``n`` times over [0, 3] s whose steps vary smoothly by about 30 %."""
    s = np.linspace(0.0, 3.0, n)
    return s + 0.1 * np.sin(3 * s)  # smooth map, steps vary by ~30 %
