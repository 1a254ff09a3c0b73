"""The README's tour runs as printed and gives the figures its comments quote."""

import contextlib
import io
import math
import re
from pathlib import Path

README = Path(__file__).resolve().parents[2] / "README.md"


def tour_source() -> str:
    text = README.read_text()
    section = text.split("## A tour: from a model to an alarm and a remaining useful life", 1)[1]
    return re.search(r"```python\n(.*?)```", section, re.S).group(1)


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


def test_readme_set_up_is_two_commands():
    text = README.read_text()
    set_up = text.split("## Set-up", 1)[1].split("\n## ", 1)[0]
    commands = re.findall(r"```bash\n(.*?)```", set_up, re.S)
    assert len(commands) == 2
    assert "examples/torsion_bar.py" in commands[0] and "pytest" in commands[1]
