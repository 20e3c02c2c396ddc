"""State->skill classifier: data split, training, metrics, class order, checkpoint, CLI."""

from __future__ import annotations

import dataclasses
import hashlib
import itertools
import json
from pathlib import Path

import numpy as np
import pytest

from osg_control.classifier.data import (
    ClassifierData,
    class_order,
    class_starts,
    dataset_path,
    load_classifier_data,
    movement_classes,
)
from osg_control.classifier.metrics import (
    accuracy,
    confusion_matrix,
    corrected_accuracy,
    format_report,
    nearest_node_predict,
)
from osg_control.classifier.model import (
    SIDECAR_FILE,
    WEIGHTS_FILE,
    StateClassifier,
    evaluate,
    reload_split,
)
from osg_control.classifier.train import PAPER_CONFIG, TrainConfig, train_classifier
from osg_control.cli import main
from osg_control.data.datasets import Episode, write_episodes
from osg_control.domain.registry import get_domain
from osg_control.domain.spaces import ACTION_DIM, OBS_DIM
from osg_control.errors import CheckpointError, DatasetError
from osg_control.execution.defaults import load_defaults
from osg_control.kitchen.skills import (
    MOVEMENT_SKILLS,
    NODES,
    SKILLS,
    TOP_DOWN_QUAT,
    SkillSpec,
    get_skill,
)
from osg_control.kitchen.world import WORLD_FIELDS

WORLD = ",".join(WORLD_FIELDS)
KITCHEN = get_domain("kitchen")

EPISODES = 20
STEPS = 25
FAST = TrainConfig(epochs=20, batch_size=64, seed=0, validation_fraction=0.0)


def _episode(skill: SkillSpec, rng: np.random.Generator, t_range: tuple[float, float]) -> Episode:
    """States along the skill's start->end segment (fraction ``t_range``) with 5 mm noise."""
    start = np.array(NODES[skill.start].position)
    end = np.array(NODES[skill.end].position)
    t = np.linspace(*t_range, STEPS + 1)[:, None]
    states = np.zeros((STEPS + 1, OBS_DIM), dtype=np.float32)
    states[:, :3] = start + t * (end - start) + rng.normal(0.0, 0.005, (STEPS + 1, 3))
    states[:, 3:7] = TOP_DOWN_QUAT
    states[:, 9] = 0.08
    rewards = np.zeros(STEPS, dtype=np.float32)
    rewards[-1] = 1.0
    return Episode(
        observations=states[:-1],
        next_observations=states[1:],
        actions=np.zeros((STEPS, ACTION_DIM), dtype=np.float32),
        rewards=rewards,
        terminations=rewards > 0,
        truncations=np.zeros(STEPS, dtype=bool),
        world_states=np.zeros((STEPS, 11), dtype=np.float32),
    )


def write_movement_datasets(
    data_dir: Path, t_range: tuple[float, float] = (0.25, 0.5), seed: int = 0
) -> None:
    """One synthetic data set per movement skill; the default range keeps them separable."""
    rng = np.random.default_rng(seed)
    for name in MOVEMENT_SKILLS:
        skill = get_skill(name)
        episodes = [_episode(skill, rng, t_range) for _ in range(EPISODES)]
        write_episodes(
            dataset_path(data_dir, name),
            episodes,
            {"skill": skill.to_json(), "seed": 0, "world_fields": WORLD},
        )


@pytest.fixture(scope="module")
def data_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("movement-data")
    write_movement_datasets(path)
    return path


@pytest.fixture(scope="module")
def data(data_dir: Path) -> ClassifierData:
    return load_classifier_data(data_dir, movement_classes(KITCHEN), seed=0)


@pytest.fixture(scope="module")
def model(data: ClassifierData) -> StateClassifier:
    return train_classifier(data, FAST)


def _shares_node(a: SkillSpec, b: SkillSpec) -> bool:
    return bool({a.start, a.end} & {b.start, b.end})


def _sharing_pairs(order: list[str] | tuple[SkillSpec, ...]) -> int:
    skills = [get_skill(s) if isinstance(s, str) else s for s in order]
    return sum(_shares_node(a, b) for a, b in itertools.pairwise(skills))


