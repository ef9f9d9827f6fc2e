"""``tslam worlds``, ``tslam world info`` and ``tslam world render``."""

from __future__ import annotations

import argparse
import json
from typing import Any

from sim_backend.builtin_worlds import builtin_names
from sim_backend.ground_truth import compute_gvg
from sim_backend.svg import render_world_svg
from sim_backend.world_files import load_world
from tslam.programs.output import write_text_atomic


def add_parsers(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("worlds", help="list the built-in worlds")
    p.add_argument("--json", action="store_true", help="print a JSON list")
    p.set_defaults(run=_worlds)

    world = sub.add_parser("world", help="inspect a world: info, render")
    wsub = world.add_subparsers(dest="world_command", required=True, metavar="ACTION")
    info = wsub.add_parser("info", help="size, free area and ground-truth GVG of a world")
    info.add_argument("world", help="built-in name (see 'tslam worlds') or a world file")
    info.add_argument("--json", action="store_true", help="print JSON")
    info.set_defaults(run=_info)
    render = wsub.add_parser("render", help="draw walls and ground-truth GVG to SVG")
    render.add_argument("world", help="built-in name or a world file")
    render.add_argument("--out", required=True, help="output .svg file")
    render.add_argument("--no-gvg", action="store_true", help="draw the walls only")
    render.set_defaults(run=_render)


def _worlds(args: argparse.Namespace) -> int:
    names = builtin_names()
    print(json.dumps(names) if args.json else "\n".join(names))
    return 0


def world_info(spec: str) -> dict[str, Any]:
    """Everything ``tslam world info`` reports, as a JSON-ready dict."""
    world = load_world(spec)
    gvg = compute_gvg(world)
    g = gvg.to_dict()
    xmin, ymin, xmax, ymax = world.bounds
    return {
        "name": world.name,
        "source": world.source,
        "bounds_m": [xmin, ymin, xmax, ymax],
        "size_m": [round(xmax - xmin, 3), round(ymax - ymin, 3)],
        "free_area_m2": round(world.free_area_m2, 3),
        "walls": len(world.segments),
        "start": {"x": world.start.x, "y": world.start.y, "theta": world.start.theta},
        "gvg_length_m": round(gvg.gvg_length_m, 3),
        "meet_point_count": len(gvg.meet_points),
        "boundary_point_count": len(gvg.boundary_points),
        "edge_count": len(gvg.edges),
        "meet_points": [n for n in g["nodes"] if n["kind"] == "meet"],
        "boundary_points": [n for n in g["nodes"] if n["kind"] == "boundary"],
        "other_nodes": [n for n in g["nodes"] if n["kind"] not in ("meet", "boundary")],
        "edges": [{k: v for k, v in e.items() if k != "points"} for e in g["edges"]],
        "gvg_parameters": g.get("parameters", {}),
    }


def _info(args: argparse.Namespace) -> int:
    info = world_info(args.world)
    if args.json:
        print(json.dumps(info, indent=2))
        return 0
    w, h = info["size_m"]
    print(f"{info['name']} ({info['source']})")
    print(f"  size           {w:.2f} x {h:.2f} m, free area {info['free_area_m2']:.1f} m2")
    print(f"  walls          {info['walls']} segments")
    print(
        f"  ground truth   {info['meet_point_count']} meet points, "
        f"{info['boundary_point_count']} boundary points, {info['edge_count']} edges, "
        f"{info['gvg_length_m']:.1f} m of GVG"
    )
    return 0


def _render(args: argparse.Namespace) -> int:
    world = load_world(args.world)
    gvg = None if args.no_gvg else compute_gvg(world)
    svg = render_world_svg(world, gvg, None)
    write_text_atomic(args.out, svg)
    print(f"wrote {args.out}")
    return 0
