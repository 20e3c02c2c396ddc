"""Labelled states for the state->skill classifier: class order, merged data sets, split.

The classes are the movement skills, ordered along the skill graph (``class_order``) so that
skills sharing a start or end node sit next to each other; the corrected accuracy of
``osg_control.classifier.metrics`` relies on that order. Every step of ``<DIR>/<skill>.h5``
contributes its ``observations`` row (the state before the step) and its motion input (the
commands before it, ``classifier.motion``) labelled with the index of its skill in that
order, up to the step that reaches the skill's end node (the steps recorded after it,
holding the node, are on the graph and not the classifier's business). The train/test split
is by episode, within each data set, so no test state shares an episode with a training
state; a validation split for choosing the training epoch (``validation_episodes``) is drawn
the same way from the training episodes only, so it never touches the test split."""

from __future__ import annotations

import hashlib
import itertools
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from osg_control.classifier.motion import motion_features
from osg_control.data.datasets import Dataset, load_dataset
from osg_control.domain.base import Domain
from osg_control.domain.frames import offsets_of, skill_frame, skill_offset
from osg_control.domain.spec import SkillSpec
from osg_control.errors import DatasetError
from osg_control.learning.checkpoints import sha256_file

MAX_ORDERED_CLASSES = 9
"""``class_order`` tries every permutation; 9! = 362,880 is the most it accepts."""


def _shared_nodes(a: SkillSpec, b: SkillSpec) -> int:
    return len({a.start, a.end} & {b.start, b.end})


def class_order(skills: Sequence[SkillSpec]) -> list[str]:
    """Order skills so that skills sharing a start or end node are adjacent.

    Up to ``MAX_ORDERED_CLASSES`` skills, tries every permutation and keeps the best by,
    in turn:

    1. the number of adjacent pairs that share a node;
    2. the number of nodes shared over adjacent pairs (a skill sits next to its reverse);
    3. the number of adjacent pairs that end at the same node: a policy slows down into
       its termination pose, so skills ending together have the most similar states;
    4. the first in permutation order of ``skills`` (deterministic).

    More skills than that (the permutations grow too fast) are ordered greedily: from the
    first skill, repeatedly append the remaining one that best continues the last by the
    same criteria for one pair (earliest in ``skills`` on ties).

    Args:
        skills: the skills to order.

    Returns:
        Their names in the chosen order.
    """
    if len(skills) > MAX_ORDERED_CLASSES:
        return _greedy_order(skills)

    def score(order: tuple[SkillSpec, ...]) -> tuple[int, int, int]:
        pairs = list(itertools.pairwise(order))
        shared = [_shared_nodes(a, b) for a, b in pairs]
        same_end = sum(a.end == b.end for a, b in pairs)
        return sum(1 for s in shared if s), sum(shared), same_end

    best = max(itertools.permutations(skills), key=score)
    return [skill.name for skill in best]


def _greedy_order(skills: Sequence[SkillSpec]) -> list[str]:
    """``class_order`` for many skills: nearest-neighbour by the pairwise criteria."""
    remaining = list(skills)
    order = [remaining.pop(0)]
    while remaining:
        last = order[-1]
        best = max(
            remaining,
            key=lambda s: (
                _shared_nodes(last, s) > 0,
                _shared_nodes(last, s),
                last.end == s.end,
                -remaining.index(s),
            ),
        )
        remaining.remove(best)
        order.append(best)
    return [skill.name for skill in order]


def movement_classes(domain: Domain) -> tuple[str, ...]:
    """The classifier's classes: a domain's movement skills in ``class_order``."""
    return tuple(class_order(list(domain.movement_skills)))


def class_starts(domain: Domain, classes: Sequence[str]) -> np.ndarray:
    """(K, 3) start-node positions of the classes (for the nearest-node baseline)."""
    return np.array([domain.node_of(domain.skill(name), "start").position for name in classes])


@dataclass(frozen=True)
class LabelledStates:
    """States with their motion inputs and class labels.

    Attributes:
        observations: (N, 10) float32 states.
        motion: (N, ``MOTION_FEATURES``) float32 motion inputs (``classifier.motion``).
        labels: (N,) int64 class indices.
    """

    observations: np.ndarray
    motion: np.ndarray
    labels: np.ndarray

    def __len__(self) -> int:
        return len(self.labels)

    @property
    def inputs(self) -> np.ndarray:
        """The classifier's inputs: each state followed by its motion input."""
        return np.concatenate([self.observations, self.motion], axis=1)


