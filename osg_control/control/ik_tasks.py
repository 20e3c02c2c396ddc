r"""The IK QP's open lists: tasks (costs) and limits (bounds), composed into one QP.

As in mink's and Pink's ``build_ik``, every task adds a least-squares cost in the joint
displacement :math:`\Delta q`,

.. math:: \tfrac12 \|W (J \Delta q + g\,e)\|^2 + \tfrac12 \mu \|\Delta q\|^2,
    \qquad \mu = \epsilon_{lm} \|g W e\|^2,

that is a Hessian :math:`(WJ)^\top WJ + \mu I` and a linear term :math:`(gWe)^\top WJ`;
a task can instead be held as the equality :math:`J \Delta q = -g\,e` (the joint reset's
TCP). Every limit bounds :math:`\Delta q` from below and above; the bounds of all limits
are intersected into one box (the solvers' simple bounds). ``compose_qp`` sums the terms
into one ``qpsolvers.Problem``.

A new task subclasses ``ResidualTask`` (error and Jacobian at the state; weights, gain and
LM damping are handled here) or, for a cost whose Hessian is a constant diagonal,
``Task``; a new limit subclasses ``Limit``. Both are passed to ``DiffIKController`` (``tasks``,
``limits``) and join the defaults: the TCP ``FrameTask`` (``control.ik_backends``), a
``PostureTask``, the ``ConfigurationLimit`` and the ``VelocityLimit``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, NamedTuple

import numpy as np
import qpsolvers

from osg_control.errors import ControllerError

if TYPE_CHECKING:
    from osg_control.control.ik_backends import Backend


class IKState(NamedTuple):
    """What a task or limit may read at one solve.

    Attributes:
        q: the arm configuration [rad] (n,), inside the joint limits.
        target_pos: the TCP target position [m] (3,), base frame.
        target_rot: the TCP target rotation matrix (3, 3).
        kinematics: the backend (``tcp_pose``, ``frame_residual``, joint limits).
    """

    q: np.ndarray
    target_pos: np.ndarray
    target_rot: np.ndarray
    kinematics: Backend


@dataclass
class Objective:
    r"""The QP's cost being assembled: :math:`\tfrac12 \Delta q^\top H \Delta q + c^\top
    \Delta q` with :math:`H` = ``dense`` + diag(``diagonal``).

    Attributes:
        dense: the sum of the tasks' full Hessian terms (n, n), or None (none yet).
        diagonal: the diagonal terms, a number or one per joint (n,); starts at the tasks'
            ``constant_diagonal`` plus the QP's Tikhonov damping.
        linear: the sum of the tasks' linear terms (n,), or None (none yet).
    """

    dense: np.ndarray | None
    diagonal: float | np.ndarray
    linear: np.ndarray | None

    def add(
        self,
        dense: np.ndarray | None = None,
        diagonal: float | np.ndarray = 0.0,
        linear: np.ndarray | None = None,
    ) -> None:
        """Add one task's terms."""
        if dense is not None:  # copied: compose_qp adds the diagonal in place
            self.dense = dense.copy() if self.dense is None else self.dense + dense
        if linear is not None:  # never changed in place
            self.linear = linear if self.linear is None else self.linear + linear
        self.diagonal = self.diagonal + diagonal


class Task:
    """A cost of the IK QP.

    Subclasses implement ``add_to`` (and ``equality`` if the task can be held as a
    constraint); a Hessian term that is the same diagonal at every solve goes in
    ``constant_diagonal``, summed once when the QP is set up.
    """

    @property
    def constant_diagonal(self) -> float | np.ndarray:
        """The task's constant diagonal Hessian term: a number, or one per joint."""
        return 0.0

    def check(self, n: int) -> None:
        """Refuse an arm of ``n`` joints this task cannot act on.

        Raises:
            ControllerError: sizes that do not match ``n`` joints.
        """

    def add_to(self, objective: Objective, state: IKState) -> None:
        """Add this task's per-solve terms at ``state`` to ``objective``."""
        raise NotImplementedError

    def equality(self, state: IKState) -> tuple[np.ndarray, np.ndarray]:
        """The task as the equality ``A dq = b``: ``(A, b)``.

        Raises:
            ControllerError: a task that cannot be held as a constraint.
        """
        raise ControllerError(f"{type(self).__name__} cannot be held as an equality")


class ResidualTask(Task):
    """A task given by its error ``e`` (k,) and Jacobian ``J`` (k, n) at the state, with
    one weight per error row (``cost``), a gain and Levenberg-Marquardt damping: the
    terms of mink's ``Task.compute_qp_objective``.

    Args:
        cost: weight per error row, or one for all (>= 0, finite).
        gain: fraction of the error to remove in one step, in [0, 1].
        lm_damping: Levenberg-Marquardt damping (>= 0).
    """

    def __init__(self, cost: float | np.ndarray, gain: float = 1.0, lm_damping: float = 0.0):
        cost_array = np.atleast_1d(np.asarray(cost, dtype=float))
        if cost_array.ndim != 1 or not (np.isfinite(cost_array).all() and cost_array.min() >= 0):
            raise ControllerError(f"{type(self).__name__}: cost must be finite and >= 0: {cost!r}")
        if not (0.0 <= gain <= 1.0 and np.isfinite(lm_damping) and lm_damping >= 0.0):
            raise ControllerError(
                f"{type(self).__name__}: gain must be in [0, 1] and lm_damping >= 0"
            )
        self.cost = cost_array
        self.gain = gain
        self.lm_damping = lm_damping
        self._cost_column = cost_array[:, None]
        self._gain_cost = gain * cost_array

    def residual(self, state: IKState) -> tuple[np.ndarray, np.ndarray]:
        """The error ``e`` (k,) and its Jacobian ``J`` (k, n) at ``state``."""
        raise NotImplementedError

    def add_to(self, objective: Objective, state: IKState) -> None:
        error, jacobian = self.residual(state)
        weighted_jacobian = self._cost_column * jacobian
        weighted_error = self._gain_cost * error
        objective.add(
            dense=weighted_jacobian.T @ weighted_jacobian,
            diagonal=self.lm_damping * float(weighted_error @ weighted_error),
            linear=weighted_error @ weighted_jacobian,
        )

    def equality(self, state: IKState) -> tuple[np.ndarray, np.ndarray]:
        error, jacobian = self.residual(state)
        return jacobian, -self.gain * error


def joint_values(name: str, values: float | np.ndarray, n: int, one: bool = False) -> None:
    """Refuse per-joint values that are not ``n`` (or, with ``one``, a single value).

    Raises:
        ControllerError: another number of values.
    """
    if np.shape(values) != (n,) and not (one and np.size(values) == 1):
        raise ControllerError(f"{name}: has {np.size(values)} values for {n} joints")


class PostureTask(Task):
    """Pull toward a configuration: ``1/2 w^2 |dq + g (q - target)|^2`` (mink's and
    Pink's ``PostureTask``; ``w`` one number or one per joint).

    Args:
        target: the configuration to pull toward [rad] (n,).
        cost: the weight ``w`` [1/rad] (>= 0), one or one per joint.
        gain: the task gain ``g`` in [0, 1].
    """

    def __init__(self, target: np.ndarray, cost: float | np.ndarray, gain: float = 1.0) -> None:
        self.target = np.array(target, dtype=float)
        squared = np.asarray(cost, dtype=float) ** 2
        if not (np.isfinite(self.target).all() and np.isfinite(squared).all()):
            raise ControllerError(f"PostureTask: target and cost must be finite: {cost!r}")
        if np.min(cost) < 0 or not 0.0 <= gain <= 1.0:
            raise ControllerError("PostureTask: cost must be >= 0 and gain in [0, 1]")
        self._squared = float(squared) if squared.ndim == 0 else squared
        self._pull = self._squared * gain

    @property
    def constant_diagonal(self) -> float | np.ndarray:
        return self._squared

    def check(self, n: int) -> None:
        joint_values("PostureTask target", self.target, n)
        joint_values("PostureTask cost", self._squared, n, one=True)

    def add_to(self, objective: Objective, state: IKState) -> None:
        objective.add(linear=self._pull * (state.q - self.target))


class DampingTask(Task):
    """Favour small joint motion: ``1/2 w^2 |dq|^2`` (mink's and Pink's ``DampingTask``;
    ``w`` one number or one per joint, >= 0)."""

    def __init__(self, cost: float | np.ndarray) -> None:
        squared = np.asarray(cost, dtype=float) ** 2
        if not np.isfinite(squared).all() or np.min(cost) < 0:
            raise ControllerError(f"DampingTask: cost must be finite and >= 0: {cost!r}")
        self._squared = float(squared) if squared.ndim == 0 else squared

    @property
    def constant_diagonal(self) -> float | np.ndarray:
        return self._squared

    def check(self, n: int) -> None:
        joint_values("DampingTask cost", self._squared, n, one=True)

    def add_to(self, objective: Objective, state: IKState) -> None:
        """Nothing per solve: the whole term is ``constant_diagonal``."""


class Limit:
    """A bound on the joint displacement: ``lower <= dq <= upper`` at the state (one value
    per joint; -inf/inf where it does not bound). All limits' boxes are intersected."""

    def check(self, n: int) -> None:
        """Refuse an arm of ``n`` joints this limit cannot bound.

        Raises:
            ControllerError: sizes that do not match ``n`` joints.
        """

    def box(self, state: IKState) -> tuple[np.ndarray, np.ndarray]:
        """``(lower, upper)`` bounds on ``dq`` [rad] at ``state``."""
        raise NotImplementedError


class ConfigurationLimit(Limit):
    """Approach the joint position limits with gain ``gamma`` in (0, 1]: ``gamma (q_min -
    q) <= dq <= gamma (q_max - q)`` (mink's and Pink's ``ConfigurationLimit``)."""

    def __init__(self, lower: np.ndarray, upper: np.ndarray, gain: float) -> None:
        self._limits = np.stack([lower, upper])
        self.gain = gain

    def check(self, n: int) -> None:
        joint_values("ConfigurationLimit", self._limits[0], n)

    def box(self, state: IKState) -> tuple[np.ndarray, np.ndarray]:
        lower, upper = self.gain * (self._limits - state.q)
        return lower, upper


class VelocityLimit(Limit):
    """``|dq| <= v_max dt`` (mink's and Pink's ``VelocityLimit``).

    Args:
        velocity: the joint speed limits [rad/s] (n,).
        dt: the step [s].
    """

    def __init__(self, velocity: np.ndarray, dt: float) -> None:
        self._step = np.asarray(velocity, dtype=float) * dt

    def check(self, n: int) -> None:
        joint_values("VelocityLimit", self._step, n)

    def box(self, state: IKState) -> tuple[np.ndarray, np.ndarray]:
        return -self._step, self._step


def constant_diagonal(tasks: list[Task], damping: float) -> float | np.ndarray:
    """The Hessian's constant diagonal: the tasks' own plus the Tikhonov ``damping``."""
    total: float | np.ndarray = 0.0
    for task in tasks:
        total = total + task.constant_diagonal
    return total + damping


def compose_qp(
    tasks: list[Task],
    limits: list[Limit],
    constraints: list[Task],
    diagonal: float | np.ndarray,
    state: IKState,
) -> qpsolvers.Problem:
    """One QP from the tasks (costs), limits (box) and constraints (equality rows).

    Args:
        tasks: the costs.
        limits: the bounds on ``dq``, intersected into one box.
        constraints: tasks held as ``A dq = b`` instead of costs.
        diagonal: ``constant_diagonal(tasks, damping)``, computed once.
        state: the configuration and target of this solve.

    Returns:
        ``qpsolvers.Problem`` with ``P``, ``q``, box ``lb``/``ub`` and the equality
        ``A``/``b`` (None without constraints).
    """
    n = state.q.size
    objective = Objective(dense=None, diagonal=diagonal, linear=None)
    for task in tasks:
        task.add_to(objective, state)
    hessian = np.zeros((n, n)) if objective.dense is None else objective.dense
    hessian.flat[:: n + 1] += objective.diagonal
    linear = np.zeros(n) if objective.linear is None else objective.linear
    if limits:
        lower, upper = limits[0].box(state)
        for limit in limits[1:]:
            low, high = limit.box(state)
            lower, upper = np.maximum(lower, low), np.minimum(upper, high)
    else:
        lower, upper = np.full(n, -np.inf), np.full(n, np.inf)
    equality_matrix = equality_vector = None
    if len(constraints) == 1:
        equality_matrix, equality_vector = constraints[0].equality(state)
    elif constraints:
        rows = [task.equality(state) for task in constraints]
        equality_matrix = np.vstack([a for a, _ in rows])
        equality_vector = np.concatenate([b for _, b in rows])
    return qpsolvers.Problem(
        hessian, linear, A=equality_matrix, b=equality_vector, lb=lower, ub=upper
    )
