"""``bgphm sensors``: where to add sensors to reach a detection or isolation goal."""

from __future__ import annotations

import json

from bgphm.errors import EXIT_OK
from bondgraph.io import load_model

from ._outputs import emit, output_file
from ._progress import Progress

__all__ = ["run"]


def run(args, progress: Progress) -> int:
    """``bgphm sensors``: the minimal sets of detectors reaching ``args.goal``, cheapest first, as a
    table on stdout and, with ``--out``, as JSON; returns 0."""
    from diagnosis import place_sensors

    out = output_file(args)
    spec = load_model(args.model)
    progress(f"trying the detectors {spec.model.name!r} lacks, up to {args.max_sensors} at a time")
    placements = place_sensors(spec.model, goal=args.goal, cost=dict(args.cost or []),
                               fallible=not args.healthy_sensors, max_sensors=args.max_sensors,
                               check=not args.no_check, inside_elements=args.inside_elements)
    print("\n".join(_lines(placements, args.goal)))
    if out is not None:
        emit(json.dumps({"model": spec.model.name, "goal": args.goal, "alternatives": [
            {"sensors": list(p.sensors), "cost": p.cost, "detects": sorted(p.detects),
             "isolates": sorted(map(list, p.isolates)),
             "derived": None if p.derived is None else {"detects": sorted(p.derived["detects"]),
                                                        "isolates": sorted(map(list, p.derived["isolates"]))}}
            for p in placements]}, indent=1) + "\n", out)
    return EXIT_OK


def _lines(placements: list, goal: str) -> list[str]:
    if not placements:
        return [f"the model's sensors reach the goal ({goal}): nothing to add"]
    lines = []
    for p in placements:
        checked = "" if p.derived is None else (f"; its ARRs detect {len(p.derived['detects'])}, "
                                                f"tell {len(p.derived['isolates'])} pairs apart")
        lines.append(f"{' + '.join(p.sensors)}  (cost {p.cost:g}): detects {len(p.detects)} faults, tells "
                     f"{len(p.isolates)} ordered pairs apart{checked}")
    return lines