# --- data ---------------------------------------------------------------------------------


def test_split_is_by_episode_and_seeded(data_dir: Path, data: ClassifierData) -> None:
    held_out = round(EPISODES * 0.2)
    assert len(data.test) == len(MOVEMENT_SKILLS) * held_out * STEPS
    assert len(data.train) == len(MOVEMENT_SKILLS) * (EPISODES - held_out) * STEPS
    assert np.bincount(data.test.labels).tolist() == [held_out * STEPS] * len(MOVEMENT_SKILLS)
    again = load_classifier_data(data_dir, movement_classes(KITCHEN), seed=0)
    np.testing.assert_array_equal(again.test.observations, data.test.observations)
    other = load_classifier_data(data_dir, movement_classes(KITCHEN), seed=1)
    assert not np.array_equal(other.test.observations, data.test.observations)
    assert set(data.sha256) == set(MOVEMENT_SKILLS)
    # a skill's held-out episodes do not depend on the class order
    reordered = load_classifier_data(data_dir, movement_classes(KITCHEN)[::-1], seed=0)
    assert sorted(map(tuple, reordered.test.observations.tolist())) == sorted(
        map(tuple, data.test.observations.tolist())
    )
    with pytest.raises(ValueError, match="seed must be non-negative"):
        load_classifier_data(data_dir, movement_classes(KITCHEN), seed=-1)


def test_validation_split_is_drawn_from_training_episodes_only(
    data_dir: Path, data: ClassifierData
) -> None:
    split = load_classifier_data(
        data_dir, movement_classes(KITCHEN), seed=0, validation_fraction=0.25
    )
    np.testing.assert_array_equal(split.test.observations, data.test.observations)
    held_out = round(EPISODES * 0.2)
    validation = round((EPISODES - held_out) * 0.25)
    assert len(split.validation) == len(MOVEMENT_SKILLS) * validation * STEPS
    assert len(split.train) + len(split.validation) == len(data.train)
    rows = {tuple(row) for row in data.train.observations.tolist()}
    train_rows = {tuple(row) for row in split.train.observations.tolist()}
    validation_rows = {tuple(row) for row in split.validation.observations.tolist()}
    assert validation_rows <= rows and not validation_rows & train_rows
    assert len(data.validation) == 0
    with pytest.raises(ValueError, match=r"validation_fraction must be in \[0, 1\)"):
        load_classifier_data(data_dir, movement_classes(KITCHEN), seed=0, validation_fraction=1.0)


def test_validation_split_needs_two_training_episodes(tmp_path: Path, data_dir: Path) -> None:
    name = movement_classes(KITCHEN)[0]
    episodes = [_episode(get_skill(name), np.random.default_rng(i), (0.25, 0.5)) for i in range(2)]
    write_episodes(
        dataset_path(tmp_path, name),
        episodes,
        {"skill": get_skill(name).to_json(), "seed": 0, "world_fields": WORLD},
    )
    load_classifier_data(tmp_path, [name], seed=0)  # no validation split: 1 train, 1 test
    with pytest.raises(DatasetError, match=f"{name}.h5: 1 training episode"):
        load_classifier_data(tmp_path, [name], seed=0, validation_fraction=0.2)


def test_missing_or_mislabelled_data_set_is_named(tmp_path: Path, data_dir: Path) -> None:
    with pytest.raises(
        DatasetError, match=f"{movement_classes(KITCHEN)[0]}.h5: data set file not found"
    ):
        load_classifier_data(tmp_path, movement_classes(KITCHEN), seed=0)
    (tmp_path / "move-home-to-door.h5").write_bytes(
        dataset_path(data_dir, "move-home-to-cube").read_bytes()
    )
    with pytest.raises(DatasetError, match="records skill 'move-home-to-cube'"):
        load_classifier_data(tmp_path, ["move-home-to-door"], seed=0)


# --- training and prediction --------------------------------------------------------------


def test_training_separates_synthetic_skills(model: StateClassifier, data: ClassifierData) -> None:
    report = evaluate(model, data.test, class_starts(KITCHEN, model.classes))
    assert report.accuracy >= 0.95
    assert report.corrected_accuracy >= report.accuracy
    losses = model.info["training"]["epoch_losses"]
    assert len(losses) == FAST.epochs and losses[-1] < losses[0]


