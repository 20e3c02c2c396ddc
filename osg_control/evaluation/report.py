"""The reproduction report: Markdown beside the paper's numbers, JSON, and one plot per
table (``report_plots``)."""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from osg_control.evaluation.report_plots import write_plots
from osg_control.io_safety import atomic_write

PUBLISHED_KEYS = ("table_i", "table_i_noise", "table_ii", "table_iii", "task_averages")
"""What a domain's ``published`` figures may hold: Table I rates per skill (one per noise
level of ``table_i_noise``, in metres), Table II's accuracies, Table III's rates per start
region, Tables IV/V's averages per task. Missing keys print as blanks."""


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
    paper_noise = published.get("table_i_noise", ())
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
            ["#", "skill"]
            + [f"σ={n:g}" for n in t["noise"]]
            + ["scripted", "paper σ=" + "/".join(f"{n * 100:g}" for n in paper_noise) + " cm"]
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


def write_report(
    figures: dict[str, Any], out_dir: Path, published: Mapping[str, Any] | None = None
) -> list[Path]:
    """Write ``report.md``, ``figures.json`` and the plots into ``out_dir``."""
    figures_text, report_text = json.dumps(figures, indent=2), markdown(figures, published)
    atomic_write(out_dir / "figures.json", lambda tmp: tmp.write_text(figures_text))
    atomic_write(out_dir / "report.md", lambda tmp: tmp.write_text(report_text))
    plots = write_plots(figures, out_dir, published)
    return [out_dir / "report.md", out_dir / "figures.json", *plots]
