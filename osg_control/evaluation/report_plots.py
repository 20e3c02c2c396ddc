"""The reproduction report's figures: one per table, every rate of ours with its 95 %
Wilson interval, the published figure beside it where the domain has one.

Table I: a panel per noise level, a bar per skill; Table II: the classifier's accuracies
(intervals over its states); Table III: per start region, the classifier's entry and the
nearest-node baseline; Tables IV/V: per task, the average over the start regions at each
replanning budget (its interval over all the regions' episodes). The published bars carry
no interval: their trial counts are not among the published figures.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np
from scipy.stats import norm

from osg_control.evaluation.check import wilson_interval
from osg_control.io_safety import atomic_write

PLOT_CONFIDENCE = 0.95
"""The confidence of the plotted intervals."""
PLOT_Z = float(norm.ppf(0.5 + PLOT_CONFIDENCE / 2))
PUBLISHED_LABEL = "paper"
PUBLISHED_STYLE = {"color": "0.75", "hatch": "//", "edgecolor": "0.4"}


@dataclass
class Series:
    """One set of bars: a rate per label and its trials (None: published, no interval)."""

    name: str
    rates: list[float | None]
    trials: int | None = None


@dataclass
class Panel:
    """One axes: its title, the labels along x and the series side by side."""

    title: str
    labels: list[str]
    series: list[Series] = field(default_factory=list)


@dataclass
class Plot:
    """One figure: its file name, title, axis labels and panels."""

    name: str
    title: str
    xlabel: str
    panels: list[Panel]
    ylabel: str = "success rate"


def _published_at(values: Sequence[Any], index: int) -> float | None:
    return float(values[index]) if index < len(values) else None


def _table_i(t: dict[str, Any], published: Mapping[str, Any]) -> Plot:
    paper = published.get("table_i", {})
    paper_noise = list(published.get("table_i_noise", ()))
    skills = [r["skill"] for r in t["rows"]]
    panels = []
    for k, sigma in enumerate(t["noise"]):
        panel = Panel(f"σ = {sigma * 100:g} cm", skills)
        panel.series.append(Series("ours", [r["rates"][k] for r in t["rows"]], t["episodes"]))
        if paper and sigma in paper_noise:
            at = paper_noise.index(sigma)
            panel.series.append(
                Series(PUBLISHED_LABEL, [_published_at(paper.get(s, ()), at) for s in skills])
            )
        panels.append(panel)
    title = f"Table I: skill success under observation noise ({t['episodes']} episodes/bar)"
    return Plot("table_i.png", title, "skill", panels)


def _table_ii(t: dict[str, Any], published: Mapping[str, Any]) -> Plot:
    keys = ("accuracy", "corrected_accuracy")
    panel = Panel("", ["accuracy", "corrected accuracy"])
    panel.series.append(Series("ours", [t[k] for k in keys], t["num_states"]))
    paper = published.get("table_ii", {})
    if paper:
        panel.series.append(Series(PUBLISHED_LABEL, [paper.get(k) for k in keys]))
    title = f"Table II: entry classifier ({t['num_states']} states)"
    return Plot("table_ii.png", title, "metric", [panel], "accuracy")


def _table_iii(t: dict[str, Any], published: Mapping[str, Any]) -> Plot:
    rows = t["rows"]
    panel = Panel("", [r["start"] for r in rows])
    panel.series.append(Series("classifier", [r["success"] for r in rows], t["episodes"]))
    panel.series.append(
        Series("nearest node", [r["nearest_node_success"] for r in rows], t["episodes"])
    )
    paper = list(published.get("table_iii", ()))
    if paper:
        panel.series.append(
            Series(PUBLISHED_LABEL, [_published_at(paper, i) for i in range(len(rows))])
        )
    title = f"Table III: reaching the graph ({t['episodes']} episodes/bar)"
    return Plot("table_iii.png", title, "start region", [panel])


def _tables_iv_v(t: dict[str, Any], published: Mapping[str, Any]) -> Plot:
    trials = t["episodes"] * len(t["regions"])
    panel = Panel("", list(t["tasks"]))
    for k, budget in enumerate(t["replans"]):
        panel.series.append(Series(f"max replans {budget}", list(t["averages"][k]), trials))
    paper = published.get("task_averages", {})
    if paper:
        panel.series.append(Series(PUBLISHED_LABEL, [paper.get(task) for task in t["tasks"]]))
    title = (
        f"Tables IV/V: task success, σ = {t['noise'] * 100:g} cm "
        f"(average of {len(t['regions'])} start regions × {t['episodes']} episodes)"
    )
    return Plot("tables_iv_v.png", title, "task", [panel])


PLOTS = {
    "table_i": _table_i,
    "table_ii": _table_ii,
    "table_iii": _table_iii,
    "tables_iv_v": _tables_iv_v,
}
"""Each table of ``figures.json`` and how it is plotted."""


def plots(figures: dict[str, Any], published: Mapping[str, Any] | None = None) -> list[Plot]:
    """What to draw: one ``Plot`` per table that was computed."""
    return [make(figures[key], published or {}) for key, make in PLOTS.items() if key in figures]


def yerr(series: Series) -> np.ndarray | None:
    """The (2, N) distances from each rate down and up to its 95 % Wilson bounds."""
    if series.trials is None:
        return None
    bounds = [
        wilson_interval(rate, series.trials, PLOT_Z) if rate is not None else (0.0, 0.0)
        for rate in series.rates
    ]
    rates = np.array([rate or 0.0 for rate in series.rates])
    low, high = np.array(bounds).T
    return np.vstack([rates - low, high - rates]).clip(min=0.0)


def _pyplot() -> Any:
    """``matplotlib.pyplot`` on the Agg backend (no display needed)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def draw(plot: Plot) -> Any:
    """The matplotlib figure of ``plot`` (Agg)."""
    plt = _pyplot()
    width = max(6.0, 0.45 * len(plot.panels[0].labels) * max(len(p.series) for p in plot.panels))
    fig, axes = plt.subplots(
        len(plot.panels), 1, figsize=(width, 3.2 * len(plot.panels) + 0.8), squeeze=False
    )
    for ax, panel in zip(axes[:, 0], plot.panels, strict=True):
        positions = np.arange(len(panel.labels))
        step = 0.8 / len(panel.series)
        for j, series in enumerate(panel.series):
            heights = [np.nan if r is None else r for r in series.rates]
            style = PUBLISHED_STYLE if series.trials is None else {}
            ax.bar(
                positions + (j - (len(panel.series) - 1) / 2) * step,
                heights,
                step,
                yerr=yerr(series),
                capsize=2,
                label=series.name,
                **style,
            )
        ax.set_xticks(positions, panel.labels, rotation=45, ha="right", fontsize=7)
        ax.set_ylim(0, 1.08)
        ax.set_title(panel.title, fontsize=9)
        ax.set_xlabel(plot.xlabel)
        ax.set_ylabel(f"{plot.ylabel} ({PLOT_CONFIDENCE:.0%} Wilson interval)", fontsize=8)
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.0, 1.0))
    fig.suptitle(plot.title, fontsize=10)
    fig.tight_layout()
    return fig


def write_plots(
    figures: dict[str, Any], out_dir: Path, published: Mapping[str, Any] | None = None
) -> list[Path]:
    """Write one PNG per computed table into ``out_dir``."""
    plt = _pyplot()
    written = []
    for plot in plots(figures, published):
        fig = draw(plot)
        written.append(atomic_write(out_dir / plot.name, partial(fig.savefig, dpi=110)))
        plt.close(fig)
    return written
