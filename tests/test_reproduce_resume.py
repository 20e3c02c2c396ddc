"""``osg reproduce`` keeps a skill's checkpoint only when it was trained on these data."""

from __future__ import annotations

import json

from osg_control.domain.registry import get_domain
from osg_control.learning.checkpoints import sha256_file
from osg_control.pipeline.resume import untrained_skills


def _fake_run(tmp_path, domain, steps=300, seed=0):
    data, skills = tmp_path / "data", tmp_path / "skills"
    data.mkdir()
    skills.mkdir()
    for skill in domain.skills:
        path = data / f"{skill.name}.h5"
        path.write_bytes(skill.name.encode())
        sidecar = {
            "steps": steps,
            "seed": seed,
            "skill_spec": json.loads(skill.to_json()),
            "dataset_sha256": sha256_file(path),
            "train_config": {"obs_noise": domain.recipe(skill.name).obs_noise},
        }
        (skills / f"{skill.name}.json").write_text(json.dumps(sidecar))
        (skills / f"{skill.name}.safetensors").write_bytes(b"weights")
    return data, skills


def test_matching_checkpoints_are_kept(tmp_path) -> None:
    domain = get_domain("kitchen")
    data, skills = _fake_run(tmp_path, domain)
    assert untrained_skills(domain, data, skills, 300, 0) == []


def test_any_difference_retrains_that_skill(tmp_path) -> None:
    domain = get_domain("kitchen")
    data, skills = _fake_run(tmp_path, domain)
    everything = [skill.name for skill in domain.skills]
    assert untrained_skills(domain, data, skills, 10000, 0) == everything  # other steps
    assert untrained_skills(domain, data, skills, 300, 1) == everything  # other seed
    first, second = everything[:2]
    (data / f"{first}.h5").write_bytes(b"new data")  # the data set changed
    assert untrained_skills(domain, data, skills, 300, 0) == [first]
    (tmp_path / "b").mkdir()
    data, skills = _fake_run(tmp_path / "b", domain)
    (skills / f"{first}.safetensors").unlink()  # a checkpoint missing
    (skills / f"{second}.json").write_text("{not json")  # a corrupt sidecar
    assert untrained_skills(domain, data, skills, 300, 0) == [first, second]


def _stopped_early(skills, domain, rule, budget) -> None:
    """Rewrite every sidecar as an early-stopped run's (``rule``, ``budget``)."""
    for skill in domain.skills:
        path = skills / f"{skill.name}.json"
        sidecar = json.loads(path.read_text())
        sidecar["steps"] = 3000  # the kept weights' updates, not the budget
        stopped = {"early_stopping": {"rule": rule, "max_updates": budget}}
        sidecar["train_config"] = {**sidecar["train_config"], **stopped}
        path.write_text(json.dumps(sidecar))


def test_early_stopped_checkpoints_are_kept_only_under_the_same_rule_and_budget(tmp_path) -> None:
    domain = get_domain("kitchen")
    everything = [skill.name for skill in domain.skills]
    data, skills = _fake_run(tmp_path, domain)
    rule = {"check_every": 1000, "patience": 2, "held_out": {"episodes": 50, "noise": (0.02,)}}
    _stopped_early(skills, domain, json.loads(json.dumps(rule)), 10000)
    assert untrained_skills(domain, data, skills, 10000, 0, rule) == []  # tuples as lists
    assert untrained_skills(domain, data, skills, 20000, 0, rule) == everything  # budget
    assert untrained_skills(domain, data, skills, 10000, 0, {**rule, "patience": 3}) == everything
    assert untrained_skills(domain, data, skills, 10000, 0) == everything  # a fixed-steps run
    assert untrained_skills(domain, data, skills, 3000, 0) == everything


def test_a_checkpoint_trained_with_other_observation_noise_than_its_recipe_is_retrained(
    tmp_path,
) -> None:
    """``osg reproduce`` trains each skill with its recipe's noise (``Domain.recipe``: 0 for
    most, 1 cm for grab-cube): a checkpoint with another is not its own."""
    domain = get_domain("kitchen")
    assert domain.recipe("grab-cube").obs_noise == 0.01
    data, skills = _fake_run(tmp_path, domain)
    plain = domain.skills[0].name
    assert domain.recipe(plain).obs_noise == 0.0
    for name, other, own in ((plain, 0.01, 0.0), ("grab-cube", 0.0, 0.01)):
        path = skills / f"{name}.json"
        sidecar = json.loads(path.read_text())
        sidecar["train_config"] = {"obs_noise": other}
        path.write_text(json.dumps(sidecar))
        assert untrained_skills(domain, data, skills, 300, 0) == [name]
        sidecar["train_config"] = {"obs_noise": own}
        path.write_text(json.dumps(sidecar))
        assert untrained_skills(domain, data, skills, 300, 0) == []
    del sidecar["train_config"]  # none recorded: trained before the field, without noise
    path.write_text(json.dumps(sidecar))
    assert untrained_skills(domain, data, skills, 300, 0) == ["grab-cube"]
