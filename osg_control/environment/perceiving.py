"""``Perceiving``: ``ArmEnv``'s percepts: the simulated sensors read once per reset, step
or joint reset (``config.perception``), the ``camera`` perception's cameras, and what the
robot perceives (the only input of whatever decides)."""

from __future__ import annotations

import mujoco
import numpy as np

from osg_control.environment.camera_sensing import CameraPerception, CameraSensing
from osg_control.environment.config import EnvConfig
from osg_control.environment.skill_step import SkillStepper
from osg_control.environment.truth import SceneTruth
from osg_control.errors import EnvOptionError
from osg_control.perception.percept import Percept
from osg_control.perception.sensors import noisy_world
from osg_control.perception.spec import SIMULATED_PERCEPTIONS, PerceptionSpec


class Perceiving(SceneTruth, SkillStepper):
    """The percept part of ``ArmEnv`` (``ArmEnv.__init__`` sets the attributes below); the
    ``sim`` perception reads the truth (``SceneTruth``) exactly."""

    config: EnvConfig
    model: mujoco.MjModel
    cameras: CameraSensing | None
    np_random: np.random.Generator
    _percept: Percept | None
    _sensor_slices: dict[str, np.ndarray]
    _fixture_random: np.random.Generator | None = None

    camera_perception: CameraPerception | None = None
    """The scene's fixed cameras and what they locate (the ``camera`` perception), if any."""

    @property
    def perceptions(self) -> tuple[str, ...]:
        """The perceptions it simulates: ``camera`` too where the scene declares cameras."""
        return SIMULATED_PERCEPTIONS + (("camera",) if self.camera_perception is not None else ())

    @property
    def perception(self) -> PerceptionSpec:
        """The perception it perceives with (``config.perception``)."""
        return self.config.perception

    def seed_fixture_noise(self, fresh: bool) -> None:
        """Give the ``FIXTURE`` sensors their own stream, spawned from the env's generator
        (``Generator.spawn`` draws nothing from it) when it was just seeded (``fresh``) or
        at the first reset: the other sensors' draws are then those of an env without
        fixtures."""
        if fresh or self._fixture_random is None:
            self._fixture_random = self.np_random.spawn(1)[0]

    def sense(self) -> Percept:
        """Read the sensors now without stepping (e.g. after the scene was edited from
        outside); ``percept`` then returns this reading."""
        return self._perceive()

    def _perceive(
        self,
        truth: np.ndarray | None = None,
        truth_facts: frozenset[str] | None = None,
        decision: bool = True,
    ) -> Percept:
        """Read the simulated sensors once (``config.perception``) and keep the percept
        (``truth``: the world vector, if the caller has read it already; ``truth_facts``:
        its facts, if computed, which an exact ``sim`` perception then reuses; ``decision``:
        a decision point, where the ``camera`` perception renders whatever its rate)."""
        spec = self.config.perception
        truth = self.read_world() if truth is None else truth
        if truth.shape != (len(self.world_sensors),):
            raise EnvOptionError(
                f"{type(self).__name__}: world_sensors name {len(self.world_sensors)} fields, "
                f"read_world gives {truth.shape}; declare a sensor for every world field"
            )
        if spec.name == "sim":
            state = self.true_state()
            facts = self.facts_of(truth) if truth_facts is None else truth_facts
            self._percept = Percept(state, self.arm_q, truth, facts)
        else:
            state, joints = self.sensors.perceived(
                self.data, self._gripper_cmd, spec, self.np_random
            )
            self.seed_fixture_noise(fresh=False)
            seen = noisy_world(
                spec, self.np_random, truth, self._sensor_slices, self._fixture_random
            )
            if spec.name == "camera":
                seen = self._camera_world(state, seen, decision)
            world = self.detect_world(state, seen)
            self._percept = Percept(state, joints, world, self.facts_of(world))
        return self._percept

    def _camera_world(self, state: np.ndarray, world: np.ndarray, decision: bool) -> np.ndarray:
        """``world`` with the objects the scene's cameras locate (``camera_sensing``; the
        ``camera`` perception is refused at construction where the scene declares none)."""
        if self.cameras is None:
            assert self.camera_perception is not None  # ``perceptions`` lists camera
            self.cameras = CameraSensing(
                self.model,
                self.camera_perception,
                self.config.perception,
                self.world_sensors,
                self.robot.control_hz,
            )
        previous = self._percept.facts if self._percept is not None else frozenset()
        held = {frame.name for frame in self.objects if frame.held_fact in previous}
        return self.cameras.read(self.data, state[:3], world, held, decision)
