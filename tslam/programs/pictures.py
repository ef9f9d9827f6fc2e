"""Pictures of simulated runs: walls, ground-truth GVG, the true and dead-reckoned paths."""

from __future__ import annotations

from collections.abc import Sequence

from sim_backend.ground_truth import GroundTruthGVG
from sim_backend.svg import SvgCanvas, draw_gvg, draw_world
from sim_backend.world import World

Point = tuple[float, float]


def run_canvas(
    world: World,
    gvg: GroundTruthGVG,
    true_path: Sequence[Point],
    dr_path: Sequence[Point],
    legend: str = "black: true path   red: dead reckoning   blue: ground-truth GVG",
) -> SvgCanvas:
    """The paper's Fig. 7 view of a run; callers may draw more on the canvas."""
    canvas = SvgCanvas(world.bounds)
    draw_world(canvas, world)
    draw_gvg(canvas, gvg)
    canvas.polyline(dr_path, stroke="#d62728", stroke_width=1.3, fill="none")
    canvas.polyline(true_path, stroke="#111111", stroke_width=1.3, fill="none")
    xmin, _, _, ymax = world.bounds
    canvas.text(xmin, ymax + 0.2, legend, font_size=12)
    return canvas
