"""r_n + Psi_2 = 0 for the true system: simulate with perturbed parameters, evaluate both parts on exact signals."""

import numpy as np
import pytest
import sympy as sp

from bondgraph import simulate
from bondgraph.library import three_tank, torsion_bar_monitorable
from diagnosis import derive_arrs
from diagnosis.residuals import read_record


def identity_error(arr, record, exact, deltas, integral=None):
    """max |r_n + Psi_2(deltas)| and max |Psi_2| over the record (``integral``: exact value of its one integral)."""
    compiled = arr.compiled
    points = compiled.point_values(read_record(arr, record), exact=exact)
    if compiled.integrals:
        assert len(compiled.integrals) == 1 and integral is not None
        points[compiled.points.index(next(iter(compiled.integrals)))] = integral
    r_n = compiled.residual(points)
    symbols = [sp.Symbol(f"delta_{p}") for p in arr.uncertainties]
    psi = np.asarray(compiled.function("psi at a point", compiled.uncertain, tuple(symbols))(
        *points, *[deltas[p] for p in arr.uncertainties]), float)
    return np.max(np.abs(r_n + psi)), np.max(np.abs(psi))


def effort_into(bg, result, element):
    bond = next(b for b in bg.bonds if b.head == element and not b.is_signal)
    return result.efforts[bond.label]


def flow_into(bg, result, element):
    bond = next(b for b in bg.bonds if b.head == element and not b.is_signal)
    return result.flows[bond.label]


@pytest.mark.parametrize("corner", [0, *(pytest.param(c, marks=pytest.mark.slow) for c in (1, 2))])
def test_torsion_bar_identity_at_points_of_the_box(corner):
    bg = torsion_bar_monitorable()
    rng = np.random.default_rng(corner)
    box = bg.uncertainties
    deltas = {p: float(rng.uniform(lo, hi)) if corner else (hi if i % 2 else lo)
              for i, (p, (lo, hi)) in enumerate(box.items())}
    true = {p: bg.parameters[p] * (1 + d) for p, d in deltas.items()}
    t = np.linspace(0.0, 4.0, 16001)
    result = simulate(bg, (0.0, 4.0), {"tau_m": lambda s: 0.05 + 0.03 * np.sin(2.0 * s)}, parameters=true,
                      t_eval=t, rtol=1e-11, atol=1e-14)
    exact = {"omega_m": effort_into(bg, result, "J_m") / true["J_m"],
             "omega_Ld": effort_into(bg, result, "J_Ld") / true["J_Ld"]}
    twist = result.states["q_k_s"]  # the exact integral of omega_m/k_belt - omega_Ld from t = 0
    for arr in derive_arrs(bg, complete=False, integrals="keep"):
        error, scale = identity_error(arr, result.record(), exact, deltas, twist)
        assert scale > 1e-6  # the perturbation is visible in Psi_2 ...
        assert error < 1e-8 * scale  # ... and cancels the nominal residual to integration accuracy


def test_three_tank_identity_with_perturbed_valves_and_areas():
    bg = three_tank()
    deltas = {"A_1": 0.05, "A_2": -0.05, "A_3": 0.02, "az1": -0.04, "az2": 0.05, "az3": 0.03}
    true = {p: bg.parameters[p] * (1 + d) for p, d in deltas.items()}
    t = np.linspace(0.0, 300.0, 3001)
    result = simulate(bg, (0.0, 300.0), {"Q1": 4.5e-5, "Q2": lambda s: 2e-5 * (1 + np.sin(s / 20))},
                      parameters=true, x0={"A_1": 0.0154 * 0.5, "A_2": 0.0154 * 0.3, "A_3": 0.0154 * 0.4},
                      t_eval=t, rtol=1e-11, atol=1e-15)
    exact = {f"h{i}": flow_into(bg, result, f"A_{i}") / true[f"A_{i}"] for i in (1, 2, 3)}
    for arr in derive_arrs(bg, complete=False, integrals="keep"):
        error, scale = identity_error(arr, result.record(), exact, deltas)
        assert scale > 1e-8
        assert error < 1e-9 * max(scale, 1e-6) + 1e-13, arr.name
