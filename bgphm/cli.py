"""The ``bgphm`` command line: ARR reports, simulation, detection and prognosis on recorded data.

::

    bgphm arr MODEL [--format md|html|tex] [--out FILE]
    bgphm simulate MODEL [--t-end T] [--samples N] [--set PARAM=VALUE ...] [--degrade PARAM=LAW:RATE@ONSET ...]
                   [--noise SIGNAL=STD ...] [--bias SIGNAL=VALUE@ONSET ...] [--drift SIGNAL=RATE@ONSET ...]
                   [--gain SIGNAL=FACTOR@ONSET ...] [--input SIGNAL=EXPR ...] [--inputs FILE.csv] [--seed N]
                   [--out CSV]
    bgphm detect MODEL DATA.csv [--margin M | --calibrate T] [--persistence N] [--out DIR]
    bgphm calibrate MODEL HEALTHY.csv [HEALTHY.csv ...] --out FILE.json [--parameters P ...]
                    [--boxes confidence|records] [--hold-out K | --validate FILE.csv ...] [--level L] [--prior S]
                    [--report FILE.html] [--force]
    bgphm prognose MODEL DATA.csv --fail PARAM=VALUE [--fail ...] [--candidate P] [--degradation LAW] [--out DIR]
    bgphm fleet MODEL RECORDS --fail PARAM=VALUE [--fail ...] --calibrate T --out DIR [--scheduler ADDRESS]
                [--workers N] [--particles N] [--dt S] [--rul-every K] [--seed S] [--on-bad-record stop|skip]
                [--force] [--resume] [--no-page]
    bgphm demo [dc-motor|torsion-bar|three-tank] [--out DIR] [--seed N]
    bgphm codegen MODEL --lang python|c --dt DT --out DIR [--window N] [--polyorder N] [--margin M]
                  [--persistence K] [--force]

MODEL is a JSON file (networkx node-link form), a Python file defining ``model``, or a built-in example
name (see :func:`bondgraph.io.load_model`).  DATA.csv has a header row with a time column ``t`` and one
column per signal the ARRs use (see :func:`diagnosis.csv_reading.read_csv`).  RECORDS is a directory of
such CSV files, one per asset, or a Parquet file with an ``asset`` column (``docs/fleet.md``).

``simulate`` injects faults: a parameter's degradation law from an onset (``--degrade b=exp:0.8@1``, read
by :func:`bondgraph.scenarios.parse_degradation`), a sensor's bias, drift and gain from an onset
(:class:`diagnosis.records.SensorFault`) and its Gaussian noise (:func:`diagnosis.records.add_noise`, the
same draws for the same ``--seed``); its inputs may be expressions of ``t`` (``--input U='12*step(t - 0.5)'``,
:class:`bondgraph.inputs.InputExpression`, never evaluated) or samples from a CSV file (``--inputs``,
:class:`bondgraph.inputs.TabulatedInput`).

``codegen`` writes a standalone module evaluating the model's ARRs sample by sample (residuals, interval
thresholds rounded outward, alarms), in Python (``math`` alone) or C99 (``libm`` alone), with a
``manifest.json`` and a README (:func:`diagnosis.generate_code`).

``calibrate`` estimates the model's parameters from healthy records through its ARRs
(:func:`diagnosis.estimate_parameters`), gives the estimated ones uncertainty boxes (their confidence intervals,
or the spread of one estimate per record), checks the calibrated model against the datasheet's on held-out
healthy records (false alarms, smallest detectable changes, the residuals' whiteness:
:func:`diagnosis.validate_calibration`) and writes it as a JSON model whose ``graph.calibration`` block says where
its values came from (the records and their SHA-256, the method, the date), with an offline report.

Exit codes: 0 success, 2 bad usage or bad input (one line on stderr naming the file, line, column,
node or parameter), 1 anything else (an interrupted run included).  Progress goes to stderr;
``--quiet`` silences it.  Results go to stdout and to ``--out``.
"""

from __future__ import annotations

import argparse
import importlib
import sys
import warnings
from collections.abc import Collection, Sequence

from bgphm.commands import Progress
from bgphm.errors import EXIT_FAILURE, EXIT_USAGE, UsageError
from bgphm.terminal import terminal_streams
from bondgraph.errors import PHMError, SettingError

