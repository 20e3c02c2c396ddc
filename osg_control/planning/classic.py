"""Classic STRIPS benchmark domains (gripper, logistics, blocks) with problems of any size.

Written here from the domains' well-known definitions, so the planner's benchmark and tests
need no downloaded files. Every problem is seeded and deterministic; all actions cost 1.
"""

from __future__ import annotations

import random
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from osg_control.io_safety import atomic_write

GRIPPER = """(define (domain gripper)
  (:requirements :strips :typing)
  (:types room ball gripper)
  (:predicates (at-robby ?r - room) (at ?b - ball ?r - room) (free ?g - gripper)
               (carry ?b - ball ?g - gripper))
  (:action move :parameters (?from ?to - room)
    :precondition (at-robby ?from)
    :effect (and (at-robby ?to) (not (at-robby ?from))))
  (:action pick :parameters (?b - ball ?r - room ?g - gripper)
    :precondition (and (at ?b ?r) (at-robby ?r) (free ?g))
    :effect (and (carry ?b ?g) (not (at ?b ?r)) (not (free ?g))))
  (:action drop :parameters (?b - ball ?r - room ?g - gripper)
    :precondition (and (carry ?b ?g) (at-robby ?r))
    :effect (and (at ?b ?r) (free ?g) (not (carry ?b ?g)))))
"""

BLOCKS = """(define (domain blocks)
  (:requirements :strips :typing)
  (:types block)
  (:predicates (on ?x ?y - block) (ontable ?x - block) (clear ?x - block) (handempty)
               (holding ?x - block))
  (:action pick-up :parameters (?x - block)
    :precondition (and (clear ?x) (ontable ?x) (handempty))
    :effect (and (not (ontable ?x)) (not (clear ?x)) (not (handempty)) (holding ?x)))
  (:action put-down :parameters (?x - block)
    :precondition (holding ?x)
    :effect (and (not (holding ?x)) (clear ?x) (handempty) (ontable ?x)))
  (:action stack :parameters (?x ?y - block)
    :precondition (and (holding ?x) (clear ?y))
    :effect (and (not (holding ?x)) (not (clear ?y)) (clear ?x) (handempty) (on ?x ?y)))
  (:action unstack :parameters (?x ?y - block)
    :precondition (and (on ?x ?y) (clear ?x) (handempty))
    :effect (and (holding ?x) (clear ?y) (not (clear ?x)) (not (handempty))
                 (not (on ?x ?y)))))
"""

LOGISTICS = """(define (domain logistics)
  (:requirements :strips :typing)
  (:types truck airplane - vehicle package vehicle - physobj airport location - place
          city place physobj - object)
  (:predicates (in-city ?loc - place ?city - city) (at ?obj - physobj ?loc - place)
               (in ?pkg - package ?veh - vehicle))
  (:action load-truck :parameters (?pkg - package ?truck - truck ?loc - place)
    :precondition (and (at ?truck ?loc) (at ?pkg ?loc))
    :effect (and (not (at ?pkg ?loc)) (in ?pkg ?truck)))
  (:action load-airplane :parameters (?pkg - package ?airplane - airplane ?loc - place)
    :precondition (and (at ?pkg ?loc) (at ?airplane ?loc))
    :effect (and (not (at ?pkg ?loc)) (in ?pkg ?airplane)))
  (:action unload-truck :parameters (?pkg - package ?truck - truck ?loc - place)
    :precondition (and (at ?truck ?loc) (in ?pkg ?truck))
    :effect (and (not (in ?pkg ?truck)) (at ?pkg ?loc)))
  (:action unload-airplane :parameters (?pkg - package ?airplane - airplane ?loc - place)
    :precondition (and (in ?pkg ?airplane) (at ?airplane ?loc))
    :effect (and (not (in ?pkg ?airplane)) (at ?pkg ?loc)))
  (:action drive-truck :parameters (?truck - truck ?from ?to - place ?city - city)
    :precondition (and (at ?truck ?from) (in-city ?from ?city) (in-city ?to ?city))
    :effect (and (not (at ?truck ?from)) (at ?truck ?to)))
  (:action fly-airplane :parameters (?airplane - airplane ?from ?to - airport)
    :precondition (at ?airplane ?from)
    :effect (and (not (at ?airplane ?from)) (at ?airplane ?to))))
"""


