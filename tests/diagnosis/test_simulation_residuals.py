"""Simulation residuals (diagnosis.simulation_residuals) judged on records written from the physics.

The records come from an integration of the tank cascade's balances written here by hand (scipy's solve_ivp,
tight tolerances), not from the library's simulator: ``A_i dh_i/dt = q_(i-1,i) - q_(i,i+1)`` with
``q = a sign(dh) sqrt|dh|``.  The band is a claim: records whose parameters are drawn inside the box must stay
in it, a fault outside the box must leave it.
"""

import pickle
import warnings

import numpy as np
import sympy as sp
import pytest
from scipy.integrate import solve_ivp

import diagnosis.elimination as elimination
from bondgraph.library import ORIFICE, TANK_AREA, mass_spring_chain, tank_cascade
from diagnosis import (ARRError, ARRWarning, CodegenError, StreamingEvaluation, as_record, derive_arrs, detect,
                       DetectionSettings, add_noise, generate_code, structural_model)
from diagnosis.elimination import arr_from_set, faults_of_arr, unreached
from diagnosis.simulation_residuals import SimulationARR, SimulationError

INFLOW = 1e-4   # m^3/s


def inflow(t):
    return INFLOW * (1.0 + 0.3 * np.sin(0.02 * t))


def reference(n: int, values: dict, *, fault: dict | None = None, at: float = 300.0, duration: float = 600.0,
              samples: int = 1201, measured=(1, 3)):
    """A record of ``n`` tanks from rest, integrated from the balances (levels ``h_i`` for ``measured``)."""
    def flows(h, p):
        below = np.append(h[1:], 0.0)
        return np.array([p[f"a{i + 1}"] * np.sign(h[i] - below[i]) * np.sqrt(abs(h[i] - below[i]))
                         for i in range(n)])

    def rates(t, h):
        p = {**values, **(fault if fault and t >= at else {})}
        q = flows(h, p)
        into = np.concatenate([[inflow(t)], q[:-1]])
        return (into - q) / np.array([p[f"A{i + 1}"] for i in range(n)])

    rest, level = np.zeros(n), 0.0
    for i in reversed(range(n)):   # at rest every orifice passes the inflow
        level += (inflow(0.0) / values[f"a{i + 1}"]) ** 2
        rest[i] = level
    t = np.linspace(0.0, duration, samples)
    solution = solve_ivp(rates, (0.0, duration), rest, t_eval=t, rtol=1e-10, atol=1e-13, max_step=duration / samples)
    assert solution.success
    return as_record({"t": t, "q_in": inflow(t), **{f"h{i}": solution.y[i - 1] for i in measured}})


NOMINAL = {**{f"A{i}": TANK_AREA for i in range(1, 6)}, **{f"a{i}": ORIFICE for i in range(1, 6)}}


def simulated_arrs(bg):
    """The simulation residual of every minimal set of ``bg`` that has one."""
    model = structural_model(bg)
    found = []
    for k, rows in enumerate(model.mso_sets()):
        try:
            found.append(arr_from_set(bg, rows, model=model, simulated=True, name=f"ARR_SIM_{k}"))
        except ValueError:
            continue
    return found


@pytest.fixture(scope="module")
def three():
    bg = tank_cascade(3, every=2)
    return bg, simulated_arrs(bg)


@pytest.fixture(scope="module")
def two():
    """Two of them, for the fast tier: one simulating tank 2 alone (the balance of tank 3 as residual, a
    derivative of h3), one simulating tanks 2 and 3 (h3 compared with the simulated level)."""
    bg = tank_cascade(3, every=2)
    model = structural_model(bg)
    found = {}
    for k, rows in enumerate(model.mso_sets()):
        try:
            arr = arr_from_set(bg, rows, model=model, simulated=True, name=f"ARR_SIM_{k}")
        except ValueError:
            continue
        if "a2" in arr.parameters:
            found.setdefault(arr.states, arr)
        if ("q_T2",) in found and ("q_T2", "q_T3") in found:
            return bg, [found[("q_T2",)], found[("q_T2", "q_T3")]]
    raise AssertionError(f"expected sets simulating q_T2 alone and with q_T3, found {sorted(found)}")


