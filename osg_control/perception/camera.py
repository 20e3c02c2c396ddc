"""Fixed cameras of a scene: their pinhole model, and RGB + depth images rendered by MuJoCo.

A camera is data of the scene (an MJCF ``<camera>`` element): its intrinsics follow from
its vertical field of view and the image size, its extrinsics from its pose in the world.
``CameraRig`` renders the cameras of a set with one ``mujoco.Renderer`` created once,
shadows off (about 5x cheaper on a CPU, and the colour mask does not need them).
``back_project`` turns pixels and their depth into world points.

MuJoCo's camera looks along its frame's -z axis, x to the right and y up; image row 0 is
the top of the picture.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np

from osg_control.errors import UsageError


@dataclass(frozen=True)
class CameraSetup:
    """One fixed camera: where it is, where it looks and its image.

    Attributes:
        name: the model camera's name.
        width, height: the image size [px].
        fovy: the vertical field of view [deg].
        position: the camera's centre in the world [m].
        rotation: the camera frame's axes as the columns of a world rotation matrix.
    """

    name: str
    width: int
    height: int
    fovy: float
    position: np.ndarray
    rotation: np.ndarray

    @property
    def focal(self) -> float:
        """The focal length [px] (square pixels): half the image height over the tangent of
        half the vertical field of view."""
        return 0.5 * self.height / math.tan(math.radians(self.fovy) / 2)

    @property
    def intrinsics(self) -> np.ndarray:
        """The 3x3 pinhole matrix K (principal point at the image centre)."""
        f = self.focal
        return np.array([[f, 0.0, self.width / 2], [0.0, f, self.height / 2], [0.0, 0.0, 1.0]])

    def to_dict(self) -> dict[str, Any]:
        """The set-up for a command's ``--json``."""
        return {
            "name": self.name,
            "resolution": [self.width, self.height],
            "fovy_deg": round(self.fovy, 4),
            "focal_px": round(self.focal, 3),
            "position": [round(float(v), 5) for v in self.position],
            "rotation": [[round(float(v), 5) for v in row] for row in self.rotation],
        }


def camera_setups(
    model: mujoco.MjModel, data: mujoco.MjData, names: Sequence[str], width: int, height: int
) -> tuple[CameraSetup, ...]:
    """The set-ups of the named model cameras (``data``'s camera poses computed: ``mj_camlight``).

    Raises:
        UsageError: a name the model has no camera for (the model's cameras listed), or an
            image larger than the model's offscreen buffer.
    """
    known = [model.camera(i).name for i in range(model.ncam)]
    missing = [name for name in names if name not in known]
    if missing or not names:
        raise UsageError(
            f"camera perception: the scene has no camera {missing or '(none declared)'}; "
            f"its cameras: {known}"
        )
    if width > model.vis.global_.offwidth or height > model.vis.global_.offheight:
        raise UsageError(
            f"camera images of {width}x{height} exceed the scene's offscreen buffer "
            f"{model.vis.global_.offwidth}x{model.vis.global_.offheight}"
        )
    setups = []
    for name in names:
        cam = model.camera(name).id
        setups.append(
            CameraSetup(
                name,
                width,
                height,
                float(model.cam_fovy[cam]),
                data.cam_xpos[cam].copy(),
                data.cam_xmat[cam].reshape(3, 3).copy(),
            )
        )
    return tuple(setups)


class CameraRig:
    """Renders RGB and depth images of a set of fixed cameras.

    The renderer is created at the first ``render`` (0.3-0.8 s) and reused; ``close``
    frees it.
    """

    def __init__(self, model: mujoco.MjModel, setups: Sequence[CameraSetup]) -> None:
        self.model = model
        self.setups = tuple(setups)
        self._renderer: mujoco.Renderer | None = None

    def render(
        self, data: mujoco.MjData, index: int, wants_depth: Callable[[np.ndarray], bool]
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """Camera ``index``'s ``(rgb, depth)``: uint8 (H, W, 3) and float depth [m] along
        the optical axis (H, W); the depth only where ``wants_depth(rgb)`` (a depth render
        costs about half an RGB one: skipped for a camera that sees nothing of interest)."""
        if self._renderer is None:
            first = self.setups[0]
            self._renderer = mujoco.Renderer(self.model, height=first.height, width=first.width)
            self._renderer.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = False
        renderer = self._renderer
        renderer.update_scene(data, camera=self.setups[index].name)
        rgb = renderer.render().copy()
        depth = None
        if wants_depth(rgb):
            renderer.enable_depth_rendering()
            depth = renderer.render().copy()
            renderer.disable_depth_rendering()
        return rgb, depth

    def close(self) -> None:
        """Free the renderer (a later ``render`` makes a new one)."""
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None


def back_project(
    setup: CameraSetup, rows: np.ndarray, cols: np.ndarray, depth: np.ndarray
) -> np.ndarray:
    """World points [m] (N, 3) of pixels (their centres) at their depth along the axis."""
    f = setup.focal
    x = (cols + 0.5 - setup.width / 2) / f * depth
    y = -(rows + 0.5 - setup.height / 2) / f * depth
    camera = np.stack([x, y, -depth], axis=1)
    return setup.position + camera @ setup.rotation.T