@pytest.mark.slow
def test_the_epoch_with_the_best_validation_score_is_kept(tmp_path: Path) -> None:
    write_movement_datasets(tmp_path, t_range=(0.0, 1.0))  # overlapping: no epoch is perfect
    config = dataclasses.replace(FAST, epochs=6, validation_fraction=0.25)
    split = load_classifier_data(
        tmp_path, movement_classes(KITCHEN), seed=0, validation_fraction=0.25
    )
    kept = train_classifier(split, config)
    record = kept.info["training"]
    scores = record["validation_corrected_accuracy"]
    assert len(scores) == 6 and record["validation_states"] == len(split.validation)
    best = max(scores)
    assert record["epoch_kept"] == max(i + 1 for i, s in enumerate(scores) if s == best)
    assert record["epoch_kept"] < 6  # the choice is not simply the last epoch here
    starts = class_starts(KITCHEN, kept.classes)
    assert evaluate(kept, split.validation, starts).corrected_accuracy == pytest.approx(best)
    # the kept weights are those of that epoch: training exactly that long gives them
    exact = train_classifier(split, dataclasses.replace(config, epochs=record["epoch_kept"]))
    for (w1, b1), (w2, b2) in zip(kept.layers, exact.layers, strict=True):
        np.testing.assert_array_equal(w1, w2)
        np.testing.assert_array_equal(b1, b2)
    assert kept.info["split"]["validation_fraction"] == 0.25


def test_the_paper_config_trains_nine_epochs_on_all_training_states(
    data: ClassifierData,
) -> None:
    model = train_classifier(data, PAPER_CONFIG)
    record = model.info["training"]
    assert len(record["epoch_losses"]) == 9 and record["train_states"] == len(data.train)
    assert "epoch_kept" not in record and record["validation_states"] == 0


def test_data_and_config_must_agree_on_the_validation_split(data: ClassifierData) -> None:
    with pytest.raises(ValueError, match="validation_fraction=0.2"):
        train_classifier(data, dataclasses.replace(FAST, validation_fraction=0.2))
    with pytest.raises(ValueError, match=r"validation_fraction must be in \[0, 1\)"):
        TrainConfig(validation_fraction=-0.1)


@pytest.mark.slow
def test_same_seed_same_weights(data: ClassifierData, model: StateClassifier) -> None:
    again = train_classifier(data, FAST)
    for (w1, b1), (w2, b2) in zip(model.layers, again.layers, strict=True):
        np.testing.assert_array_equal(w1, w2)
        np.testing.assert_array_equal(b1, b2)
    other = train_classifier(data, dataclasses.replace(FAST, seed=1, epochs=1))
    assert not np.array_equal(other.layers[0][0], model.layers[0][0])


def test_predict_single_and_batch(model: StateClassifier, data: ClassifierData) -> None:
    states = data.test.observations[:5]
    names = model.predict(states)
    assert isinstance(names, list) and len(names) == 5
    assert model.predict(states[0]) == names[0]
    assert model.predict(states[0].tolist()) == names[0]
    proba = model.predict_proba(states)
    assert proba.shape == (5, len(model.classes))
    np.testing.assert_allclose(proba.sum(axis=1), 1.0, rtol=1e-5)
    assert model.predict_proba(states[0]).shape == (len(model.classes),)


@pytest.mark.parametrize(
    ("state", "message"),
    [
        (np.zeros(9), r"shape \(10,\) or \(B, 10\), got \(9,\)"),
        (np.zeros((2, 3)), r"got \(2, 3\)"),
        (np.zeros((1, 2, 10)), r"got \(1, 2, 10\)"),
        (np.array([*np.zeros(9), np.nan]), r"NaN or inf \(row\(s\) \[0\]\)"),
        (np.vstack([np.zeros(10), np.full(10, np.inf)]), r"NaN or inf \(row\(s\) \[1\]\)"),
    ],
)
def test_bad_states_refused(model: StateClassifier, state: np.ndarray, message: str) -> None:
    for method in (model.predict, model.predict_proba):
        with pytest.raises(ValueError, match=message):
            method(state)