__all__ = ["main"]

# Only light modules above: the library (sympy, scipy, networkx) is imported by the command that runs, and
# its defaults by the parser of that command alone, so that ``bgphm --help`` answers at once.

#: Each command's help line; its module (``bgphm.commands.NAME``) is imported when it runs: ``bgphm arr``
#: does not load the particle filters.
COMMANDS = {
    "arr": "ARR report: elements, drawing, ARRs, fault signatures",
    "simulate": "simulate the model and write its signals as CSV",
    "detect": "residuals, robust thresholds and alarms on recorded data",
    "calibrate": "parameters from healthy records, validated on held-out ones: the calibrated model (JSON, with "
                 "its provenance) and a report",
    "sensors": "where to add sensors: the cheapest minimal sets of detectors that reach a detection or "
               "isolation goal, checked by re-deriving the ARRs",
    "prognose": "estimate a degrading parameter and predict the RUL from recorded data",
    "fleet": "monitor a fleet: records of many assets to Parquet tables of alarms, estimates, RULs and residuals, "
             "on Dask workers, and an overview page (index.html)",
    "demo": "run the whole chain on a built-in example and write every output",
    "codegen": "standalone Python or C code evaluating the ARRs sample by sample: residuals, interval thresholds, "
               "alarms",
}


#: The options of the library's settings whose names differ from the settings' (``--`` + the name otherwise).
OPTIONS = {"method": "--filter", "laws": "--degradation", "candidates": "--candidate", "failures": "--fail",
           "n_particles": "--particles"}


def _option(setting: str) -> str:
    return OPTIONS.get(setting, "--" + setting.replace("_", "-"))


# ------------------------------------------------------------------------------------------- parser

class _Parser(argparse.ArgumentParser):
    """argparse with a one-line error: ``bgphm: error: argument --k: invalid float value: 'x' (see ...)``."""

    def error(self, message: str):
        self.exit(EXIT_USAGE, f"bgphm: error: {_one_line(message)} (see {self.prog} --help)\n")


def build_parser(commands: Collection[str] | None = None) -> argparse.ArgumentParser:
    """The ``bgphm`` argument parser: ``--quiet``, ``--debug``, ``--version`` and the commands arr, simulate, detect,
    calibrate, sensors, prognose, fleet, demo, codegen.

    ``commands`` are those whose options are built (the others are listed with their help line); :func:`main`
    builds the one on the line alone, or none for ``bgphm --help``: a command's defaults are the library's, and
    reading them imports it.  ``None`` builds every command's.  ``--quiet`` and ``--debug`` are taken anywhere
    on the line.

    >>> build_parser(["arr"]).parse_args(["arr", "rlc", "--quiet"]).quiet
    True
    """
    parser = _Parser(prog="bgphm", description="Bond-graph modelling, robust fault diagnosis and "
                                     "prognosis: ARR reports, simulation, detection and RUL prediction.")
    _global_options(parser, default=False)
    parser.add_argument("--version", action=_Version, help="print the version and exit")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for name, helptext in COMMANDS.items():
        extra = {"formatter_class": argparse.RawDescriptionHelpFormatter} if name == "demo" else {}
        p = sub.add_parser(name, help=helptext, description=helptext, **extra)
        _global_options(p, default=argparse.SUPPRESS)  # given after the command, it overrides; absent, it does not
        if commands is None or name in commands:
            OPTIONS_OF[name](p)
    return parser


def _global_options(parser: argparse.ArgumentParser, default) -> None:
    parser.add_argument("--quiet", action="store_true", default=default, help="no progress on stderr")
    parser.add_argument("--debug", action="store_true", default=default,
                        help="show the traceback of an unexpected error")


class _Version(argparse.Action):
    """``--version``: the installed distribution's version, read only when asked."""

    def __init__(self, option_strings, dest, **kwargs):
        super().__init__(option_strings, dest, nargs=0, default=argparse.SUPPRESS, **kwargs)

    def __call__(self, parser, namespace, values, option_string=None):
        from importlib.metadata import PackageNotFoundError, version

        try:
            number = version("bondgraph-phm")
        except PackageNotFoundError:  # run from a source tree that was never installed
            number = "unknown (not installed)"
        print(f"bgphm (bondgraph-phm) {number}")  # on stdout, as argparse's own version action does
        parser.exit(0)