@pytest.mark.slow
def test_every_set_with_a_state_of_the_three_tank_cascade_gets_a_simulation_residual(three):
    bg, arrs = three
    assert len(arrs) >= 4 and all(isinstance(a, SimulationARR) and a.form == "simulation" for a in arrs)
    for arr in arrs:
        assert arr.states and set(arr.signals) <= {"q_in", "h1", "h3"}
        assert not set(arr.states) & set(arr.signals)
        # the rates use the parameters the set holds, which the residual is sensitive to
        assert {p for f in arr.rates for p in map(str, f.free_symbols)} - {"t"} <= set(arr.parameters)
    assert any("A2" in arr.parameters for arr in arrs)   # tank 2, unmeasured, is seen through its dynamics


@pytest.mark.slow
@pytest.mark.parametrize("seed", [11, 12, 13])
def test_records_with_parameters_drawn_in_the_box_stay_inside_the_band(three, seed):
    bg, arrs = three
    rng = np.random.default_rng(seed)
    values = {p: v * (1 + rng.uniform(-0.02, 0.02) if p.startswith("A") else 1 + rng.uniform(-0.1, 0.1))
              for p, v in NOMINAL.items()}
    record = reference(3, values)
    for arr in arrs:
        result = arr.evaluate(record)
        decided = ~np.isnan(result.residual)
        assert decided.mean() > 0.95, arr.name
        assert not result.violation.any(), (arr.name, values)


def test_an_orifice_clogging_past_its_box_leaves_the_band_after_it_and_never_before(two):
    bg, arrs = two
    record = reference(3, NOMINAL, fault={"a2": 0.6 * ORIFICE}, at=300.0)
    seeing = [arr for arr in arrs if "a2" in arr.parameters]
    assert seeing
    times = []
    for arr in seeing:
        result = arr.evaluate(record)
        assert not result.violation[result.t < 300.0].any(), arr.name
        times.append(result.detection_time)
    assert any(t is not None and 300.0 <= t < 360.0 for t in times), times


def test_a_residual_from_a_given_initial_box_holds_a_record_that_does_not_start_at_rest(two):
    bg, arrs = two
    arr = next(a for a in arrs if a.states == ("q_T2",))
    record = reference(3, NOMINAL)
    # a record started above rest: the given box holds its start, "rest" would not
    t = record.t
    values = dict(NOMINAL)

    def rates(time, h):
        q = [values[f"a{i + 1}"] * np.sign(h[i] - (h[i + 1] if i < 2 else 0.0)) * np.sqrt(
            abs(h[i] - (h[i + 1] if i < 2 else 0.0))) for i in range(3)]
        return [(inflow(time) - q[0]) / TANK_AREA, (q[0] - q[1]) / TANK_AREA, (q[1] - q[2]) / TANK_AREA]

    start = np.array([0.0075, 0.0065, 0.0025])
    y = solve_ivp(rates, (t[0], t[-1]), start, t_eval=t, rtol=1e-10, atol=1e-13, max_step=0.5).y
    lifted = as_record({"t": t, "q_in": inflow(t), "h1": y[0], "h3": y[2]})
    given = arr.evaluate(lifted, initial={"q_T2": (0.0060 * TANK_AREA, 0.0070 * TANK_AREA)})
    assert not given.violation.any()
    assert arr.evaluate(lifted).violation.any()   # the rest assumption, wrong here, is what fails


def test_initial_states_are_checked_and_named(two):
    bg, arrs = two
    arr = arrs[0]
    record = reference(3, NOMINAL, samples=101)
    with pytest.raises(SimulationError, match=r"initial: no state 'h2'"):
        arr.evaluate(record, initial={"h2": 0.1, **{x: 1.0 for x in arr.states}})
    with pytest.raises(SimulationError, match=rf"initial\['{arr.states[0]}'\] must be a finite value"):
        arr.evaluate(record, initial={x: (2.0, 1.0) for x in arr.states})
    with pytest.raises(SimulationError, match="initial must be 'rest'"):
        arr.evaluate(record, initial="steady")


def test_a_simulation_residual_pickles_without_its_numerics_and_evaluates_the_same(two):
    bg, arrs = two
    arr = arrs[0]
    record = reference(3, NOMINAL, samples=201, duration=100.0)
    before = arr.evaluate(record)
    copy = pickle.loads(pickle.dumps(arr))   # a process pool or Dask sends ARRs this way
    assert copy == arr and copy._simulator is None
    after = copy.evaluate(record)
    np.testing.assert_array_equal(after.residual, before.residual)
    np.testing.assert_array_equal(after.lower, before.lower)