def _problem(name: str, domain: str, objects: str, init: list[str], goal: list[str]) -> str:
    """A problem file's text."""
    return (
        f"(define (problem {name})\n  (:domain {domain})\n  (:objects {objects})\n"
        f"  (:init {' '.join(init)})\n  (:goal (and {' '.join(goal)})))\n"
    )


def gripper(size: int, seed: int = 0) -> str:
    """``size`` balls to carry from room a to room b with two grippers (the optimum is
    known: ``2 * size + 2 * ceil(size / 2) - 1`` steps)."""
    balls = [f"ball{i}" for i in range(1, size + 1)]
    init = ["(at-robby rooma)", "(free left)", "(free right)"]
    init += [f"(at {b} rooma)" for b in balls]
    objects = f"rooma roomb - room left right - gripper {' '.join(balls)} - ball"
    return _problem(f"gripper-{size}", "gripper", objects, init, [f"(at {b} roomb)" for b in balls])


def _towers(blocks: list[str], rng: random.Random) -> list[list[str]]:
    """A random arrangement of ``blocks`` into towers (bottom first)."""
    order = blocks[:]
    rng.shuffle(order)
    towers: list[list[str]] = []
    for block in order:
        if towers and rng.random() < 0.6:
            rng.choice(towers).append(block)
        else:
            towers.append([block])
    return towers


def blocks(size: int, seed: int = 0) -> str:
    """``size`` blocks from one random set of towers to another."""
    rng = random.Random(seed * 1000 + size)
    names = [f"b{i}" for i in range(1, size + 1)]
    init = ["(handempty)"]
    for tower in _towers(names, rng):
        init += [f"(ontable {tower[0]})", f"(clear {tower[-1]})"]
        init += [f"(on {up} {down})" for down, up in zip(tower, tower[1:], strict=False)]
    goal = [
        f"(on {up} {down})"
        for tower in _towers(names, rng)
        for down, up in zip(tower, tower[1:], strict=False)
    ]
    return _problem(f"blocks-{size}", "blocks", f"{' '.join(names)} - block", init, goal)


def logistics(size: int, seed: int = 0) -> str:
    """``size`` packages between random places of ``max(2, size // 2)`` cities (two places
    each: an airport and a post office), one truck per city and one airplane."""
    rng = random.Random(seed * 1000 + size)
    cities = [f"city{i}" for i in range(1, max(2, size // 2) + 1)]
    airports = [f"{c}-airport" for c in cities]
    offices = [f"{c}-office" for c in cities]
    places = airports + offices
    packages = [f"p{i}" for i in range(1, size + 1)]
    objects = (
        f"{' '.join(cities)} - city {' '.join(airports)} - airport {' '.join(offices)} - "
        f"location {' '.join(f'truck-{c}' for c in cities)} - truck plane - airplane "
        f"{' '.join(packages)} - package"
    )
    init = [f"(in-city {c}-airport {c})" for c in cities]
    init += [f"(in-city {c}-office {c})" for c in cities]
    init += [f"(at truck-{c} {c}-office)" for c in cities] + [f"(at plane {airports[0]})"]
    init += [f"(at {p} {rng.choice(places)})" for p in packages]
    goal = [f"(at {p} {rng.choice(places)})" for p in packages]
    return _problem(f"logistics-{size}", "logistics", objects, init, goal)


@dataclass(frozen=True)
class ClassicDomain:
    """A classic domain: its PDDL text and its problem generator ``(size, seed) -> text``."""

    name: str
    text: str
    problem: Callable[[int, int], str]


DOMAINS = {
    "gripper": ClassicDomain("gripper", GRIPPER, gripper),
    "blocks": ClassicDomain("blocks", BLOCKS, blocks),
    "logistics": ClassicDomain("logistics", LOGISTICS, logistics),
}
"""The classic domains by name."""


def write_classic(name: str, size: int, out_dir: str | Path, seed: int = 0) -> tuple[Path, Path]:
    """Write a classic domain and one of its problems; return the two paths."""
    domain = DOMAINS[name]
    out = Path(out_dir)
    problem_text = domain.problem(size, seed)
    domain_file = atomic_write(out / f"{name}-domain.pddl", lambda tmp: tmp.write_text(domain.text))
    problem_file = atomic_write(
        out / f"{name}-{size}-{seed}.pddl", lambda tmp: tmp.write_text(problem_text)
    )
    return domain_file, problem_file
