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