MODEL_HELP = "JSON (node-link) or Python model file, or a built-in example (dc-motor, rlc, three-tank, torsion-bar)"


def _arr_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("model", metavar="MODEL", help=MODEL_HELP)
    p.add_argument("--format", choices=("md", "html", "tex"), default="md", help="report format (default md)")
    p.add_argument("--simulated", action="store_true", help=SIMULATED_HELP)
    p.add_argument("--out", help="output file (default: stdout)")
    p.add_argument("--force", action="store_true", help="replace an existing --out file (never an input)")


def _simulate_options(p: argparse.ArgumentParser) -> None:
    from bondgraph.simulation import DEFAULT_T_END, OUTPUT_SAMPLES

    p.add_argument("model", metavar="MODEL", help=MODEL_HELP)
    p.add_argument("--t-end", type=float,
                   help=f"horizon in s (default: the model file's t_end, else {DEFAULT_T_END:g})")
    p.add_argument("--samples", type=int, default=OUTPUT_SAMPLES, help=f"output samples (default {OUTPUT_SAMPLES})")
    p.add_argument("--set", action="append", metavar="PARAM=VALUE", help="override a parameter (repeatable)")
    p.add_argument("--degrade", action="append", metavar="PARAM=LAW:RATE@ONSET",
                   help="a parameter degrading from ONSET s on, tau = t - ONSET (repeatable): lin:RATE is nominal + "
                        "RATE tau, exp:RATE nominal exp(RATE tau), pow:RATE^EXPONENT nominal + RATE tau^EXPONENT, "
                        "step:SIZE nominal + SIZE; without @ONSET from 0 (e.g. b=exp:0.05@10)")
    p.add_argument("--noise", action="append", metavar="SIGNAL=STD",
                   help="Gaussian noise of standard deviation STD on a signal's reading (repeatable; --seed)")
    p.add_argument("--bias", action="append", metavar="SIGNAL=VALUE@ONSET",
                   help="the sensor of SIGNAL reads VALUE too much from ONSET s on (repeatable; without @ONSET from 0)")
    p.add_argument("--drift", action="append", metavar="SIGNAL=RATE@ONSET",
                   help="the sensor of SIGNAL reads RATE (t - ONSET) too much from ONSET s on (repeatable)")
    p.add_argument("--gain", action="append", metavar="SIGNAL=FACTOR@ONSET",
                   help="the sensor of SIGNAL reads FACTOR times the signal from ONSET s on (repeatable); a sensor's "
                        "gain acts first, then its bias and drift, then its noise")
    p.add_argument("--input", action="append", metavar="SIGNAL=EXPR",
                   help="an input signal as an expression of t (repeatable), parsed, never evaluated: numbers, + - * "
                        "/ **, pi, sign, Abs, sqrt, exp, log, sin, cos, tanh, Min, Max and step (0 before 0, 1 from 0 "
                        "on), e.g. U='12*step(t - 0.5)'")
    p.add_argument("--inputs", metavar="FILE.csv",
                   help="input signals from a CSV file: a column t and one column per input, linear between the "
                        "samples and held at the first and last value outside them")
    p.add_argument("--seed", type=int, default=0, help="seed of the --noise draws (default 0)")
    p.add_argument("--report", metavar="FILE.html", help="also write an offline page of the run: each signal of the "
                   "record over time, the faults injected, the parameters and units, the settings")
    p.add_argument("--out", help="CSV file (default: stdout)")
    p.add_argument("--force", action="store_true", help="replace an existing --out file (never an input)")


SIMULATED_HELP = ("fill the gaps no closed-form ARR fills with simulation residuals: the states of the set "
                  "integrated from the record, which must start at rest")


def _detect_options(p: argparse.ArgumentParser) -> None:
    _record_options(p, "detect")
    p.add_argument("--simulated", action="store_true", help=SIMULATED_HELP)


