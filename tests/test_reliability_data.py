"""Data-set writers and readers under hostile input and hostile disks: a refused import,
collection or write leaves every existing file byte-identical; Minari metadata and arrays
are checked (field, episode, step and bound named); a full disk is refused up front where
the output's size is known, and mid-write it is a named error that keeps finished chunks;
a flipped bit inside a stored array is detected by its content checksum."""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import json
import os
import shutil
import subprocess
import sys
from collections.abc import Callable, Iterator
from pathlib import Path

import h5py
import numpy as np
import pytest

from osg_control.cli import main
from osg_control.data.collect import collect_skill
from osg_control.data.datasets import CHECKSUM_ATTR, Episode, load_dataset, write_episodes
from osg_control.data.minari_export import export_minari
from osg_control.data.minari_import import import_minari
from osg_control.domain.registry import get_domain
from osg_control.errors import EXIT_CODES, DatasetError, OutputError
from osg_control.learning.td3bc import TD3BCConfig
from osg_control.pipeline.collect import collection_bytes
from osg_control.pipeline.train import checkpoint_bytes
from tests.datagen import chained_dataset, write_synthetic_dataset
from tests.filesystems import tmpfs

KITCHEN = get_domain("kitchen")
FAILURE = EXIT_CODES["failure"]
FAST_SKILL = "move-home-to-door"
"""A skill whose scripted episodes are short (about 10 steps): cheap to collect."""


def _tree_hashes(root: Path) -> dict[str, str]:
    """sha256 of every file under ``root``, by relative path."""
    return {
        str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(root.rglob("*"))
        if p.is_file()
    }


