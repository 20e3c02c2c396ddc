"""The empty hand approaching a shut drawer turns level for the pull on its way
(``fixtures.drawer_hand``): the open's first leg then has no quarter turn left to make
in place (it took 31-40 of LIBERO-Goal task 3's 300 steps). Needs the libero extra."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

pytest.importorskip("libero.libero", reason="needs the libero extra: pip install -e .[libero]")

from osg_control.libero.controllers import operator_legs  # noqa: E402
from osg_control.libero.drive import JointTargetDriver  # noqa: E402
from osg_control.libero.env import LiberoEnv  # noqa: E402
from osg_control.libero.legs import Context  # noqa: E402
from osg_control.libero.perception import LiberoPerception  # noqa: E402
from osg_control.libero.robot import mounted_panda  # noqa: E402

REGION = "white_cabinet_1_bottom_region"
JOINT = "white_cabinet_1_bottom_level"


def test_a_shut_drawer_is_approached_with_the_hand_the_open_takes() -> None:
    """LIBERO-10 task 3, state 0, its bottom drawer sensed open: approached with the
    start's hand (the close comes next); sensed shut: with the open's level hand, and the
    open's legs in free space (the turn, the way down in front of the handle) run at the
    transit pace."""
    env = LiberoEnv("libero_10", 3)
    try:
        obs = env.reset(0)
        scene, percept = LiberoPerception(env).reset(obs, 0)
        robot = mounted_panda(env.sim)
        ctx = Context.at_start(scene, JointTargetDriver(robot), robot, percept, env.problem)
        shut = replace(percept.fixtures[JOINT], value=scene.joints[JOINT].shut)
        closed = replace(percept, fixtures={**percept.fixtures, JOINT: shut})

        def approached(p):  # the approach's last leg's rotation
            return operator_legs(ctx, "approach", (REGION,), None)[-1].target(p, p)[1]

        assert np.allclose(approached(percept), ctx.base)
        level = operator_legs(ctx, "open", (REGION, REGION), None)
        assert np.allclose(approached(closed), level[0].target(closed, closed)[1])
        assert not np.allclose(approached(closed), ctx.base)
        assert [leg.transit for leg in level[:3]] == [True, True, False]
    finally:
        env.close()
