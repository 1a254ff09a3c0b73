"""The commands of ``bgphm``, one module each, imported by :func:`bgphm.cli.main` when it runs one.

Each command module has ``run(args, progress) -> int``: ``args`` is the parsed command line
(:func:`bgphm.cli.build_parser`), ``progress`` prints progress lines on stderr.  A command builds the
library's settings from its options, reads its files, calls the library's pipeline and prints or
writes what it returns; every numerical decision and every default is the library's.

* :mod:`.arr`: the ARR report; :mod:`.simulate`: a model's record as CSV;
* :mod:`.detect`: :func:`diagnosis.detect`; :mod:`.calibrate`: :func:`diagnosis.estimate_parameters` and
  :func:`diagnosis.validate_calibration`; :mod:`.prognose`: :func:`prognosis.prognose`;
* :mod:`.fleet`: :func:`bgphm.fleet.run_fleet`; :mod:`.demo`: a built-in example end to end.

Shared by them: what they read (:mod:`._inputs`), what they write (:mod:`._outputs`), progress
(:mod:`._progress`).
"""

from ._progress import Progress

__all__ = ["Progress"]