@dataclass(frozen=True)
class ClassifierData:
    """The merged movement data sets, split into train and test states.

    Attributes:
        classes: class names; a label is an index into it.
        train: training states.
        test: held-out states (whole episodes).
        validation: states of training-side episodes set aside to choose the epoch
            (whole episodes, none in ``train`` or ``test``); empty without a validation split.
        sha256: hex digest of each data set file, by skill name.
        seed: the seed of the split.
        test_fraction: fraction of each data set's episodes held out.
        validation_fraction: fraction of each data set's non-test episodes in ``validation``.
    """

    classes: tuple[str, ...]
    train: LabelledStates
    test: LabelledStates
    validation: LabelledStates
    sha256: dict[str, str]
    seed: int
    test_fraction: float
    validation_fraction: float


def dataset_path(data_dir: Path, skill: str) -> Path:
    """Where a skill's data set lives: ``<data_dir>/<skill>.h5``."""
    return Path(data_dir) / f"{skill}.h5"


def held_out_episodes(num_episodes: int, test_fraction: float, seed: int, skill: str) -> np.ndarray:
    """Choose the held-out episodes of one skill's data set.

    The choice depends only on the arguments, not on which other data sets are loaded or
    in what order.

    Args:
        num_episodes: episodes in the data set, at least 2.
        test_fraction: fraction to hold out, in (0, 1); rounded, but at least one episode
            on each side.
        seed: non-negative split seed.
        skill: the skill's name, mixed into the seed.

    Returns:
        (num_episodes,) bool, True for a test episode.
    """
    return _draw(np.arange(num_episodes), num_episodes, test_fraction, [seed, _skill_key(skill)])


def validation_episodes(
    in_test: np.ndarray, validation_fraction: float, seed: int, skill: str
) -> np.ndarray:
    """Choose the validation episodes of one skill's data set among its non-test ones.

    Drawn like ``held_out_episodes`` from a stream of its own (the seed, the skill and a
    salt), so the test split is the same with or without a validation split.

    Args:
        in_test: (num_episodes,) bool, the ``held_out_episodes`` mask.
        validation_fraction: fraction of the non-test episodes, in [0, 1); 0 gives none,
            else rounded, but at least one, and at least one left for training.
        seed: non-negative split seed.
        skill: the skill's name, mixed into the seed.

    Returns:
        (num_episodes,) bool, True for a validation episode (never a test one).

    Raises:
        ValueError: a validation split asked for with fewer than two non-test episodes.
    """
    if validation_fraction == 0.0:
        return np.zeros(len(in_test), dtype=bool)
    candidates = np.flatnonzero(~np.asarray(in_test, dtype=bool))
    if len(candidates) < 2:
        raise ValueError(
            f"{len(candidates)} training episode(s): a validation split needs at least 2"
        )
    return _draw(candidates, len(in_test), validation_fraction, [seed, _skill_key(skill), 1])


def _skill_key(skill: str) -> int:
    return int.from_bytes(hashlib.sha256(skill.encode()).digest()[:8], "little")


def _draw(
    candidates: np.ndarray, num_episodes: int, fraction: float, entropy: list[int]
) -> np.ndarray:
    """Mark a seeded random ``fraction`` of ``candidates`` (at least one, one left over)."""
    count = min(max(round(len(candidates) * fraction), 1), len(candidates) - 1)
    mask = np.zeros(num_episodes, dtype=bool)
    rng = np.random.default_rng(entropy)
    mask[rng.permutation(candidates)[:count]] = True
    return mask


def _merge(parts: list[LabelledStates]) -> LabelledStates:
    return LabelledStates(
        observations=np.concatenate([p.observations for p in parts]).astype(np.float32),
        motion=np.concatenate([p.motion for p in parts]).astype(np.float32),
        labels=np.concatenate([p.labels for p in parts]).astype(np.int64),
    )


