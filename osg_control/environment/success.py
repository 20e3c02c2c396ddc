"""A skill's success predicate (beta), pure so that it also runs over recorded states."""

from __future__ import annotations

import math

import numpy as np

from osg_control.domain.spec import Node, SkillSpec

GRIPPER_OPEN_CMD = 1.0
"""The observation's gripper command when open (-1 closed)."""
GRIPPER_CLOSED_CMD = -1.0


def success_holds(
    skill: SkillSpec,
    end: Node,
    position: np.ndarray,
    gripper_cmd: float,
    facts: frozenset[str],
    end_position: np.ndarray | None = None,
) -> bool:
    """A skill's success predicate (beta): TCP ``position`` within tolerance of its ``end``
    node, the gripper command of that node, its effects among ``facts``. Pure, so it also
    runs over recorded states.

    ``end_position``: where the end node is now, if it moved with its anchor (default:
    ``end.position``)."""
    gap = np.asarray(position) - np.asarray(end.position if end_position is None else end_position)
    if math.sqrt(gap @ gap) > skill.success_tolerance:  # np.linalg.norm, without its checks
        return False
    wanted = GRIPPER_OPEN_CMD if end.gripper == "open" else GRIPPER_CLOSED_CMD
    if gripper_cmd != wanted:
        return False
    return effects_hold(skill, facts)


def effects_hold(skill: SkillSpec, facts: frozenset[str]) -> bool:
    """The world part of beta: every add effect among ``facts``, no delete effect."""
    return skill.add_effects <= facts and not (skill.del_effects & facts)
