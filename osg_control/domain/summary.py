"""A domain as a JSON-ready description (``osg domains --json``)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from osg_control.domain.base import Domain


def domain_summary(domain: Domain) -> dict[str, Any]:
    """The domain's nodes, facts, skills, objects, tasks, start regions, world fields and
    perceptions as plain JSON values."""
    return {
        "name": domain.name,
        "description": domain.description,
        "nodes": {
            n.name: {
                "position": list(n.position),
                "gripper": n.gripper,
                "orientation": list(n.orientation),
            }
            for n in domain.nodes.values()
        },
        "facts": list(domain.facts),
        "skills": [
            {
                "name": s.name,
                "kind": s.kind,
                "start": s.start,
                "end": s.end,
                "preconditions": sorted(s.preconditions),
                "add_effects": sorted(s.add_effects),
                "del_effects": sorted(s.del_effects),
                "parameters": [f"?{var} - {kind}" for var, kind in s.parameters],
            }
            for s in domain.skills
        ],
        "types": dict(domain.types),
        "instances": {i.name: i.type for i in domain.instances},
        "fact_atoms": {f.name: "(" + " ".join(f.atom) + ")" for f in domain.fact_atoms},
        "tasks": [
            {
                "name": t.name,
                "goal": list(t.goal),
                "world": list(domain.task_world(t)),
                "node": domain.task_node(t),
                "description": t.description,
                "counts": dict(t.counts),
            }
            for t in domain.tasks
        ],
        "start_regions": [
            {
                "name": r.name,
                "position": list(r.position),
                "radius": r.radius,
                "angle": r.angle,
                "facts": list(r.facts),
            }
            for r in domain.start_regions
        ],
        "world_fields": list(domain.world_fields),
        "hand_empty": domain.hand_empty,
        "watched_facts": sorted(domain.watched_facts),
        "env_id": domain.env_id,
        "perceptions": list(domain.perceptions),
        "robot": domain.robot,
    }
