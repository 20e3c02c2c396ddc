"""Drawing a skill graph as a PNG (matplotlib's Agg canvas, no pyplot)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from matplotlib.patches import FancyArrowPatch

from osg_control.io_safety import atomic_write
from osg_control.planning.graph import SkillGraph

PROJECTIONS: dict[str, tuple[int, int]] = {"xy": (0, 1), "xz": (0, 2), "yz": (1, 2)}
"""Axis pairs for ``draw_graph``; y-z (the robot seen from the front) is the default: nodes
above one another often share x and y."""


def draw_graph(graph: SkillGraph, path: str | Path, projection: str = "yz") -> None:
    """Draw the graph as a PNG: nodes at their TCP positions, edges labelled by skill.

    Args:
        graph: the graph to draw.
        path: the PNG file to write.
        projection: ``xy``, ``xz`` or ``yz``, the plane the positions are projected on.

    Raises:
        ValueError: an unknown projection.
    """
    if projection not in PROJECTIONS:
        raise ValueError(f"unknown projection {projection!r}; known: {', '.join(PROJECTIONS)}")
    a, b = PROJECTIONS[projection]
    where = {n.name: (n.position[a], n.position[b]) for n in graph.nodes}
    fig = Figure(figsize=(10, 8))  # Agg canvas, no pyplot: never touches the global backend
    ax = fig.subplots()
    bend = 0.2
    for edge in graph.edges:
        p, q = np.array(where[edge.start]), np.array(where[edge.end])
        ax.add_patch(
            FancyArrowPatch(
                where[edge.start],
                where[edge.end],
                connectionstyle=f"arc3,rad={bend}",
                arrowstyle="-|>",
                mutation_scale=14,
                shrinkA=14,
                shrinkB=14,
                color="tab:gray",
            )
        )
        normal = np.array([q[1] - p[1], p[0] - q[0]])  # arc3 bends towards this side
        label = edge.name if edge.success_rate is None else f"{edge.name} ({edge.success_rate:.2f})"
        x, y = (p + q) / 2 + bend / 2 * normal
        ax.text(
            x,
            y,
            label,
            fontsize=7,
            ha="center",
            va="center",
            bbox={"boxstyle": "round", "fc": "white", "ec": "none", "alpha": 0.8},
        )
    for node in graph.nodes:
        x, y = where[node.name]
        ax.scatter(
            [x], [y], s=250, c="tab:orange" if node.gripper == "closed" else "tab:blue", zorder=3
        )
        ax.annotate(
            node.name,
            (x, y),
            xytext=(0, 12),
            textcoords="offset points",
            ha="center",
            fontsize=9,
            weight="bold",
        )
    names = "xyz"
    ax.set_xlabel(f"{names[a]} [m]")
    ax.set_ylabel(f"{names[b]} [m]")
    ax.set_aspect("equal")
    ax.margins(0.15)
    ax.set_title("Skill graph (blue: gripper open, orange: closed)")
    fig.tight_layout()
    atomic_write(path, lambda tmp: fig.savefig(tmp, dpi=120))
