"""bgphm.plotting (on the Agg backend, asserting on the artists) and the to_frame() conveniences."""

import math
import re
import subprocess
import sys

import pytest

matplotlib = pytest.importorskip("matplotlib")   # the plot extra
matplotlib.use("Agg")
pytestmark = pytest.mark.extras
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from bgphm import plotting  # noqa: E402
from bondgraph import simulate  # noqa: E402
from bondgraph.library import rlc_circuit  # noqa: E402
from diagnosis import derive_arrs  # noqa: E402
from prognosis.degradation import LinearDegradation  # noqa: E402
from prognosis.health_monitor import MonitorResult  # noqa: E402
from prognosis.rul import RULPredictor  # noqa: E402

MATPLOTLIB_MESSAGE = "matplotlib is needed for plots: pip install 'bondgraph-phm[plot]'"
PANDAS_MESSAGE = "pandas is needed for to_frame(): pip install pandas"
MARGIN = 1e-3


@pytest.fixture(autouse=True)
def close_figures():
    yield
    plt.close("all")


@pytest.fixture(scope="module")
def simulation():
    """RLC circuit driven by a sine; R doubles at t = 0.25 s."""
    return simulate(rlc_circuit(), (0, 0.5), {"V": lambda t: np.sin(40 * t)}, t_eval=np.linspace(0, 0.5, 201),
                    parameters={"R": lambda t: np.where(np.asarray(t) < 0.25, 10.0, 20.0)})


@pytest.fixture(scope="module")
def arr():
    return derive_arrs(rlc_circuit())[0]


@pytest.fixture(scope="module")
def faulty(arr, simulation):
    evaluation = arr.evaluate(simulation.record(), margin=MARGIN, persistence=3)
    assert evaluation.detection_time == pytest.approx(0.25)
    return evaluation


@pytest.fixture(scope="module")
def healthy(arr):
    record = simulate(rlc_circuit(), (0, 0.5), {"V": 1.0}, t_eval=np.linspace(0, 0.5, 201)).record()
    evaluation = arr.evaluate(record, margin=1e-5)
    assert evaluation.detection_time is None
    return evaluation


def _prediction(mean_rate: float, seed: int):
    """RUL of 200 particles at theta = 1 growing at ~mean_rate per second to theta_fail = 2 (horizon 20 s)."""
    rng = np.random.default_rng(seed)
    predictor = RULPredictor(LinearDegradation(0.0), dt=0.1, theta_fail=2.0, horizon=20.0, seed=seed)
    gamma = rng.normal(mean_rate, 0.05, (1, 200, 1))
    weights = rng.uniform(0.5, 1.5, (1, 200))
    return predictor.predict(np.ones((1, 200)), gamma, weights / weights.sum(), 0.01)


@pytest.fixture(scope="module")
def monitored():
    """A MonitorResult assembled from library predictions (no filter run): 5 estimates, 3 predictions."""
    t = np.array([1.0, 1.1, 1.2, 1.3, 1.4])
    theta_mean = 1.0 + 0.1 * np.arange(5)
    theta = {"mean": theta_mean, "rmad": np.full(5, 0.02),
             "quantiles": np.column_stack([theta_mean - 0.05, theta_mean, theta_mean + 0.07])}
    gamma = {"mean": np.full(5, 0.1), "rmad": np.full(5, 0.3),
             "quantiles": np.column_stack([np.full(5, 0.05), np.full(5, 0.1), np.full(5, 0.15)])}
    rul = [_prediction(rate, seed) for seed, rate in enumerate((0.08, 0.1, 0.3))]
    return MonitorResult(1.0, t=t, theta=theta, gamma=gamma, rul_t=t[::2].copy(), rul=rul)


