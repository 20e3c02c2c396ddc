"""Resume merges only chunks that are what their names claim: a foreign file under a
chunk's name (another skill, seed or range, another format, garbage) is discarded with a
warning and recomputed, so the merged data set equals a clean collection. So is a chunk
whose array lost its checksum, was edited, or holds an impossible value."""

from __future__ import annotations

import logging
import shutil
from pathlib import Path

import h5py
import numpy as np
import pytest

from osg_control.data import collect
from osg_control.data.collect import ChunkTask, _run_chunk, collect_skill, parts_dir
from osg_control.data.datasets import CHECKSUM_ATTR, content_sha256, write_episodes
from osg_control.domain.registry import get_domain
from osg_control.kitchen.skills import get_skill

KITCHEN = get_domain("kitchen")

SKILL = get_skill("grab-cube")
EPISODES, CHUNK = 4, 2


def _chunk_path(out: Path, start: int, seed: int = 0) -> Path:
    return parts_dir(out, SKILL) / f"seed{seed}_{start:06d}_{start + CHUNK:06d}.h5"


@pytest.fixture(scope="module")
def clean(tmp_path_factory: pytest.TempPathFactory) -> dict[str, np.ndarray]:
    out = tmp_path_factory.mktemp("clean")
    return collect_skill(
        KITCHEN, SKILL, EPISODES, 0, out, progress=False, chunk_episodes=CHUNK
    ).arrays


def _foreign_other_skill(tmp: Path, target: Path) -> None:
    other = collect_skill(KITCHEN, "move-home-to-cube", CHUNK, 0, tmp / "o", progress=False)
    shutil.copy(other.path, target)


def _foreign_other_seed(tmp: Path, target: Path) -> None:
    collect_skill(KITCHEN, SKILL, CHUNK, 7, tmp / "s", progress=False, chunk_episodes=CHUNK)
    shutil.copy(tmp / "s" / f"{SKILL.name}.h5", target)


def _foreign_other_range(tmp: Path, target: Path) -> None:
    out = tmp / "r"
    collect_skill(KITCHEN, SKILL, EPISODES, 0, out, progress=False, chunk_episodes=CHUNK)
    # the merged file holds episodes 0-3: the right skill and seed, the wrong range
    shutil.copy(out / f"{SKILL.name}.h5", target)


def _foreign_format(tmp: Path, target: Path) -> None:
    _foreign_other_range(tmp, target)
    with h5py.File(target, "a") as f:
        f.attrs["format_version"] = 99


def _garbage(_tmp: Path, target: Path) -> None:
    target.write_bytes(b"\x89HDF\r\n not really")


def _genuine(target: Path) -> None:
    """The chunk an interrupted run would have kept at ``target`` (episodes 2-3)."""
    task = ChunkTask(KITCHEN.name, SKILL, 0, CHUNK, 2 * CHUNK, target)
    write_episodes(
        target, _run_chunk(task), {**collect._attrs(KITCHEN, SKILL, 0), **collect._identity(task)}
    )


def _checksum_stripped(_tmp: Path, target: Path) -> None:
    _genuine(target)
    with h5py.File(target, "a") as f:
        del f["rewards"].attrs[CHECKSUM_ATTR]


def _reward_flipped(_tmp: Path, target: Path) -> None:
    _genuine(target)
    with h5py.File(target, "a") as f:
        f["rewards"][0] = 1.0 - f["rewards"][0]


def _impossible_reward_resealed(_tmp: Path, target: Path) -> None:
    _genuine(target)
    with h5py.File(target, "a") as f:
        f["rewards"][0] = 7.0
        f["rewards"].attrs[CHECKSUM_ATTR] = content_sha256(f["rewards"][()])


@pytest.mark.parametrize(
    ("plant", "reason"),
    [
        (_foreign_other_skill, "another spec"),
        (_foreign_other_seed, "seed 7"),
        (_foreign_other_range, "chunk_start"),
        (_foreign_format, "format version 99"),
        (_garbage, "not a readable HDF5"),
        (_checksum_stripped, "'rewards' lacks its sha256 content checksum"),
        (_reward_flipped, "'rewards' does not match its sha256"),
        (_impossible_reward_resealed, "rewards"),
    ],
)
def test_foreign_chunk_is_discarded_and_recomputed(plant, reason, clean, tmp_path, caplog):
    out = tmp_path / "data"
    target = _chunk_path(out, CHUNK)
    target.parent.mkdir(parents=True)
    plant(tmp_path, target)
    with caplog.at_level(logging.WARNING, logger="osg_control.data.chunks"):
        merged = collect_skill(
            KITCHEN, SKILL, EPISODES, 0, out, progress=False, chunk_episodes=CHUNK
        )
    assert f"{target}: discarded" in caplog.text and reason in caplog.text
    for key, value in clean.items():
        np.testing.assert_array_equal(merged.arrays[key], value, err_msg=key)


def test_genuine_chunks_are_kept(clean, tmp_path, caplog, monkeypatch):
    out = tmp_path / "data"
    first = ChunkTask(KITCHEN.name, SKILL, 0, 0, CHUNK, _chunk_path(out, 0))
    attrs = {**collect._attrs(KITCHEN, SKILL, 0), **collect._identity(first)}
    write_episodes(first.path, _run_chunk(first), attrs)  # an interrupted run's chunk
    ran: list[int] = []
    original = collect._run_chunk
    monkeypatch.setattr(
        collect, "_run_chunk", lambda task: (ran.append(task.start), original(task))[1]
    )
    with caplog.at_level(logging.WARNING):
        again = collect_skill(
            KITCHEN, SKILL, EPISODES, 0, out, progress=False, chunk_episodes=CHUNK
        )
    assert "discarded" not in caplog.text
    assert ran == [CHUNK]  # only the missing chunk was computed
    for key, value in clean.items():
        np.testing.assert_array_equal(again.arrays[key], value, err_msg=key)
