"""The IK's QP solvers: DAQP and OSQP called directly on ``qpsolvers.Problem`` (box
bounds and equality rows only), without qpsolvers' per-call conversions."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import qpsolvers
from scipy import sparse

SOLVERS: tuple[str, ...] = ("daqp", "osqp")
"""The QP solvers the IK can use."""

QPSolver = Callable[[qpsolvers.Problem], "np.ndarray | None"]
"""Solves a box- and equality-constrained QP; None when it finds no solution."""


def qp_solver(name: str, osqp_eps: float, n: int) -> QPSolver:
    """A ``SOLVERS`` solver for ``n`` unknowns (``osqp_eps``: OSQP's absolute and relative
    tolerance)."""
    return DaqpSolver(n) if name == "daqp" else OsqpSolver(osqp_eps, n)


class DaqpSolver:
    """DAQP called directly: the box as simple bounds, the equality rows with sense 5
    (DAQP's default settings), for ``n`` unknowns."""

    def __init__(self, n: int) -> None:
        import daqp

        self._solve = daqp.solve
        self._n = n
        self._no_rows = np.zeros((0, n))
        self._senses: dict[int, np.ndarray] = {}

    def _sense(self, n_eq: int) -> np.ndarray:
        sense = self._senses.get(n_eq)
        if sense is None:
            sense = np.zeros(self._n + n_eq, dtype=np.intc)
            sense[self._n :] = 5  # equality rows
            self._senses[n_eq] = sense
        return sense

    def __call__(self, problem: qpsolvers.Problem) -> np.ndarray | None:
        if problem.A is None:
            rows, upper, lower = self._no_rows, problem.ub, problem.lb
        else:
            rows = problem.A
            upper = np.concatenate([problem.ub, problem.b])
            lower = np.concatenate([problem.lb, problem.b])
        sense = self._sense(rows.shape[0])
        x, _, exitflag, _ = self._solve(problem.P, problem.q, rows, upper, lower, sense)
        return np.asarray(x) if exitflag > 0 else None


class OsqpSolver:
    """OSQP on CSC matrices: ``l <= [I; A] dq <= u`` with the upper triangle of ``P``.

    One OSQP workspace per number of equality rows is set up on first use and then only
    updated (``Px``, ``q``, ``Ax``, ``l``, ``u``): the sparsity pattern never changes, so
    the expensive Python-side setup runs once. Warm starting is off and the step size
    ``rho`` is reset before each solve, so a solve does not depend on the previous ones
    (beyond rounding). For ``n`` unknowns.
    """

    def __init__(self, eps: float, n: int) -> None:
        import osqp

        self._osqp = osqp
        self._rho = 0.1  # OSQP's default initial step size
        self._settings: dict[str, Any] = {
            "eps_abs": eps,
            "eps_rel": eps,
            "max_iter": 20000,
            "rho": self._rho,
            "polishing": False,
            "warm_starting": False,
            "verbose": False,
        }
        # Upper triangle of the n x n Hessian in CSC (column-major) order.
        self._n = n
        cols, rows = np.tril_indices(n)
        self._p_rows, self._p_cols = rows, cols
        self._p_pattern = sparse.csc_matrix(
            (np.ones(rows.size), rows, np.concatenate([[0], np.cumsum(np.arange(1, n + 1))])),
            shape=(n, n),
        )
        self._workspaces: dict[int, Any] = {}

    def __call__(self, problem: qpsolvers.Problem) -> np.ndarray | None:
        n_eq = 0 if problem.A is None else problem.A.shape[0]
        upper, lower = problem.ub, problem.lb
        n = self._n
        columns = np.ones((1 + n_eq, n))  # column j of [I; A]: 1 at row j, then A[:, j]
        if problem.A is not None:
            columns[1:] = problem.A
            upper = np.concatenate([upper, problem.b])
            lower = np.concatenate([lower, problem.b])
        p_data = problem.P[self._p_rows, self._p_cols]
        a_data = columns.ravel(order="F")
        solver = self._workspaces.get(n_eq)
        if solver is None:
            indices = np.concatenate([[j, *range(n, n + n_eq)] for j in range(n)])
            a_matrix = sparse.csc_matrix(
                (a_data, indices, np.arange(n + 1) * (1 + n_eq)), shape=(n + n_eq, n)
            )
            p_matrix = self._p_pattern.copy()
            p_matrix.data = p_data
            solver = self._osqp.OSQP()
            solver.setup(P=p_matrix, q=problem.q, A=a_matrix, l=lower, u=upper, **self._settings)
            self._workspaces[n_eq] = solver
        else:
            solver.update(q=problem.q, l=lower, u=upper, Px=p_data, Ax=a_data)
            solver.update_settings(rho=self._rho)  # undo the previous solve's adaptation
        result = solver.solve(raise_error=False)
        if result.info.status_val != self._osqp.SolverStatus.OSQP_SOLVED:
            return None
        return np.array(result.x)
