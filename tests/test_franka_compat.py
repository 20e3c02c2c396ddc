"""The mujoco >= 3.12 fix for FrankaKitchen-v1 and the version checks (``osg_control.franka``)."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("gymnasium_robotics")

import gymnasium as gym  # noqa: E402
import mujoco  # noqa: E402
from gymnasium_robotics.utils import mujoco_utils  # noqa: E402

from osg_control.errors import DomainError  # noqa: E402
from osg_control.franka import compat  # noqa: E402


def _library_functions():
    qpos = compat.ORIGINALS.get("get_joint_qpos", mujoco_utils.get_joint_qpos)
    qvel = compat.ORIGINALS.get("get_joint_qvel", mujoco_utils.get_joint_qvel)
    assert qpos.__module__ == mujoco_utils.__name__
    return qpos, qvel


@pytest.fixture(scope="module")
def kitchen():
    compat.prepare()
    env = gym.make("FrankaKitchen-v1", tasks_to_complete=["microwave"])
    env.reset(seed=3)
    for _ in range(5):
        env.step(env.action_space.sample())
    yield env.unwrapped
    env.close()


def test_unpatched_library_fails_where_the_bug_is(kitchen) -> None:
    qpos, qvel = _library_functions()
    if not compat.comparison_bug_present():
        pytest.skip(f"mujoco {mujoco.__version__} compares np.int32 joint types correctly")
    with pytest.raises(AssertionError):
        qpos(kitchen.model, kitchen.data, "robot:panda0_joint1")
    with pytest.raises(AssertionError):
        qvel(kitchen.model, kitchen.data, "robot:panda0_joint1")


def test_patched_functions_equal_an_independent_read(kitchen) -> None:
    model, data = kitchen.model, kitchen.data
    assert compat.apply_compat_fix() == compat.comparison_bug_present()
    for j in range(model.njnt):
        name = model.joint(j).name
        if not name:
            continue
        np.testing.assert_array_equal(
            mujoco_utils.get_joint_qpos(model, data, name), data.joint(name).qpos
        )
        if model.jnt_type[j] != mujoco.mjtJoint.mjJNT_BALL:
            np.testing.assert_array_equal(
                mujoco_utils.get_joint_qvel(model, data, name), data.joint(name).qvel
            )
    # The env's robot observation (9 qpos, 9 qvel) reads exactly these joints.
    qpos, qvel = mujoco_utils.robot_get_obs(model, data, kitchen.robot_env.model_names.joint_names)
    np.testing.assert_array_equal(qpos, data.qpos[:9])
    np.testing.assert_array_equal(qvel, data.qvel[:9])


def test_fix_is_skipped_without_the_bug(monkeypatch) -> None:
    monkeypatch.setattr(compat, "comparison_bug_present", lambda: False)
    before = mujoco_utils.get_joint_qpos
    assert compat.apply_compat_fix() is False
    assert mujoco_utils.get_joint_qpos is before


def test_unknown_joint_still_asserts(kitchen) -> None:
    with pytest.raises(AssertionError, match="not part of the model"):
        compat.joint_qpos(kitchen.model, kitchen.data, "no-such-joint")


def test_versions_outside_the_tested_range_are_refused(monkeypatch) -> None:
    compat.check_versions()
    versions = {"gymnasium-robotics": "1.5.0", "mujoco": "4.0.0"}
    monkeypatch.setattr(compat.metadata, "version", lambda name: versions[name])
    with pytest.raises(DomainError, match=r"gymnasium-robotics 1\.5\.0 is outside"):
        compat.check_versions()
    versions.update({"gymnasium-robotics": "1.4.2", "mujoco": "3.2.0"})
    with pytest.raises(DomainError, match=r"mujoco 3\.2\.0 is outside"):
        compat.check_versions()
