"""Metrics of the state->skill classifier (the paper's Table II) and a nearest-node baseline.

The confusion matrix has a row per true skill and a column per predicted skill, each cell
the fraction of *all* test states (the matrix sums to 1), so its trace is the accuracy. With
the classes in ``classifier_data.class_order``, neighbouring classes share a start or end
node; the corrected accuracy also counts the two diagonals next to the main one, i.e. a
confusion between neighbouring skills counts as right.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np


def confusion_matrix(labels: np.ndarray, predictions: np.ndarray, n_classes: int) -> np.ndarray:
    """Confusion matrix normalised to the total number of points.

    Args:
        labels: (N,) true class indices.
        predictions: (N,) predicted class indices.
        n_classes: number of classes.

    Returns:
        (n_classes, n_classes) float64, row = true class, column = predicted; sums to 1.

    Raises:
        ValueError: no points, mismatched lengths or an index outside [0, n_classes).
    """
    labels = np.asarray(labels, dtype=np.int64)
    predictions = np.asarray(predictions, dtype=np.int64)
    if labels.shape != predictions.shape or labels.ndim != 1 or len(labels) == 0:
        raise ValueError(
            f"labels and predictions must be non-empty 1-D arrays of one length, got shapes "
            f"{labels.shape} and {predictions.shape}"
        )
    for name, values in (("labels", labels), ("predictions", predictions)):
        if values.min() < 0 or values.max() >= n_classes:
            raise ValueError(f"{name} must be class indices in [0, {n_classes})")
    counts = np.zeros((n_classes, n_classes), dtype=np.float64)
    np.add.at(counts, (labels, predictions), 1.0)
    return counts / len(labels)


def accuracy(confusion: np.ndarray) -> float:
    """Sum of the main diagonal of a normalised confusion matrix."""
    return float(np.trace(confusion))


def corrected_accuracy(confusion: np.ndarray) -> float:
    """Sum of the main diagonal and the two diagonals adjacent to it.

    Args:
        confusion: a normalised confusion matrix with classes in ``class_order``.

    Returns:
        The fraction of points classified as their skill or one of its order neighbours.
    """
    return float(sum(np.trace(confusion, offset=k) for k in (-1, 0, 1)))


def nearest_node_predict(observations: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """Baseline: the class whose start node is nearest to the state's TCP position.

    Args:
        observations: (N, 10) states; columns 0-2 are the TCP position.
        starts: (K, 3) start-node positions of the classes, in class order.

    Returns:
        (N,) int64 class indices; ties go to the first class.
    """
    starts = np.asarray(starts, dtype=float)
    distances = np.linalg.norm(observations[:, None, :3] - starts[None, :, :], axis=-1)
    return np.argmin(distances, axis=1).astype(np.int64)


@dataclass(frozen=True)
class EvaluationReport:
    """Table II: the test-set confusion matrix and accuracies.

    Attributes:
        classes: class names in matrix order.
        confusion: normalised confusion matrix (row = true, column = predicted).
        num_states: test states counted.
        baseline_accuracy: accuracy of ``nearest_node_predict`` on the same states.
    """

    classes: tuple[str, ...]
    confusion: np.ndarray
    num_states: int
    baseline_accuracy: float

    @property
    def accuracy(self) -> float:
        """Sum of the diagonal."""
        return accuracy(self.confusion)

    @property
    def corrected_accuracy(self) -> float:
        """Sum of the main and the two adjacent diagonals."""
        return corrected_accuracy(self.confusion)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form."""
        return {
            "classes": list(self.classes),
            "confusion": self.confusion.tolist(),
            "num_states": self.num_states,
            "accuracy": self.accuracy,
            "corrected_accuracy": self.corrected_accuracy,
            "baseline_accuracy": self.baseline_accuracy,
        }


def evaluate_predictions(
    observations: np.ndarray,
    labels: np.ndarray,
    predictions: np.ndarray,
    classes: Sequence[str],
    starts: np.ndarray,
) -> EvaluationReport:
    """Build the report of a classifier's predictions, with the baseline on the same states.

    Args:
        observations: (N, 10) test states.
        labels: (N,) true class indices.
        predictions: (N,) the classifier's class indices.
        classes: class names in ``class_order``.
        starts: (K, 3) start-node positions of the classes (``data.class_starts``).

    Returns:
        The report.
    """
    baseline = confusion_matrix(labels, nearest_node_predict(observations, starts), len(classes))
    return EvaluationReport(
        classes=tuple(classes),
        confusion=confusion_matrix(labels, predictions, len(classes)),
        num_states=len(labels),
        baseline_accuracy=accuracy(baseline),
    )


def format_report(report: EvaluationReport) -> str:
    """Render the report like the paper's Table II.

    Args:
        report: the evaluation.

    Returns:
        A multi-line table: numbered rows (true skill) and columns (predicted skill) with
        cells as fractions of all test states, then the accuracies.
    """
    n = len(report.classes)
    name_width = max(len(name) for name in report.classes) + 5
    header = " " * name_width + "".join(f"{f'({j + 1})':>7}" for j in range(n))
    rows = [
        f"{f'({i + 1}) {name}':<{name_width}}" + "".join(f"{v:7.3f}" for v in report.confusion[i])
        for i, name in enumerate(report.classes)
    ]
    return "\n".join(
        [
            f"Confusion matrix on {report.num_states} test states "
            "(rows: true skill, columns: predicted; fractions of all states)",
            header,
            *rows,
            "",
            f"accuracy (main diagonal):                    {report.accuracy:.3f}",
            f"corrected accuracy (main + adjacent diags):  {report.corrected_accuracy:.3f}",
            f"nearest-start-node baseline accuracy:        {report.baseline_accuracy:.3f}",
        ]
    )
