"""The graph and PDDL stage, run after Table I: the skill graph built from the data sets
with the measured success rates, saved and drawn, and exported as PDDL whose operator costs
are ``round(-ln p * 1000)`` of those rates (plus a domain's step cost)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from osg_control.data.datasets import load_dataset
from osg_control.domain.base import Domain
from osg_control.planning.graph import SkillGraph, save_graph
from osg_control.planning.graph_data import graph_from_datasets
from osg_control.planning.graph_draw import draw_graph
from osg_control.planning.pddl_io import export_pddl

GRAPH_FILE = "graph.json"
GRAPH_PNG = "graph.png"
PDDL_DIR = "pddl"


@dataclass(frozen=True)
class ExportedPlan:
    """What the stage wrote.

    Attributes:
        graph: the skill graph (measured rates on its edges, data disagreements listed).
        graph_file: its JSON (``planning.graph.load_graph`` reads it).
        graph_png: its drawing, or None when not drawn.
        pddl: the PDDL files, the domain first, then one problem per task.
    """

    graph: SkillGraph
    graph_file: Path
    graph_png: Path | None
    pddl: list[Path]


def measured_data_graph(
    domain: Domain, data_dir: Path, rates: Mapping[str, float] | None
) -> SkillGraph:
    """The skill graph from the domain's data sets in ``data_dir`` (``<skill>.h5`` each)
    with the measured success ``rates`` on its edges.

    Raises:
        DatasetError: a data set missing or malformed, named.
    """
    datasets = [load_dataset(Path(data_dir) / f"{skill.name}.h5") for skill in domain.skills]
    return graph_from_datasets(domain, datasets, rates)


def export_measured_pddl(
    domain: Domain,
    data_dir: Path,
    rates: Mapping[str, float] | None,
    out: Path,
    draw: bool = True,
) -> ExportedPlan:
    """Build the graph from the data with the measured ``rates``, write ``<out>/graph.json``
    (and ``graph.png`` if ``draw``) and the PDDL under ``<out>/pddl/``.

    Raises:
        DatasetError: a data set missing or malformed.
        OutputError: a file cannot be written, named.
    """
    out = Path(out)
    graph = measured_data_graph(domain, data_dir, rates)
    save_graph(graph, out / GRAPH_FILE)
    png = out / GRAPH_PNG if draw else None
    if png is not None:
        draw_graph(graph, png)
    return ExportedPlan(graph, out / GRAPH_FILE, png, export_pddl(domain, out / PDDL_DIR, graph))


def format_export(exported: ExportedPlan) -> str:
    """The graph's size, the data's disagreements with the specs and the files written."""
    graph = exported.graph
    lines = [f"{len(graph.nodes)} nodes, {len(graph.edges)} skills"]
    lines.append(f"{len(graph.disagreements)} disagreement(s) between data and specs")
    lines += [f"  [{d.kind}] {d.subject}: {d.detail}" for d in graph.disagreements]
    written = [exported.graph_file, *([exported.graph_png] if exported.graph_png else [])]
    lines += [f"wrote {path}" for path in [*written, *exported.pddl]]
    return "\n".join(lines)
