"""Early stopping of batched skills: the rule (``learning.early_stopping``), dropping skills
from a batch (``TD3BC.keep``) and the training rounds (``pipeline.training_loop``)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from osg_control.domain.registry import get_domain
from osg_control.learning.checkpoints import Checkpoint, load_checkpoint, save_checkpoint
from osg_control.learning.early_stopping import EarlyStopping, SkillProgress
from osg_control.learning.replay import BatchedReplay, SkillData
from osg_control.learning.td3bc import TD3BC, TD3BCConfig
from osg_control.pipeline.training_loop import EarlyStop, train_early_stopped

OBS, ACT = 10, 7
SMALL = TD3BCConfig(hidden_sizes=(16, 16), batch_size=8)


def _data(name: str, size: int, rng: np.random.Generator) -> SkillData:
    rows = rng.normal(size=(size, 2 * OBS + ACT + 2)).astype(np.float32)
    rows[:, OBS : OBS + ACT] = np.tanh(rows[:, OBS : OBS + ACT])
    rows[:, -1] = 0.0
    return SkillData(
        name, rows, np.zeros(OBS, np.float32), np.ones(OBS, np.float32), np.ones(ACT, np.float32)
    )


def _batch(sizes: Sequence[int]) -> tuple[TD3BC, BatchedReplay]:
    rng = np.random.default_rng(0)
    data = [_data(f"s{k}", size, rng) for k, size in enumerate(sizes)]
    seeds = [11 * (k + 1) for k in range(len(sizes))]
    return TD3BC(SMALL, seeds), BatchedReplay(data, SMALL.batch_size, seeds)


def test_a_tie_keeps_the_later_weights_but_is_no_improvement() -> None:
    rule = EarlyStopping(check_every=10, patience=2)
    progress = SkillProgress()
    assert progress.record(10, 0.5) and not progress.stopped(rule)
    assert progress.record(20, 0.8) and not progress.stopped(rule)
    assert progress.record(30, 0.8)  # a tie: these weights are kept ...
    assert (progress.best_updates, progress.checks_without_improvement) == (30, 1)
    assert not progress.record(40, 0.7)  # ... and a worse check keeps them
    assert progress.stopped(rule) and progress.best_updates == 30
    record = progress.to_json_dict({"check_every": 10}, 100)
    assert record["checks"] == [[10, 0.5], [20, 0.8], [30, 0.8], [40, 0.7]]
    assert (record["kept_updates"], record["kept_rate"], record["max_updates"]) == (30, 0.8, 100)


@pytest.mark.parametrize("field", ["check_every", "patience"])
def test_the_rule_refuses_settings_below_one(field: str) -> None:
    with pytest.raises(ValueError, match=field):
        EarlyStopping(**{field: 0})


@pytest.mark.slow
def test_skills_kept_in_a_batch_train_as_in_the_full_batch() -> None:
    full, full_replay = _batch([40, 50, 60])
    cut, cut_replay = _batch([40, 50, 60])
    for _ in range(7):  # an odd count: the cut lands between actor updates
        full.train_step(full_replay.sample())
        cut.train_step(cut_replay.sample())
    cut.keep([2, 0])
    cut_replay.keep([2, 0])
    assert cut.num_skills == 2
    for _ in range(9):
        full.train_step(full_replay.sample())
        cut.train_step(cut_replay.sample())
    for before, after in ((2, 0), (0, 1)):
        for (w_full, b_full), (w_cut, b_cut) in zip(
            full.actor_layers(before), cut.actor_layers(after), strict=True
        ):
            np.testing.assert_allclose(w_cut, w_full, rtol=0, atol=1e-6)
            np.testing.assert_allclose(b_cut, b_full, rtol=0, atol=1e-6)


def _write_snapshot(folder: Path, layers: dict[str, Any], updates: int) -> None:
    """Checkpoints of the kitchen skills named in ``layers`` (unit normalisation)."""
    domain = get_domain("kitchen")
    for name, weights in layers.items():
        checkpoint = Checkpoint(
            domain.skill(name), weights, np.zeros(OBS), np.ones(OBS), np.ones(ACT), {}, updates,
            0, "0" * 64,
        )  # fmt: skip
        save_checkpoint(folder, checkpoint)


class ScriptedRates:
    """Held-out rates scripted per skill and check; records the weights each check read."""

    def __init__(self, rates: dict[str, list[float]], every: int) -> None:
        self.rates, self.every = rates, every
        self.seen: dict[tuple[str, int], list[Any]] = {}
        self.asked: list[list[str]] = []

    def __call__(self, policy_dir: Path, names: Sequence[str]) -> Mapping[str, float]:
        updates = int(policy_dir.name)
        self.asked.append(list(names))
        for name in names:
            self.seen[name, updates] = load_checkpoint(policy_dir, name, OBS, ACT).layers
        return {name: self.rates[name][updates // self.every - 1] for name in names}

    def describe(self) -> dict[str, Any]:
        return {"scripted": True}


@pytest.mark.slow
def test_training_rounds_stop_each_skill_by_the_rule_and_keep_its_best_checked_weights() -> None:
    trainer, replay = _batch([40, 50])
    names = ["grab-cube", "release-cube"]
    check = ScriptedRates({"grab-cube": [0.2, 0.9, 0.6, 0.6], "release-cube": [1.0, 1.0, 1.0]}, 4)
    stop = EarlyStop(EarlyStopping(check_every=4, patience=2), check)
    outcomes, seconds = train_early_stopped(trainer, replay, names, 100, stop, _write_snapshot)
    assert seconds >= 0.0
    # release-cube: 1.0, then two ties -> stops at 12, keeps the latest weights (12).
    # grab-cube: best 0.9 at 8, then two checks without improvement -> stops at 16.
    assert check.asked == [names, names, names, ["grab-cube"]]
    grab, release = outcomes
    assert (grab.updates, grab.trained_updates) == (8, 16)
    assert (release.updates, release.trained_updates) == (12, 12)
    for outcome, name in ((grab, "grab-cube"), (release, "release-cube")):
        for kept, checked in zip(outcome.layers, check.seen[name, outcome.updates], strict=True):
            np.testing.assert_array_equal(kept[0], checked[0])
    assert grab.progress is not None and grab.progress.checks[-1] == (16, 0.6)


def test_training_rounds_end_at_the_budget() -> None:
    trainer, replay = _batch([40])
    check = ScriptedRates({"grab-cube": [0.1, 0.2, 0.3]}, 4)
    stop = EarlyStop(EarlyStopping(check_every=4, patience=2), check)
    (outcome,), _ = train_early_stopped(trainer, replay, ["grab-cube"], 12, stop, _write_snapshot)
    assert (outcome.updates, outcome.trained_updates, trainer.steps) == (12, 12, 12)


def test_held_out_snapshots_live_in_the_output_folder_one_round_at_a_time(tmp_path: Path) -> None:
    """Every round's snapshot was kept in the system's temp folder until the end (17 MB after
    25 s, left behind on SIGKILL, outside the free-space check)."""
    from osg_control.pipeline.training_loop import SCRATCH_PREFIX

    stale = tmp_path / f"{SCRATCH_PREFIX}killed"
    (stale / "4").mkdir(parents=True)  # what a killed run left
    trainer, replay = _batch([40])
    seen: list[list[str]] = []
    rates = ScriptedRates({"grab-cube": [0.1, 0.2, 0.3]}, 4)

    def check(policy_dir: Path, names: Sequence[str]) -> Mapping[str, float]:
        scratch = policy_dir.parent
        assert scratch.parent == tmp_path and scratch.name.startswith(SCRATCH_PREFIX)
        seen.append(sorted(p.name for p in scratch.iterdir()))
        return rates(policy_dir, names)

    stop = EarlyStop(EarlyStopping(check_every=4, patience=2), check)
    train_early_stopped(trainer, replay, ["grab-cube"], 12, stop, _write_snapshot, tmp_path)
    assert seen == [["4"], ["8"], ["12"]]  # each round's snapshot alone
    assert not list(tmp_path.iterdir())  # the scratch and the stale one removed
