"""``osg classifier``: train and evaluate the state->skill classifier (the paper's Table II).

Each verb is one ``add_<verb>(verbs)`` function listed in ``VERBS`` that adds its parser and
sets ``func``; a new verb (e.g. the simulation test ``reach``) is one more such function.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeAlias

from osg_control.classifier.data import class_starts, load_classifier_data, movement_classes
from osg_control.classifier.metrics import format_report
from osg_control.classifier.model import StateClassifier, evaluate, reload_split
from osg_control.classifier.train import TrainConfig, train_classifier
from osg_control.commands import (
    add_backend_arguments,
    add_perception_arguments,
    domain_of,
    perception_of,
)
from osg_control.domain.base import Domain
from osg_control.execution.defaults import defaults_root, describe_models, models_in_use
from osg_control.io_safety import check_output_dir
from osg_control.json_files import dump_json
from osg_control.paths import cache_dir

Verbs: TypeAlias = "argparse._SubParsersAction[argparse.ArgumentParser]"


def _data_dir(domain: Domain, path: Path | None) -> Path:
    return Path(path) if path else cache_dir() / domain.ref / "data"


def _trained_dir(domain: Domain, path: Path | None) -> Path:
    """Where ``osg classifier train`` writes: the given folder, else the cache (never the
    installed package)."""
    return Path(path) if path else cache_dir() / domain.ref / "classifier"


def _model_dir(domain: Domain, path: Path | None) -> Path:
    """The given folder, else the one ``osg classifier train`` wrote, else the shipped one."""
    trained = _trained_dir(domain, path)
    if path or trained.is_dir():
        return trained
    return defaults_root(domain) / "classifier"


def _add_data_argument(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--data",
        type=Path,
        help="folder of the movement data sets <skill>.h5 (default: $OSG_CACHE_DIR/DOMAIN/data)",
    )


def _emit(args: argparse.Namespace, payload: dict[str, Any], text: str) -> None:
    print(dump_json(payload) if args.json else text)


def run_train(args: argparse.Namespace) -> int:
    """Train on the movement data sets, save the checkpoint, print Table II on the test split.

    Args:
        args: parsed ``osg classifier train`` arguments.

    Returns:
        0.
    """
    config = TrainConfig(
        epochs=args.epochs,
        batch_size=args.batch_size,
        seed=args.seed,
        threads=args.threads,
        validation_fraction=args.validation_fraction,
    )
    domain = domain_of(args)
    out = check_output_dir(_trained_dir(domain, args.out), "classifier folder")
    classes = movement_classes(domain)
    data = load_classifier_data(
        _data_dir(domain, args.data),
        classes,
        args.seed,
        domain=domain,
        validation_fraction=config.validation_fraction,
    )
    model = train_classifier(data, config, progress=True)
    sidecar = model.save(out)
    report = evaluate(model, data.test, class_starts(domain, classes))
    losses = model.info["training"]["epoch_losses"]
    kept = model.info["training"].get("epoch_kept")
    chosen = (
        f"; kept epoch {kept} of {config.epochs} by its corrected accuracy on "
        f"{len(data.validation)} validation states"
        if kept
        else ""
    )
    text = (
        f"trained on {len(data.train)} states, tested on {len(data.test)} held-out states "
        f"(split by episode, seed {args.seed}); final training loss {losses[-1]:.4f}{chosen}\n"
        f"{format_report(report)}\nsaved {out}"
    )
    payload = {"model": str(out), "sidecar": str(sidecar), **model.info, **report.to_dict()}
    _emit(args, payload, text)
    return 0


def run_eval(args: argparse.Namespace) -> int:
    """Print Table II of a saved classifier on the test split it was trained with.

    Args:
        args: parsed ``osg classifier eval`` arguments.

    Returns:
        0.
    """
    domain = domain_of(args)
    model_dir = _model_dir(domain, args.model)
    model = StateClassifier.load(model_dir, movement_classes(domain))
    data, same_data = reload_split(model, _data_dir(domain, args.data), domain)
    if not same_data:
        print(
            "osg: warning: the data sets differ from those the classifier was trained on "
            "(sha256); the test split may overlap its training states",
            file=sys.stderr,
        )
    report = evaluate(model, data.test, class_starts(domain, model.classes))
    payload = {"model": str(model_dir), "same_data": same_data, **report.to_dict()}
    _emit(args, payload, format_report(report))
    return 0


def add_train(verbs: Verbs) -> None:
    """Add ``osg classifier train``."""
    parser = verbs.add_parser(
        "train",
        help="train the classifier on the movement data sets",
        description="Merge the movement skills' data sets (states labelled by skill), split "
        "them 80/20 by episode, train the MLP and save it; prints Table II on the test split. "
        "By default a fifth of the training episodes is set aside and the epoch with the best "
        "corrected accuracy on it is kept; --epochs 9 --validation-fraction 0 is the paper's "
        "training.",
    )
    _add_data_argument(parser)
    parser.add_argument(
        "--out", type=Path, help="checkpoint folder (default: $OSG_CACHE_DIR/classifier)"
    )
    parser.add_argument(
        "--seed",
        type=int,
        default=0,
        help="split, init and shuffle seed (default: %(default)s)",
    )
    defaults = TrainConfig()
    parser.add_argument(
        "--epochs",
        type=int,
        default=defaults.epochs,
        help="epochs (with a validation split: the most, the best on it kept; "
        "default: %(default)s)",
    )
    parser.add_argument(
        "--validation-fraction",
        type=float,
        default=defaults.validation_fraction,
        help="fraction of each data set's training episodes that chooses the epoch; "
        "0: train exactly --epochs on all (default: %(default)s)",
    )
    parser.add_argument(
        "--batch-size",
        type=int,
        default=defaults.batch_size,
        help="states per step (default: %(default)s)",
    )
    parser.add_argument(
        "--threads",
        type=int,
        default=defaults.threads,
        help="torch CPU threads (default: %(default)s)",
    )
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    parser.set_defaults(func=run_train)


def add_eval(verbs: Verbs) -> None:
    """Add ``osg classifier eval``."""
    parser = verbs.add_parser(
        "eval",
        help="print Table II of a saved classifier",
        description="Confusion matrix on the checkpoint's held-out episodes, accuracy, "
        "corrected accuracy and the nearest-start-node baseline.",
    )
    _add_data_argument(parser)
    parser.add_argument(
        "--model",
        type=Path,
        help="checkpoint folder (default: $OSG_CACHE_DIR/classifier if trained, else shipped)",
    )
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    parser.set_defaults(func=run_eval)


def run_reach(args: argparse.Namespace) -> int:
    """Print Table III: classify random starts, run the chosen movement skill."""
    from osg_control.evaluation.evaluate import format_reach_table, reach_table
    from osg_control.parallel import open_executor

    models = str(args.models) if args.models else None
    domain = domain_of(args)
    perception = perception_of(args, domain)
    with open_executor(args.backend, args.workers, args.address) as executor:
        table = reach_table(
            domain,
            models,
            args.episodes,
            args.seed,
            args.workers,
            executor,
            progress=not args.json,
            perception=perception,
        )
    table["models"] = models_in_use(domain, models)
    _emit(args, table, f"{format_reach_table(table)}\n{describe_models(table['models'])}")
    return 0


def add_reach(verbs: Verbs) -> None:
    """Add ``osg classifier reach``."""
    parser = verbs.add_parser(
        "reach",
        help="print Table III: reaching the graph from random starts",
        description="From the domain's start regions (the kitchen: 4 nodes, 4 edge midpoints, "
        "15 cm and 0.2 rad): classify, run the chosen movement skill, count arrivals at its "
        "termination node; beside it, how often the start lay outside the chosen skill's "
        "initiation region and the success of the nearest-start-node baseline.",
    )
    parser.add_argument("--episodes", type=int, default=200, help="per start region")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--workers", type=int, default=2)
    add_backend_arguments(parser)
    parser.add_argument(
        "--noise", type=float, default=None, help="the paper protocol's TCP noise [m] (default 0)"
    )
    add_perception_arguments(parser)
    parser.add_argument("--models", type=Path, help="defaults folder (default: shipped)")
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    parser.set_defaults(func=run_reach)


VERBS: tuple[Callable[[Verbs], None], ...] = (add_train, add_eval, add_reach)
"""The ``osg classifier`` verbs, in help order."""


def register(subparsers: Verbs) -> None:
    """Add ``osg classifier`` and its verbs.

    Args:
        subparsers: the ``osg`` sub-command group.
    """
    parser = subparsers.add_parser(
        "classifier",
        help="state->skill classifier: train, eval, reach",
        description="The state->skill classifier of the Offline Skill Graph paper.",
    )

    def show_help(_args: argparse.Namespace) -> int:
        parser.print_help()
        return 0

    parser.set_defaults(func=show_help)
    verbs = parser.add_subparsers(dest="classifier_command", metavar="VERB")
    for add_verb in VERBS:
        add_verb(verbs)
