"""The README's python blocks run as printed: the tour (once) gives the figures its comments quote, and the
three shell commands after it give the same figures through ``bgphm``."""

import contextlib
import io
import json
import math
import re
import shlex
from pathlib import Path

import pytest

from bgphm.cli import main

README = Path(__file__).resolve().parents[2] / "README.md"
TOUR_HEADING = "## A tour: from a model to an alarm and a remaining useful life"


def tour_section() -> str:
    return README.read_text().split(TOUR_HEADING, 1)[1].split("\n## ", 1)[0]


def tour_source() -> str:
    return re.search(r"```python\n(.*?)```", tour_section(), re.S).group(1)


def tour_commands() -> list[list[str]]:
    """The shell commands after the tour, as argument lists without ``bgphm`` (comments dropped)."""
    block = re.search(r"```bash\n(.*?)```", tour_section(), re.S).group(1)
    commands = [shlex.split(line, comments=True) for line in block.splitlines() if line.strip()]
    assert all(c[0] == "bgphm" for c in commands)
    return [c[1:] for c in commands]


@pytest.fixture(scope="module")
def tour():
    """The tour run once: its namespace and its printed lines."""
    namespace: dict = {}
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(tour_source(), str(README), "exec"), namespace)
    return namespace, out.getvalue().splitlines()


def tour_figures(namespace) -> dict:
    """What the tour computes: the alarm of the detection, the last RUL's time and percentiles."""
    detection = namespace["detect"](namespace["motor"], namespace["record"], namespace["healthy"])
    result = namespace["result"]
    return {"alarm": detection.detection_time, "t": float(result.rul_t[-1]),
            "percentiles": result.rul[-1].percentile([5, 50, 95])[0].tolist()}


@pytest.mark.slow
def test_readme_tour_runs_and_its_comments_are_true(tour):
    namespace, lines = tour
    source = tour_source()
    assert lines[0].startswith("-J*Derivative(omega(t), t) - b*omega(t) + k_m*i(t) |")
    assert "delta_b" in lines[0]
    figures = tour_figures(namespace)
    assert float(lines[1]) == figures["alarm"]
    assert f"alarm at {lines[1]} s" in source                         # the comment's alarm time
    assert lines[2] == "b exponential" and "# b exponential" in source
    p5, p50, p95 = figures["percentiles"]
    true_rul = 1.0 + math.log(2e-3 / 1e-4) / 0.8 - figures["t"]
    assert p5 <= true_rul <= p95
    assert abs(p50 - true_rul) < 0.1 * true_rul
    last = source.splitlines()[-1]
    assert f"at {figures['t']:.2f} s: [[{p5:.2f} {p50:.2f} {p95:.2f}]]" in last
    assert f"true RUL {true_rul:.2f} s" in last


@pytest.mark.slow
def test_readme_commands_give_the_tours_figures(tour, tmp_path, monkeypatch, capsys):
    """``simulate``, ``detect`` and ``prognose`` as the README prints them (each with an ``--out`` added to read
    the figures exactly) give the alarm and the RUL percentiles the tour computes, and their comments quote them."""
    figures = tour_figures(tour[0])
    commands = tour_commands()
    assert [c[0] for c in commands] == ["simulate", "detect", "prognose"]
    monkeypatch.chdir(tmp_path)
    printed = []
    for argv in commands:
        extra = [] if argv[0] == "simulate" else ["--out", argv[0]]
        assert main(["--quiet", *argv, *extra]) == 0
        printed.append(capsys.readouterr().out)
    detection = json.loads((tmp_path / "detect" / "detection.json").read_text())
    assert detection["detection_time"] == figures["alarm"]
    assert f"alarm at t = {figures['alarm']:g} s" in printed[1]
    summary = json.loads((tmp_path / "prognose" / "prognosis.json").read_text())
    last = summary["last"]
    assert summary["detection_time"] == figures["alarm"]
    assert (summary["candidate"], summary["degradation"]) == ("b", "exponential")
    assert last["t"] == figures["t"]
    assert [last["rul_p5"], last["rul_median"], last["rul_p95"]] == figures["percentiles"]  # the same computation
    assert f"at t = {figures['t']:g} s RUL median {figures['percentiles'][1]:.4g} s" in printed[2]
    block = re.search(r"```bash\n(.*?)```", tour_section(), re.S).group(1)
    assert f"alarm at t = {figures['alarm']:g} s" in block
    assert f"RUL median {figures['percentiles'][1]:.4g} s at {figures['t']:g} s" in block


def test_readme_other_python_blocks_run(capsys):
    """Every python block but the tour, which the test above runs."""
    blocks = re.findall(r"```python\n(.*?)```", README.read_text(), re.S)
    tour = tour_source()
    assert tour in blocks and len(blocks) > 1
    for block in blocks:
        if block != tour:
            exec(compile(block, "README.md", "exec"), {})
    printed = capsys.readouterr().out
    assert "{'L': 'integral'}" in printed and "dp_L/dt = V(t) - R*p_L/L" in printed
    assert "r_n = -J*Derivative(omega(t), t) - b*omega(t) + k_m*i(t)" in printed
    detection = float(printed.strip().splitlines()[-1])  # the tripled friction is detected early in the run
    assert 0.0 <= detection < 0.5


def test_readme_set_up_is_two_commands():
    text = README.read_text()
    set_up = text.split("## Set-up", 1)[1].split("\n## ", 1)[0]
    commands = re.findall(r"```bash\n(.*?)```", set_up, re.S)
    assert len(commands) == 2
    assert "examples/torsion_bar.py" in commands[0]
    tests = commands[1]
    if tests.strip() == "bash .ci/run":  # the CI script: it installs what the tests need, then runs them
        tests = (README.parent / ".ci" / "run").read_text()
    assert 'pip install ".[test]"' in tests and "python -m pytest" in tests