def _record_options(p: argparse.ArgumentParser, command: str) -> None:
    """The options detect and prognose share: the model, the record and the detection settings."""
    from diagnosis import DetectionSettings

    DETECTION = DetectionSettings()  # the library's defaults, shown in the help
    p.add_argument("model", metavar="MODEL", help=MODEL_HELP)
    p.add_argument("data", metavar="DATA.csv", help="CSV with a column t and one per signal")
    p.add_argument("--arr", help="use only this ARR (default: all; for prognose the first sensitive one)")
    p.add_argument("--margin", type=float, help="noise margin added to the thresholds (default: calibrated)")
    p.add_argument("--calibrate", type=float, metavar="T",
                   help="calibrate the margin on t <= T, assumed fault-free (default: the first 20 %%)")
    p.add_argument("--k", type=float, default=DETECTION.k,
                   help=f"margin = k robust std of the residual (default {DETECTION.k:g})")
    p.add_argument("--persistence", type=int, default=DETECTION.persistence,
                   help=f"consecutive violations for an alarm (default {DETECTION.persistence}; detect: at least "
                        "half the derivative window)")
    if command == "detect":
        p.add_argument("--window", type=int, help="Savitzky-Golay window for derivatives (odd; default: "
                                                  "chosen per ARR from the record)")
        p.add_argument("--integrals", choices=("auto", "avoid", "keep"), default="auto",
                       help="auto: per ARR, the form that detects the smallest changes on the record "
                            "(default); avoid: differentiate an ARR that would integrate measured signals; "
                            "keep: keep the integrals")
    else:
        p.add_argument("--window", type=int, help="Savitzky-Golay window for derivatives (odd; default 11)")
        p.add_argument("--integrals", choices=("avoid", "keep"), default="avoid",
                       help="avoid: differentiate an ARR that would integrate measured signals (default); keep: "
                            "keep the integrals (better on long records sampled fast, where a second "
                            "derivative of the noise is larger than the integral's random walk)")
    p.add_argument("--resample", action="store_true",
                   help="put a record with uneven steps on a uniform grid of its median step (linear "
                        "interpolation within runs of data, never across a gap)")
    p.add_argument("--out", help="output directory (new or empty, unless --force)")
    p.add_argument("--force", action="store_true",
                   help="write into a non-empty --out directory, replacing files of the same names")


def _calibrate_options(p: argparse.ArgumentParser) -> None:
    import inspect

    from diagnosis import estimate_parameters
    from diagnosis.parameter_estimation import INTEGRATION_WINDOW, QUADRATURES

    ESTIMATION = {k: v.default for k, v in inspect.signature(estimate_parameters).parameters.items()}  # its defaults
    p.add_argument("model", metavar="MODEL", help=MODEL_HELP)
    p.add_argument("records", metavar="HEALTHY.csv", nargs="+", help="healthy records, each a CSV with a column t "
                   "and one per signal the ARRs use, from different days or operating points")
    p.add_argument("--out", required=True, metavar="FILE.json", help="the calibrated model: JSON that every command "
                   "reads as MODEL, with a graph.calibration block (records and their SHA-256, method, date, "
                   "estimates, intervals, validation)")
    p.add_argument("--parameters", nargs="+", action="extend", metavar="P", help="the parameters to estimate "
                   "(several after one --parameters, or it repeated; default: every parameter the ARRs and the "
                   "records identify)")
    p.add_argument("--boxes", choices=("confidence", "records", "set-membership"), default="confidence",
                   help="the calibrated uncertainty boxes: each estimate's confidence interval (default), the "
                        "spread of one estimate per training record (needs two training records or more), or the "
                        "smallest boxes that keep every training record inside the thresholds")
    held = p.add_mutually_exclusive_group()
    held.add_argument("--hold-out", type=int, metavar="K", help="validate on the last K records, estimate on the "
                      "others (default: 1 with two records or more, else 0: no validation)")
    held.add_argument("--validate", nargs="+", action="extend", metavar="FILE.csv",
                      help="validate on these healthy records instead, and estimate on every HEALTHY.csv")
    p.add_argument("--level", type=float, default=ESTIMATION["level"],
                   help=f"confidence level of the intervals (default {ESTIMATION['level']:g})")
    p.add_argument("--prior", type=_prior, default=ESTIMATION["prior"], metavar="S",
                   help="the datasheet's relative standard deviation: a parameter the records barely see stays near "
                        f"its datasheet value (default {ESTIMATION['prior']:g}; none: the records alone)")
    p.add_argument("--window", type=_window, default=None, metavar="N",
                   help="samples each row integrates the ARRs over (default "
                        f"{INTEGRATION_WINDOW}; shorter for records of a few hundred samples)")
    p.add_argument("--quadrature", choices=QUADRATURES, default=ESTIMATION["quadrature"],
                   help="the window integral of a feature's samples: trapezoid (default, a continuous machine) or "
                        "euler (the left rectangle rule, exact for records of an explicit-Euler model)")
    p.add_argument("--report", metavar="FILE.html", help="the offline report (default: --out with .html)")
    p.add_argument("--force", action="store_true", help="replace existing --out and report files (never an input)")


