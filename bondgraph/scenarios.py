"""The case studies' faults and sensors: truth laws of degradation and the records a rig gives.

One home for what the tests, the doctests, the examples and the benchmarks simulate, so that a
scenario is written once:

* :func:`drift`: a parameter's true value over time, constant until an onset, then linear or
  exponential (Jha et al. (2016), eqs. 59-60): the truth a simulation follows and a metric
  scores against;
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

from collections.abc import Callable, Mapping

import numpy as np
from scipy.integrate import cumulative_trapezoid

from .library import THREE_TANK, TORSION_BAR, rlc_circuit, torsion_bar, torsion_bar_controller
from .simulation import simulate

__all__ = ["ANTIDERIVATIVES", "ENCODER_COUNT", "TORSION_DT", "drift", "encoder_angles", "rig_signals", "rlc_record",
           "three_tank_az2", "torsion_bar_record"]

TORSION_DT = 0.01  # s, sampling of the torsion bar's sensors
ENCODER_COUNT = 2 * np.pi / 2000  # rad, 2000 counts per revolution
ANTIDERIVATIVES = {"omega_m": "theta_m", "omega_Ld": "theta_Ld"}  # the encoder angle of each speed


def drift(nominal: float, rate: float, onset: float = 0.0, law: str = "linear") -> Callable:
    """The true value of a parameter: ``nominal`` until ``onset``, then ``nominal + rate (t - onset)`` (linear)
    or ``nominal exp(rate (t - onset))`` (exponential).

    The callable takes a time or an array of times (a float for a scalar), as the simulator and
    the metrics call it.

    >>> drift(10.0, 6.0, onset=0.5)(np.array([0.0, 1.0])).tolist()
    [10.0, 13.0]
    """
    if law not in ("linear", "exponential"):
        raise ValueError(f"law must be 'linear' or 'exponential', got {law!r}")

    def truth(t):
        elapsed = np.maximum(np.asarray(t, float) - onset, 0.0)
        value = nominal * np.exp(rate * elapsed) if law == "exponential" else nominal + rate * elapsed
        return float(value) if np.ndim(value) == 0 else value

    return truth


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
