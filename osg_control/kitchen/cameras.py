"""The kitchen's cameras for the ``camera`` perception: two fixed cameras and the red cube.

``counter_cam`` faces the arm across the cube's placement region (it sees the cube resting
and, from the side, held in the hand); ``cabinet_cam`` looks down into the cabinet through
its opening (a placed cube). Both are ``<camera>`` elements of ``robots/kitchen.xml``. The
cube is the scene's only red thing (``material cube``, rgba 0.85 0.15 0.15): its mask is
the red hues; the brown door (hue about 13 of 179) and the grey metal stay out.
"""

from __future__ import annotations

from osg_control.environment.camera_sensing import CameraPerception
from osg_control.kitchen.world import CUBE_HALF_SIZE
from osg_control.perception.colour_pose import ColourTarget

CUBE_TARGET = ColourTarget(
    name="cube",
    hue_ranges=((0, 6), (174, 179)),
    min_saturation=120,
    min_value=60,
    half_height=CUBE_HALF_SIZE,
)
"""The cube's colour and size for the colour mask."""
KITCHEN_CAMERAS = CameraPerception(
    cameras=("counter_cam", "cabinet_cam"),
    targets=(CUBE_TARGET,),
    fields={"cube": ("cube_x", "cube_y", "cube_z", "cube_qw", "cube_qx", "cube_qy", "cube_qz")},
)
"""What the kitchen's camera perception renders and looks for."""
