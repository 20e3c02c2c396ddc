"""osg-control: Offline Skill Graph robot-control stack.

MuJoCo kitchen with example-robot-data arms (``osg_control.robots``), a differential-IK
controller (mink or Pinocchio/Pink), TD3+BC skills learned from offline data, a skill graph
exported as PDDL, a symbolic planner, a state-to-skill classifier and an executor.

Importing the package registers its Gymnasium environments (``osg/Kitchen-v0``; see
``osg_control.registration``).
"""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("osg-control")
except PackageNotFoundError:  # pragma: no cover - running from a source tree
    __version__ = "0.0.0+unknown"

from osg_control.registration import register_envs

register_envs()

__all__ = ["__version__"]