def _prior(text: str) -> float | None:
    """``--prior``: a number, or ``none``."""
    return None if text.strip().lower() == "none" else float(text)


_prior.__name__ = "prior"  # argparse names the type in its message: "invalid prior value: 'x'"


def _window(text: str) -> int:
    """``--window``: a whole number of samples, at least 2."""
    value = int(text)
    if value < 2:
        raise ValueError(text)
    return value


_window.__name__ = "window (a whole number of samples >= 2)"


def _sensors_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("model", metavar="MODEL", help=MODEL_HELP)
    p.add_argument("--goal", choices=("detect", "isolate"), default="isolate",
                   help="what every candidate detector together would give: every fault detected, or moreover "
                        "every pair told apart (default isolate)")
    p.add_argument("--max-sensors", type=int, default=3, metavar="N", help="the most detectors a set adds "
                   "(default 3)")
    p.add_argument("--cost", nargs="+", action="extend", type=_detector_cost, metavar="DETECTOR=COST",
                   help="a detector's cost, e.g. 'Df 1_e=2' (default 1 each)")
    p.add_argument("--healthy-sensors", action="store_true", help="sensors cannot fail (their faults not counted)")
    p.add_argument("--inside-elements", action="store_true", help="also try detectors inside an element's bond "
                   "(the flow of one valve, the torque of one friction), on an inserted junction")
    p.add_argument("--no-check", action="store_true", help="judge by the structure alone, without re-deriving "
                   "the ARRs of each set")
    p.add_argument("--out", metavar="FILE.json", help="the alternatives as JSON")
    p.add_argument("--force", action="store_true", help="replace an existing --out file (never an input)")


def _detector_cost(text: str) -> tuple[str, float]:
    """``--cost``: ``DETECTOR=COST``."""
    name, _, value = text.rpartition("=")
    if not name.strip():
        raise ValueError(text)
    return name.strip(), float(value)


_detector_cost.__name__ = "DETECTOR=COST"


def _prognose_options(p: argparse.ArgumentParser) -> None:
    from prognosis import IsolationSettings

    PROGNOSIS = IsolationSettings()  # the library's defaults, shown in the help
    _record_options(p, "prognose")
    p.add_argument("--fail", action="append", required=True, metavar="PARAM=VALUE",
                   help="failure value of a parameter that can fail (repeatable); the candidates are those whose "
                        "signature matches the ARRs that fired")
    p.add_argument("--candidate", help="only this candidate (it needs a failure value; a bare --fail VALUE is its)")
    p.add_argument("--degradation", choices=("exponential", "linear", "power", "saturating"), action="append",
                   help="a law that competes (repeatable; default: linear, exponential and power compete on "
                        "evidence); power: a power of the time since onset, its exponent estimated too; "
                        "saturating: that power law levelling off (fouling, a sigmoid wear)")
    p.add_argument("--sensors", action=argparse.BooleanOptionalAction, default=True,
                   help="weigh a bias, drift or gain of each sensor consistent with the ARRs that fired too "
                        "(default; --no-sensors: the sensors are healthy)")
    p.add_argument("--pairs", action=argparse.BooleanOptionalAction, default=None,
                   help="weigh two parameters wearing at once too, from the first alarm (the resample-move filter "
                        "only), declared only when the data demand two faults; the RUL is the first failure's "
                        "(default: weighed only when no single fault explains the residuals, or no single parameter "
                        "sees every ARR fired; --no-pairs: never)")
    p.add_argument("--direction", choices=("up", "down"), help="check that --candidate's failure value lies on "
                   "this side of nominal")
    p.add_argument("--rate", type=float, nargs=2, metavar=("LO", "HI"),
                   help="uniform prior interval of the rate (default: the life from nominal to failure "
                        "log-uniform over 10 to 1e5 filter steps)")
    p.add_argument("--particles", type=int, default=PROGNOSIS.n_particles,
                   help=f"particles per hypothesis (default {PROGNOSIS.n_particles})")
    p.add_argument("--filter", choices=("resample-move", "sir"), default="resample-move",
                   help="resample-move (the default): the law's parameters weighed on the whole history, moved "
                        "by MCMC, with the residual noise measured on the healthy stretch; a law the data "
                        "contradict is reported inadequate.  sir: the random-walk particle filter of Jha et al. "
                        "2016 (collapses on a clean residual; no adequacy check)")
    p.add_argument("--dt", type=float, help="filter step in s, a multiple of the record's (default: one "
                   "derivative window of samples)")
    p.add_argument("--rul-every", type=int, default=PROGNOSIS.rul_every,
                   help=f"predict the RUL every N filter steps (default {PROGNOSIS.rul_every})")
    p.add_argument("--horizon", type=float, help="RUL horizon cap in s (default 2000 filter steps)")
    p.add_argument("--seed", type=int, default=PROGNOSIS.seed, help=f"random seed (default {PROGNOSIS.seed})")
    p.add_argument("--truth", metavar="FILE.json", help="the true end of life (and degradation) of the record, as "
                   "bgphm demo writes truth.json: the predictions are scored against it (relative accuracy, the "
                   "bands' coverage) in prognosis.json and on stdout, and drawn on the plots and the report")



