"""The README's python blocks run as printed: the tour (once) gives the figures its comments quote."""

import contextlib
import io
import math
import re
from pathlib import Path

import pytest

README = Path(__file__).resolve().parents[2] / "README.md"


def tour_source() -> str:
    text = README.read_text()
    section = text.split("## A tour: from a model to an alarm and a remaining useful life", 1)[1]
    return re.search(r"```python\n(.*?)```", section, re.S).group(1)


@pytest.mark.slow
def test_readme_tour_runs_and_its_comments_are_true():
    namespace: dict = {}
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(tour_source(), str(README), "exec"), namespace)
    lines = out.getvalue().splitlines()
    assert lines[0].startswith("-J*Derivative(omega(t), t) - b*omega(t) + k_m*i(t) |")
    assert "delta_b" in lines[0]
    assert float(lines[1]) == namespace["result"].detection_time
    assert abs(float(lines[1]) - 1.70) < 0.01                        # the comment's alarm time
    p5, p50, p95 = namespace["result"].rul[-1].percentile([5, 50, 95])[0]
    true_rul = 1.0 + math.log(2e-3 / 1e-4) / 0.8 - namespace["result"].t[-1]
    assert p5 <= true_rul <= p95
    assert abs(p50 - true_rul) < 0.1 * true_rul
    assert f"[[{p5:.2f} {p50:.2f} {p95:.2f}]]" in source_comment()


def source_comment() -> str:
    return tour_source().splitlines()[-1]


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
    assert "examples/torsion_bar.py" in commands[0] and "pytest" in commands[1]
