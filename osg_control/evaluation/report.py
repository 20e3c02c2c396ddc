"""The reproduction report: Markdown beside the paper's numbers, JSON, and bar plots."""

from __future__ import annotations

import json
from collections.abc import Mapping
from functools import partial
from pathlib import Path
from typing import Any

from osg_control.io_safety import atomic_write

PUBLISHED_KEYS = ("table_i", "table_ii", "table_iii", "task_averages")
"""What a domain's ``published`` figures may hold: Table I rates per skill (one per noise
level), Table II's accuracies, Table III's rates per start region, Tables IV/V's averages
per task. Missing keys print as blanks."""


def _md_table(header: list[str], rows: list[list[Any]]) -> list[str]:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    for row in rows:
        cells = [f"{v:.3f}" if isinstance(v, float) else str(v) for v in row]
        lines.append("| " + " | ".join(cells) + " |")
    return lines


def markdown(figures: dict[str, Any], published: Mapping[str, Any] | None = None) -> str:
    """The report as Markdown: every table that was computed, beside the published figures
    of its domain (``Domain.published``, see ``PUBLISHED_KEYS``)."""
    published = published or {}
    paper_i = published.get("table_i", {})
    paper_ii = published.get("table_ii", {})
    paper_iii = list(published.get("table_iii", ()))
    paper_tasks = published.get("task_averages", {})
    out = ["# osg-control reproduction report", ""]
    out += [f"- {k}: {v}" for k, v in figures.get("run", {}).items()]
    out.append("")
    if "stage_seconds" in figures:
        out += ["## Stage times", ""]
        out += _md_table(
            ["stage", "seconds"], [[k, v] for k, v in figures["stage_seconds"].items()]
        )
        out.append("")
    if "table_i" in figures:
        t = figures["table_i"]
        header = (
            ["#", "skill"] + [f"σ={n:g}" for n in t["noise"]] + ["scripted", "paper σ=0/1/2 cm"]
        )
        rows = [
            [
                i + 1,
                r["skill"],
                *r["rates"],
                r["scripted"],
                "/".join(map(str, paper_i.get(r["skill"], ()))) or "—",
            ]
            for i, r in enumerate(t["rows"])
        ]
        out += [f"## Table I: skills under observation noise ({t['episodes']} episodes/cell)", ""]
        out += _md_table(header, rows) + [""]
    if "table_ii" in figures:
        t = figures["table_ii"]
        out += ["## Table II: classifier", ""]
        out += _md_table(
            ["metric", "ours", "paper"],
            [
                ["accuracy", t["accuracy"], paper_ii.get("accuracy", "—")],
                [
                    "corrected accuracy",
                    t["corrected_accuracy"],
                    paper_ii.get("corrected_accuracy", "—"),
                ],
            ],
        ) + [""]
    if "table_iii" in figures:
        t = figures["table_iii"]
        rows = [
            [
                i + 1,
                r["start"],
                r["success"],
                r["nearest_node_success"],
                paper_iii[i] if i < len(paper_iii) else "—",
            ]
            for i, r in enumerate(t["rows"])
        ]
        paper_average = sum(paper_iii) / len(paper_iii) if paper_iii else "—"
        rows.append(["", "average", t["average"], t["nearest_node_average"], paper_average])
        out += [f"## Table III: reaching the graph ({t['episodes']} episodes/start)", ""]
        out += _md_table(["#", "start", "classifier", "nearest node", "paper"], rows) + [""]
    if "tables_iv_v" in figures:
        t = figures["tables_iv_v"]
        for k, budget in enumerate(t["replans"]):
            out += [f"## Tables IV/V: tasks, σ = {t['noise']} m, max replans = {budget}", ""]
            rows = [
                [r + 1, region, *[t["rates"][k][ti][r] for ti in range(len(t["tasks"]))]]
                for r, region in enumerate(t["regions"])
            ]
            rows.append(["", "average", *t["averages"][k]])
            rows.append(["", "paper average", *[paper_tasks.get(x, "—") for x in t["tasks"]]])
            out += _md_table(["#", "start", *t["tasks"]], rows) + [""]
    return "\n".join(out)


def bar_plots(figures: dict[str, Any], out_dir: Path) -> list[Path]:
    """One PNG of success bars per table that was computed."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    written = []
    plots: list[tuple[str, list[str], list[float]]] = []
    if "table_i" in figures:
        t = figures["table_i"]
        plots.append(
            ("table_i.png", [r["skill"] for r in t["rows"]], [r["rates"][-1] for r in t["rows"]])
        )
    if "table_iii" in figures:
        t = figures["table_iii"]
        plots.append(
            ("table_iii.png", [r["start"] for r in t["rows"]], [r["success"] for r in t["rows"]])
        )
    if "tables_iv_v" in figures:
        t = figures["tables_iv_v"]
        plots.append(("tables_iv_v.png", t["tasks"], t["averages"][-1]))
    for name, labels, values in plots:
        fig, ax = plt.subplots(figsize=(8, 3.5))
        ax.bar(range(len(values)), values, color="tab:blue")
        ax.set_xticks(range(len(values)), labels, rotation=45, ha="right", fontsize=7)
        ax.set_ylim(0, 1.05)
        ax.axhline(0.95, color="tab:red", lw=0.8, ls="--")
        ax.set_ylabel("success rate")
        fig.tight_layout()
        written.append(atomic_write(out_dir / name, partial(fig.savefig, dpi=110)))
        plt.close(fig)
    return written


def write_report(
    figures: dict[str, Any], out_dir: Path, published: Mapping[str, Any] | None = None
) -> list[Path]:
    """Write ``report.md``, ``figures.json`` and the plots into ``out_dir``."""
    figures_text, report_text = json.dumps(figures, indent=2), markdown(figures, published)
    atomic_write(out_dir / "figures.json", lambda tmp: tmp.write_text(figures_text))
    atomic_write(out_dir / "report.md", lambda tmp: tmp.write_text(report_text))
    return [out_dir / "report.md", out_dir / "figures.json", *bar_plots(figures, out_dir)]