def world_frame_observations(domain: Domain, dataset: Dataset) -> np.ndarray:
    """A data set's observations in the world frame: a skill that acts in an object's
    frame records the TCP relative to the object (``domain.frames``); each episode's
    object displacement is read back from its recorded world states (its first step's:
    the object rests until the skill grasps it)."""
    observations = np.array(dataset.arrays["observations"], dtype=np.float32)
    skill = domain.skills_by_name.get(dataset.skill_name)
    if skill is None or skill_frame(domain, skill) is None:
        return observations
    worlds = dataset.arrays["world_states"][dataset.episode_starts]
    if not np.all(np.isfinite(worlds)):
        return observations  # world states not recorded (e.g. imported data)
    offsets = np.array(
        [
            skill_offset(domain, skill, offsets_of(domain.objects, domain.world_fields, w))
            for w in worlds
        ]
    )
    observations[:, :3] += np.repeat(offsets, dataset.episode_lengths, axis=0)
    return observations


def load_classifier_data(
    data_dir: Path,
    classes: Sequence[str],
    seed: int,
    test_fraction: float = 0.2,
    domain: Domain | None = None,
    validation_fraction: float = 0.0,
) -> ClassifierData:
    """Load, label, merge and split the data sets of ``classes``.

    Args:
        data_dir: folder holding ``<skill>.h5`` for every class.
        classes: skill names; the label of a state is its skill's index here.
        seed: non-negative seed of the episode split (same seed, same file: same split).
        test_fraction: fraction of each data set's episodes held out, in (0, 1).
        domain: the classes' domain: observations recorded in an object's frame are put
            back in the world frame (``world_frame_observations``), the frame the classifier
            sees at run time; None keeps them as recorded.
        validation_fraction: fraction of each data set's non-test episodes set aside as
            ``validation`` (``validation_episodes``), in [0, 1); the test split is the same
            whatever its value.

    Returns:
        The split data with the files' digests.

    Raises:
        ValueError: ``test_fraction`` outside (0, 1), ``validation_fraction`` outside
            [0, 1) or a negative seed.
        DatasetError: a file is missing or malformed, records another skill, or has fewer
            than two episodes (three with a validation split); the message names the file.
    """
    if not 0.0 < test_fraction < 1.0:
        raise ValueError(f"test_fraction must be in (0, 1), got {test_fraction}")
    if not 0.0 <= validation_fraction < 1.0:
        raise ValueError(f"validation_fraction must be in [0, 1), got {validation_fraction}")
    if seed < 0:
        raise ValueError(f"seed must be non-negative, got {seed}")
    parts: dict[str, list[LabelledStates]] = {"train": [], "test": [], "validation": []}
    digests: dict[str, str] = {}
    for label, skill in enumerate(classes):
        path = dataset_path(data_dir, skill)
        dataset = load_dataset(path)
        if dataset.skill_name != skill:
            raise DatasetError(f"{path}: records skill {dataset.skill_name!r}, expected {skill!r}")
        if dataset.num_episodes < 2:
            raise DatasetError(
                f"{path}: {dataset.num_episodes} episode(s); the train/test split needs at least 2"
            )
        approach = dataset.approach_mask
        recorded = (
            dataset.arrays["observations"]
            if domain is None
            else world_frame_observations(domain, dataset)
        )
        observations = recorded[approach]
        motion = motion_features(dataset.arrays["actions"], dataset.episode_starts)[approach]
        test_episodes = held_out_episodes(dataset.num_episodes, test_fraction, seed, skill)
        try:
            validation = validation_episodes(test_episodes, validation_fraction, seed, skill)
        except ValueError as err:
            raise DatasetError(f"{path}: {err}") from err
        masks = {
            "test": test_episodes,
            "validation": validation,
            "train": ~(test_episodes | validation),
        }
        labels = np.full(len(observations), label, dtype=np.int64)
        for name, episodes in masks.items():
            rows = np.repeat(episodes, dataset.episode_lengths)[approach]
            parts[name].append(LabelledStates(observations[rows], motion[rows], labels[rows]))
        digests[skill] = sha256_file(path)
    return ClassifierData(
        classes=tuple(classes),
        train=_merge(parts["train"]),
        test=_merge(parts["test"]),
        validation=_merge(parts["validation"]),
        sha256=digests,
        seed=seed,
        test_fraction=test_fraction,
        validation_fraction=validation_fraction,
    )
