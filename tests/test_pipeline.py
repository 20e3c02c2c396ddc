"""The library pipeline (``osg_control.pipeline``): its PDDL carries the costs of the success
rates Table I measured, and its model bundle records what they were measured under.

The end-to-end run is the minimal domain (``tests/minidomain``) at a tiny scale: a few
scripted episodes, a few hundred TD3+BC updates, a few evaluation episodes (about 15 s).
"""

from __future__ import annotations

import ast
import json
import math
import re
from dataclasses import replace
from pathlib import Path

import pytest
from minidomain import DOMAIN_NAME, mini_domain

from osg_control.domain.base import Domain
from osg_control.domain.registry import get_domain, register_domain
from osg_control.errors import CheckpointError, OutputError
from osg_control.execution import bundle
from osg_control.execution.bundle import DEPLOYMENT_NOISE, RATES_KEY, ModelBundle, measured_graph
from osg_control.execution.defaults import load_defaults
from osg_control.perception.spec import PerceptionSpec, perception_spec
from osg_control.pipeline import (
    ReproduceConfig,
    Reproduction,
    Scale,
    StageError,
    deployment_rates,
    export_measured_pddl,
    measured_rates,
    reproduce,
    train_missing,
)
from osg_control.pipeline.reproduction import training_early_stop
from osg_control.planning.pddl_io import skill_cost

TINY = Scale(
    episodes=16, train_steps=150, table_i_episodes=3, reach_episodes=1, task_episodes=1,
    check_every=50, patience=1, check_episodes=2,
)  # fmt: skip
MANIFEST_KEYS = {
    "domain", "command", "seed", "scale", "package_version", "git_commit", "datasets_sha256",
    "perception", "filter_gain", "success_rates", "success_rates_from", "motion_model",
}  # fmt: skip
"""The keys the manifest kept (``execution.bundle`` and tests read them)."""


@pytest.fixture(scope="module")
def domain() -> Domain:
    register_domain(DOMAIN_NAME, mini_domain)
    return get_domain(DOMAIN_NAME)


@pytest.fixture(scope="module")
def run(domain: Domain, tmp_path_factory: pytest.TempPathFactory) -> Reproduction:
    return reproduce(_tiny_config(domain, tmp_path_factory.mktemp("pipeline")))


def _tiny_config(domain: Domain, out: Path) -> ReproduceConfig:
    """The end-to-end run's configuration (TINY, one worker, the filter)."""
    return ReproduceConfig(
        domain, out, TINY, workers=1, train_threads=1, filter_gain=0.2, progress=False
    )


def _pddl_costs(path: Path) -> dict[str, int]:
    text = path.read_text()
    found = re.findall(r"\(:action (\S+).*?\(increase \(total-cost\) (\d+)\)", text, re.DOTALL)
    return {name: int(cost) for name, cost in found}


@pytest.mark.slow
def test_the_pddl_carries_the_costs_of_the_rates_table_i_measured(
    domain: Domain, run: Reproduction
) -> None:
    rates = deployment_rates(run.figures["table_i"])
    assert set(rates) == {s.name for s in domain.skills}
    assert run.bundle.success_rates == rates
    assert list(run.stage_seconds).index("table I") < list(run.stage_seconds).index("graph+pddl")
    costs = _pddl_costs(run.exported.pddl[0])
    expected = {name: max(1, round(-math.log(max(p, 1e-3)) * 1000)) for name, p in rates.items()}
    assert costs == expected == {name: skill_cost(p) for name, p in rates.items()}
    assert all(run.exported.graph.edge(n).success_rate == p for n, p in rates.items())
    # The manifest on disk sets the same costs for `osg plan`, the executor and Tables III-V.
    manifest = json.loads((run.out / "defaults" / "manifest.json").read_text())
    assert manifest[RATES_KEY] == rates
    graph = measured_graph(domain, run.out / "defaults")
    assert all(graph.edge(n).success_rate == p for n, p in rates.items())
    assert load_defaults(domain, run.out / "defaults").graph.edges == graph.edges