def _band_curves(collection, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """x, lower and upper curves of a fill_between polygon over n points.

    The polygon is: a start vertex, the lower curve forwards, an end vertex, the upper curve backwards, closing.
    """
    vertices = collection.get_paths()[0].vertices
    assert len(vertices) == 2 * n + 3
    forward, backward = vertices[1:n + 1], vertices[n + 2:2 * n + 2][::-1]
    assert np.array_equal(forward[:, 0], backward[:, 0])
    return forward[:, 0], forward[:, 1], backward[:, 1]


# -- plotting -------------------------------------------------------------------------------------------

def test_evaluation_plot_draws_residual_bands_and_alarm(faulty):
    ax = plotting.plot_evaluation(faulty, bglft=True)
    n = faulty.t.size
    assert len(ax.lines) == 2  # -r_n and the alarm marker
    assert np.array_equal(ax.lines[0].get_ydata(), -faulty.residual)
    assert len(ax.collections) == 2
    x, lower, upper = _band_curves(ax.collections[0], n)
    assert np.allclose(x, faulty.t)
    assert np.allclose(lower, faulty.lower - MARGIN) and np.allclose(upper, faulty.upper + MARGIN)
    _, lower, upper = _band_curves(ax.collections[1], n)
    assert np.allclose(lower, -faulty.bglft - MARGIN) and np.allclose(upper, faulty.bglft + MARGIN)
    assert list(ax.lines[1].get_xdata()) == [faulty.detection_time] * 2
    labels = [text.get_text() for text in ax.get_legend().get_texts()]
    assert labels[:3] == ["$-r_n$", "interval threshold", "BG-LFT threshold"] and labels[3].startswith("alarm")
    assert ax.get_title() == faulty.name


def test_evaluation_plot_without_alarm_or_bglft_on_given_axes(healthy):
    fig, (left, right) = plt.subplots(1, 2)
    ax = plotting.plot_evaluation(healthy, right, title="healthy")
    assert ax is right and not left.lines
    assert len(ax.lines) == 1 and len(ax.collections) == 1
    assert ax.get_title() == "healthy"


def test_titles_from_data_are_plain_text_not_mathtext(healthy):
    title = r"cost $\frac{1$ in $x$"  # as mathtext, it would fail to parse at draw time
    ax = plotting.plot_evaluation(healthy, title=title)
    assert ax.get_title() == title and ax.title.get_parse_math() is False
    ax.title.get_window_extent(ax.figure.canvas.get_renderer())  # laid out: the dollars are shown, not parsed


def test_band_defaults_and_overrides():
    fig, ax = plt.subplots()
    shaded = plotting.band(ax, [0, 1, 2], [0, 1, 2], 5.0, label="b")
    assert shaded in ax.collections and shaded.get_alpha() == 0.25 and shaded.get_label() == "b"
    _, lower, upper = _band_curves(shaded, 3)
    assert lower.tolist() == [0, 1, 2] and upper.tolist() == [5, 5, 5]
    assert plotting.band(ax, [0, 1], [0, 0], [1, 1], alpha=0.6).get_alpha() == 0.6


def test_save_figure_writes_closes_and_returns_the_path(tmp_path):
    fig, ax = plt.subplots(figsize=(4, 3))
    ax.plot([0, 1], [0, 1])
    path = plotting.save_figure(fig, str(tmp_path / "f.png"), dpi=50)
    assert path == tmp_path / "f.png" and not plt.fignum_exists(fig.number)
    header = path.read_bytes()[:24]
    assert header[:8] == b"\x89PNG\r\n\x1a\n"
    assert (int.from_bytes(header[16:20], "big"), int.from_bytes(header[20:24], "big")) == (200, 150)


def test_simulation_plot_one_subplot_per_signal(simulation):
    fig = plotting.plot_simulation(simulation)
    assert [ax.get_ylabel() for ax in fig.axes] == list(simulation.signals)
    for ax, name in zip(fig.axes, simulation.signals):
        assert np.array_equal(ax.lines[0].get_ydata(), simulation.signals[name])
    fig2, axes = plt.subplots(2, 1)
    assert plotting.plot_simulation(simulation, ["v_C", "q_C"], axes) is fig2
    assert np.array_equal(axes[1].lines[0].get_ydata(), simulation.states["q_C"])
    with pytest.raises(ValueError, match="2 signals need 2 axes"):
        plotting.plot_simulation(simulation, ["v_C", "q_C"], axes[0])


def test_estimate_plot_mean_band_and_truth(monitored):
    ax = plotting.plot_estimate(monitored, truth=lambda t: 1.0 + (t - 1.0))
    x, lower, upper = _band_curves(ax.collections[0], 5)
    assert np.allclose(x, monitored.t)
    quantiles = monitored.theta["quantiles"]
    assert np.allclose(lower, quantiles[:, 0]) and np.allclose(upper, quantiles[:, 2])
    assert len(ax.lines) == 2
    assert np.array_equal(ax.lines[0].get_ydata(), monitored.theta["mean"])
    assert np.allclose(ax.lines[1].get_ydata(), monitored.t)
    # gamma, with a truth that only takes one time at a time
    ax = plotting.plot_estimate(monitored, "gamma", truth=lambda t: math.exp(-t) * 0 + 0.1)
    assert ax.get_ylabel() == "gamma" and np.allclose(ax.lines[1].get_ydata(), 0.1)
    with pytest.raises(ValueError, match="parameter_name"):
        plotting.plot_estimate(monitored, "omega")


def test_rul_plot_band_clipped_at_the_horizon_and_alpha_cone(monitored):
    ax = plotting.plot_rul(monitored, eol=12.0, alpha=0.2)
    t = monitored.rul_t
    assert len(ax.collections) == 2  # cone, 5-95 %
    assert [line.get_label() for line in ax.lines[:4]] == ["true RUL", "median", "mean", "horizon"]
    _, lower, upper = _band_curves(ax.collections[0], t.size)
    assert np.allclose(lower, 0.8 * (12.0 - t)) and np.allclose(upper, 1.2 * (12.0 - t))
    q = monitored.rul_percentiles((5, 95))
    assert np.isinf(q[0, 1])  # the slowest prediction has > 5 % censored particles
    _, lower, upper = _band_curves(ax.collections[1], t.size)
    assert np.allclose(lower, q[:, 0]) and np.allclose(upper, np.minimum(q[:, 1], 20.0))
    assert np.allclose(ax.lines[1].get_ydata(), monitored.rul_median)
    assert np.allclose(ax.lines[2].get_ydata(), monitored.rul_mean)
    # the percentiles cut at the horizon are marked there, each at the predictions where it is censored
    horizon = np.array([p.horizon for p in monitored.rul])
    marked = {line.get_label(): line.get_xdata() for line in ax.lines[4:]}
    assert np.array_equal(marked["95 % beyond the horizon"], t[q[:, 1] > horizon])
    assert ax.get_xlabel() == "t (s)" and ax.get_ylabel() == "RUL (s)"
    bare = plotting.plot_rul(monitored)
    assert len(bare.collections) == 1 and [line.get_label() for line in bare.lines[:2]] == ["median", "mean"]


def test_axes_name_the_quantities_and_their_units(monitored, simulation, faulty):
    ax = plotting.plot_estimate(monitored, label="b", unit="N*m*s/rad", failure=2.5)
    assert ax.get_ylabel() == "b (N*m*s/rad)" and ax.get_xlabel() == "t (s)"
    failure = [line for line in ax.lines if line.get_label().startswith("failure value")]
    assert len(failure) == 1 and np.allclose(failure[0].get_ydata(), 2.5)
    assert failure[0].get_label() == "failure value 2.5 N*m*s/rad"
    ax = plotting.plot_evaluation(faulty, unit="N*m")
    assert ax.get_ylabel() == "$-r_n$ (N*m)" and ax.get_xlabel() == "t (s)"
    fig = plotting.plot_simulation(simulation, ["v_C"], units={"v_C": "V"})
    assert fig.axes[0].get_ylabel() == "v_C (V)" and fig.axes[0].get_xlabel() == "t (s)"
    title = plotting.plot_rul_distribution(monitored.rul[0]).get_title()
    assert title.endswith(f"{monitored.rul[0].horizon:g} s)")


def test_rul_distribution_reports_the_censored_fraction(monitored):
    prediction = monitored.rul[0]
    censored = float(prediction.censored_weight[0] / prediction.weights[0].sum())
    assert 0.05 < censored < 0.95
    ax = plotting.plot_rul_distribution(prediction, bins=25)
    assert len(ax.patches) == 25
    assert sum(p.get_height() for p in ax.patches) == pytest.approx(1.0 - censored)
    assert f"{censored:.1%} censored" in ax.get_title()
    assert ax.lines[0].get_xdata()[0] == pytest.approx(prediction.mean[0])


@pytest.mark.slow
def test_importing_the_packages_does_not_import_matplotlib_or_pandas():
    code = ("import sys, bondgraph, diagnosis, prognosis, bgphm.plotting\n"
            "print(sorted(m for m in ('matplotlib', 'pandas') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


@pytest.mark.parametrize("call", [
    lambda s, e, m: plotting.plot_evaluation(e),
    lambda s, e, m: plotting.plot_simulation(s),
    lambda s, e, m: plotting.plot_estimate(m),
    lambda s, e, m: plotting.plot_rul(m),
    lambda s, e, m: plotting.plot_rul_distribution(m.rul[0]),
    lambda s, e, m: plotting.save_figure(None, "unused.png"),
    lambda s, e, m: plotting.pyplot("Agg"),
], ids=["evaluation", "simulation", "estimate", "rul", "rul_distribution", "save_figure", "pyplot"])
def test_plots_without_matplotlib_say_how_to_install_it(monkeypatch, call, simulation, faulty, monitored):
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    with pytest.raises(ImportError, match=re.escape(MATPLOTLIB_MESSAGE)):
        call(simulation, faulty, monitored)


def test_write_figures_runs_the_drawing_on_agg_or_skips_it_without_matplotlib(monkeypatch, capsys, tmp_path):
    calls = []

    def draw(out, name="f.png"):
        calls.append(matplotlib.get_backend())
        fig, ax = plotting.pyplot().subplots()
        return [plotting.save_figure(fig, out / name)]

    matplotlib.use("svg")  # another file backend: write_figures selects Agg
    assert plotting.write_figures(draw, tmp_path, name="g.png") == [tmp_path / "g.png"]
    assert [backend.lower() for backend in calls] == ["agg"] and (tmp_path / "g.png").exists()
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    assert plotting.write_figures(draw, tmp_path) == [] and len(calls) == 1
    assert capsys.readouterr().err.strip() == f"no figures: {MATPLOTLIB_MESSAGE}"


# -- pandas conveniences ---------------------------------------------------------------------------

def test_evaluation_frame(faulty):
    frame = faulty.to_frame()
    assert list(frame.columns) == ["t", "residual", "lower", "upper", "bglft", "violation", "alarm"]
    for column in frame.columns:
        assert np.array_equal(frame[column].to_numpy(), getattr(faulty, column))
    assert frame["alarm"].dtype == bool and frame.index.tolist() == list(range(faulty.t.size))


def test_simulation_frame(simulation):
    frame = simulation.to_frame()
    assert list(frame.columns) == ["t", *simulation.signals, *simulation.states]
    assert np.array_equal(frame["t"].to_numpy(), simulation.t)
    for name in [*simulation.signals, *simulation.states]:
        assert np.array_equal(frame[name].to_numpy(), simulation[name])


def test_monitor_frames(monitored):
    frame = monitored.to_frame()
    assert np.array_equal(frame["t"].to_numpy(), monitored.t)
    for name in ("theta", "gamma"):
        estimate = getattr(monitored, name)
        assert np.array_equal(frame[f"{name}_mean"].to_numpy(), estimate["mean"])
        assert np.array_equal(frame[f"{name}_rmad"].to_numpy(), estimate["rmad"])
        for column, k in (("p5", 0), ("median", 1), ("p95", 2)):
            assert np.array_equal(frame[f"{name}_{column}"].to_numpy(), estimate["quantiles"][:, k])
    rul = monitored.rul_frame()
    assert list(rul.columns) == ["rul_t", "mean", "median", "p5", "p95"]
    q = monitored.rul_percentiles((5, 95))
    assert np.array_equal(rul["rul_t"].to_numpy(), monitored.rul_t)
    assert np.array_equal(rul["mean"].to_numpy(), monitored.rul_mean)
    assert np.array_equal(rul["median"].to_numpy(), monitored.rul_median)
    assert np.array_equal(rul["p5"].to_numpy(), q[:, 0]) and np.array_equal(rul["p95"].to_numpy(), q[:, 1])
    empty = MonitorResult(None)
    assert empty.to_frame().shape == (0, 11) and empty.rul_frame().shape == (0, 5)


def test_frames_without_pandas_say_how_to_install_it(monkeypatch, simulation, faulty, monitored):
    monkeypatch.setitem(sys.modules, "pandas", None)
    for result in (faulty, simulation, monitored):
        with pytest.raises(ImportError, match=re.escape(PANDAS_MESSAGE)):
            result.to_frame()
    with pytest.raises(ImportError, match=re.escape("pandas is needed for rul_frame(): pip install pandas")):
        monitored.rul_frame()
