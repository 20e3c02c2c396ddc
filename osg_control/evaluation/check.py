"""``osg reproduce --check``: a reproduction's figures against the shipped ones, within
their confidence intervals.

Bytes reproduce only on the machine type that made them (floating-point kernels differ
between CPUs), so across machines the claim is statistical: every success rate of a
reproduction must agree with the shipped figure of the same cell. Two rates agree when
their Wilson score intervals at ``CONFIDENCE`` overlap; each cell's episode count comes from
its table. Table II's accuracies count states, not episodes, and are compared the same way.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from osg_control.errors import DatasetError
from osg_control.json_files import read_json_object

FIGURES = "figures.json"
Z = 2.576
"""Two-sided 99 % normal quantile: with several hundred cells, 95 % intervals would flag a
few agreeing cells by chance on every run."""
CONFIDENCE = 0.99


@dataclass(frozen=True)
class Cell:
    """One success rate of a table: where it is, its value and its number of trials."""

    where: str
    rate: float
    trials: int


@dataclass(frozen=True)
class Mismatch:
    """A cell whose reproduced rate lies outside the shipped one's interval."""

    where: str
    shipped: float
    reproduced: float
    shipped_interval: tuple[float, float]
    reproduced_interval: tuple[float, float]


def wilson_interval(rate: float, trials: int, z: float = Z) -> tuple[float, float]:
    """The Wilson score interval of a success rate observed over ``trials`` trials."""
    if trials <= 0:
        return 0.0, 1.0
    denominator = 1 + z * z / trials
    centre = (rate + z * z / (2 * trials)) / denominator
    half = z * math.sqrt(rate * (1 - rate) / trials + z * z / (4 * trials * trials)) / denominator
    return max(0.0, centre - half), min(1.0, centre + half)


def cells(figures: dict[str, Any]) -> Iterator[Cell]:
    """Every success rate of a report's figures, with its trial count."""
    if "table_i" in figures:
        table = figures["table_i"]
        for row in table["rows"]:
            for noise, rate in zip(table["noise"], row["rates"], strict=True):
                yield Cell(f"Table I {row['skill']} sigma={noise}", rate, table["episodes"])
    if "table_ii" in figures:
        table = figures["table_ii"]
        for key in ("accuracy", "corrected_accuracy"):
            yield Cell(f"Table II {key}", table[key], table["num_states"])
    if "table_iii" in figures:
        table = figures["table_iii"]
        for row in table["rows"]:
            yield Cell(f"Table III {row['start']}", row["success"], table["episodes"])
    if "tables_iv_v" in figures:
        table = figures["tables_iv_v"]
        for k, budget in enumerate(table["replans"]):
            for t, task in enumerate(table["tasks"]):
                for r, region in enumerate(table["regions"]):
                    yield Cell(
                        f"Tables IV/V replans={budget} {task} {region}",
                        table["rates"][k][t][r],
                        table["episodes"],
                    )


def compare(shipped: dict[str, Any], reproduced: dict[str, Any]) -> tuple[int, list[Mismatch]]:
    """Compare every cell both reports have; returns (cells compared, mismatches).

    Raises:
        DatasetError: the reports share no cell (different tables or scales).
    """
    reference = {cell.where: cell for cell in cells(shipped)}
    compared, mismatches = 0, []
    for cell in cells(reproduced):
        if cell.where not in reference:
            continue
        compared += 1
        ref = reference[cell.where]
        a, b = wilson_interval(ref.rate, ref.trials), wilson_interval(cell.rate, cell.trials)
        if a[1] < b[0] or b[1] < a[0]:
            mismatches.append(Mismatch(cell.where, ref.rate, cell.rate, a, b))
    if not compared:
        raise DatasetError("the reproduction and the shipped figures share no table cell")
    return compared, mismatches


def read_figures(path: Path) -> dict[str, Any]:
    """A report's ``figures.json`` (a file, or the folder holding it).

    Raises:
        DatasetError: missing or unreadable, naming the file.
    """
    path = path / FIGURES if path.is_dir() else path
    return read_json_object(path, "reproduction figures", DatasetError)
