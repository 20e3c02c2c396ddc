"""``osg reproduce --check``: a reproduction's figures against the shipped ones, within
their confidence intervals.

Bytes reproduce only on the machine type that made them (floating-point kernels differ
between CPUs), so across machines the claim is statistical: every success rate of a
reproduction must agree with the shipped figure of the same cell. Two rates agree when
their Wilson score intervals at ``CONFIDENCE`` overlap; each cell's episode count comes from
its table. Table II's accuracies count states, not episodes, and are compared the same way.

Both sides are validated before anything is compared: a rate must be a finite number in
[0, 1], a trial count a positive integer, every table, row and axis of the expected shape,
and every cell of the shipped figures must be in the reproduction. A comparison that cannot
be made is a ``DatasetError`` naming the file and the cell or key, never a pass.

A comparison must also have the power to find a difference: at one trial a Wilson interval
covers almost all of [0, 1], so nothing could ever be outside it. Every compared cell needs
at least ``MIN_TRIALS`` trials on both sides, and the reproduction at least the shipped
cell's own count; otherwise the comparison is refused, naming the cells. Each compared cell
reports the smallest difference from the shipped rate that would have been found
(``detectable_difference``), so a pass says how close the agreement was checked.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from osg_control.errors import DatasetError
from osg_control.json_files import is_json_number, read_json_object

FIGURES = "figures.json"
Z = 2.576
"""Two-sided 99 % normal quantile: with several hundred cells, 95 % intervals would flag a
few agreeing cells by chance on every run."""
CONFIDENCE = 0.99
MAX_TRIALS = 10**9
"""The most trials a cell may count (a 401-digit count overflowed the interval)."""
MIN_TRIALS = 30
"""The fewest trials a compared cell may have, on either side: at 30 trials a rate of 0.5
is told from one of 0.9 (their 99 % intervals are disjoint); at 1 or 2 nothing is."""


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


@dataclass(frozen=True)
class Comparison:
    """The outcome of a comparison: how many cells, which disagree, and per cell the
    smallest difference from the shipped rate the comparison would have found (None: none
    in either direction)."""

    compared: int
    mismatches: list[Mismatch]
    detectable: dict[str, float | None]

    def least_power(self) -> tuple[str, float | None]:
        """The cell whose detectable difference is the largest, with it (None counts as
        larger than any number)."""
        return max(
            self.detectable.items(), key=lambda item: math.inf if item[1] is None else item[1]
        )

    def summary(self) -> dict[str, Any]:
        """The detectable differences over all cells (smallest, median, largest, and the
        cell of the largest), for the text and ``--json`` reports."""
        values = sorted(d for d in self.detectable.values() if d is not None)
        where, worst = self.least_power()
        return {
            "smallest": values[0] if values else None,
            "median": values[len(values) // 2] if values else None,
            "largest": worst,
            "largest_at": where,
        }


def wilson_interval(rate: float, trials: int, z: float = Z) -> tuple[float, float]:
    """The Wilson score interval of a success rate observed over ``trials`` trials.

    Raises:
        ValueError: a rate outside [0, 1] or a trial count above ``MAX_TRIALS``.
    """
    if not 0.0 <= rate <= 1.0 or trials > MAX_TRIALS:
        raise ValueError(
            f"a Wilson interval needs a rate in [0, 1] and at most {MAX_TRIALS:,} trials, "
            f"got {rate!r} over {_shown(trials)}"
        )
    if trials <= 0:
        return 0.0, 1.0
    denominator = 1 + z * z / trials
    centre = (rate + z * z / (2 * trials)) / denominator
    half = z * math.sqrt(rate * (1 - rate) / trials + z * z / (4 * trials * trials)) / denominator
    return max(0.0, centre - half), min(1.0, centre + half)


def detectable_difference(rate: float, shipped_trials: int, trials: int) -> float | None:
    """The smallest difference from a shipped ``rate`` (over ``shipped_trials``) that a
    reproduced rate over ``trials`` trials must have for their intervals to be disjoint:
    up or down, whichever is smaller; None when no rate in [0, 1] is disjoint either way.
    Found by bisection (an interval's bounds grow with its rate)."""
    low, high = wilson_interval(rate, shipped_trials)
    found = []
    if wilson_interval(1.0, trials)[0] > high:
        found.append(_bisect(lambda r: wilson_interval(r, trials)[0] > high, rate, 1.0) - rate)
    if wilson_interval(0.0, trials)[1] < low:
        found.append(rate - _bisect(lambda r: wilson_interval(r, trials)[1] >= low, 0.0, rate))
    return min(found) if found else None


def _bisect(outside: Any, below: float, above: float) -> float:
    """The boundary in [below, above] where ``outside`` turns from false to true."""
    for _ in range(60):
        middle = (below + above) / 2
        below, above = (below, middle) if outside(middle) else (middle, above)
    return above


class _Fields:
    """Typed access to one report's figures: every malformed value is a ``DatasetError``
    naming the report and the key or cell."""

    def __init__(self, source: str) -> None:
        """Name errors after ``source`` (the file, or what the figures are)."""
        self.source = source

    def fail(self, where: str, message: str) -> DatasetError:
        """The error for a malformed value at ``where``."""
        return DatasetError(f"{self.source}: {where}: {message}")

    def field(self, mapping: dict[str, Any], key: str, where: str) -> Any:
        """``mapping[key]``, which must be there."""
        if key not in mapping:
            raise self.fail(where, f"{key!r} is missing")
        return mapping[key]

    def get(self, mapping: dict[str, Any], key: str, kind: type, where: str) -> Any:
        """``mapping[key]``, which must be a ``kind`` (a dict or a list)."""
        value = self.field(mapping, key, where)
        if not isinstance(value, kind):
            raise self.fail(where, f"{key!r} must be a {_JSON_NAMES[kind]}, got {_shown(value)}")
        return value

    def table(self, figures: dict[str, Any], key: str) -> dict[str, Any] | None:
        """The table ``key`` if the figures have it (it must be an object)."""
        if key not in figures:
            return None
        return self.get(figures, key, dict, TABLE_NAMES[key])  # type: ignore[no-any-return]

    def sized(self, value: Any, where: str, length: int | None = None) -> list[Any]:
        """``value`` as a list, of ``length`` entries when given."""
        if not isinstance(value, list) or length is not None and len(value) != length:
            entries = "a list" if length is None else f"a list of {length} entries"
            raise self.fail(where, f"must be {entries}, got {_shown(value)}")
        return value

    def rows(self, table: dict[str, Any], key: str, where: str, length: int | None) -> list[Any]:
        """The list ``table[key]``, of ``length`` entries when given."""
        return self.sized(self.field(table, key, where), f"{where} {key!r}", length)

    def records(self, table: dict[str, Any], where: str) -> Iterator[tuple[str, dict[str, Any]]]:
        """Each row of ``table['rows']`` (a JSON object), with where it is."""
        for i, row in enumerate(self.rows(table, "rows", where, None)):
            at = f"{where} row {i + 1}"
            if not isinstance(row, dict):
                raise self.fail(at, f"must be a JSON object, got {_shown(row)}")
            yield at, row

    def label(self, value: Any, where: str) -> str:
        """A row or column label (a name, or a number such as a noise level)."""
        if isinstance(value, str) or is_json_number(value) and math.isfinite(value):
            return str(value)
        raise self.fail(where, f"a label must be a string or a finite number, got {_shown(value)}")

    def trials(self, table: dict[str, Any], key: str, where: str) -> int:
        """A table's trial count ``table[key]``: a positive integer."""
        value = self.field(table, key, where)
        if isinstance(value, bool) or not isinstance(value, int) or not 0 < value <= MAX_TRIALS:
            raise self.fail(
                where, f"{key!r} must be a positive integer <= {MAX_TRIALS:,}, got {_shown(value)}"
            )
        return value

    def cell(self, where: str, value: Any, trials: int) -> Cell:
        """The cell at ``where``: its rate must be a finite number in [0, 1]."""
        if not (is_json_number(value) and math.isfinite(value) and 0.0 <= value <= 1.0):
            raise self.fail(where, f"rate must be a finite number in [0, 1], got {_shown(value)}")
        return Cell(where, float(value), trials)


_JSON_NAMES: dict[type, str] = {dict: "JSON object", list: "JSON list"}
TABLE_NAMES = {
    "table_i": "Table I",
    "table_ii": "Table II",
    "table_iii": "Table III",
    "tables_iv_v": "Tables IV/V",
}
"""The tables whose success rates are compared, by their key in ``figures.json``."""


def _shown(value: Any) -> str:
    text = json.dumps(value, default=repr)
    return text if len(text) <= 40 else text[:37] + "..."


def cells(figures: Any, source: str = "figures") -> Iterator[Cell]:
    """Every success rate of a report's figures, with its trial count.

    Raises:
        DatasetError: a table, row, label, rate or trial count is malformed (a rate not a
            finite number in [0, 1], a trial count not a positive integer), naming
            ``source`` and the key or cell.
    """
    fields = _Fields(source)
    if not isinstance(figures, dict):
        raise fields.fail("figures", f"must be a JSON object, got {_shown(figures)}")
    if (table := fields.table(figures, "table_i")) is not None:
        trials = fields.trials(table, "episodes", "Table I")
        noise = [
            fields.label(n, "Table I 'noise'") for n in fields.rows(table, "noise", "Table I", None)
        ]
        for at, row in fields.records(table, "Table I"):
            skill = fields.label(fields.field(row, "skill", at), f"{at} 'skill'")
            rates = fields.rows(row, "rates", f"Table I {skill}", len(noise))
            for sigma, rate in zip(noise, rates, strict=True):
                yield fields.cell(f"Table I {skill} sigma={sigma}", rate, trials)
    if (table := fields.table(figures, "table_ii")) is not None:
        trials = fields.trials(table, "num_states", "Table II")
        for key in ("accuracy", "corrected_accuracy"):
            yield fields.cell(f"Table II {key}", fields.field(table, key, "Table II"), trials)
    if (table := fields.table(figures, "table_iii")) is not None:
        trials = fields.trials(table, "episodes", "Table III")
        for at, row in fields.records(table, "Table III"):
            start = fields.label(fields.field(row, "start", at), f"{at} 'start'")
            where = f"Table III {start}"
            yield fields.cell(where, fields.field(row, "success", where), trials)
    if (table := fields.table(figures, "tables_iv_v")) is not None:
        yield from _task_cells(fields, table)


def _task_cells(fields: _Fields, table: dict[str, Any]) -> Iterator[Cell]:
    """Tables IV/V's cells: ``rates[budget][task][region]``, each axis labelled."""
    trials = fields.trials(table, "episodes", "Tables IV/V")
    axes = [
        [
            fields.label(x, f"Tables IV/V {key!r}")
            for x in fields.rows(table, key, "Tables IV/V", None)
        ]
        for key in ("replans", "tasks", "regions")
    ]
    budgets, tasks, regions = axes
    by_budget = fields.rows(table, "rates", "Tables IV/V", len(budgets))
    for budget, by_task in zip(budgets, by_budget, strict=True):
        at = f"Tables IV/V replans={budget}"
        for task, by_region in zip(tasks, fields.sized(by_task, at, len(tasks)), strict=True):
            rates = fields.sized(by_region, f"{at} {task}", len(regions))
            for region, rate in zip(regions, rates, strict=True):
                yield fields.cell(f"{at} {task} {region}", rate, trials)


def _cells_by_place(figures: Any, source: str) -> dict[str, Cell]:
    """The cells of ``figures`` by where they are; a place given twice is an error."""
    found: dict[str, Cell] = {}
    for cell in cells(figures, source):
        if cell.where in found:
            raise DatasetError(f"{source}: {cell.where}: the cell appears twice")
        found[cell.where] = cell
    return found


def _listed(names: list[str]) -> str:
    return ", ".join(names[:5]) + (f" and {len(names) - 5} more" if len(names) > 5 else "")


def _check_power(
    reference: dict[str, Cell], found: dict[str, Cell], shipped_source: str, source: str
) -> None:
    """Refuse a comparison with too few trials to find a difference (see the module)."""
    thin = [f"{w} ({c.trials})" for w, c in reference.items() if c.trials < MIN_TRIALS]
    if thin:
        raise DatasetError(
            f"{shipped_source}: {len(thin)} cells have fewer than {MIN_TRIALS} trials, too few "
            f"to compare against: {_listed(thin)}"
        )
    short = [
        f"{where} ({cell.trials} < {max(MIN_TRIALS, reference[where].trials)})"
        for where, cell in found.items()
        if where in reference and cell.trials < max(MIN_TRIALS, reference[where].trials)
    ]
    if short:
        raise DatasetError(
            f"{source}: {len(short)} cells have fewer trials than the shipped cell's (and at "
            f"least {MIN_TRIALS}): a comparison without the power to find a difference cannot "
            f"pass: {_listed(short)}"
        )


def compare(
    shipped: Any,
    reproduced: Any,
    shipped_source: str = "shipped figures",
    reproduced_source: str = "reproduction",
) -> Comparison:
    """Compare every cell of the shipped figures with the reproduction's. Cells only the
    reproduction has are not compared.

    Raises:
        DatasetError: either side is malformed (see ``cells``), the reproduction lacks cells
            the shipped figures have, the two share no cell, or a compared cell has too few
            trials (fewer than ``MIN_TRIALS`` on either side, or the reproduction fewer than
            the shipped cell); named after the sources and the cells.
    """
    reference = _cells_by_place(shipped, shipped_source)
    found = _cells_by_place(reproduced, reproduced_source)
    shared = [where for where in reference if where in found]
    if not shared:
        raise DatasetError(
            f"{reproduced_source}: the reproduction and the shipped figures ({shipped_source}) "
            "share no table cell"
        )
    missing = [where for where in reference if where not in found]
    if missing:
        raise DatasetError(
            f"{reproduced_source}: lacks {len(missing)} of the {len(reference)} cells of the "
            f"shipped figures ({shipped_source}): {_listed(missing)}"
        )
    _check_power(reference, found, shipped_source, reproduced_source)
    mismatches = []
    detectable: dict[str, float | None] = {}
    for where in shared:
        ref, cell = reference[where], found[where]
        a, b = wilson_interval(ref.rate, ref.trials), wilson_interval(cell.rate, cell.trials)
        if a[1] < b[0] or b[1] < a[0]:
            mismatches.append(Mismatch(where, ref.rate, cell.rate, a, b))
        detectable[where] = detectable_difference(ref.rate, ref.trials, cell.trials)
    return Comparison(len(shared), mismatches, detectable)


def figures_file(path: Path) -> Path:
    """A report's ``figures.json``: ``path`` itself, or the file in the folder ``path``."""
    return path / FIGURES if path.is_dir() else path


def read_figures(path: Path) -> dict[str, Any]:
    """A report's ``figures.json`` (a file, or the folder holding it).

    Raises:
        DatasetError: missing or unreadable, naming the file.
    """
    return read_json_object(figures_file(path), "reproduction figures", DatasetError)