def _demo_options(p: argparse.ArgumentParser) -> None:
    from bgphm.demo_cases import DEMOS

    listing = "\n".join(f"  {name:<13} {demo.description}" for name, demo in DEMOS.items())
    p.description = ("Simulate an example with a degrading parameter, write the model, the record and "
                       "truth.json,\nthen run arr, detect and prognose on those files (each command is printed so "
                       f"it can be\nrerun by hand with the same results).\n\ndemos:\n{listing}")
    p.add_argument("name", nargs="?", default="dc-motor", metavar="NAME",
                   help=f"demo to run: {', '.join(DEMOS)} (default dc-motor)")
    p.add_argument("--out", default="results/demo", help="output directory (default results/demo; new or "
                   "empty, unless --force)")
    p.add_argument("--force", action="store_true",
                   help="write into a non-empty --out directory, replacing files of the same names")
    p.add_argument("--seed", type=int, default=0, help="noise seed (default 0)")


def _fleet_options(p: argparse.ArgumentParser) -> None:
    from diagnosis import POOLED_RECORDS, DetectionSettings
    from prognosis import IsolationSettings

    DETECTION, PROGNOSIS = DetectionSettings(), IsolationSettings()  # the library's defaults, shown in the help
    p.add_argument("model", metavar="MODEL", help=MODEL_HELP)
    p.add_argument("records", metavar="RECORDS", help="a directory of CSV files, one per asset (the asset id is the "
                   "file name), or a Parquet file with a column 'asset' (its rows sorted by t or not)")
    p.add_argument("--fail", action="append", required=True, metavar="PARAM=VALUE",
                   help="failure value of a parameter that can fail (repeatable)")
    p.add_argument("--candidate", help="only this candidate (it needs a failure value)")
    p.add_argument("--degradation", choices=("exponential", "linear"),
                   help="only this law (default: linear and exponential compete on evidence)")
    p.add_argument("--calibrate", type=float, required=True, metavar="T",
                   help="every record is fault-free for t <= T: the noise and margins are calibrated there, and "
                        "alarms there start nothing")
    p.add_argument("--calibrate-assets", type=int, default=POOLED_RECORDS, metavar="N",
                   help=f"calibrate on the first N records by asset id, the median per ARR (default {POOLED_RECORDS})")
    p.add_argument("--arr", help="use only this ARR (default: every ARR sensitive to a candidate)")
    p.add_argument("--k", type=float, default=DETECTION.k,
                   help=f"margin = k robust std of the residual (default {DETECTION.k:g})")
    p.add_argument("--persistence", type=int, default=DETECTION.persistence,
                   help=f"consecutive violations for an alarm (default {DETECTION.persistence})")
    p.add_argument("--window", type=int, help="Savitzky-Golay window for derivatives (odd; default 11)")
    p.add_argument("--integrals", choices=("avoid", "keep"), default="avoid",
                   help="as for prognose: avoid (differentiate) or keep the integrals of measured signals")
    p.add_argument("--particles", type=int, default=PROGNOSIS.n_particles,
                   help=f"particles per hypothesis (default {PROGNOSIS.n_particles})")
    p.add_argument("--dt", type=float, help="filter step in s, a multiple of the records' (default: one "
                   "derivative window of samples)")
    p.add_argument("--rul-every", type=int, default=PROGNOSIS.rul_every,
                   help=f"predict the RUL every N filter steps (default {PROGNOSIS.rul_every})")
    p.add_argument("--horizon", type=float, help="RUL horizon cap in s (default 2000 filter steps)")
    p.add_argument("--seed", type=int, default=PROGNOSIS.seed, help=f"random seed (default {PROGNOSIS.seed}); each "
                   "asset's draws depend only on "
                   "it, the asset id and the step")
    p.add_argument("--out", required=True, help="output directory (new or empty, unless --force): the Parquet "
                   "tables alarms/, estimates/, rul/ and residuals/, summary.json, index.html (the overview page: "
                   "open it in a browser, it needs no network) and manifest.json")
    p.add_argument("--force", action="store_true", help="write into a non-empty --out directory (a previous "
                   "fleet run's tables there are replaced, whole, when this one ends)")
    p.add_argument("--no-page", action="store_true", help="write no index.html (the page reads the tables whole "
                   "in this process: for fleets far beyond 10^4 assets)")
    p.add_argument("--on-bad-record", choices=("stop", "skip"), default="stop",
                   help="a record that cannot be used (unreadable, a column without a value, a stuck sensor, too "
                   "short): stop the run naming it (default), or skip the asset and list it with the reason in "
                   "summary.json")
    p.add_argument("--resume", action="store_true", help="go on with the run interrupted in --out: the same "
                   "options and records, its finished shards kept (checked by SHA-256), the same tables as "
                   "an uninterrupted run")
    p.add_argument("--truth", metavar="FILE.json", help="the true end of life of each asset, a JSON object "
                   "{asset: {\"eol\": s}} (null eol: the asset does not fail): the predictions are scored against it "
                   "(relative accuracy, the 5-95 %% band's coverage, medians within 20 %%), per asset and pooled, "
                   "in summary.json and on stdout")
    p.add_argument("--scheduler", metavar="ADDRESS", help="a running Dask scheduler, e.g. tcp://10.0.0.5:8786 "
                   "(default: a local cluster of --workers processes)")
    # None: run_fleet's own default (bgphm.fleet.engine.WORKERS), read when the command runs, so that the
    # parser does not import the fleet engine for every command
    p.add_argument("--workers", type=int,
                   help="worker processes of the local cluster (default: bgphm.fleet.engine.WORKERS, 2; 0 runs "
                   "every asset in this process, without Dask)")
    p.add_argument("--shard-size", type=int, metavar="N", help="assets per task (default: a quarter of each "
                   "worker's share, at most 1000); the results do not depend on it")
    p.set_defaults(margin=None, direction=None)


