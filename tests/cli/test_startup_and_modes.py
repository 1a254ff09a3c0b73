"""The command line's polish: ``--version``, global options anywhere, a ``--help`` that loads no library, and
files readable by others as the umask says."""

from __future__ import annotations

import os
import stat
import subprocess
import sys
from importlib.metadata import version

import pytest

from bgphm.cli import main
from bgphm.files import write_text

HEAVY = ("sympy", "scipy", "networkx", "numpy", "diagnosis", "prognosis", "matplotlib")


def test_version_prints_the_installed_distribution_s(capsys):
    with pytest.raises(SystemExit) as stop:
        main(["--version"])
    assert stop.value.code == 0
    assert capsys.readouterr().out.strip() == f"bgphm (bondgraph-phm) {version('bondgraph-phm')}"


@pytest.mark.parametrize("argv", [["--help"], ["arr", "--help"], ["--version"]])
def test_help_and_version_load_no_numerical_library(argv):
    """The CPU time of ``bgphm --help`` is that of the modules it imports: none of the heavy ones (the
    benchmark ``benchmarks/bench_cli.py`` measures it against ``python -c pass``)."""
    probe = ("import sys\nfrom bgphm.cli import main\ntry:\n    main(sys.argv[1:])\nexcept SystemExit:\n    pass\n"
             f"print(sorted({{m.split('.')[0] for m in sys.modules}} & set({HEAVY!r})))")
    done = subprocess.run([sys.executable, "-c", probe, *argv], capture_output=True, text=True, check=True)
    assert done.stdout.strip().splitlines()[-1] == "[]"


def test_help_costs_a_few_interpreter_starts_of_cpu():
    """CPU time, not wall-clock: ``bgphm --help`` within 8 times ``python -c pass`` (75 times before the
    parser stopped importing the library)."""
    import resource

    def cpu(arguments):
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        subprocess.run([sys.executable, *arguments], check=True, capture_output=True)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        return after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime

    baseline = min(cpu(["-c", "pass"]) for _ in range(3))
    help_cpu = min(cpu(["-m", "bgphm", "--help"]) for _ in range(3))
    assert help_cpu < 8 * max(baseline, 0.005)


def test_global_options_are_taken_after_the_command_too(tmp_path, capsys):
    out = tmp_path / "rlc.csv"
    assert main(["simulate", "rlc", "--t-end", "0.1", "--samples", "11", "--out", str(out), "--quiet"]) == 0
    assert capsys.readouterr().err == ""  # no progress line
    assert main(["simulate", "rlc", "--t-end", "0.1", "--samples", "11", "--out", str(tmp_path / "b.csv")]) == 0
    assert "simulating" in capsys.readouterr().err
    assert out.read_text() == (tmp_path / "b.csv").read_text()


def test_debug_after_the_command_shows_the_traceback(monkeypatch):
    def broken(args, progress):
        raise RuntimeError("a bug")

    import bgphm.commands.arr as arr

    monkeypatch.setattr(arr, "run", broken)
    assert main(["arr", "rlc"]) == 1
    with pytest.raises(RuntimeError, match="a bug"):
        main(["arr", "rlc", "--debug"])


@pytest.fixture
def umask():
    """Set the process' umask for a test, and restore it."""
    saved = os.umask(0o022)
    yield lambda mask: os.umask(mask)
    os.umask(saved)


@pytest.mark.parametrize("mask, mode", [(0o022, 0o644), (0o077, 0o600), (0o002, 0o664)])
def test_written_files_take_the_mode_the_umask_gives(tmp_path, umask, mask, mode):
    umask(mask)
    path = write_text(tmp_path / "report.md", "text")
    assert stat.S_IMODE(path.stat().st_mode) == mode


def test_every_file_of_a_command_is_readable_by_others_under_umask_022(tmp_path, umask):
    umask(0o022)
    record = tmp_path / "run.csv"
    assert main(["--quiet", "simulate", "dc-motor", "--t-end", "2", "--samples", "401", "--out", str(record)]) == 0
    assert main(["--quiet", "arr", "dc-motor", "--format", "html", "--out", str(tmp_path / "arr.html")]) == 0
    assert main(["--quiet", "detect", "dc-motor", str(record), "--out", str(tmp_path / "detect")]) == 0
    written = [p for p in tmp_path.rglob("*") if p.is_file()]
    assert len(written) >= 4
    assert {p.name: oct(stat.S_IMODE(p.stat().st_mode)) for p in written} == \
        {p.name: oct(0o644) for p in written}


def test_detect_states_the_units_of_signals_parameters_and_residuals(tmp_path):
    """The electrical balance of the motor is in volts, the mechanical one in newton-metres."""
    import json

    record = tmp_path / "run.csv"
    assert main(["--quiet", "simulate", "dc-motor", "--t-end", "2", "--samples", "401", "--out", str(record)]) == 0
    assert main(["--quiet", "detect", "dc-motor", str(record), "--out", str(tmp_path / "detect")]) == 0
    units = json.loads((tmp_path / "detect" / "detection.json").read_text())["units"]
    assert units["t"] == "s" and units["signals"] == {"U": "V", "i": "A", "omega": "rad/s"}
    assert units["parameters"]["b"] == "N*m*s/rad" and units["parameters"]["J"] == "kg*m^2"
    assert units["residuals"] == {"ARR_1_e": "V", "ARR_1_m": "N*m"}


@pytest.mark.parametrize("command", ["arr", "simulate", "detect", "calibrate", "prognose", "fleet", "demo"])
def test_every_command_s_help_renders(command, capsys):
    """argparse formats a help text only when asked: a stray '%' in one would fail here, not at a user's."""
    with pytest.raises(SystemExit) as stop:
        main([command, "--help"])
    assert stop.value.code == 0 and f"usage: bgphm {command}" in capsys.readouterr().out
