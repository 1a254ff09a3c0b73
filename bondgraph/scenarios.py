"""The case studies' faults and sensors: truth laws of degradation and the records a rig gives.

One home for what the tests, the doctests, the examples and the benchmarks simulate, so that a
scenario is written once:

* :func:`drift`: a parameter's true value over time, constant until an onset, then linear or
  exponential (Jha et al. (2016), eqs. 59-60), a power of the time since the onset, or a step:
  the truth a simulation follows and a metric scores against; :class:`Degradation` is such a law
  without its nominal value, and :func:`parse_degradation` reads one from the text
  ``LAW:RATE@ONSET`` (``bgphm simulate --degrade``);
* the torsion bar of Jha et al. (2016) under its PI speed loop: :func:`rig_signals` (the speeds,
  the exact shaft angles and the motor torque ``k_m i``), :func:`encoder_angles` (the angles read
  by encoders of :data:`ENCODER_COUNT`, at a phase of their own) and :func:`torsion_bar_record`
  (both, simulated with a parameter following a truth law);
* the RLC circuit under ``V = 5 + sin(7 t)``: :func:`rlc_record`;
* the three tanks of Du et al. (n.d.): :func:`three_tank_az2`, the outlet coefficient's drift of
  their eq. (61).

Examples
--------
The motor-disk friction of section 6.3.2, and the RLC's resistance drifting from 10 ohm:

>>> from bondgraph.library import TORSION_BAR
>>> b_md = drift(TORSION_BAR["b_Md"][0], 0.05, onset=10.0, law="exponential")
>>> round(b_md(10.0) / TORSION_BAR["b_Md"][0], 6), round(b_md(30.0) / TORSION_BAR["b_Md"][0], 6)
(1.0, 2.718282)
>>> record = rlc_record(np.linspace(0.0, 1.0, 101), {"R": drift(10.0, 6.0, onset=0.5)})
>>> sorted(record), round(float(record["i"][-1]), 4)
(['V', 'i', 't', 'v_C'], 0.0056)
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np
from scipy.integrate import cumulative_trapezoid

from .errors import SimulationError
from .library import THREE_TANK, TORSION_BAR, rlc_circuit, torsion_bar, torsion_bar_controller
from .simulation import simulate

__all__ = ["ANTIDERIVATIVES", "DEGRADATION_LAWS", "DEGRADATION_SYNTAX", "Degradation", "ENCODER_COUNT", "LAW_NAMES",
           "TORSION_DT", "drift", "encoder_angles", "parse_degradation", "rig_signals", "rlc_record", "three_tank_az2",
           "torsion_bar_record"]

TORSION_DT = 0.01  # s, sampling of the torsion bar's sensors
ENCODER_COUNT = 2 * np.pi / 2000  # rad, 2000 counts per revolution
ANTIDERIVATIVES = {"omega_m": "theta_m", "omega_Ld": "theta_Ld"}  # the encoder angle of each speed


#: The laws of :func:`drift`, and the short names the spec text of :func:`parse_degradation` may use.
DEGRADATION_LAWS = ("linear", "exponential", "power", "step")
LAW_NAMES = {"lin": "linear", "exp": "exponential", "pow": "power", "step": "step"}
#: How :func:`parse_degradation` says what it expects.
DEGRADATION_SYNTAX = "LAW:RATE@ONSET (LAW lin, exp, pow or step; pow:RATE^EXPONENT@ONSET), e.g. exp:0.05@10"


def drift(nominal: float, rate: float, onset: float = 0.0, law: str = "linear", exponent: float = 1.0) -> Callable:
    """The true value of a parameter: ``nominal`` until ``onset``, then with ``tau = t - onset``

    * ``"linear"``: ``nominal + rate tau``;
    * ``"exponential"``: ``nominal exp(rate tau)``;
    * ``"power"``: ``nominal + rate tau^exponent`` (``exponent`` > 0; 1 is the linear law, the family of
      :class:`prognosis.PowerDegradation`);
    * ``"step"``: ``nominal + rate`` from ``t = onset`` on (an abrupt change by ``rate``, in the
      parameter's unit).

    The callable takes a time or an array of times (a float for a scalar), as the simulator and
    the metrics call it.

    >>> drift(10.0, 6.0, onset=0.5)(np.array([0.0, 1.0])).tolist()
    [10.0, 13.0]
    >>> drift(10.0, 2.0, onset=1.0, law="power", exponent=2.0)(3.0), drift(10.0, -4.0, onset=1.0, law="step")(1.0)
    (18.0, 6.0)
    """
    if law not in DEGRADATION_LAWS:
        raise ValueError(f"law must be one of {', '.join(map(repr, DEGRADATION_LAWS))}, got {law!r}")
    if law == "power" and not (math.isfinite(exponent) and exponent > 0):
        raise ValueError(f"the exponent of a power law must be a finite number > 0, got {exponent!r}")

    def truth(t):
        t = np.asarray(t, float)
        elapsed = np.maximum(t - onset, 0.0)
        if law == "exponential":
            value = nominal * np.exp(rate * elapsed)
        elif law == "power":
            value = nominal + rate * elapsed ** exponent
        elif law == "step":
            value = np.where(t >= onset, nominal + rate, nominal)
        else:
            value = nominal + rate * elapsed
        return float(value) if np.ndim(value) == 0 else value

    return truth


@dataclass(frozen=True)
class Degradation:
    """A degradation law of a parameter, whatever its nominal value: :func:`drift`'s ``law``, ``rate``, ``onset``
    and ``exponent``; :meth:`truth` puts it on a nominal value.

    Written and read as text (:func:`parse_degradation`): ``exp:0.05@10`` is the exponential law
    ``nominal exp(0.05 (t - 10))`` from t = 10 s.

    >>> law = Degradation("exponential", 0.8, onset=1.0)
    >>> str(law), round(law.truth(1e-4)(2.0) / 1e-4, 6)
    ('exp:0.8@1', 2.225541)
    """

    law: str
    rate: float
    onset: float = 0.0
    exponent: float = 1.0

    def truth(self, nominal: float) -> Callable:
        """The parameter's true value over time from ``nominal`` (:func:`drift`)."""
        return drift(nominal, self.rate, self.onset, self.law, self.exponent)

    def value_range(self, nominal: float, t_end: float) -> tuple[float, float]:
        """The smallest and largest values the law takes over ``[0, t_end]`` (each law is monotonic in time).

        >>> Degradation("linear", -2.0, onset=1.0).value_range(10.0, 4.0)
        (4.0, 10.0)
        """
        truth = self.truth(nominal)
        with np.errstate(over="ignore"):  # an exponential law that overflows is infinite: check_domain says so
            ends = [truth(0.0), truth(max(t_end, 0.0))]
        return min(ends), max(ends)

    def check_domain(self, nominal: float, domain: tuple[float, float], t_end: float, *, where: str) -> None:
        """Raise a SimulationError, starting with ``where``, when the law leaves ``domain`` (lo, hi) within
        ``[0, t_end]``: a friction that a falling linear law takes below zero, say.

        >>> Degradation("linear", -1e-4, onset=1.0).check_domain(1e-4, (0.0, float("inf")), 4.0, where="b")
        Traceback (most recent call last):
        ...
        bondgraph.errors.SimulationError: b: the law takes the value from 0.0001 to -0.0002 by t = 4 s, outside ...
        """
        low, high = self.value_range(nominal, t_end)
        lo, hi = domain
        if not (math.isfinite(low) and math.isfinite(high)):
            raise SimulationError(f"{where}: the value overflows to infinity by t = {t_end:g} s")
        if low < lo or high > hi:
            far = low if low < lo else high
            raise SimulationError(f"{where}: the law takes the value from {nominal:g} to {far:g} by t = {t_end:g} s, "
                                  f"outside the physical domain ({lo:g}, {hi:g})")

    def __str__(self) -> str:
        short = {long: name for name, long in LAW_NAMES.items()}[self.law]
        power = f"^{self.exponent:g}" if self.law == "power" else ""
        return f"{short}:{self.rate:g}{power}@{self.onset:g}"


def parse_degradation(text: str, *, where: str = "degradation") -> Degradation:
    """Read a degradation law from the text ``LAW:RATE@ONSET``: what ``bgphm simulate --degrade`` takes.

    ``LAW`` is ``lin``, ``exp``, ``pow`` or ``step`` (or the names ``linear``, ``exponential``, ``power``);
    ``RATE`` is :func:`drift`'s rate (the size of the change for a step); the power law needs its
    exponent, ``pow:RATE^EXPONENT``; ``@ONSET`` (s) may be left out for an onset at 0.  Numbers are
    parsed with ``float``, never evaluated.

    Raises
    ------
    SimulationError
        Starting with ``where`` (the parameter, say) and naming the part at fault: the law, the rate,
        the exponent or the onset.

    Examples
    --------
    >>> parse_degradation("exp:0.05@10")
    Degradation(law='exponential', rate=0.05, onset=10.0, exponent=1.0)
    >>> round(parse_degradation("pow:2e-4^1.5@1").truth(1e-4)(5.0), 9)   # 1e-4 + 2e-4 * 4^1.5
    0.0017
    >>> parse_degradation("exp:fast@10", where="b")
    Traceback (most recent call last):
    ...
    bondgraph.errors.SimulationError: b: the rate 'fast' is not a number (expected LAW:RATE@ONSET ...
    """
    if not isinstance(text, str):
        raise SimulationError(f"{where}: expected the text {DEGRADATION_SYNTAX}, got {type(text).__name__}")
    name, colon, rest = text.strip().partition(":")
    if not colon:
        raise SimulationError(f"{where}: {text!r} has no law (expected {DEGRADATION_SYNTAX})")
    law = LAW_NAMES.get(name.strip().lower(), name.strip().lower())
    if law not in DEGRADATION_LAWS:
        raise SimulationError(f"{where}: unknown law {name.strip()!r} (expected {DEGRADATION_SYNTAX})")
    size, at, onset = rest.partition("@")
    rate, caret, exponent = size.partition("^")
    if caret and law != "power":
        raise SimulationError(f"{where}: only a power law has an exponent, got {size.strip()!r} for the law {law!r}")
    if law == "power" and not caret:
        raise SimulationError(f"{where}: a power law needs its exponent: pow:RATE^EXPONENT@ONSET, e.g. pow:2e-4^2@1")
    degradation = Degradation(law, _spec_number(rate, "rate", where),
                              _spec_number(onset, "onset", where) if at else 0.0,
                              _spec_number(exponent, "exponent", where) if caret else 1.0)
    if degradation.exponent <= 0:
        raise SimulationError(f"{where}: the exponent must be > 0, got {exponent.strip()!r}")
    return degradation


def _spec_number(text: str, part: str, where: str) -> float:
    """A finite number of a spec text (``float``, never evaluated), or a SimulationError naming the part."""
    try:
        number = float(text)
    except ValueError:
        raise SimulationError(f"{where}: the {part} {text.strip()!r} is not a number (expected "
                              f"{DEGRADATION_SYNTAX})") from None
    if not math.isfinite(number):
        raise SimulationError(f"{where}: the {part} must be finite, got {text.strip()!r}")
    return number


def rig_signals(result, bg, every: int = 1) -> dict:
    """What the torsion bar's rig measures, every ``every`` outputs of a simulation ``result`` of ``bg``.

    The speeds ``omega_m`` and ``omega_Ld``, their exact angles ``theta_m`` and ``theta_Ld`` (the
    integrals of the speeds over the solver's outputs, before the sampling: the trapezoidal rule on
    the sensors' samples would miss the shaft's twist in the start-up) and the motor torque
    ``tau_m = k_m i``.  :func:`encoder_angles` reads the angles as encoders do.
    """
    current = next(b.label for b in bg.bonds if b.key == ("1_e", "GY"))
    columns = {"t": result.t, "omega_m": result["omega_m"], "omega_Ld": result["omega_Ld"],
               "tau_m": TORSION_BAR["k_m"][0] * result.flows[current]}
    for speed, angle in ANTIDERIVATIVES.items():
        columns[angle] = cumulative_trapezoid(columns[speed], result.t, initial=0.0)
    return {name: values[::every] for name, values in columns.items()}


def encoder_angles(record: Mapping, phases: Mapping[str, float] | None = None) -> dict:
    """The record with each angle read by an encoder of :data:`ENCODER_COUNT` per count.

    An encoder counts edges from wherever its disk stands at power-up (it reads 0 there): ``phases``
    (angle name -> rad in ``[0, ENCODER_COUNT)``, default 0) is where its grid of edges lies, so
    that records of different runs carry different quantization errors.
    """
    out = dict(record)
    for angle in ANTIDERIVATIVES.values():
        phase = 0.0 if phases is None else float(phases[angle])
        counts = np.round((record[angle] + phase) / ENCODER_COUNT) - np.round(phase / ENCODER_COUNT)
        out[angle] = counts * ENCODER_COUNT
    return out


def torsion_bar_record(t_end: float, parameters: Mapping[str, Callable], phases: Mapping[str, float] | None = None,
                       bg=None) -> dict:
    """The noise-free sensor record of the torsion bar under PI speed control, its parameters following
    ``parameters`` (name -> truth law), sampled every :data:`TORSION_DT` up to ``t_end``.

    The solver's output is taken every ``TORSION_DT / 10`` so that the angles are accurate integrals
    of the speeds, then read by encoders at ``phases`` (:func:`encoder_angles`).  ``bg``: the bond
    graph to simulate (default the full :func:`~bondgraph.library.torsion_bar`).
    """
    full = torsion_bar() if bg is None else bg
    equations = full.state_equations(full.assign_causality("integral"))
    every = 10
    t_eval = np.arange(0.0, t_end + TORSION_DT / (2 * every), TORSION_DT / every)
    t_end = max(t_end, float(t_eval[-1]))  # the last point may overshoot by a rounding error
    run = simulate(equations, (0.0, t_end), {"U": torsion_bar_controller()}, t_eval=t_eval,
                   parameters=dict(parameters))
    return encoder_angles(rig_signals(run, full, every), phases)


def rlc_record(t: np.ndarray, parameters: Mapping[str, Callable] | None = None):
    """The RLC circuit (:func:`~bondgraph.library.rlc_circuit`) under ``V = 5 + sin(7 t)``, sampled at ``t``,
    its parameters following ``parameters`` (name -> truth law; nominal otherwise): a
    record as a mapping of arrays (``t``, ``V``, ``i``, ``v_C``)."""
    t = np.asarray(t, float)
    return simulate(rlc_circuit(), (float(t[0]), float(t[-1])), {"V": lambda s: 5 + np.sin(7 * s)}, t_eval=t,
                    parameters=dict(parameters or {})).record()


def three_tank_az2(steps: int, onset: int = 10, rate: float = 1e-4) -> np.ndarray:
    """The three tanks' az2 over ``steps`` steps of 1 s by eq. (61) of Du et al. (n.d.): nominal for
    ``k <= onset``, then ``az2_k = az2_{k-1} + rate (k - onset)``; entry ``k - 1`` is step ``k``.

    >>> three_tank_az2(13)[-4:].round(6).tolist()
    [0.6, 0.6001, 0.6003, 0.6006]
    """
    k = np.arange(1, steps + 1)
    return THREE_TANK["az2"] + rate * np.cumsum(np.where(k > onset, k - onset, 0))
