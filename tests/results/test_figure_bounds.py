"""Every figure reads well at any budget: drawn for 1, 3 and many jobs, no text, legend or
axes reaches outside the figure (clipped in the saved file), and the tuning figures show
penalised trials and single values without inventing a scale."""

from __future__ import annotations

from types import SimpleNamespace

import matplotlib
import numpy as np
import pandas as pd
import pytest
from matplotlib.text import Text

from compliant_docking.results.figures import force_overlay, metric_bars, success_map, success_vs_misalignment
from tests.results.test_figures import runs

matplotlib.use("Agg")

#: jobs: 1, 3 (three controllers) and many (2 robots × 2 controllers × 2 planners × 5 draws)
BUDGETS = {
    "1 job": dict(repeats=1, robots=("fr3",), controllers=("hqp",), trajectories=("quintic",)),
    "3 jobs": dict(repeats=1, robots=("fr3",), controllers=("impedance", "hqp", "se3_lie"), trajectories=("quintic",)),
    "40 jobs": dict(repeats=5),
}  # fmt: skip


def outside(fig) -> list[str]:
    """The figure's texts and legends and each axes as drawn (title, labels, the tick labels
    drawn, its texts) whose extent leaves the figure (1 px slack): what a saved file clips."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    box = fig.bbox
    artists = [*fig.texts, *fig.legends, *([fig._suptitle] if fig._suptitle else [])]
    artists += [ax for ax in fig.axes if ax.get_visible()]
    artists += [ax.get_legend() for ax in fig.axes if ax.get_legend() is not None]
    found = []
    for artist in artists:
        if not artist.get_visible() or (isinstance(artist, Text) and not artist.get_text().strip()):
            continue
        if isinstance(artist, matplotlib.axes.Axes):
            extent = artist.get_tightbbox(renderer)
        else:
            extent = artist.get_window_extent(renderer)
        if extent is None or extent.width == 0:
            continue
        if (
            extent.x0 < box.x0 - 1
            or extent.y0 < box.y0 - 1
            or extent.x1 > box.x1 + 1
            or extent.y1 > box.y1 + 1
        ):
            what = artist.get_text()[:50] if isinstance(artist, Text) else type(artist).__name__
            found.append(
                f"{what!r}: {tuple(round(v) for v in extent.extents)} outside {tuple(round(v) for v in box.extents)}"
            )
    return found


#: each figure at each budget (a few seconds each: slow); the default suite draws the
#: single misalignment panel and checks the note's fit on its own (below)
MATRIX = [
    pytest.param(draw, budget, marks=pytest.mark.slow)
    for draw in (metric_bars, success_vs_misalignment, success_map, force_overlay)
    for budget in BUDGETS
]


def test_a_long_note_is_shrunk_to_the_figures_width():
    """Before: the overlay of 40 runs wrote its note 6 px past a 4.5 in figure's edge."""
    import matplotlib.pyplot as plt

    from compliant_docking.results.figures import common

    fig = plt.figure(figsize=(2.9, 2.0))
    common.note(
        fig, ["40 runs of 8 configurations (5–5 each); median and 10–90 % band; " * 2, "pooled over: x"]
    )
    try:
        assert outside(fig) == [] and fig.texts[0].get_fontsize() < common.FONT - 1.5
    finally:
        plt.close(fig)


def fits(fig) -> None:
    """``fig`` (None: nothing to draw at this budget, e.g. one job has no spread to map)
    lies inside its frame; closed."""
    import matplotlib.pyplot as plt

    if fig is not None:
        try:
            assert outside(fig) == []
        finally:
            plt.close(fig)


@pytest.mark.parametrize(("draw", "budget"), MATRIX)
def test_the_comparison_figures_fit_in_their_frame(draw, budget, tmp_path):

    fits(draw(runs(tmp_path, **BUDGETS[budget])))


@pytest.mark.parametrize(
    "budget", [pytest.param(b, marks=[] if b == "3 jobs" else [pytest.mark.slow]) for b in BUDGETS]
)
def test_the_single_panel_misalignment_figure_fits(budget, tmp_path):
    """One misalignment component varies (misalignment_keyed: the yaw): one panel, on which
    the title, the legend and the note were clipped."""

    df = runs(tmp_path, **BUDGETS[budget]).assign(misalignment_lateral_m=0.0, misalignment_tilt_deg=0.0)
    fits(success_vs_misalignment(df))


# --------------------------------------------------------------------------- tuning figures
def trials(n: int, feasible: int, *, pareto: bool = False) -> pd.DataFrame:
    """``n`` trials, the first ``feasible`` of them docked on every draw."""
    rng = np.random.default_rng(1)
    frame = pd.DataFrame({"number": range(n), "feasible": [i < feasible for i in range(n)]})
    frame["force_N"] = np.where(frame["feasible"], 20 + 5 * rng.random(n), 1e6)
    if pareto:
        frame["time_s"] = np.where(frame["feasible"], 12 + rng.random(n), 1e6)
    return frame


@pytest.fixture
def drawn(monkeypatch):
    """The tuning figures drawn, not saved: {stem: figure}."""
    from compliant_docking.tune import figures

    kept: dict = {}
    monkeypatch.setattr(figures, "save", lambda fig, out_dir, stem, formats: kept.update({stem: fig}) or [])
    monkeypatch.setattr("matplotlib.pyplot.close", lambda fig=None: None)
    return kept


@pytest.mark.parametrize(("n", "feasible"), [(1, 1), (1, 0), (3, 1), (3, 0), (40, 30)])
def test_the_tuning_figures_fit_and_show_penalised_trials_at_the_edge(drawn, n, feasible, tmp_path):
    from compliant_docking.tune.figures import HISTORY, PARETO, plot_history, plot_pareto

    one = SimpleNamespace(name="mean first-strike force", value_names=["force_N"])
    two = SimpleNamespace(name="force and time", value_names=["force_N", "time_s"])
    plot_history(trials(n, feasible), one, tmp_path, metric="first-strike force")
    plot_pareto(trials(n, feasible, pareto=True), two, tmp_path, metric="first-strike force")
    history, pareto = drawn[HISTORY], drawn[PARETO]
    assert outside(history) == [] and outside(pareto) == []
    ax = history.axes[0]
    low, high = ax.get_ylim()
    if feasible:
        assert high - low >= 1.0  # a readable span, not 1e-10 around a single value
    else:  # no value to scale: no force axis invented (before: penalised trials at 1.0 N)
        assert len(ax.get_yticks()) == 0 or not any(t.get_text() for t in ax.get_yticklabels())
        assert "no trial docked on every draw" in " ".join(t.get_text() for t in ax.texts)
    penalised = [line for line in ax.lines if line.get_label() == "penalised"]
    if feasible < n:  # along the top edge of the panel, whatever the values
        (line,) = penalised
        assert np.allclose(line.get_ydata(), 1.0) and line.get_transform() != ax.transData
    pareto_text = " ".join(t.get_text() for t in pareto.axes[0].texts)
    if not feasible:  # before: an empty plot
        assert "no trial docked on every draw" in pareto_text