# --- metrics ------------------------------------------------------------------------------


def test_confusion_matrix_sums_to_one_and_trace_is_accuracy(
    model: StateClassifier, data: ClassifierData
) -> None:
    rng = np.random.default_rng(0)
    labels, predictions = rng.integers(0, 6, 500), rng.integers(0, 6, 500)
    matrix = confusion_matrix(labels, predictions, 6)
    assert matrix.sum() == pytest.approx(1.0)
    assert accuracy(matrix) == pytest.approx(np.mean(labels == predictions))
    report = evaluate(model, data.test, class_starts(KITCHEN, model.classes))
    assert report.confusion.sum() == pytest.approx(1.0)
    predicted = model.predict_index(data.test.observations)
    assert report.accuracy == pytest.approx(np.mean(predicted == data.test.labels))
    with pytest.raises(ValueError, match="class indices"):
        confusion_matrix(np.array([0, 6]), np.array([0, 1]), 6)


def test_corrected_accuracy_hand_example() -> None:
    counts = np.array(
        [
            [10, 2, 1, 0],
            [3, 12, 0, 1],
            [0, 2, 8, 4],
            [1, 0, 1, 5],
        ],
        dtype=float,
    )
    matrix = counts / counts.sum()  # 50 points
    assert accuracy(matrix) == pytest.approx(35 / 50)
    # main diagonal 35 + upper neighbours (2, 0, 4) + lower neighbours (3, 2, 1) = 47
    assert corrected_accuracy(matrix) == pytest.approx(47 / 50)


def test_nearest_node_baseline(model: StateClassifier, data: ClassifierData) -> None:
    classes = movement_classes(KITCHEN)
    states = np.zeros((len(classes), OBS_DIM))
    states[:, :3] = [NODES[get_skill(name).start].position for name in classes]
    predicted = nearest_node_predict(states, class_starts(KITCHEN, classes))
    first_with_start: dict[str, int] = {}
    for i, name in enumerate(classes):
        first_with_start.setdefault(get_skill(name).start, i)
    assert predicted.tolist() == [first_with_start[get_skill(n).start] for n in classes]
    report = evaluate(model, data.test, class_starts(KITCHEN, model.classes))
    assert 0.0 < report.baseline_accuracy < report.accuracy


def test_format_report_lists_classes_and_accuracies(
    model: StateClassifier, data: ClassifierData
) -> None:
    report = evaluate(model, data.test, class_starts(KITCHEN, model.classes))
    text = format_report(report)
    for name in report.classes:
        assert name in text
    assert f"{report.accuracy:.3f}" in text and f"{report.corrected_accuracy:.3f}" in text
    assert f"{report.baseline_accuracy:.3f}" in text


# --- class order --------------------------------------------------------------------------


def test_class_order_of_real_skills_keeps_node_sharing_skills_adjacent() -> None:
    movement = [s for s in SKILLS if s.is_movement]
    order = class_order(movement)
    assert sorted(order) == sorted(MOVEMENT_SKILLS)
    assert tuple(order) == movement_classes(KITCHEN)
    best = max(_sharing_pairs(p) for p in itertools.permutations(movement))
    assert _sharing_pairs(order) == best == len(order) - 1
    # a skill and its reverse share both nodes, so they are adjacent
    position = {name: i for i, name in enumerate(order)}
    for a, b in itertools.combinations(movement, 2):
        if {a.start, a.end} == {b.start, b.end}:
            assert abs(position[a.name] - position[b.name]) == 1
    # with both reverse pairs adjacent, at most 3 adjacent pairs can end at one node
    # (the two ending above the cube, and two of the three pairs ending at home)
    ends = [get_skill(name).end for name in order]
    assert sum(a == b for a, b in itertools.pairwise(ends)) == 3


