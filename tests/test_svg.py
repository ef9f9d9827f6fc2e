"""SVG writer and world/GVG drawings: well-formed XML, one element per thing, y flipped."""

from __future__ import annotations

import math
import os
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from sim_backend.ground_truth import compute_gvg
from sim_backend.svg import SvgCanvas, draw_gvg, draw_world, render_world_svg
from sim_backend.world import GridWorld, PolygonWorld, StartPose

NS = "{http://www.w3.org/2000/svg}"


def ring_world():
    room = [(0, 0), (6, 0), (6, 6), (0, 6)]
    return PolygonWorld("ring", room, [[(2, 2), (4, 2), (4, 4), (2, 4)]], StartPose(1.0, 3.0))


def by_class(root: ET.Element, cls: str) -> list[ET.Element]:
    return [el for el in root.iter() if el.get("class") == cls]


def test_world_y_up_becomes_svg_y_down():
    c = SvgCanvas((0.0, 0.0, 10.0, 5.0), px_per_m=20, margin_m=0.5)
    assert (c.width_px, c.height_px) == (220.0, 120.0)
    c.circle(1.0, 5.0, 0.1, class_="top")
    c.circle(1.0, 0.0, 0.1, class_="bottom")
    c.rect(2.0, 1.0, 3.0, 2.0, class_="box")
    root = ET.fromstring(c.to_string())
    (top,) = by_class(root, "top")
    (bottom,) = by_class(root, "bottom")
    assert float(top.get("cy")) == pytest.approx(10.0)  # the margin only
    assert float(bottom.get("cy")) == pytest.approx(110.0)
    assert float(top.get("cx")) == pytest.approx(30.0)
    assert float(top.get("r")) == pytest.approx(2.0)
    (rect,) = by_class(root, "box")
    # Lower-left corner (2, 1), 3 x 2 m: its top edge is y = 3 m -> (5 - 3 + 0.5) * 20 px.
    assert float(rect.get("y")) == pytest.approx(50.0)
    assert float(rect.get("x")) == pytest.approx(50.0)
    assert (float(rect.get("width")), float(rect.get("height"))) == (60.0, 40.0)
    assert root.get("viewBox") == "0 0 220 120"


def test_text_and_attributes_are_escaped():
    c = SvgCanvas((0, 0, 1, 1))
    nasty = 'a < b & "c" > d\x01'
    with c.group(title="g <1>", class_="grp"):
        c.text(0.5, 0.5, nasty, class_="label", title="t & t")
        c.polyline([(0, 0), (1, 1)], stroke="#000", data_note='say "hi" & <bye>')
    root = ET.fromstring(c.to_string())
    (label,) = by_class(root, "label")
    assert "".join(label.itertext()) == "t & t" + 'a < b & "c" > d'
    (line,) = root.iter(f"{NS}polyline")
    assert line.get("data-note") == 'say "hi" & <bye>'
    assert line.get("fill") == "none"
    (grp,) = by_class(root, "grp")
    assert grp.find(f"{NS}title").text == "g <1>"


def test_save_is_atomic_and_complete(tmp_path):
    c = SvgCanvas((0, 0, 2, 2))
    c.polygon([(0, 0), (2, 0), (1, 2)], fill="red")
    target = tmp_path / "out.svg"
    target.write_text("old contents")
    c.save(target)
    assert target.read_text(encoding="utf-8") == c.to_string()
    assert os.listdir(tmp_path) == ["out.svg"]  # no temporary left behind
    with pytest.raises(OSError):
        c.save(tmp_path / "missing-dir" / "x.svg")
    assert os.listdir(tmp_path) == ["out.svg"]


def test_non_finite_coordinates_are_refused():
    c = SvgCanvas((0, 0, 1, 1))
    with pytest.raises(ValueError):
        c.circle(math.nan, 0.0, 0.1)


