"""The command line over the zoo: ``arr`` (md, html, tex), ``simulate``, ``detect`` and ``prognose``.

Each ends with exit 0, or 2 and one line naming what is wrong: never exit 1 (an internal error).  The
model goes in as JSON (constant inputs where the zoo's are constant), the records are the model's
reference runs with step inputs and noise; ``prognose`` is told a failure value (twice nominal) for
every parameter an ARR sees, and a 30 % rise of one of them starts at the calibration end.
"""

import contextlib
import io
import warnings

import pytest
import sympy as sp

from bgphm.cli import main
from bgphm.files import csv_text
from bondgraph.io import to_json
from diagnosis import derive_arrs
from tests.zoo.chain import CALIBRATE, CHANGE, cases
from tests.zoo.reference import record, simulate_reference

BY_NAME = {case.name: case for case in cases()}
FAST = ["flywheel_speed_loop"]
#: about 20 s of CPU each: one per domain and feature here, every model in benchmarks/zoo_cli.py
SLOW = ["quarter_car", "level_loop", "loudspeaker"]


def bgphm(*argv: str) -> tuple[int, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main(["--quiet", *argv])
        except SystemExit as exc:
            code = exc.code
    return code, err.getvalue()


def constant_inputs(case) -> dict:
    """The zoo's last step levels where they are numbers (a controller law cannot go in a JSON model)."""
    levels = {}
    for name, profile in case.step_inputs.items():
        level = sp.sympify(profile[-1][1])
        if level.is_number:
            levels[name] = float(level)
    return levels


def run_the_chain(case, tmp_path) -> dict:
    """Run the commands on ``case`` in ``tmp_path``; assert exit 0 or 2 (one line); return command -> exit code."""
    bg = case.build()
    model = tmp_path / "model.json"
    model.write_text(to_json(bg, inputs=constant_inputs(case), t_end=case.t_end))
    healthy, faulty = tmp_path / "healthy.csv", tmp_path / "faulty.csv"
    healthy.write_text(csv_text(record(simulate_reference(case, inputs="step"), noise=case.noise, seed=1)))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        seen = sorted({p for arr in derive_arrs(bg) for p in arr.parameters})
    assert seen, f"{case.name}: no ARR sees any parameter"
    worn = seen[0]
    run = simulate_reference(case, inputs="step", parameters={worn: bg.parameters[worn] * (1 + CHANGE)},
                             fault_at=CALIBRATE * case.t_end)
    faulty.write_text(csv_text(record(run, noise=case.noise, seed=2)))
    calibrate = f"{CALIBRATE * case.t_end:g}"
    fails = [f"--fail={p}={2 * bg.parameters[p]:g}" for p in seen]
    commands = [["arr", str(model), "--format", form] for form in ("md", "html", "tex")]
    commands += [["simulate", str(model), "--samples", "201"],
                 ["detect", str(model), str(healthy), "--calibrate", calibrate],
                 ["detect", str(model), str(faulty), "--calibrate", calibrate],
                 ["prognose", str(model), str(faulty), *fails, "--calibrate", calibrate, "--particles", "50",
                  "--rul-every", "50"]]   # the exit codes are checked, not the figures: few particles do
    codes = {}
    for argv in commands:
        code, err = bgphm(*argv)
        assert code in (0, 2), f"{case.name}: bgphm {' '.join(argv[:1])} exit {code}:\n{err}"
        if code == 2:
            lines = [line for line in err.splitlines() if not line.startswith("bgphm: warning: ")]
            assert len(lines) == 1 and lines[0].startswith("bgphm: error: "), err
        codes[" ".join(a for a in argv[:3] if not a.startswith("/"))] = code
    return codes


@pytest.mark.parametrize("name", FAST)
def test_the_command_line_on_a_zoo_model(name, tmp_path):
    run_the_chain(BY_NAME[name], tmp_path)


@pytest.mark.slow
@pytest.mark.parametrize("name", SLOW)
def test_the_command_line_over_the_zoo(name, tmp_path):
    run_the_chain(BY_NAME[name], tmp_path)
