"""``bgphm arr --simulated`` and ``bgphm detect --simulated`` on three tanks with the first and last levels measured.

The operation cap is lowered (in process) so that no closed form of the sets that see tank 2 is kept, as on
a model whose sets have none: the simulation residuals are then the only ARRs there are.  The record is
integrated here from the balances (scipy), not by the library's simulator.
"""

import json
import warnings

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import diagnosis.elimination as elimination
from bgphm.cli import main
from bondgraph.io import to_json
from bondgraph.library import ORIFICE, TANK_AREA, tank_cascade

pytestmark = pytest.mark.slow   # two derivations and a detection: 8 s


@pytest.fixture
def capped(monkeypatch):
    monkeypatch.setattr(elimination, "MAX_OPERATIONS", 30)   # the closed forms take 36 to 221 operations


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("tanks")
    model = folder / "tanks.json"
    model.write_text(to_json(tank_cascade(3, every=2)))
    t = np.linspace(0.0, 600.0, 1201)

    def inflow(time):
        return 1e-4 * (1.0 + 0.3 * np.sin(0.02 * time))

    def rates(time, h):
        a2 = ORIFICE * (0.6 if time >= 300.0 else 1.0)   # tank 2's outlet clogs at 300 s
        q = [ORIFICE * np.sqrt(max(h[0] - h[1], 0.0)), a2 * np.sqrt(max(h[1] - h[2], 0.0)),
             ORIFICE * np.sqrt(max(h[2], 0.0))]
        return [(inflow(time) - q[0]) / TANK_AREA, (q[0] - q[1]) / TANK_AREA, (q[1] - q[2]) / TANK_AREA]

    head = (inflow(0.0) / ORIFICE) ** 2   # at rest each orifice passes the inflow
    y = solve_ivp(rates, (0.0, 600.0), [3 * head, 2 * head, head], t_eval=t, rtol=1e-10, atol=1e-13,
                  max_step=0.5).y
    rng = np.random.default_rng(21)
    data = folder / "tanks.csv"
    rows = np.column_stack([t, inflow(t), y[0] + rng.normal(0, 1e-6, t.size), y[2] + rng.normal(0, 1e-6, t.size)])
    np.savetxt(data, rows, delimiter=",", header="t,q_in,h1,h3", comments="")
    return model, data


def test_the_report_shows_the_simulated_states_and_their_rates(files, capped, tmp_path, capsys):
    model, _ = files
    out = tmp_path / "arr.md"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert main(["--quiet", "arr", str(model), "--simulated", "--out", str(out)]) == 0
    text = out.read_text()
    assert "written as: simulation" in text and "Simulated states" in text
    assert r"\frac{\mathrm{d} q_{T_{2}}}{\mathrm{d} t}" in text
    assert main(["--quiet", "arr", str(model), "--out", str(tmp_path / "plain.md")]) == 0
    assert "written as: simulation" not in (tmp_path / "plain.md").read_text()


def test_detect_fires_a_simulation_residual_on_the_clogged_outlet(files, capped, tmp_path, capsys):
    model, data = files
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        code = main(["--quiet", "detect", str(model), str(data), "--simulated", "--calibrate", "250",
                     "--out", str(tmp_path)])
    assert code == 0
    summary = json.loads((tmp_path / "detection.json").read_text())
    simulated = [name for name, form in summary["forms"].items() if form["form"] == "simulation"]
    assert simulated and set(simulated) & set(summary["alarming_arrs"])
    assert all(300.0 <= summary["arrs"][name]["detection_time"] < 400.0
               for name in set(simulated) & set(summary["alarming_arrs"]))
    assert "a2" in summary["candidates"]