def _codegen_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("model", metavar="MODEL", help=MODEL_HELP)
    p.add_argument("--lang", required=True, choices=("python", "c"), help="the language of the module")
    p.add_argument("--dt", required=True, type=float, metavar="DT",
                   help="the sampling step in seconds (the derivative filters are computed for it)")
    p.add_argument("--out", required=True, metavar="DIR", help="output directory (new or empty, unless --force)")
    p.add_argument("--method", choices=("savgol", "central"), default="savgol",
                   help="derivative estimator (default savgol; central only for ARRs without derivatives)")
    p.add_argument("--window", type=int, default=None, metavar="N",
                   help="Savitzky-Golay window, odd (default: 11, or more for a high polyorder)")
    p.add_argument("--polyorder", type=int, default=None, metavar="N",
                   help="Savitzky-Golay polynomial order (default 3, or the ARR's highest derivative order)")
    p.add_argument("--margin", type=float, default=0.0, metavar="M", help="noise margin added to the thresholds "
                   "(default 0)")
    p.add_argument("--persistence", type=int, default=1, metavar="K",
                   help="consecutive violations before an alarm (default 1)")
    p.add_argument("--force", action="store_true",
                   help="write into a non-empty --out directory, replacing files of the same names")


#: Each command's options.
OPTIONS_OF = {"arr": _arr_options, "simulate": _simulate_options, "detect": _detect_options,
              "calibrate": _calibrate_options, "sensors": _sensors_options, "prognose": _prognose_options,
              "fleet": _fleet_options, "demo": _demo_options, "codegen": _codegen_options}


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``bgphm`` console script; returns the exit code.

    Commands: ``arr`` (the ARR report), ``simulate``, ``detect``, ``calibrate``, ``sensors``, ``prognose``,
    ``fleet``, ``demo`` and ``codegen``; ``bgphm COMMAND --help`` lists each one's options.  Exit codes: 0 success,
    2 bad usage or bad input (one line on stderr naming the file, line, column, node or parameter), 1 anything
    else, including an interrupted run.  Progress goes to stderr unless ``--quiet``.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> out = pathlib.Path(tempfile.mkdtemp()) / "rlc.csv"
    >>> main(["--quiet", "simulate", "rlc", "--t-end", "0.1", "--samples", "11",
    ...       "--out", str(out)])  # doctest: +ELLIPSIS
    wrote ...rlc.csv
    0
    >>> out.read_text().splitlines()[0]
    't,V,i,v_C'
    >>> main(["--quiet", "simulate", "no-such-model.json"])   # exit code 2, message on stderr
    2
    """
    with terminal_streams():  # a file name's escape sequence is shown, never obeyed (argparse's messages too)
        argv = sys.argv[1:] if argv is None else list(argv)
        args = build_parser(_command_in(argv)).parse_args(argv)  # exits with 2 on bad usage
        return _run(args, Progress(args.quiet))


def _command_in(argv: Sequence[str]) -> list[str]:
    """The command named on the line, if any: the first word that is not an option (the global options take no
    value)."""
    word = next((w for w in argv if not w.startswith("-")), None)
    return [word] if word in COMMANDS else []


def _run(args, progress: Progress) -> int:
    """Run the command; the exit code, and one line on stderr for an error."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("default")  # each distinct warning once, as one line without a source path
            warnings.showwarning = _warning_line
            _check_options(args)
            return importlib.import_module(f"bgphm.commands.{args.command}").run(args, progress)
    except SettingError as exc:  # a setting that does not fit the input: named as the option that gave it
        print(f"bgphm: error: {_one_line(exc.naming(_option))}", file=sys.stderr)
        return EXIT_USAGE
    except PHMError as exc:  # bad usage or bad input: a model, a record, equations, a simulation
        print(f"bgphm: error: {_one_line(exc)}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt:
        print("bgphm: interrupted", file=sys.stderr)
        return EXIT_FAILURE
    except Exception as exc:  # anything else is a bug or an environment problem: exit 1
        if args.debug:
            raise
        print(f"bgphm: {type(exc).__name__}: {_one_line(exc)} (run with --debug for the traceback)", file=sys.stderr)
        return EXIT_FAILURE


def _check_options(args) -> None:
    """The options checked before any file is read: the library's settings (an error names the option, see
    :func:`_run`) and the fleet engine's sizes (a UsageError)."""
    if hasattr(args, "k"):  # detect, prognose, fleet
        from bgphm.commands._inputs import detection_settings

        detection_settings(args)
    if hasattr(args, "particles"):  # prognose, fleet
        from prognosis import IsolationSettings

        IsolationSettings(n_particles=args.particles, rul_every=args.rul_every, horizon=args.horizon, dt=args.dt,
                          seed=args.seed)
    elif getattr(args, "seed", 0) < 0:  # demo: a noise seed
        raise UsageError(f"--seed must be a whole number >= 0, got {args.seed}")
    for option, low in (("workers", 0), ("shard_size", 1), ("calibrate_assets", 1)):
        value = getattr(args, option, None)
        if value is not None and value < low:
            raise UsageError(f"--{option.replace('_', '-')} must be at least {low}, got {value}")


def _warning_line(message, category, filename, lineno, file=None, line=None) -> None:
    """``warnings.showwarning`` for the commands: ``bgphm: warning: ...`` on one line, no source path."""
    print(f"bgphm: warning: {_one_line(message)}", file=sys.stderr, flush=True)


def _one_line(exc: BaseException) -> str:
    return " ".join(str(exc).split())


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