def test_class_order_recovers_a_chain_and_is_deterministic() -> None:
    base = get_skill(MOVEMENT_SKILLS[0])
    nodes = ["n0", "n1", "n2", "n3", "n4", "n5", "n6"]
    chain = [
        dataclasses.replace(base, name=f"s{i}", start=nodes[i], end=nodes[i + 1]) for i in range(6)
    ]
    shuffled = [chain[i] for i in (3, 0, 5, 1, 4, 2)]
    order = class_order(shuffled)
    assert order in (["s0", "s1", "s2", "s3", "s4", "s5"], ["s5", "s4", "s3", "s2", "s1", "s0"])
    assert class_order(shuffled) == order


def test_class_order_of_many_skills_is_greedy_along_shared_nodes() -> None:
    """Beyond the exhaustive search's limit, a chain of 12 shuffled skills still comes out
    with every neighbour sharing a node, the same way each time."""
    base = get_skill(MOVEMENT_SKILLS[0])
    chain = [
        dataclasses.replace(base, name=f"s{i}", start=f"n{i}", end=f"n{i + 1}") for i in range(12)
    ]
    shuffled = [chain[i] for i in (0, 7, 3, 11, 1, 9, 5, 2, 10, 4, 8, 6)]
    order = class_order(shuffled)
    assert order == [f"s{i}" for i in range(12)]
    assert class_order(shuffled) == order


# --- checkpoint ---------------------------------------------------------------------------


