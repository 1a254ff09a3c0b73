"""``bgphm arr``: the ARR report of a model."""

from __future__ import annotations

from bgphm.errors import EXIT_OK
from bondgraph.io import load_model

from ._outputs import emit, output_file
from ._progress import Progress

__all__ = ["run"]


def run(args, progress: Progress) -> int:
    """``bgphm arr``: the ARR report of ``args.model`` in ``args.format``, to stdout or ``args.out``; returns 0.

    ``args`` is the parsed command line (:func:`build_parser`); ``progress`` prints progress lines on
    stderr.
    """
    from diagnosis import derive_arrs
    from diagnosis.report import arr_report

    out = output_file(args)
    spec = load_model(args.model)
    progress(f"deriving the ARRs of {spec.model.name!r}")
    arrs = derive_arrs(spec.model, simulated=True) if args.simulated else None
    text = arr_report(spec.model, format=args.format, arrs=arrs)
    emit(text, out)
    return EXIT_OK
