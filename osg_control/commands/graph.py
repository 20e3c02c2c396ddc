"""``osg graph``: build the skill graph (from the specs, or checked against data sets)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TypeAlias

from osg_control.commands import domain_of
from osg_control.data.datasets import load_dataset
from osg_control.errors import DatasetError
from osg_control.json_files import dump_json, is_json_number, read_json_object
from osg_control.planning.graph import (
    SkillGraph,
    graph_from_specs,
    save_graph,
)
from osg_control.planning.graph_data import graph_from_datasets
from osg_control.planning.graph_draw import PROJECTIONS, draw_graph

Verbs: TypeAlias = "argparse._SubParsersAction[argparse.ArgumentParser]"


def _read_rates(path: Path | None) -> dict[str, float] | None:
    if path is None:
        return None
    rates = read_json_object(path, "success rates", DatasetError)
    bad = {k: v for k, v in rates.items() if not (is_json_number(v) and 0 <= v <= 1)}
    if bad:
        raise DatasetError(
            f"{path}: expected a JSON object of skill name -> success rate in [0, 1]; "
            f"not rates: {bad}"
        )
    return {str(k): float(v) for k, v in rates.items()}


def _data_files(folder: Path) -> list[Path]:
    files = sorted([*folder.glob("*.h5"), *folder.glob("*.hdf5")])
    if not files:
        raise DatasetError(f"{folder}: no data sets (*.h5, *.hdf5) found")
    return files


def format_graph(graph: SkillGraph) -> str:
    """The graph's nodes, skills and disagreements as text."""
    lines = [f"{len(graph.nodes)} nodes, {len(graph.edges)} skills"]
    for node in graph.nodes:
        seen = ""
        if node.observed is not None and node.observed.position is not None:
            seen = (
                f"  data: ({', '.join(f'{v:.3f}' for v in node.observed.position)}) "
                f"from {node.observed.points} points"
            )
        lines.append(
            f"  node {node.name:<14} ({', '.join(f'{v:.3f}' for v in node.position)}){seen}"
        )
    for edge in graph.edges:
        rate = "" if edge.success_rate is None else f"  success {edge.success_rate:.2f}"
        lines.append(f"  skill {edge.name:<22} {edge.start} -> {edge.end}{rate}")
    lines.append(f"{len(graph.disagreements)} disagreement(s) between data and specs")
    lines += [f"  [{d.kind}] {d.subject}: {d.detail}" for d in graph.disagreements]
    return "\n".join(lines)


def run_graph(args: argparse.Namespace) -> int:
    """Build, print and optionally save/draw the graph.

    Args:
        args: parsed ``osg graph`` arguments.

    Returns:
        0.
    """
    domain = domain_of(args)
    rates = _read_rates(args.rates)
    if args.data:
        datasets = [load_dataset(path) for path in _data_files(args.data)]
        graph = graph_from_datasets(domain, datasets, rates)
    else:
        graph = graph_from_specs(domain, success_rates=rates)
    if args.out:
        save_graph(graph, args.out)
    if args.png:
        draw_graph(graph, args.png, args.projection)
    print(dump_json(graph.to_dict()) if args.json else format_graph(graph))
    return 0


def register(subparsers: Verbs) -> None:
    """Add ``osg graph``."""
    parser = subparsers.add_parser(
        "graph",
        help="build the skill graph, check it against data, save or draw it",
        description="Build the skill graph from the skill specs, or from data sets: cluster "
        "start/end TCP positions into nodes, derive effects from world states, and list "
        "every disagreement with the specs.",
    )
    parser.add_argument(
        "--data",
        type=Path,
        help="folder of data sets, one <skill>.h5 per skill (default: specs only)",
    )
    parser.add_argument(
        "--rates", type=Path, help="JSON object skill name -> measured success rate (sets costs)"
    )
    parser.add_argument("--out", type=Path, help="write the graph as JSON here")
    parser.add_argument("--png", type=Path, help="draw the graph as a PNG here")
    parser.add_argument(
        "--projection",
        choices=sorted(PROJECTIONS),
        default="yz",
        help="plane for --png (default: yz)",
    )
    parser.add_argument("--json", action="store_true", help="print the graph as JSON")
    parser.set_defaults(func=run_graph)
