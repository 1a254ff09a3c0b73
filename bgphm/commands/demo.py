"""``bgphm demo``: a built-in example written to files, then the commands run on them."""

from __future__ import annotations

from bgphm.errors import EXIT_OK
from bgphm.files import check_output

from ._progress import Progress

__all__ = ["run"]


def run(args, progress: Progress) -> int:
    """``bgphm demo``: write the files of the demo ``args.name`` into ``args.out`` and run its commands.

    :func:`bgphm.demo_cases.prepare_demo` writes the model, the record and ``truth.json`` and lists the
    ``arr``, ``detect`` and ``prognose`` command lines; each is printed, then run as :func:`main` runs
    it, and the true end of life is printed beside the prediction.  Returns 0, or the exit code of
    the first command that fails.
    """
    from bgphm.cli import main
    from bgphm.demo_cases import prepare_demo

    out = check_output(args.out, kind="directory", force=args.force)
    plan = prepare_demo(args.name, out, progress, seed=args.seed)
    quiet = ["--quiet"] if progress.quiet else []
    for command in plan.commands:
        print("$ bgphm " + " ".join(command))
        code = main(quiet + command)
        if code:
            return code
    line = plan.truth_line()
    if line is not None:
        print(line)
    return EXIT_OK
