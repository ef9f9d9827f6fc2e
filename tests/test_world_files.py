"""Loading worlds from files: polygon JSON, ROS map_server YAML + PGM/PNG, and every bad file.

Every malformed case checks the message names the file and the specific problem on one line,
since that message is all a user of the command line ever sees.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from PIL import Image

from sim_backend.builtin_worlds import builtin_world
from sim_backend.world import GridWorld, PolygonWorld, WorldError, point_segments_distance
from sim_backend.world_files import (
    builtin_names,
    load_world,
    map_server_values,
    polygon_world_to_json,
)

ROOM = [[0, 0], [10, 0], [10, 6], [0, 6]]
BLOCK = [[4, 2], [6, 2], [6, 4], [4, 4]]


def polygon_doc(**overrides: object) -> dict:
    doc: dict = {
        "name": "room",
        "boundary": ROOM,
        "obstacles": [BLOCK],
        "start": {"x": 1.0, "y": 1.0, "theta": 0.5},
    }
    doc.update(overrides)
    return doc


def write_json(tmp_path: Path, doc: object, name: str = "w.json") -> Path:
    path = tmp_path / name
    path.write_text(doc if isinstance(doc, str) else json.dumps(doc))
    return path


# A 20 x 30 map at 0.1 m: occupied border, an occupied block, an unknown (205) patch, and a
# marker in the image's top-left corner to check the vertical flip.
ROWS, COLS, RES = 20, 30, 0.1


def map_pixels() -> np.ndarray:
    img = np.full((ROWS, COLS), 254, dtype=np.uint8)
    img[0, :] = img[-1, :] = img[:, 0] = img[:, -1] = 0
    img[8:12, 10:14] = 0  # occupied block, 4 x 4 cells
    img[3:5, 20:25] = 205  # unknown patch, 2 x 5 cells
    img[1, 1] = 0  # marker: top-left interior cell of the image
    return img


FREE_CELLS = (ROWS - 2) * (COLS - 2) - 16 - 10 - 1


def write_map(
    tmp_path: Path,
    pixels: np.ndarray | None = None,
    image: str = "m.pgm",
    yaml_name: str = "m.yaml",
    **keys: object,
) -> Path:
    if pixels is None:
        pixels = map_pixels()
    Image.fromarray(pixels).save(tmp_path / image)
    doc = {
        "image": image,
        "resolution": RES,
        "origin": [-2.0, 3.0, 0.0],
        "negate": 0,
        "occupied_thresh": 0.65,
        "free_thresh": 0.196,
    }
    doc.update(keys)
    doc = {k: v for k, v in doc.items() if v is not None}
    path = tmp_path / yaml_name
    path.write_text("\n".join(f"{k}: {json.dumps(v)}" for k, v in doc.items()) + "\n")
    return path


def cell_centre(row_from_top: int, col: int, origin: tuple[float, float] = (-2.0, 3.0)) -> list:
    row = ROWS - 1 - row_from_top
    return [origin[0] + (col + 0.5) * RES, origin[1] + (row + 0.5) * RES]


def load_error(spec: object) -> str:
    with pytest.raises(WorldError) as info:
        load_world(spec)  # type: ignore[arg-type]
    message = str(info.value)
    assert "\n" not in message
    return message


# --- polygon JSON ------------------------------------------------------------------------------


def test_polygon_json_loads_geometry_start_and_name(tmp_path):
    world = load_world(write_json(tmp_path, polygon_doc()))
    assert isinstance(world, PolygonWorld)
    assert world.name == "room"
    assert world.free_area_m2 == pytest.approx(60.0 - 4.0)
    assert world.bounds == (0.0, 0.0, 10.0, 6.0)
    assert (world.start.x, world.start.y, world.start.theta) == (1.0, 1.0, 0.5)
    assert world.source.endswith("w.json")
    free = world.is_free(np.array([[1, 1], [5, 3], [8, 5], [11, 3]]))
    assert free.tolist() == [True, False, True, False]


def test_polygon_json_optional_fields_default(tmp_path):
    doc = {"boundary": ROOM, "start": {"x": 2, "y": 3}}
    world = load_world(write_json(tmp_path, doc, "plain.json"))
    assert world.name == "plain"
    assert world.start.theta == 0.0
    assert world.free_area_m2 == pytest.approx(60.0)


def test_polygon_json_accepts_path_objects_and_closed_rings(tmp_path):
    doc = polygon_doc(boundary=[*ROOM, ROOM[0]])
    world = load_world(write_json(tmp_path, doc))
    assert world.free_area_m2 == pytest.approx(56.0)


def test_builtin_world_round_trips_through_json(tmp_path):
    original = builtin_world("fig14")
    path = write_json(tmp_path, polygon_world_to_json(original), "fig14.json")
    loaded = load_world(path)
    assert loaded.free_area_m2 == pytest.approx(original.free_area_m2)
    rng = np.random.default_rng(3)
    x0, y0, x1, y1 = original.bounds
    pts = rng.uniform((x0, y0), (x1, y1), size=(2000, 2))
    assert np.array_equal(loaded.is_free(pts), original.is_free(pts))


# --- ROS map_server ----------------------------------------------------------------------------


@pytest.mark.parametrize("image", ["m.pgm", "m.png"])
def test_map_server_cells_origin_and_flip(tmp_path, image):
    world = load_world(write_map(tmp_path, image=image))
    assert isinstance(world, GridWorld)
    assert world.name == "m"
    assert world.bounds == pytest.approx((-2.0, 3.0, -2.0 + COLS * RES, 3.0 + ROWS * RES))
    assert world.free_area_m2 == pytest.approx(FREE_CELLS * RES**2)
    probes = {
        (1, 1): False,  # the marker at the image's top-left stays at the world's top-left
        (ROWS - 2, 1): True,  # the bottom-left interior cell is free
        (10, 12): False,  # occupied block
        (4, 22): False,  # unknown patch counts as occupied
        (6, 22): True,
        (0, 5): False,  # border
        (15, 25): True,
    }
    pts = np.array([cell_centre(r, c) for r, c in probes])
    assert world.is_free(pts).tolist() == list(probes.values())


def test_pgm_and_png_give_the_same_grid(tmp_path):
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    pgm = load_world(write_map(tmp_path / "a", image="m.pgm"))
    png = load_world(write_map(tmp_path / "b", image="m.png"))
    assert np.array_equal(pgm.occupied, png.occupied)


def test_negate_swaps_black_and_white(tmp_path):
    plain = load_world(write_map(tmp_path, yaml_name="plain.yaml"))
    negated = load_world(
        write_map(tmp_path, 255 - map_pixels(), image="neg.pgm", yaml_name="neg.yaml", negate=1)
    )
    assert np.array_equal(plain.occupied, negated.occupied)


def test_trinary_thresholds_decide_each_cell(tmp_path):
    # p = (255 - v) / 255 with occupied_thresh 0.6 and free_thresh 0.3.
    values = [0, 100, 110, 178, 180, 254]
    p = [(255 - v) / 255 for v in values]
    assert p[1] > 0.6 > p[2] and p[3] > 0.3 > p[4]
    got = map_server_values(np.array([values]), False, 0.6, 0.3, "trinary")
    assert got.tolist() == [[100, 100, -1, -1, 0, 0]]

    # 1 m cells, so that a single free cell has room for the robot.
    img = np.zeros((5, 8), dtype=np.uint8)
    img[2, 1:7] = values
    world = load_world(
        write_map(tmp_path, img, occupied_thresh=0.6, free_thresh=0.3, resolution=1.0)
    )
    centres = [[-2.0 + c + 0.5, 3.0 + 2.5] for c in range(1, 7)]
    assert world.is_free(np.array(centres)).tolist() == [False, False, False, False, True, True]


def test_scale_and_raw_modes_follow_map_server(tmp_path):
    px = np.array([[0, 120, 254, 255]])
    scaled = map_server_values(px, False, 0.65, 0.196, "scale")
    assert scaled[0, 0] == 100 and scaled[0, 2] == 0 and scaled[0, 3] == 0
    assert 1 <= scaled[0, 1] <= 99
    raw = map_server_values(np.array([[0, 50, 100, 101, 255]]), False, 0.65, 0.196, "raw")
    assert raw.tolist() == [[0, 50, 100, -1, -1]]
    raw_neg = map_server_values(np.array([[255, 155]]), True, 0.65, 0.196, "raw")
    assert raw_neg.tolist() == [[0, 100]]

    # In a world only certainly-free cells are free: intermediate probabilities are walls.
    img = np.zeros((3, 5), dtype=np.uint8)
    img[1, 1:4] = [254, 120, 254]
    world = load_world(write_map(tmp_path, img, mode="scale", resolution=1.0))
    row = [[-2.0 + c + 0.5, 3.0 + 1.5] for c in (1, 2, 3)]
    assert world.is_free(np.array(row)).tolist() == [True, False, True]

    raw_img = np.full((3, 5), 100, dtype=np.uint8)
    raw_img[1, 1:4] = [0, 30, 0]
    raw_world = load_world(
        write_map(tmp_path, raw_img, "r.pgm", "r.yaml", mode="raw", resolution=1.0)
    )
    assert raw_world.is_free(np.array(row)).tolist() == [True, False, True]


def test_colour_images_average_channels_like_ros(tmp_path):
    # (255, 110, 255) averages to 206.7 (p = 0.19: free) but has luma 170 (p = 0.33: unknown).
    img = np.zeros((3, 3, 3), dtype=np.uint8)
    img[1, 1] = (255, 110, 255)
    world = load_world(write_map(tmp_path, img, image="c.png", resolution=1.0))
    assert world.is_free(np.array([[-0.5, 4.5]])).tolist() == [True]
    assert world.free_area_m2 == pytest.approx(1.0)


def test_sixteen_bit_pgm_is_scaled_to_eight_bits(tmp_path):
    data = np.full((5, 6), 65535, dtype=">u2")
    data[0, :] = data[-1, :] = data[:, 0] = data[:, -1] = 0
    data[2, 3] = 20000  # 78 in 8 bits: p = 0.69, occupied
    (tmp_path / "d.pgm").write_bytes(b"P5\n6 5\n65535\n" + data.tobytes())
    path = write_map(tmp_path, np.zeros((1, 1), np.uint8), image="unused.pgm", resolution=0.5)
    path.write_text(path.read_text().replace("unused.pgm", "d.pgm"))
    world = load_world(path)
    assert world.free_area_m2 == pytest.approx(11 * 0.25)  # 3 x 4 interior, one cell occupied


def test_map_start_explicit_or_farthest_from_walls(tmp_path):
    world = load_world(write_map(tmp_path, start=[-1.0, 3.5, 1.5], name="lab"))
    assert world.name == "lab"
    assert (world.start.x, world.start.y, world.start.theta) == (-1.0, 3.5, 1.5)

    img = np.zeros((13, 13), dtype=np.uint8)
    img[1:12, 1:12] = 254  # an 11 x 11 free square: its centre cell is farthest from walls
    auto = load_world(write_map(tmp_path, img, "sq.pgm", "sq.yaml"))
    assert (auto.start.x, auto.start.y, auto.start.theta) == pytest.approx(
        (-2.0 + 6.5 * RES, 3.0 + 6.5 * RES, 0.0)
    )
    clearance = point_segments_distance(np.array([[auto.start.x, auto.start.y]]), auto.segments)
    assert clearance[0] == pytest.approx(5.5 * RES)


def test_numeric_strings_are_numbers_as_in_ros(tmp_path):
    path = write_map(tmp_path)
    path.write_text(path.read_text().replace("resolution: 0.1", "resolution: 1e-1"))
    assert load_world(path).resolution_m == pytest.approx(0.1)


# --- names ---------------------------------------------------------------------------------------


def test_builtin_names_load_by_name():
    names = builtin_names()
    figures = ["fig1", "fig12", "fig13", "fig14", "fig15", "fig16"]
    assert names == [*figures, "office:SEED", "maze:SEED"]
    assert load_world("fig12").source == "builtin:fig12"
    assert load_world("maze:3").name == "maze:3"


def test_builtin_name_wins_over_a_file_of_the_same_name(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    Path("fig1").write_text("not a world")
    assert load_world("fig1").source == "builtin:fig1"


# --- every malformed file --------------------------------------------------------------------


JSON_CASES = {
    "not JSON": ('{\n  "boundary": [\n    [0, 0] [1, 0]\n]}', ["line 3 column 12", "invalid JSON"]),
    "truncated": ('{"boundary": ', ["invalid JSON"]),
    "top level list": ("[1, 2]", ["top level must be a JSON object, got a list"]),
    "missing boundary": ({"start": {"x": 1, "y": 1}}, ["missing key 'boundary'"]),
    "missing start": ({"boundary": ROOM}, ["missing key 'start'"]),
    "typo key": (polygon_doc(obstacle=[BLOCK]), ["unknown key 'obstacle'"]),
    "duplicate key": ('{"boundary": [], "boundary": []}', ["duplicate key 'boundary'"]),
    "name type": (polygon_doc(name=3), ["'name' must be a non-empty string"]),
    "boundary type": (polygon_doc(boundary="square"), ["boundary: must be a list", "string"]),
    "vertex shape": (polygon_doc(boundary=[[0, 0], [1], [1, 1]]), ["boundary vertex 1", "[x, y]"]),
    "vertex type": (
        polygon_doc(boundary=[[0, 0], ["a", 0], [1, 1]]),
        ["boundary vertex 1 x must be a number"],
    ),
    "bool coordinate": (
        polygon_doc(obstacles=[[[4, 2], [6, 2], [6, True]]]),
        ["obstacle 0 vertex 2 y must be a number"],
    ),
    "nan": (
        '{"boundary": [[0, 0], [NaN, 0], [1, 1]], "start": {"x": 0, "y": 0}}',
        ["boundary vertex 1 x must be a finite number, got nan"],
    ),
    "infinity": (
        '{"boundary": [[0, 0], [1e999, 0], [1, 1]], "start": {"x": 0, "y": 0}}',
        ["boundary vertex 1 x must be a finite number, got inf"],
    ),
    "too few vertices": (polygon_doc(boundary=[[0, 0], [1, 0]]), ["at least 3 vertices, got 2"]),
    "degenerate boundary": (
        polygon_doc(boundary=[[0, 0], [5, 0], [10, 0]]),
        ["boundary: degenerate polygon with zero area"],
    ),
    "zero-area obstacle": (
        polygon_doc(obstacles=[BLOCK, [[7, 1], [8, 2], [7, 1], [8, 2]]]),
        ["obstacle 1: degenerate polygon"],
    ),
    "self-intersecting obstacle": (
        polygon_doc(obstacles=[BLOCK, BLOCK, [[7, 1], [9, 3], [9, 1], [7, 3]]]),
        ["obstacle 2: not a simple polygon (Self-intersection"],
    ),
    "obstacles type": (polygon_doc(obstacles={"a": 1}), ["'obstacles' must be a list"]),
    "start type": (polygon_doc(start=[1, 1]), ["'start' must be an object"]),
    "start missing y": (polygon_doc(start={"x": 1}), ["start: missing key 'y'"]),
    "start theta type": (
        polygon_doc(start={"x": 1, "y": 1, "theta": "north"}),
        ["start theta must be a number"],
    ),
    "start in obstacle": (
        polygon_doc(start={"x": 5, "y": 3}),
        ["start (5.000, 3.000) is not in free space"],
    ),
    "start outside boundary": (
        polygon_doc(start={"x": 12, "y": 3}),
        ["start (12.000, 3.000) is not in free space"],
    ),
    "start too close to a wall": (
        polygon_doc(start={"x": 0.1, "y": 3}),
        ["is 0.100 m from a wall", "needs 0.230 m"],
    ),
    "no free space": (
        polygon_doc(obstacles=[[[-1, -1], [11, -1], [11, 7], [-1, 7]]]),
        ["no free space"],
    ),
    "not UTF-8": (b'{"name": "\xff"}', ["not UTF-8"]),
}


@pytest.mark.parametrize("case", JSON_CASES, ids=list(JSON_CASES))
def test_bad_polygon_json_names_file_and_problem(tmp_path, case):
    content, expected = JSON_CASES[case]
    path = tmp_path / "w.json"
    if isinstance(content, bytes):
        path.write_bytes(content)
    else:
        path.write_text(content if isinstance(content, str) else json.dumps(content))
    message = load_error(path)
    assert message.startswith(f"{path}: ")
    for fragment in expected:
        assert fragment in message


def yaml_with(**keys: object) -> dict:
    return keys


YAML_CASES = {
    "not YAML": ("image: [m.pgm\nresolution: 0.1\n", ["invalid YAML", "line"]),
    "empty": ("", ["empty"]),
    "top level list": ("- 1\n- 2\n", ["top level must be a YAML mapping, got a list"]),
    "missing keys": (
        "image: m.pgm\norigin: [0, 0, 0]\n",
        ["missing key 'resolution', 'negate'"],
    ),
    "negative resolution": (
        yaml_with(resolution=-0.05),
        ["'resolution' must be a positive number, got -0.05"],
    ),
    "resolution text": (yaml_with(resolution="fine"), ["'resolution' must be a number"]),
    "resolution nan": (yaml_with(resolution=".nan"), ["'resolution' must be a finite number"]),
    "origin length": (yaml_with(origin=[0, 0]), ["'origin' must be a list [x, y, yaw]"]),
    "origin yaw": (yaml_with(origin=[0, 0, 0.5]), ["yaw is 0.5", "rotated maps are not supported"]),
    "origin type": (yaml_with(origin=[0, "left", 0]), ["'origin' y must be a number"]),
    "negate": (yaml_with(negate=2), ["'negate' must be 0, 1, true or false, got 2"]),
    "occupied above 1": (
        yaml_with(occupied_thresh=1.5),
        ["'occupied_thresh' must be between 0 and 1, got 1.5"],
    ),
    "free below 0": (yaml_with(free_thresh=-0.1), ["'free_thresh' must be between 0 and 1"]),
    "free above occupied": (
        yaml_with(free_thresh=0.7),
        ["'free_thresh' (0.7) must be less than 'occupied_thresh' (0.65)"],
    ),
    "free equals occupied": (
        yaml_with(free_thresh=0.65),
        ["'free_thresh' (0.65) must be less than 'occupied_thresh' (0.65)"],
    ),
    "unknown mode": (
        yaml_with(mode="fancy"),
        ["unknown 'mode' \"fancy\"", "trinary, scale or raw"],
    ),
    "image type": (yaml_with(image=5), ["'image' must be a file name"]),
    "image missing": (yaml_with(image="gone.pgm"), ["image 'gone.pgm' not found"]),
    "name type": (yaml_with(name=["a"]), ["'name' must be a non-empty string"]),
    "start type": (yaml_with(start={"x": 1}), ["'start' must be a list [x, y]"]),
    "start value": (yaml_with(start=[0, "a"]), ["'start' y must be a number"]),
    "start occupied": (yaml_with(start=[-1.95, 3.05]), ["start (-1.950, 3.050) is not in free"]),
}


@pytest.mark.parametrize("case", YAML_CASES, ids=list(YAML_CASES))
def test_bad_map_server_yaml_names_file_and_problem(tmp_path, case):
    content, expected = YAML_CASES[case]
    path = write_map(tmp_path)
    if isinstance(content, str):
        path.write_text(content)
    else:
        text = path.read_text() + "".join(f"{k}: {json.dumps(v)}\n" for k, v in content.items())
        text = text.replace('".nan"', ".nan")
        path.write_text(text)  # later keys win in PyYAML, so these override
    message = load_error(path)
    assert message.startswith(f"{path}: ")
    for fragment in expected:
        assert fragment in message


def test_image_that_is_not_an_image(tmp_path):
    path = write_map(tmp_path)
    (tmp_path / "m.pgm").write_text("hello, I am text")
    message = load_error(path)
    assert message.startswith(f"{path}: ")
    assert "image 'm.pgm' is not an image" in message


def test_truncated_image(tmp_path):
    path = write_map(tmp_path)
    (tmp_path / "m.pgm").write_bytes(b"P5\n30 20\n255\n" + bytes(17))
    message = load_error(path)
    assert "image 'm.pgm' is damaged or unreadable" in message


def test_image_is_a_directory(tmp_path):
    path = write_map(tmp_path, image="m.png")
    path.write_text(path.read_text().replace("m.png", "sub"))
    (tmp_path / "sub").mkdir()
    assert "image 'sub' is a directory" in load_error(path)


def test_all_occupied_map(tmp_path):
    message = load_error(write_map(tmp_path, np.zeros((4, 4), np.uint8)))
    assert "m.yaml: " in message and "every cell is occupied" in message


def test_map_too_narrow_for_the_robot(tmp_path):
    img = np.zeros((9, 9), dtype=np.uint8)
    img[4, 1:8] = 254  # a 0.1 m wide slot
    message = load_error(write_map(tmp_path, img))
    assert "no free cell leaves room for the robot" in message
    assert "the robot needs 0.230 m" in message


@pytest.mark.parametrize(
    ("name", "setup", "expected"),
    [
        ("missing.json", None, "no such file"),
        ("missing.yaml", None, "no such file"),
        ("dir.json", "dir", "is a directory"),
        ("notes.txt", "file", "unknown extension '.txt'"),
        ("README", "file", "no file extension"),
    ],
)
def test_bad_paths(tmp_path, name, setup, expected):
    path = tmp_path / name
    if setup == "dir":
        path.mkdir()
    elif setup == "file":
        path.write_text("{}")
    message = load_error(str(path))
    assert message.startswith(f"{path}: ")
    assert expected in message


@pytest.mark.parametrize(
    ("spec", "expected"),
    [
        ("fig2", "not a built-in world (fig1, fig12, fig13, fig14, fig15, fig16, office:SEED"),
        ("office", "maze:SEED) and no such file"),
        ("office:abc", "office:abc: the seed must be a non-negative integer, got 'abc'"),
        ("maze:-3", "maze:-3: the seed must be a non-negative integer, got '-3'"),
        ("office:", "the seed must be a non-negative integer, got ''"),
        ("maze:1.5", "got '1.5'"),
        ("", "empty world name"),
    ],
)
def test_bad_names(spec, expected):
    message = load_error(spec)
    assert message.startswith(spec)
    assert expected in message


def test_unreadable_file(tmp_path, monkeypatch):
    # chmod 000 does not stop root, so make the read itself fail the way it would.
    path = write_json(tmp_path, polygon_doc())

    def denied(self: Path) -> bytes:
        raise PermissionError(13, "Permission denied", str(self))

    monkeypatch.setattr(Path, "read_bytes", denied)
    message = load_error(path)
    assert message.startswith(f"{path}: ")
    assert "cannot read the file (Permission denied)" in message


# --- nothing but WorldError escapes, whatever the file holds ------------------------------------

json_values = st.recursive(
    st.none()
    | st.booleans()
    | st.integers(-(10**30), 10**30)
    | st.floats(allow_nan=True, allow_infinity=True)
    | st.text(max_size=5),
    lambda children: (
        st.lists(children, max_size=5)
        | st.dictionaries(st.sampled_from(["x", "y", "theta", "z"]), children, max_size=4)
    ),
    max_leaves=20,
)


# Seeded, no example database: the same 150 cases on every machine.
FUZZ = settings(
    max_examples=150,
    derandomize=True,
    database=None,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)


@FUZZ
@given(
    boundary=st.one_of(
        json_values, st.lists(st.lists(st.integers(-3, 3), min_size=2, max_size=2), max_size=7)
    ),
    obstacles=json_values,
    start=json_values,
)
def test_fuzzed_polygon_json_raises_only_world_error(tmp_path, boundary, obstacles, start):
    path = tmp_path / "f.json"
    path.write_text(json.dumps({"boundary": boundary, "obstacles": obstacles, "start": start}))
    try:
        world = load_world(path)
    except WorldError as exc:
        assert str(exc).startswith(f"{path}: ")
        assert "\n" not in str(exc)
    else:
        assert world.free_area_m2 > 0 and math.isfinite(world.start.x)


@FUZZ
@given(
    key=st.sampled_from(
        [
            *("image", "resolution", "origin", "negate", "occupied_thresh", "free_thresh"),
            *("mode", "start", "name"),
        ]
    ),
    value=json_values,
)
def test_fuzzed_map_yaml_raises_only_world_error(tmp_path, key, value):
    path = write_map(tmp_path)
    path.write_text(path.read_text() + f"{key}: {json.dumps(value)}\n")
    try:
        world = load_world(path)
    except WorldError as exc:
        assert str(exc).startswith(f"{path}: ")
        assert "\n" not in str(exc)
    else:
        assert world.free_area_m2 > 0
