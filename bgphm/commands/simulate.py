"""``bgphm simulate``: a model's record, as CSV."""

from __future__ import annotations

import math

import numpy as np

from bgphm.errors import EXIT_OK, UsageError
from bgphm.files import csv_text
from bondgraph.io import load_model

from ._inputs import (
    assignments,
    has_value,
)
from ._outputs import emit, output_file
from ._progress import Progress

__all__ = ["run"]


def run(args, progress: Progress) -> int:
    """``bgphm simulate``: simulate ``args.model`` over ``[0, t_end]`` and write its record as CSV; returns 0.

    ``args.samples`` evenly spaced times, parameters overridden by ``--set``, inputs from the model file;
    the CSV goes to stdout or ``args.out``.  Raises :class:`UsageError` for a bad ``--t-end``,
    ``--samples`` or ``--set``, or an input signal without a value.
    """
    from bondgraph.simulation import DEFAULT_T_END, MIN_SPAN, check_sample_count, simulate

    out = output_file(args)
    check_sample_count(args.samples, "--samples", least=3)
    spec = load_model(args.model)
    t_end = args.t_end if args.t_end is not None else (spec.t_end or DEFAULT_T_END)
    if not (math.isfinite(t_end) and t_end >= MIN_SPAN):
        raise UsageError(f"--t-end must be a number of seconds of at least {MIN_SPAN:g}, got {t_end:g}")
    parameters = assignments(args.set, spec.model.parameters, "--set")
    missing = [s for s in spec.model.inputs if s not in spec.inputs and not has_value(spec.model, s)]
    if missing:
        raise UsageError(f"{spec.source}: no value for the input signal(s) {missing}; give them in the model file "
                         "('inputs' in a Python file, graph.inputs in JSON)")
    progress(f"simulating {spec.model.name!r} over [0, {t_end:g}] s")
    result = simulate(spec.model, (0.0, t_end), spec.inputs, x0=spec.x0, parameters=parameters,
                      t_eval=np.linspace(0.0, t_end, args.samples))
    emit(csv_text(result.record()), out)
    return EXIT_OK