def test_consumers_that_need_a_closed_form_refuse_a_simulation_residual_by_name(two):
    bg, arrs = two
    arr = arrs[0]
    with pytest.raises(ARRError, match=rf"StreamingEvaluation: {arr.name} is a simulation residual"):
        StreamingEvaluation(arr)
    with pytest.raises(CodegenError, match=rf"{arr.name}: a simulation residual"):
        generate_code([arr], "python", dt=0.5)


@pytest.mark.slow
def test_detect_takes_a_simulation_residual_beside_the_closed_forms(three):
    bg, arrs = three
    record = add_noise(reference(3, NOMINAL, fault={"a2": 0.6 * ORIFICE}), {"h1": 1e-5, "h3": 1e-5, "q_in": 1e-7},
                       seed=5)
    chosen = next(a for a in arrs if "a2" in a.parameters and a.order == 0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = detect(bg, record, DetectionSettings(calibrate=250.0), arrs=derive_arrs(bg) + [chosen])
    assert chosen.name in result.fired
    assert result.forms[chosen.name]["form"] == "simulation"
    assert "a2" in result.candidates


@pytest.mark.slow
def test_the_derivation_falls_back_on_simulation_where_no_closed_form_is_kept(monkeypatch):
    """With the operation cap so low that no inversion of an orifice survives, the closed forms of the sets
    that see tank 2 are refused; ``simulated=True`` realises the sets by their dynamics instead."""
    bg = tank_cascade(3, every=2)
    monkeypatch.setattr(elimination, "MAX_OPERATIONS", 30)   # the closed forms take 36 to 221
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ARRWarning)
        closed = derive_arrs(bg, max_order=None)
        both = derive_arrs(bg, max_order=None, simulated=True)
    model = structural_model(bg)
    missed = unreached(bg, closed)
    reached = unreached(bg, both)
    assert missed["detect"] or missed["isolate"]   # the cap leaves gaps
    assert not reached["detect"] and len(reached["isolate"]) < len(missed["isolate"])
    added = [a for a in both if a.form == "simulation"]
    assert added and all(faults_of_arr(model, a) for a in added)


@pytest.mark.slow
def test_five_tanks_measured_every_other_one_reach_every_isolable_pair_with_simulation():
    """Without simulation 6 ordered pairs are left (benchmarks/bench_completeness.py): the sets that would tell
    tanks 3 to 5 from the last level sensor are closed only by their own dynamics."""
    bg = tank_cascade(5, every=2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ARRWarning)
        both = derive_arrs(bg, max_order=None, simulated=True)
    assert any(a.form == "simulation" for a in both)
    assert unreached(bg, both) == {"detect": [], "isolate": []}
    record = reference(5, NOMINAL, measured=(1, 3, 5))
    for arr in (a for a in both if a.form == "simulation"):
        assert not arr.evaluate(record).violation.any(), arr.name


@pytest.mark.slow
def test_a_set_of_the_shape_of_one_simulated_takes_its_residual_renamed_and_that_is_the_sets_own():
    """Another stage of a chain: the simulation residual of the first set, renamed, equals the set's own."""
    bg = mass_spring_chain(6)
    shared = elimination._Shared(bg, structural_model(bg), True, True)   # the derivation's own cache
    renamed = []
    for mass in range(2, 6):   # the inner stages: the same sets, renamed
        for rows in shared.near(f"m{mass}", set()):
            arr = shared.simulation(rows, set())
            if shared.reused.get(rows) and arr is not None:
                renamed.append((rows, arr))
    assert renamed
    rows, arr = renamed[0]
    fresh = shared.simulated(rows, arr.name)
    assert set(arr.states) == set(fresh.states) and arr.junction == fresh.junction   # in any order
    assert sp.simplify(arr.nominal - fresh.nominal) == 0
    for kind in ("rates", "rates_true"):
        ours, own = (dict(zip(a.states, getattr(a, kind))) for a in (arr, fresh))
        assert all(sp.simplify(ours[x] - own[x]) == 0 for x in own)
    assert (arr.parameters, arr.values, arr.uncertainties) == (fresh.parameters, fresh.values, fresh.uncertainties)