def test_checkpoint_round_trip(
    tmp_path: Path, model: StateClassifier, data: ClassifierData
) -> None:
    model.save(tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([SIDECAR_FILE, WEIGHTS_FILE])
    loaded = StateClassifier.load(tmp_path)
    states = data.test.observations
    np.testing.assert_array_equal(loaded.predict_proba(states), model.predict_proba(states))
    assert loaded.predict(states) == model.predict(states)
    sidecar = json.loads((tmp_path / SIDECAR_FILE).read_text())
    for key in ("classes", "normalisation", "config", "seed", "datasets", "package_version"):
        assert key in sidecar
    assert sidecar["datasets"] == data.sha256
    assert sidecar["config"]["batch_size"] == FAST.batch_size


def test_checkpoint_class_mismatch_names_both_lists(tmp_path: Path, model: StateClassifier) -> None:
    model.save(tmp_path)
    sidecar_path = tmp_path / SIDECAR_FILE
    sidecar = json.loads(sidecar_path.read_text())
    stale = list(reversed(sidecar["classes"]))
    sidecar["classes"] = stale
    sidecar_path.write_text(json.dumps(sidecar))
    with pytest.raises(CheckpointError) as err:
        StateClassifier.load(tmp_path, movement_classes(KITCHEN))
    assert str(stale) in str(err.value) and str(list(movement_classes(KITCHEN))) in str(err.value)


def test_checkpoint_missing_or_corrupt_file_is_named(
    tmp_path: Path, model: StateClassifier
) -> None:
    with pytest.raises(CheckpointError, match=f"{SIDECAR_FILE}: .*not found"):
        StateClassifier.load(tmp_path / "nowhere")
    model.save(tmp_path)
    weights = tmp_path / WEIGHTS_FILE
    weights.write_bytes(b"not safetensors")
    with pytest.raises(CheckpointError, match=f"{WEIGHTS_FILE}: contents do not match"):
        StateClassifier.load(tmp_path)
    sidecar_path = tmp_path / SIDECAR_FILE
    sidecar = json.loads(sidecar_path.read_text())
    sidecar["weights_sha256"] = hashlib.sha256(weights.read_bytes()).hexdigest()
    sidecar_path.write_text(json.dumps(sidecar))
    with pytest.raises(CheckpointError, match=f"{WEIGHTS_FILE}: corrupt"):
        StateClassifier.load(tmp_path)
    sidecar_path.write_text("{ truncated")
    with pytest.raises(CheckpointError, match=f"{SIDECAR_FILE}: corrupt"):
        StateClassifier.load(tmp_path)
    weights.unlink()
    with pytest.raises(CheckpointError, match=f"{WEIGHTS_FILE}: .*not found"):
        StateClassifier.load(tmp_path)


def test_reload_split_recreates_the_test_set_and_flags_changed_data(
    tmp_path: Path, model: StateClassifier, data: ClassifierData, data_dir: Path
) -> None:
    again, same = reload_split(model, data_dir)
    assert same
    np.testing.assert_array_equal(again.test.observations, data.test.observations)
    write_movement_datasets(tmp_path, seed=1)
    assert reload_split(model, tmp_path)[1] is False


# --- CLI ----------------------------------------------------------------------------------


def test_cli_train_then_eval(
    tmp_path: Path, data_dir: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "clf"
    args = ["classifier", "train", "--data", str(data_dir), "--out", str(out)]
    assert main([*args, "--epochs", "3", "--batch-size", "256", "--json"]) == 0
    trained = json.loads(capsys.readouterr().out)
    assert trained["classes"] == list(movement_classes(KITCHEN))
    assert trained["config"]["epochs"] == 3
    assert trained["config"]["validation_fraction"] == 0.2
    assert 1 <= trained["training"]["epoch_kept"] <= 3
    assert main(["classifier", "eval", "--data", str(data_dir), "--model", str(out), "--json"]) == 0
    evaluated = json.loads(capsys.readouterr().out)
    assert evaluated["same_data"] is True
    assert evaluated["accuracy"] == pytest.approx(trained["accuracy"])
    np.testing.assert_allclose(evaluated["confusion"], trained["confusion"])
    assert main(["classifier", "eval", "--data", str(data_dir), "--model", str(out)]) == 0
    assert "corrected accuracy" in capsys.readouterr().out


def test_cli_defaults_to_cache_dir_and_reports_errors(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setenv("OSG_CACHE_DIR", str(tmp_path))
    # No classifier trained in the cache: eval falls back to the shipped one, then needs data.
    assert main(["classifier", "eval"]) == 1
    assert str(tmp_path / "kitchen" / "data" / "move-home-to-door.h5") in capsys.readouterr().err
    (tmp_path / "kitchen" / "classifier").mkdir(parents=True)
    assert main(["classifier", "eval"]) == 1
    assert str(tmp_path / "kitchen" / "classifier" / SIDECAR_FILE) in capsys.readouterr().err
    assert main(["classifier", "train"]) == 1
    assert str(tmp_path / "kitchen" / "data") in capsys.readouterr().err


def test_motion_features_of_the_data_are_what_the_run_time_memory_gives() -> None:
    """Training inputs (``motion_features`` of recorded actions) and the executor's input
    (``MotionMemory`` fed the same commands) follow one rule; zero at each episode start."""
    from osg_control.classifier.motion import MOTION_FEATURES, MotionMemory, motion_features

    rng = np.random.default_rng(0)
    actions = rng.uniform(-0.02, 0.02, (12, 7))
    features = motion_features(actions, np.array([0, 7]))
    assert features.shape == (12, MOTION_FEATURES)
    np.testing.assert_array_equal(features[[0, 7]], 0.0)  # each episode starts at rest
    for start, stop in ((0, 7), (7, 12)):
        memory = MotionMemory()
        for step in range(start, stop):
            np.testing.assert_allclose(features[step], memory.features(), atol=1e-7)
            memory.commanded(actions[step])
    memory.still(100)  # a long joint reset: back to rest
    np.testing.assert_allclose(memory.features(), 0.0, atol=1e-6)


def test_the_motion_input_tells_a_skill_from_its_reverse_on_the_shipped_classifier() -> None:
    """Halfway between home and the door, the state alone is ambiguous; the commanded
    direction of travel decides (the shipped classifier, trained with the motion input)."""
    from osg_control.classifier.motion import MotionMemory

    classifier = load_defaults(KITCHEN).classifier
    home = np.array(KITCHEN.nodes["home"].position)
    door = np.array(KITCHEN.nodes["door-front"].position)
    state = np.concatenate([(home + door) / 2, [0.0, 1.0, 0.0, 0.0], [1.0, 0.0, 0.08]])
    chosen = {}
    for name, direction in (("to-door", door - home), ("to-home", home - door)):
        memory = MotionMemory()
        for _ in range(10):
            memory.commanded(np.append(0.02 * direction / np.linalg.norm(direction), [0] * 4))
        chosen[name] = classifier.predict(state, memory.features())
    assert chosen == {"to-door": "move-home-to-door", "to-home": "move-door-to-home"}