def test_world_and_gvg_drawing_counts(tmp_path):
    world = ring_world()
    gvg = compute_gvg(world)
    path = tmp_path / "ring.svg"
    text = render_world_svg(world, gvg, path)
    assert path.read_text(encoding="utf-8") == text
    canvas = SvgCanvas(world.bounds)  # the same default scale, to map world points to pixels
    root = ET.parse(path).getroot()
    assert root.tag == f"{NS}svg"
    assert len(by_class(root, "gvg-edge")) == len(gvg.edges) == 8
    meets = by_class(root, "gvg-meet")
    assert len(meets) == len(gvg.meet_points) == 4
    labels = by_class(root, "gvg-meet-label")
    assert sorted("".join(t.itertext()) for t in labels) == ["3", "3", "3", "3"]
    assert len(by_class(root, "gvg-boundary")) == len(gvg.boundary_points) == 4
    assert not by_class(root, "gvg-horizon")
    assert len(by_class(root, "start")) == 1
    (free,) = by_class(root, "free")  # one polygon with a hole, drawn even-odd
    assert free.get("fill-rule") == "evenodd" and free.get("d").count("M") == 2
    # The meet point nearest the top of the world has the smallest SVG y.
    top = max(gvg.meet_points, key=lambda n: n.y)
    ys = [float(m.get("cy")) for m in meets]
    assert min(ys) == pytest.approx(canvas.px(top.x, top.y)[1], abs=0.006)
    # Edge polylines keep every vertex, flipped.
    first = by_class(root, "gvg-edge")[0]
    xy = np.array([[float(v) for v in p.split(",")] for p in first.get("points").split()])
    e0 = gvg.edges[0]
    assert len(xy) == len(e0.points)
    expect = np.array([canvas.px(x, y) for x, y in e0.points])
    assert np.allclose(xy, expect, atol=0.006)


def test_horizon_ends_are_drawn_distinctly():
    hall = PolygonWorld("hall", [(0, 0), (30, 0), (30, 20), (0, 20)], [], StartPose(2, 1.5))
    gvg = compute_gvg(hall)
    canvas = SvgCanvas(hall.bounds, px_per_m=10)
    draw_world(canvas, hall)
    draw_gvg(canvas, gvg)
    root = ET.fromstring(canvas.to_string())
    (diamond,) = by_class(root, "gvg-horizon")
    assert len(gvg.horizon_points) == 1
    assert diamond.tag == f"{NS}polygon" and len(diamond.get("points").split()) == 4
    (square,) = by_class(root, "gvg-boundary")
    assert square.tag == f"{NS}rect"
    # The horizon end (6.73, 6.73) sits above the boundary point (0.4, 0.4): smaller SVG y.
    dy = min(float(p.split(",")[1]) for p in diamond.get("points").split())
    assert dy < float(square.get("y"))


def test_grid_world_free_cells_drawn_as_row_runs(tmp_path):
    occ = np.ones((4, 6), dtype=bool)
    occ[1, 1:5] = False  # one run
    occ[2, 1:2] = False  # two runs in row 2
    occ[2, 3:5] = False
    world = GridWorld("grid", occ, 0.5, (0.0, 0.0), StartPose(1.0, 0.75))
    path = tmp_path / "grid.svg"
    text = render_world_svg(world, None, path, px_per_m=10, margin_m=0.0)
    root = ET.parse(path).getroot()
    assert path.read_text(encoding="utf-8") == text
    assert render_world_svg(world, None, px_per_m=10, margin_m=0.0) == text  # no path: no file
    assert os.listdir(tmp_path) == ["grid.svg"]
    free = by_class(root, "free")
    assert len(free) == 3
    # Row 1 spans y in [0.5, 1.0] m; flipped: top at (2.0 - 1.0) * 10 px.
    rows = sorted((float(r.get("y")), float(r.get("x")), float(r.get("width"))) for r in free)
    assert rows == [(5.0, 5.0, 5.0), (5.0, 15.0, 10.0), (10.0, 5.0, 20.0)]
    (walls,) = by_class(root, "walls")
    assert walls.get("d").count("M") == len(world.segments)
    assert len(by_class(root, "start")) == 1
