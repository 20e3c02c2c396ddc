"""Property tests over every loader of a user file (data sets, skill checkpoints, classifier
checkpoints): whatever the bytes, each input either loads or raises the package's error type
naming the file, never anything else. Seeded (derandomised) and small, so quick in CI."""

from __future__ import annotations

import json
import shutil
import tempfile
from pathlib import Path

import h5py
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_td3bc import toy_checkpoint, toy_data, train

from osg_control.classifier.model import SIDECAR_FILE, WEIGHTS_FILE, StateClassifier
from osg_control.data.datasets import STEP_FIELDS, load_dataset
from osg_control.domain.registry import get_domain
from osg_control.errors import CheckpointError, DatasetError
from osg_control.learning.checkpoints import checkpoint_paths, load_checkpoint, save_checkpoint
from tests.datagen import write_synthetic_dataset

KITCHEN = get_domain("kitchen")

SETTINGS = settings(
    derandomize=True,
    max_examples=40,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
FIELDS = [*STEP_FIELDS, "episode_starts", "episode_lengths", "episode_successes"]
ARRAYS = st.one_of(
    st.lists(st.floats(allow_nan=True, allow_infinity=True), max_size=12).map(
        lambda v: np.asarray(v, dtype=np.float64)
    ),
    st.lists(st.integers(-5, 50), max_size=12).map(lambda v: np.asarray(v, dtype=np.int64)),
    st.lists(st.booleans(), max_size=12).map(lambda v: np.asarray(v, dtype=bool)),
    st.integers(1, 4).map(lambda n: np.zeros((n, 3, 2), dtype=np.float32)),
    st.text(max_size=5).map(lambda t: np.bytes_(t.encode())),
)
JSON_VALUES = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=8),
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=6), inner),
    max_leaves=10,
)


@pytest.fixture(scope="module")
def scratch(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """One folder per module under pytest's temp root, which pytest prunes (last 3 runs kept),
    so the hundreds of examples leave nothing behind in the system temp folder."""
    return tmp_path_factory.mktemp("prop")


def _workdir(scratch: Path) -> Path:
    return Path(tempfile.mkdtemp(prefix="example-", dir=scratch))


def _must_load_or_name(path: Path, load, error) -> None:
    try:
        load()
    except error as err:
        assert str(path) in str(err)


@pytest.fixture(scope="module")
def valid_dataset(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_synthetic_dataset(tmp_path_factory.mktemp("d") / "grab-cube.h5")


@SETTINGS
@given(
    edits=st.lists(st.tuples(st.sampled_from(FIELDS), st.none() | ARRAYS), max_size=3),
    attrs=st.dictionaries(st.sampled_from(["skill", "seed", "format_version"]), JSON_VALUES),
)
def test_hdf5_data_set_loads_or_is_named(scratch, valid_dataset, edits, attrs) -> None:
    path = _workdir(scratch) / "grab-cube.h5"
    shutil.copy(valid_dataset, path)
    with h5py.File(path, "a") as f:
        for key, value in edits:
            if key in f:
                del f[key]
            if value is not None:
                f.create_dataset(key, data=value)
        for key, value in attrs.items():
            f.attrs[key] = json.dumps(value) if key == "skill" else str(value)
    _must_load_or_name(path, lambda: load_dataset(path), DatasetError)


@SETTINGS
@given(data=st.binary(max_size=300), keep=st.integers(0, 4000))
def test_arbitrary_bytes_as_data_set_are_named(scratch, valid_dataset, data, keep) -> None:
    path = _workdir(scratch) / "grab-cube.h5"
    path.write_bytes(valid_dataset.read_bytes()[:keep] + data)
    _must_load_or_name(path, lambda: load_dataset(path), DatasetError)


@pytest.fixture(scope="module")
def saved_skill(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str]:
    root = tmp_path_factory.mktemp("ckpt")
    data = toy_data(root)
    checkpoint = toy_checkpoint(train([data], [0], steps=2), data, steps=2, seed=0)
    save_checkpoint(root / "skills", checkpoint)
    return root / "skills", checkpoint.skill.name


@SETTINGS
@given(
    changes=st.dictionaries(
        st.sampled_from(
            [
                "format_version",
                "obs_dim",
                "action_dim",
                "hidden_sizes",
                "obs_mean",
                "obs_std",
                "action_scale",
                "skill_spec",
                "train_config",
                "steps",
                "seed",
                "weights_sha256",
            ]
        ),
        JSON_VALUES,
        max_size=3,
    ),
    drop=st.booleans(),
)
def test_skill_sidecar_loads_or_is_named(scratch, saved_skill, changes, drop) -> None:
    source, name = saved_skill
    directory = Path(shutil.copytree(source, _workdir(scratch) / "skills"))
    _weights, sidecar_path = checkpoint_paths(directory, name)
    sidecar = json.loads(sidecar_path.read_text())
    for key, value in changes.items():
        if drop:
            sidecar.pop(key, None)
        else:
            sidecar[key] = value
    sidecar_path.write_text(json.dumps(sidecar))

    def load() -> None:
        load_checkpoint(directory, name)

    try:
        load()
    except CheckpointError as err:
        assert str(directory) in str(err)


@SETTINGS
@given(data=st.binary(max_size=400), keep=st.integers(0, 2000), file=st.sampled_from([0, 1]))
def test_skill_checkpoint_bytes_load_or_are_named(scratch, saved_skill, data, keep, file) -> None:
    source, name = saved_skill
    directory = Path(shutil.copytree(source, _workdir(scratch) / "skills"))
    path = checkpoint_paths(directory, name)[file]
    path.write_bytes(path.read_bytes()[:keep] + data)
    _must_load_or_name(path, lambda: load_checkpoint(directory, name), CheckpointError)


@pytest.fixture(scope="module")
def saved_classifier(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from test_classifier import FAST, write_movement_datasets

    from osg_control.classifier.data import load_classifier_data, movement_classes
    from osg_control.classifier.train import train_classifier

    root = tmp_path_factory.mktemp("clf")
    write_movement_datasets(root / "data")
    data = load_classifier_data(root / "data", movement_classes(KITCHEN), 0)
    model = train_classifier(data, FAST)
    model.save(root / "clf")
    return root / "clf"


@pytest.mark.slow
@SETTINGS
@given(
    changes=st.dictionaries(
        st.sampled_from(["format", "format_version", "classes", "normalisation", "weights_sha256"]),
        JSON_VALUES,
        max_size=3,
    ),
    data=st.binary(max_size=200),
    keep=st.integers(0, 3000),
    corrupt_weights=st.booleans(),
)
def test_classifier_files_load_or_are_named(
    scratch, saved_classifier, changes, data, keep, corrupt_weights
) -> None:
    directory = Path(shutil.copytree(saved_classifier, _workdir(scratch) / "clf"))
    sidecar_path = directory / SIDECAR_FILE
    sidecar = json.loads(sidecar_path.read_text())
    sidecar.update(changes)
    sidecar_path.write_text(json.dumps(sidecar))
    if corrupt_weights:
        weights = directory / WEIGHTS_FILE
        weights.write_bytes(weights.read_bytes()[:keep] + data)
    try:
        StateClassifier.load(directory)
    except CheckpointError as err:
        assert str(directory) in str(err)