@pytest.mark.slow
def test_export_writes_the_costs_of_any_rates(domain: Domain, run: Reproduction, tmp_path) -> None:
    rates = {"move-home-to-button": 0.9, "move-button-to-home": 0.5, "press-button": 0.01}
    exported = export_measured_pddl(domain, run.datasets.directory, rates, tmp_path, draw=False)
    assert exported.graph_png is None and not (tmp_path / "graph.png").exists()
    assert _pddl_costs(exported.pddl[0]) == {
        "move-home-to-button": 105, "move-button-to-home": 693, "press-button": 4605,
    }  # fmt: skip


@pytest.mark.slow
def test_the_bundle_records_the_perception_noise_and_filter(
    domain: Domain, run: Reproduction
) -> None:
    bundle = ModelBundle.read(run.out / "defaults", domain)
    assert bundle == run.bundle
    assert bundle.perception == PerceptionSpec("paper", tcp_noise=DEPLOYMENT_NOISE)
    assert bundle.noise == DEPLOYMENT_NOISE and bundle.filter_gain == 0.2
    assert bundle.policies_dir == run.out / "defaults" / "skills"
    assert bundle.classifier_dir == run.classifier.directory
    manifest = json.loads(bundle.manifest_path.read_text())
    assert MANIFEST_KEYS <= set(manifest)
    assert manifest["perception"] == bundle.perception.to_dict()
    assert manifest["scale"] == TINY.__dict__ and manifest["domain"] == DOMAIN_NAME
    assert "sigma = 0.02 m" in manifest["success_rates_from"]
    assert "gain 0.2" in manifest["success_rates_from"]
    assert (run.out / "report.md").exists() and (run.out / "figures.json").exists()


@pytest.mark.slow
def test_a_rerun_keeps_the_checkpoints_trained_on_these_data(
    domain: Domain, run: Reproduction
) -> None:
    skills = run.bundle.policies_dir
    before = {p.name: p.read_bytes() for p in skills.iterdir()}
    early_stop = training_early_stop(_tiny_config(domain, run.out), run.bundle.motion_model)
    assert early_stop is not None
    kept = train_missing(
        domain, run.datasets.directory, skills, TINY.train_steps, seed=0, early_stop=early_stop
    )
    assert kept is None
    assert {p.name: p.read_bytes() for p in skills.iterdir()} == before


def test_bundle_round_trip(domain: Domain, tmp_path: Path) -> None:
    robot = perception_spec("robot", object_noise=0.02)
    bundle = ModelBundle(
        tmp_path / "defaults",
        success_rates={"press-button": 0.75, "move-home-to-button": 1.0},
        perception=robot,
        noise=0.0,
        filter_gain=None,
        provenance={"domain": DOMAIN_NAME, "command": "osg ...", "seed": 3},
    )
    path = bundle.write()
    assert path == tmp_path / "defaults" / "manifest.json"
    assert ModelBundle.read(path.parent, domain) == bundle
    assert ModelBundle.read(path.parent) == bundle
    again = bundle.with_rates({"press-button": 0.5}, 0.01)
    assert again.perception == replace(robot, tcp_noise=0.01) and again.noise == 0.01
    again.write()
    assert ModelBundle.read(path.parent, domain) == again
    assert ModelBundle.read(tmp_path / "nothing") == ModelBundle(tmp_path / "nothing")


def test_a_manifest_without_a_perception_reads_as_unrecorded(tmp_path: Path) -> None:
    kitchen = get_domain("kitchen")
    assert kitchen.defaults_dir is not None
    manifest = json.loads((kitchen.defaults_dir / "manifest.json").read_text())
    for key in ("perception", "noise", "filter_gain", "motion_model"):
        manifest.pop(key, None)
    (tmp_path / "manifest.json").write_text(json.dumps(manifest))
    old = ModelBundle.read(tmp_path, kitchen)
    assert old.perception is None and old.noise is None and old.motion_model is None
    assert old.success_rates == load_defaults(kitchen).bundle.success_rates


def test_the_shipped_kitchen_bundle_records_how_its_rates_were_measured() -> None:
    kitchen = get_domain("kitchen")
    assert kitchen.defaults_dir is not None
    shipped = ModelBundle.read(kitchen.defaults_dir, kitchen)
    assert shipped.perception == PerceptionSpec("paper", tcp_noise=0.02)
    assert shipped.noise == 0.02 and shipped.filter_gain == 0.2
    assert shipped.motion_model is not None
    assert shipped.provenance["command"].startswith("osg --domain kitchen reproduce")


