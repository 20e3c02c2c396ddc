"""Record executions for the rerun viewer (the optional ``viz`` extra: ``rerun-sdk``).

What is logged is what the robot perceived and what the executor decided, never the
simulator's truth: per control step the percept's TCP pose, joints and gripper; per
episode the domain's nodes; the executor's events (``Executor.on_event``) as the active
skill and its target node, the plan, replans and failures. Per episode, under
``episode_<i>/``::

    nodes                 Points3D, every graph node at its declared position, labelled
    target                Points3D, the node the running skill heads for (at the
                          perceived object offsets), labelled
    tcp                   Transform3D + Points3D, the perceived TCP pose
    path                  LineStrips3D, the TCP's path so far (updated at each skill end)
    joints                Scalars, one series per arm joint [rad]
    gripper/{command,force,width}   Scalars
    skill                 TextDocument, the running skill
    plan                  TextDocument, the current plan (entry skill first)
    events                TextLog: plans, skill starts and outcomes, replans, the end
    camera                EncodedImage (JPEG), the env's rendered view, where frames are given

Timelines: ``step`` (control steps over the whole run) and ``time`` (seconds within the
episode, at the domain's control rate). Headless: the recording is a stream of its own
(not rerun's global one) into memory, written atomically at ``close``; no viewer is
spawned, nothing is served or connected to, and the SDK used this way starts no usage
analytics and writes nothing under the home folder (tested). The ``rerun`` command-line
viewer does collect analytics unless told ``rerun analytics disable``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from osg_control.domain.base import Domain
from osg_control.domain.contract import SkillEnv
from osg_control.errors import UsageError
from osg_control.io_safety import atomic_write

EXTRA = "viz"
"""The package extra that installs ``rerun-sdk``."""
APP_ID = "osg-control"
STATE_GRIPPER = {"command": 7, "force": 8, "width": 9}
"""The gripper entries of the 10-D state (``environment.arm_env``)."""


def import_rerun() -> Any:
    """The ``rerun`` module.

    Raises:
        UsageError: rerun-sdk is not installed (exit 2), naming the extra.
    """
    try:
        import rerun
    except ImportError as err:
        raise UsageError(
            f"--rerun needs rerun-sdk: pip install 'osg-control[{EXTRA}]' ({err})"
        ) from err
    return rerun


class RunRecorder:
    """Builds one rerun recording of a run's episodes; ``close`` writes it to ``path``."""

    def __init__(self, path: Path, domain: Domain) -> None:
        self.rr = import_rerun()
        self.path = path
        self.domain = domain
        self.stream = self.rr.RecordingStream(APP_ID)
        self.memory = self.stream.memory_recording()
        self.episode = -1
        self.step = 0
        self.episode_step = 0
        self.tcp_path: list[np.ndarray] = []

    def _at(self, name: str) -> str:
        return f"episode_{self.episode}/{name}"

    def _clock(self) -> None:
        self.stream.set_time("step", sequence=self.step)
        self.stream.set_time("time", duration=self.episode_step / self.domain.control_hz)

    def begin_episode(self, env: SkillEnv) -> None:
        """Start a new episode at the env's current (reset) percept."""
        self.episode += 1
        self.episode_step = 0
        self.tcp_path = []
        names = list(self.domain.nodes)
        positions = np.array([self.domain.nodes[n].position for n in names])
        self._clock()
        self.stream.log(self._at("nodes"), self.rr.Points3D(positions, labels=names, radii=0.01))
        self.on_step(env, advance=False)

    def on_step(self, env: SkillEnv, frame: np.ndarray | None = None, advance: bool = True) -> None:
        """Log the percept after an env step (and ``frame``, a rendered RGB image)."""
        if advance:
            self.step += 1
            self.episode_step += 1
        self._clock()
        percept = env.percept()
        state = np.asarray(percept.state, dtype=float)
        self.tcp_path.append(state[:3].copy())
        quat = state[3:7]  # w, x, y, z
        self.stream.log(
            self._at("tcp"),
            self.rr.Transform3D(
                translation=state[:3],
                quaternion=self.rr.Quaternion(xyzw=[*quat[1:], quat[0]]),
            ),
            self.rr.Points3D([state[:3]], radii=0.008),
        )
        self.stream.log(self._at("joints"), self.rr.Scalars(np.asarray(percept.joints)))
        for name, index in STATE_GRIPPER.items():
            self.stream.log(self._at(f"gripper/{name}"), self.rr.Scalars([state[index]]))
        if frame is not None:
            self.stream.log(
                self._at("camera"), self.rr.Image(np.asarray(frame)).compress(jpeg_quality=80)
            )

    def on_event(self, kind: str, fields: dict[str, Any]) -> None:
        """Log one of the executor's events (``Executor.on_event``)."""
        self._clock()
        text, level = _event_text(kind, fields)
        self.stream.log(self._at("events"), self.rr.TextLog(text, level=level))
        if kind == "plan":
            steps = ([fields["entry"]] if fields["entry"] else []) + list(fields["plan"])
            plan = " -> ".join(steps) or "(empty)"
            self.stream.log(self._at("plan"), self.rr.TextDocument(plan))
        elif kind == "skill":
            self.stream.log(self._at("skill"), self.rr.TextDocument(fields["name"]))
            self.stream.log(
                self._at("target"),
                self.rr.Points3D([fields["position"]], labels=[fields["target"]], radii=0.02),
            )
        elif kind == "outcome" and len(self.tcp_path) > 1:
            self.stream.log(self._at("path"), self.rr.LineStrips3D([np.array(self.tcp_path)]))

    def close(self) -> Path:
        """Write the recording to ``path`` (atomically) and return it."""
        if len(self.tcp_path) > 1:
            self.stream.log(self._at("path"), self.rr.LineStrips3D([np.array(self.tcp_path)]))
        self.stream.flush()
        data = self.memory.drain_as_bytes()
        return atomic_write(self.path, lambda tmp: tmp.write_bytes(data))


def _event_text(kind: str, fields: dict[str, Any]) -> tuple[str, str]:
    """An event as one line of text and its log level."""
    if kind == "plan":
        entry = f"entry {fields['entry']}, " if fields["entry"] else ""
        return f"attempt {fields['attempt']}: {entry}plan {' -> '.join(fields['plan'])}", "INFO"
    if kind == "skill":
        return f"skill {fields['name']} -> node {fields['target']}", "INFO"
    if kind == "outcome":
        if fields["success"]:
            return f"{fields['skill']} reached its node in {fields['steps']} steps", "INFO"
        failed = f"{fields['skill']} failed after {fields['steps']} steps"
        return f"{failed}: {fields['failure']}", "WARN"
    if kind == "replan":
        return f"replan {fields['attempt']} after: {fields['failure']}", "WARN"
    if fields.get("success"):
        return f"goal reached after {fields['replans']} replans", "INFO"
    return f"FAILED: {fields.get('failure')}", "ERROR"
