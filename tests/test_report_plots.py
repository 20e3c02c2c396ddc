"""The report's figures: one per table, titled and labelled, every rate of ours with its
95 % Wilson interval, the published figures beside ours (matplotlib's Agg backend)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from matplotlib.container import BarContainer

from osg_control.evaluation.check import wilson_interval
from osg_control.evaluation.report import write_report
from osg_control.evaluation.report_plots import PUBLISHED_LABEL, draw, plots
from osg_control.kitchen.paper import PUBLISHED
from osg_control.paths import PACKAGE_DIR

FIGURES = json.loads((PACKAGE_DIR / "kitchen" / "defaults" / "figures.json").read_text())
TABLES = ("table_i", "table_ii", "table_iii", "tables_iv_v")
Z95 = 1.959964
"""The two-sided 95 % normal quantile."""


@pytest.fixture(scope="module")
def drawn():
    import matplotlib.pyplot as plt

    made = [(plot, draw(plot)) for plot in plots(FIGURES, PUBLISHED)]
    yield made
    for _, fig in made:
        plt.close(fig)


def _bars(ax) -> dict[str, BarContainer]:
    return {c.get_label(): c for c in ax.containers if isinstance(c, BarContainer)}


def _interval(container: BarContainer, index: int) -> tuple[float, float]:
    """The plotted error bar of bar ``index``: its low and high ends."""
    segment = container.errorbar.lines[2][0].get_segments()[index]
    return float(segment[0][1]), float(segment[1][1])


def test_one_titled_labelled_figure_per_table(drawn) -> None:
    assert set(TABLES) <= set(FIGURES)
    assert [plot.name for plot, _ in drawn] == [f"{t}.png" for t in TABLES]
    for plot, fig in drawn:
        assert fig.get_suptitle().startswith("Table"), plot.name
        for ax in fig.axes:
            assert ax.get_xlabel() and "95% Wilson interval" in ax.get_ylabel(), plot.name
            ticks = [t.get_text() for t in ax.get_xticklabels()]
            assert ticks and all(ticks), plot.name
            bars = _bars(ax)
            assert PUBLISHED_LABEL in bars, plot.name
            assert bars[PUBLISHED_LABEL].errorbar is None
            ours = [c for name, c in bars.items() if name != PUBLISHED_LABEL]
            assert ours and all(c.errorbar is not None for c in ours), plot.name
            assert ax.get_legend() is not None


def test_the_error_bars_are_the_95_percent_wilson_intervals(drawn) -> None:
    figs = {plot.name: fig for plot, fig in drawn}
    t = FIGURES["table_i"]
    for k, _sigma in enumerate(t["noise"]):
        ours = _bars(figs["table_i.png"].axes[k])["ours"]
        for i, row in enumerate(t["rows"]):
            expected = wilson_interval(row["rates"][k], t["episodes"], Z95)
            assert _interval(ours, i) == pytest.approx(expected, abs=1e-6)
            assert ours.patches[i].get_height() == pytest.approx(row["rates"][k])
    t = FIGURES["table_ii"]
    ours = _bars(figs["table_ii.png"].axes[0])["ours"]
    expected = wilson_interval(t["accuracy"], t["num_states"], Z95)
    assert _interval(ours, 0) == pytest.approx(expected, abs=1e-6)
    t = FIGURES["tables_iv_v"]
    bars = _bars(figs["tables_iv_v.png"].axes[0])
    for k, budget in enumerate(t["replans"]):
        series = bars[f"max replans {budget}"]
        trials = t["episodes"] * len(t["regions"])
        for i, average in enumerate(t["averages"][k]):
            expected = wilson_interval(average, trials, Z95)
            assert _interval(series, i) == pytest.approx(expected, abs=1e-6)
    nearest = _bars(figs["table_iii.png"].axes[0])["nearest node"]
    row = FIGURES["table_iii"]["rows"][0]
    expected = wilson_interval(row["nearest_node_success"], FIGURES["table_iii"]["episodes"], Z95)
    assert _interval(nearest, 0) == pytest.approx(expected, abs=1e-6)


def test_the_published_bars_are_the_papers(drawn) -> None:
    figs = {plot.name: fig for plot, fig in drawn}
    t = FIGURES["table_i"]
    for k, sigma in enumerate(t["noise"]):
        paper = _bars(figs["table_i.png"].axes[k])[PUBLISHED_LABEL]
        column = list(PUBLISHED["table_i_noise"]).index(sigma)
        for i, row in enumerate(t["rows"]):
            published = PUBLISHED["table_i"].get(row["skill"])
            height = paper.patches[i].get_height()
            if published is None:
                assert np.isnan(height), row["skill"]  # a skill the paper does not have
            else:
                assert height == pytest.approx(published[column]), row["skill"]
    paper = _bars(figs["table_iii.png"].axes[0])[PUBLISHED_LABEL]
    assert [p.get_height() for p in paper.patches] == pytest.approx(PUBLISHED["table_iii"])
    paper = _bars(figs["tables_iv_v.png"].axes[0])[PUBLISHED_LABEL]
    for task, patch in zip(FIGURES["tables_iv_v"]["tasks"], paper.patches, strict=True):
        published = PUBLISHED["task_averages"].get(task)
        assert (
            np.isnan(patch.get_height())
            if published is None
            else (patch.get_height() == pytest.approx(published))
        )


def test_the_report_writes_one_png_per_table(tmp_path) -> None:
    written = write_report(FIGURES, tmp_path, PUBLISHED)
    for table in TABLES:
        path = tmp_path / f"{table}.png"
        assert path in written and path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    report = (tmp_path / "report.md").read_text()
    assert "paper σ=0/1/2 cm" in report