@pytest.mark.parametrize(
    "field,value",
    [
        ("perception", {"name": "x-ray"}),
        ("perception", {"name": "paper", "tcp_noise": -1}),
        ("perception", "paper"),
        ("noise", float("nan")),
        ("filter_gain", "high"),
        ("success_rates", {"press-button": 1.5}),
        ("motion_model", [0.8]),
        ("motion_model", [0.8, float("nan")]),
    ],
)
def test_a_malformed_manifest_is_refused(field: str, value: object, tmp_path: Path) -> None:
    (tmp_path / "manifest.json").write_text(json.dumps({field: value}))
    with pytest.raises(CheckpointError, match="manifest.json"):
        ModelBundle.read(tmp_path)


def test_only_the_bundle_names_the_manifest_and_its_own_keys() -> None:
    """``execution/bundle.py`` owns the manifest: no other package module spells its file
    name or the keys only it has (a second reader would drift from ``ModelBundle.read``'s
    checks). ``motion_model`` and ``perception`` are left out: they are also parameter
    names."""
    owned = {bundle.MANIFEST, bundle.RATES_KEY, bundle.RATES_FROM_KEY}
    package = Path(bundle.__file__).resolve().parents[1]
    spelled = [
        f"{path.relative_to(package)}: {node.value!r}"
        for path in sorted(package.rglob("*.py"))
        if path.name != "bundle.py" or path.parent.name != "execution"
        for node in ast.walk(ast.parse(path.read_text()))
        if isinstance(node, ast.Constant) and node.value in owned
    ]
    assert spelled == []


def test_load_defaults_reads_through_the_bundle(tmp_path: Path) -> None:
    """``load_defaults`` refuses what ``ModelBundle.read`` refuses (here a perception
    whose noise is negative), naming the manifest."""
    kitchen = get_domain("kitchen")
    assert kitchen.defaults_dir is not None
    manifest = json.loads((kitchen.defaults_dir / "manifest.json").read_text())
    manifest["perception"]["tcp_noise"] = -1
    (tmp_path / "manifest.json").write_text(json.dumps(manifest))
    with pytest.raises(CheckpointError, match=f"{tmp_path / 'manifest.json'}: malformed"):
        load_defaults(kitchen, tmp_path)
    assert load_defaults(kitchen).bundle == ModelBundle.read(kitchen.defaults_dir, kitchen)


def test_measured_rates_under_the_robot_perception() -> None:
    robot = perception_spec("robot")
    table = {
        "noise": [0.0],
        "perception": robot.to_dict(),
        "filter_gain": None,
        "rows": [{"skill": "a", "rates": [0.8], "scripted": 0.5}],
    }
    measured = measured_rates(table)
    assert measured.rates == {"a": 0.8} and measured.noise == 0.0
    assert measured.perception == robot and measured.filter_gain is None


def test_a_failed_stage_is_named_and_nothing_after_it_runs(domain: Domain, tmp_path) -> None:
    (tmp_path / "data").write_text("not a folder")
    with pytest.raises(StageError, match="stage 'collect' failed: .*data") as caught:
        reproduce(ReproduceConfig(domain, tmp_path, TINY, workers=1, progress=False))
    assert isinstance(caught.value.__cause__, OutputError) and caught.value.stage == "collect"
    assert not (tmp_path / "defaults").exists()


@pytest.mark.slow
def test_the_filter_motion_model_is_fitted_on_the_runs_data_and_shipped(
    domain: Domain, run: Reproduction
) -> None:
    """The manifest carries the fit of this run's data (not the kitchen's constant), and an
    executor loaded from the bundle filters with it."""
    from osg_control.control.estimator import MOTION_MODEL
    from osg_control.execution.executor import load_executor
    from osg_control.pipeline import fit_filter_motion

    fitted = fit_filter_motion(domain, run.out / "data")
    bundle = ModelBundle.read(run.bundle.directory, domain)
    assert bundle.motion_model == pytest.approx(fitted)
    assert bundle.motion_model != MOTION_MODEL
    executor = load_executor(domain, run.bundle.directory, filter_gain=0.2)
    assert executor.motion_model == pytest.approx(fitted)
