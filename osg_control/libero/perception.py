"""Perception ``env`` for LIBERO: what the deciding layers get each step.

The benchmark's observation gives the arm's proprioception (joints, TCP position, finger
positions) and every movable object's pose. Fixture joints (drawers, the microwave door,
stove knobs) are not in it: ``FixtureSensor`` reads them from the simulator as a labelled
sensor with stated Gaussian noise (``FIXTURE_NOISE``: 5 mm on a slide, 0.02 rad on a
hinge, drawn from a seeded generator each step). ``LiberoPerception`` is the one place that
touches the env for deciding: it reads the scene's static description once after a reset
(``scene.read_scene``) and then makes one ``LiberoPercept`` per observation. Policies,
controllers and the plan executor see only percepts and the scene.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from osg_control.libero.env import LiberoEnv, episode_seeds
from osg_control.libero.scene import JOINT_HINGE, JOINT_SLIDE, Scene, read_scene

FIXTURE_NOISE: dict[str, float] = {JOINT_SLIDE: 0.005, JOINT_HINGE: 0.02}
"""The fixture sensor's standard deviation per joint kind: 5 mm on a drawer's slide, 0.02
rad on a door's or knob's hinge (zero-mean Gaussian, independent each step)."""
FIXTURE_UNITS = {JOINT_SLIDE: "m", JOINT_HINGE: "rad"}


@dataclass(frozen=True)
class SensorReading:
    """One labelled reading of the fixture sensor."""

    label: str  # ``fixture-joint/<joint>``
    value: float
    unit: str
    sigma: float


class FixtureSensor:
    """The fixture joints of a scene, read with noise (``FIXTURE_NOISE``).

    Args:
        env: the env (its simulator is read here, nowhere in the deciding layers).
        scene: which joints to read, and their kinds.
        seed: the noise's seed (one generator per episode).
    """

    def __init__(self, env: LiberoEnv, scene: Scene, seed: int) -> None:
        model = env.sim.model._model
        self._data = env.sim.data._data
        self._joints = {
            name: (int(model.jnt_qposadr[model.joint(name).id]), joint.kind)
            for name, joint in scene.joints.items()
        }
        self._rng = np.random.default_rng(seed)

    def read(self) -> dict[str, SensorReading]:
        """Every joint's noisy reading, by joint name."""
        readings = {}
        for name, (address, kind) in self._joints.items():
            sigma = FIXTURE_NOISE[kind]
            value = float(self._data.qpos[address]) + float(self._rng.normal(0.0, sigma))
            readings[name] = SensorReading(f"fixture-joint/{name}", value, FIXTURE_UNITS[kind],
                                           sigma)  # fmt: skip
        return readings


@dataclass(frozen=True)
class LiberoPercept:
    """What the deciding layers perceive at one step.

    Attributes:
        joints: the arm's joint positions [rad] (observation).
        tcp: the TCP position [m] (observation, ``robot0_eef_pos``).
        finger_width: the distance between the fingers [m] (observation).
        objects: movable object -> (position [m], rotation of its upright frame) (the
            observation's pose; ``scene.Scene.frames``).
        fixtures: fixture joint -> its noisy reading (``FixtureSensor``).
    """

    joints: np.ndarray
    tcp: np.ndarray
    finger_width: float
    objects: dict[str, tuple[np.ndarray, np.ndarray]]
    fixtures: dict[str, SensorReading]

    def position(self, obj: str) -> np.ndarray:
        """A movable object's perceived position."""
        return self.objects[obj][0]

    def joint(self, name: str) -> float:
        """A fixture joint's perceived value."""
        return self.fixtures[name].value


class LiberoPerception:
    """Percepts of one LIBERO env: the observation plus the fixture sensor.

    Args:
        env: the env.
        seed: the fixture sensor's seed; episode ``k`` of a run draws from ``(seed, k)``.
    """

    def __init__(self, env: LiberoEnv, seed: int = 0) -> None:
        self.env, self.seed = env, seed
        self.scene: Scene | None = None
        self._sensor: FixtureSensor | None = None

    def reset(self, obs: dict[str, np.ndarray], episode: int) -> tuple[Scene, LiberoPercept]:
        """After the env's reset: read the scene's description once, start the sensor's
        noise for ``episode``, and perceive ``obs``."""
        self.scene = read_scene(self.env.env, self.env.problem)
        self._sensor = FixtureSensor(self.env, self.scene, episode_seeds(self.seed, episode)[1])
        return self.scene, self.percept(obs)

    def percept(self, obs: dict[str, np.ndarray]) -> LiberoPercept:
        """The percept of one observation (and one fresh fixture reading)."""
        if self._sensor is None:
            raise RuntimeError("LiberoPerception.percept before reset")
        frames = self.scene.frames if self.scene is not None else {}
        objects = {
            name: (
                np.asarray(obs[f"{name}_pos"], dtype=float),
                # robosuite's quaternions are x, y, z, w; turned into the upright frame
                Rotation.from_quat(obs[f"{name}_quat"]).as_matrix() @ frames[name],
            )
            for name in self.env.problem.objects
            if f"{name}_pos" in obs
        }
        fingers = np.asarray(obs["robot0_gripper_qpos"], dtype=float)
        return LiberoPercept(
            joints=np.asarray(obs["robot0_joint_pos"], dtype=float),
            tcp=np.asarray(obs["robot0_eef_pos"], dtype=float),
            finger_width=float(fingers[0] - fingers[1]),
            objects=objects,
            fixtures=self._sensor.read(),
        )
