"""Fixtures shared by the test modules."""

from __future__ import annotations

import mujoco
import pytest


@pytest.fixture
def no_physics(monkeypatch: pytest.MonkeyPatch) -> None:
    """Any MuJoCo physics step fails the test: a command refused "before any work" must be
    refused before an episode runs, however loaded the machine is (no timing)."""

    def refuse(*_: object) -> None:
        raise AssertionError("a physics step ran before the command was refused")

    monkeypatch.setattr(mujoco, "mj_step", refuse)