@pytest.fixture(scope="module")
def minari_source(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A pristine Minari data set (two episodes of grab-cube); copy it before editing."""
    tmp = tmp_path_factory.mktemp("minari")
    data = chained_dataset(tmp / "grab-cube.h5")
    return export_minari(data, "osg/grab-cube-v0", KITCHEN, tmp / "root")


def _edit_h5(edit: Callable[[h5py.File], object]) -> Callable[[Path], None]:
    """An edit of a Minari data set's ``main_data.hdf5``."""

    def apply(data_dir: Path) -> None:
        with h5py.File(data_dir / "main_data.hdf5", "a") as f:
            edit(f)

    return apply


def _edit_metadata(edit: Callable[[dict], object]) -> Callable[[Path], None]:
    """An edit of a Minari data set's ``metadata.json`` (as a dict)."""

    def apply(data_dir: Path) -> None:
        path = data_dir / "metadata.json"
        metadata = json.loads(path.read_text())
        edit(metadata)
        path.write_text(json.dumps(metadata))

    return apply


def _set_cell(key: str, index: tuple[int, ...], value: float) -> Callable[[Path], None]:
    """An edit setting one element of the Minari data set ``key``."""

    def edit(f: h5py.File) -> None:
        f[key][index] = value

    return _edit_h5(edit)


def _string_rewards(f: h5py.File) -> None:
    """Episode 0's rewards as byte strings."""
    steps = len(f["episode_0/rewards"])
    del f["episode_0/rewards"]
    f["episode_0/rewards"] = np.array([b"1.0"] * steps)


def _no_episodes(f: h5py.File) -> None:
    """Remove every episode group."""
    for name in list(f):
        del f[name]


def _no_steps(f: h5py.File) -> None:
    """Cut episode 0 to zero steps (one observation, empty step arrays)."""
    group = f["episode_0"]
    for key, keep in [("observations", 1), ("actions", 0), ("rewards", 0), ("terminations", 0),
                      ("truncations", 0), ("infos/world_states", 0)]:  # fmt: skip
        value = group[key][:keep]
        del group[key]
        group[key] = value


def _write_text(text: str) -> Callable[[Path], None]:
    """An edit replacing ``metadata.json`` by ``text``."""

    def apply(data_dir: Path) -> None:
        (data_dir / "metadata.json").write_text(text)

    return apply


BAD_IMPORTS = [
    (
        "NaN observation",
        _set_cell("episode_0/observations", (1, 2), np.nan),
        ["main_data.hdf5:episode_0", "'observations'", "non-finite", "step 1"],
    ),
    (
        "inf action",
        _set_cell("episode_1/actions", (3, 0), np.inf),
        ["main_data.hdf5:episode_1", "'actions'", "non-finite", "step 3"],
    ),
    (
        "action outside the bounds",
        _set_cell("episode_0/actions", (2, 1), 0.5),
        ["main_data.hdf5:episode_0", "'actions'", "step 2", "component 1", "[-0.02, 0.02]"],
    ),
    (
        "NaN reward",
        _set_cell("episode_1/rewards", (0,), np.nan),
        ["main_data.hdf5:episode_1", "'rewards'", "non-finite", "step 0"],
    ),
    (
        "NaN world state",
        _set_cell("episode_0/infos/world_states", (0, 4), np.nan),
        ["main_data.hdf5:episode_0", "'infos/world_states'", "non-finite"],
    ),
    (
        "string rewards",
        _edit_h5(_string_rewards),
        ["main_data.hdf5:episode_0", "'rewards'", "dtype"],
    ),
    ("no episodes", _edit_h5(_no_episodes), ["main_data.hdf5", "no episodes"]),
    ("an episode without steps", _edit_h5(_no_steps), ["main_data.hdf5:episode_0", "no steps"]),
    (
        "malformed metadata.json",
        _write_text('{"dataset_id": '),
        ["metadata.json", "not a readable JSON file"],
    ),
    ("metadata.json not an object", _write_text("[1, 2]"), ["metadata.json", "JSON object"]),
    (
        "string seed",
        _edit_metadata(lambda m: m.__setitem__("osg_seed", "7")),
        ["metadata.json", "'osg_seed'", "'7'"],
    ),
    (
        "negative seed",
        _edit_metadata(lambda m: m.__setitem__("osg_seed", -3)),
        ["metadata.json", "'osg_seed'", "-3"],
    ),
    (
        "space not an object",
        _edit_metadata(lambda m: m.__setitem__("action_space", "[7]")),
        ["metadata.json", "'action_space'"],
    ),
    (
        "space without a shape",
        _edit_metadata(lambda m: m.__setitem__("observation_space", json.dumps({"type": "Box"}))),
        ["metadata.json", "'observation_space'", "shape"],
    ),
]
"""(case, edit of the Minari source folder, what the error must say)."""


@pytest.mark.parametrize(
    ("edit", "expected"), [c[1:] for c in BAD_IMPORTS], ids=[c[0] for c in BAD_IMPORTS]
)
def test_a_refused_import_leaves_the_existing_file_byte_identical(
    edit, expected, minari_source, tmp_path, capsys
):
    out_dir = tmp_path / "D"
    target = out_dir / "grab-cube.h5"
    source = shutil.copytree(minari_source, tmp_path / "src")
    argv = ["datasets", "import", str(source), "--skill", "grab-cube", "--out", str(target)]
    assert main(argv) == 0  # a good data set is there first
    before = _tree_hashes(out_dir)
    edit(source / "data")
    capsys.readouterr()
    assert main(argv) == FAILURE
    err = capsys.readouterr().err
    assert "Traceback" not in err and "internal error" not in err, err
    for part in expected:
        assert part in err, (part, err)
    assert _tree_hashes(out_dir) == before


BOUNDS = [
    ("kitchen", 0.02, True),
    ("kitchen", 0.0201, False),
    ("franka-kitchen", 0.04, True),
    ("franka-kitchen", 0.05, False),
]


@pytest.mark.parametrize(("domain", "value", "accepted"), BOUNDS)
def test_import_checks_actions_against_the_domains_bounds(
    domain, value, accepted, minari_source, tmp_path
):
    dom = get_domain(domain)
    source = shutil.copytree(minari_source, tmp_path / "src")
    with h5py.File(source / "data" / "main_data.hdf5", "a") as f:
        for name in f:
            del f[name]["infos"]  # the kitchen's world states do not fit another domain
        f["episode_1/actions"][2, 0] = np.float32(value)
    metadata = json.loads((source / "data" / "metadata.json").read_text())
    del metadata["osg_skill"]  # recorded elsewhere: imported as another skill on purpose
    (source / "data" / "metadata.json").write_text(json.dumps(metadata))
    skill = dom.skills[0].name
    out = tmp_path / f"{skill}.h5"
    if accepted:
        imported = import_minari(dom, source, skill, out)
        assert float(imported.episode(1).actions[2, 0]) == np.float32(value)
        return
    bound = f"[-{dom.action_bounds[0]:g}, {dom.action_bounds[0]:g}]"
    with pytest.raises(
        DatasetError, match=r"episode_1: field 'actions' at step 2, component 0"
    ) as err:
        import_minari(dom, source, skill, out)
    assert bound in str(err.value) and not out.exists()


def _with(episode: Episode, key: str, transform: Callable[[np.ndarray], np.ndarray]) -> Episode:
    """``episode`` with field ``key`` transformed (on a copy)."""
    return dataclasses.replace(episode, **{key: transform(getattr(episode, key).copy())})


def _poke(index: tuple[int, ...], value: float) -> Callable[[np.ndarray], np.ndarray]:
    """A transform setting one element."""

    def transform(array: np.ndarray) -> np.ndarray:
        array[index] = value
        return array

    return transform


BAD_EPISODES = [
    ("observations", _poke((2, 0), np.nan)),
    ("next_observations", _poke((0, 9), -np.inf)),
    ("actions", _poke((1, 6), np.nan)),
    ("world_states", _poke((3, 3), np.inf)),
    ("rewards", _poke((0,), 0.5)),
    ("terminations", lambda a: ~a),
]


@pytest.mark.parametrize(("field", "transform"), BAD_EPISODES)
def test_every_write_validates_in_memory_before_touching_the_file(field, transform, tmp_path):
    path = write_synthetic_dataset(tmp_path / "grab-cube.h5")
    before = _tree_hashes(tmp_path)
    good = load_dataset(path)
    bad = [_with(good.episode(0), field, transform), good.episode(1)]
    with pytest.raises(DatasetError) as err:
        write_episodes(path, bad, good.attrs)
    assert str(path) in str(err.value) and f"'{field}'" in str(err.value)
    assert _tree_hashes(tmp_path) == before


def _flip_a_bit(path: Path, key: str) -> None:
    """Flip the lowest bit of the first byte of data set ``key``'s stored array."""
    with h5py.File(path, "r") as f:
        offset = f[key].id.get_offset()
    assert offset is not None, f"{key} is not stored contiguously"
    data = bytearray(path.read_bytes())
    data[offset] ^= 0x01
    path.write_bytes(bytes(data))


@pytest.mark.parametrize(
    "key",
    ["observations", "next_observations", "actions", "world_states", "episode_lengths"],
)
def test_a_flipped_bit_inside_a_stored_array_is_detected(key, tmp_path, capsys):
    path = write_synthetic_dataset(tmp_path / "grab-cube.h5")
    _flip_a_bit(path, key)
    with pytest.raises(DatasetError, match="checksum") as err:
        load_dataset(path)
    assert str(path) in str(err.value) and f"'{key}'" in str(err.value)
    assert main(["datasets", "info", str(path)]) == FAILURE
    assert "checksum" in capsys.readouterr().out


def test_a_file_without_checksums_still_loads(tmp_path):
    path = write_synthetic_dataset(tmp_path / "grab-cube.h5")
    stamped = load_dataset(path)
    with h5py.File(path, "a") as f:  # as written before the checksums existed
        for key in f:
            del f[key].attrs[CHECKSUM_ATTR]
    unstamped = load_dataset(path)
    for key, array in stamped.arrays.items():
        np.testing.assert_array_equal(unstamped.arrays[key], array)


@pytest.mark.parametrize("field", ["observations", "rewards", "episode_successes"])
def test_an_array_stripped_of_its_checksum_beside_checksummed_ones_is_refused(tmp_path, field):
    path = write_synthetic_dataset(tmp_path / "grab-cube.h5")
    with h5py.File(path, "a") as f:
        del f[field].attrs[CHECKSUM_ATTR]
    with pytest.raises(DatasetError, match=f"{field!r} lacks its sha256 content checksum"):
        load_dataset(path)


def _short_of(needed: int, by: int) -> Callable[[str], shutil._ntuple_diskusage]:
    """A ``shutil.disk_usage`` reporting ``needed - by`` bytes free (the rest is real)."""
    real = shutil.disk_usage

    def usage(path: str) -> shutil._ntuple_diskusage:
        return real(path)._replace(free=needed - by)

    return usage


def _collect_argv(tmp: Path, out: Path) -> list[str]:
    """``osg collect`` of three short episodes into ``out``."""
    return [
        "collect",
        "--skill",
        FAST_SKILL,
        "--episodes",
        "3",
        "--workers",
        "1",
        "--out",
        str(out),
    ]


def _train_argv(tmp: Path, out: Path) -> list[str]:
    """``osg train`` of two updates on a synthetic data set, into ``out``."""
    write_synthetic_dataset(tmp / "data" / "grab-cube.h5")
    return [
        "train",
        "--skill",
        "grab-cube",
        "--steps",
        "2",
        "--data",
        str(tmp / "data"),
        "--out",
        str(out),
    ]


SIZED_COMMANDS = {
    "collect": (_collect_argv, lambda: collection_bytes(KITCHEN, [(KITCHEN.skill(FAST_SKILL), 3)])),
    "train": (_train_argv, lambda: checkpoint_bytes(TD3BCConfig(), 1)),
}
"""Commands whose output size is known up front: (argv, the bytes they need)."""


@pytest.mark.parametrize("short_by", [1, 0], ids=["one byte short", "just enough"])
@pytest.mark.parametrize("command", list(SIZED_COMMANDS))
def test_the_free_space_is_checked_up_front_against_the_output_size(
    command, short_by, tmp_path, monkeypatch, capsys
):
    argv_of, needed = SIZED_COMMANDS[command]
    out = tmp_path / "out"
    out.mkdir()
    (out / "kept.txt").write_text("an earlier file\n")
    argv = argv_of(tmp_path, out)
    before = _tree_hashes(out)
    monkeypatch.setattr(shutil, "disk_usage", _short_of(needed(), short_by))
    code = main(argv)
    err = capsys.readouterr().err
    if short_by == 0:
        assert code == 0, err
        return
    assert code == FAILURE
    assert str(out) in err and "free space" in err and "Traceback" not in err, err
    assert _tree_hashes(out) == before


def test_the_size_estimates_bound_what_is_written(tmp_path):
    skill = KITCHEN.skill(FAST_SKILL)
    data = collect_skill(KITCHEN, skill, 4, 0, tmp_path, progress=False)
    # the merged file and the chunks of the skill in progress exist together
    assert 2 * data.path.stat().st_size <= collection_bytes(KITCHEN, [(skill, 4)])
    shipped = KITCHEN.defaults_dir / "skills"
    for weights in shipped.glob("*.safetensors"):
        written = weights.stat().st_size + weights.with_suffix(".json").stat().st_size
        assert written <= checkpoint_bytes(TD3BCConfig(), 1) <= 1.1 * written, weights.name


FULL_DISK_COLLECT = """
import sys
from pathlib import Path
from osg_control.data.collect import collect_skill
from osg_control.domain.registry import get_domain
from osg_control.errors import OutputError
try:
    collect_skill(get_domain("kitchen"), sys.argv[1], 30, 0, Path(sys.argv[2]), None, False, 3)
except OutputError as err:
    print(err)
    sys.exit(1)
"""


@pytest.mark.slow
def test_a_disk_filling_up_mid_collection_is_named_and_keeps_finished_chunks(tmp_path):
    with tmpfs(tmp_path / "disk", "size=48k") as disk:
        kept = write_synthetic_dataset(disk / "grab-cube.h5", episodes=1)
        before = _tree_hashes(disk)
        done = subprocess.run(
            [sys.executable, "-c", FULL_DISK_COLLECT, FAST_SKILL, str(disk)],
            capture_output=True,
            text=True,
            timeout=120,
            env={**os.environ, "PYTHONPATH": str(Path.cwd())},
            check=False,
        )
        chunks = sorted((disk / ".parts" / FAST_SKILL).glob("*.h5"))
        assert done.returncode == 1, (done.returncode, done.stderr[-2000:])  # not 139
        assert "No space left on device" in done.stdout and str(disk / ".parts") in done.stdout
        assert "Traceback" not in done.stderr, done.stderr  # none as h5py's objects are freed
        assert chunks and all(load_dataset(c).num_episodes == 3 for c in chunks)
        assert not (disk / f"{FAST_SKILL}.h5").exists()
        assert _tree_hashes(disk)[kept.name] == before[kept.name]


@contextlib.contextmanager
def _read_only(folder: Path, fill: Callable[[Path], object]) -> Iterator[Path]:
    """``folder`` holding what ``fill`` put there, then made read-only: a tmpfs remounted
    read-only where we are root (root writes through file modes), else mode 0555."""
    if os.geteuid() != 0:
        folder.mkdir()
        fill(folder)
        folder.chmod(0o555)
        try:
            yield folder
        finally:
            folder.chmod(0o755)
        return
    with tmpfs(folder, "size=4m") as mount:
        fill(mount)
        subprocess.run(["mount", "-o", "remount,ro", str(mount)], check=True)
        yield mount


def _import(ro: Path, source: Path) -> int:
    """``osg datasets import`` over the folder's grab-cube.h5."""
    return main(
        [
            "datasets",
            "import",
            str(source),
            "--skill",
            "grab-cube",
            "--out",
            str(ro / "grab-cube.h5"),
        ]
    )


def _export(ro: Path, _source: Path) -> int:
    """``osg datasets minari --force`` over the folder's Minari data set."""
    data = chained_dataset(ro.parent / "data" / "grab-cube.h5")
    return main(
        [
            "datasets",
            "minari",
            str(data),
            "--id",
            "osg/grab-cube-v0",
            "--out",
            str(ro / "minari"),
            "--force",
        ]
    )


def _collect(ro: Path, _source: Path) -> int:
    """``osg collect`` into the folder."""
    return main(["collect", "--skill", "grab-cube", "--episodes", "2", "--out", str(ro)])


def _collect_save_path(ro: Path, _source: Path) -> int:
    """``collect_skill`` itself, past the command's up-front folder check."""
    collect_skill(KITCHEN, FAST_SKILL, 2, 0, ro, progress=False)
    return 0


READ_ONLY_WRITERS = {
    "datasets import": _import,
    "datasets minari": _export,
    "collect": _collect,
    "collect's save path": _collect_save_path,
}


@pytest.mark.parametrize("writer", list(READ_ONLY_WRITERS))
def test_every_data_writer_on_a_read_only_folder_is_named_and_changes_nothing(
    writer, minari_source, tmp_path, capsys
):
    def fill(folder: Path) -> None:
        write_synthetic_dataset(folder / "grab-cube.h5")
        write_synthetic_dataset(folder / f"{FAST_SKILL}.h5", skill=FAST_SKILL)
        shutil.copytree(minari_source, folder / "minari" / "osg" / "grab-cube-v0")

    with _read_only(tmp_path / "ro", fill) as ro:
        before = _tree_hashes(ro)
        capsys.readouterr()
        try:
            code, message = READ_ONLY_WRITERS[writer](ro, minari_source), capsys.readouterr().err
        except OutputError as err:
            code, message = FAILURE, str(err)
        after = _tree_hashes(ro)
    assert code == FAILURE, message
    assert str(ro) in message and "Traceback" not in message, message
    assert after == before
