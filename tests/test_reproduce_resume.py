"""``osg reproduce`` keeps a training stage only when its checkpoints match these data."""

from __future__ import annotations

import json

from osg_control.commands.reproduce import trained_already
from osg_control.domain.registry import get_domain
from osg_control.learning.checkpoints import sha256_file


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
    assert trained_already(domain, data, skills, 300, 0)


def test_any_difference_retrains(tmp_path) -> None:
    domain = get_domain("kitchen")
    data, skills = _fake_run(tmp_path, domain)
    assert not trained_already(domain, data, skills, 10000, 0)  # other steps
    assert not trained_already(domain, data, skills, 300, 1)  # other seed
    name = domain.skills[0].name
    (data / f"{name}.h5").write_bytes(b"new data")  # the data set changed
    assert not trained_already(domain, data, skills, 300, 0)
    (tmp_path / "b").mkdir()
    data, skills = _fake_run(tmp_path / "b", domain)
    (skills / f"{name}.safetensors").unlink()  # a checkpoint missing
    assert not trained_already(domain, data, skills, 300, 0)
    (skills / f"{domain.skills[1].name}.json").write_text("{not json")
    assert not trained_already(domain, data, skills, 300, 0)
