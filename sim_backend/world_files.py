"""Loading worlds from built-in names, polygon JSON files and ROS map_server maps.

``load_world(spec)`` is the one entry point the simulator and the command line use. Whatever
goes wrong with a user's file comes back as a ``WorldError`` whose message is a single line
starting with the path as the user typed it, so a CLI can print it verbatim and an editor can
jump to the file; no KeyError, TypeError, PIL or YAML exception ever escapes for a bad file.

Polygon JSON (metres)::

    {"name": "lab", "boundary": [[x, y], ...], "obstacles": [[[x, y], ...], ...],
     "start": {"x": 1.0, "y": 2.0, "theta": 0.0}}

``name`` defaults to the file stem, ``obstacles`` to none and ``theta`` to 0. Unknown keys
are refused: in a hand-written file they are nearly always typos ("obstacle") that would
otherwise silently drop half the world.

ROS map_server YAML: ``image``, ``resolution``, ``origin``, ``negate``, ``occupied_thresh``,
``free_thresh`` and optionally ``mode``, plus two keys of ours: ``name`` and
``start: [x, y, theta]``. Other keys are ignored, as map_server ignores them.
"""

from __future__ import annotations

import json
import math
import os
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np
import shapely
import yaml
from PIL import Image, UnidentifiedImageError
from scipy import ndimage

from sim_backend.builtin_worlds import (
    ROBOT_RADIUS_M,
    builtin_names,
    builtin_world,
    is_builtin_name,
)
from sim_backend.ground_truth import compute_gvg
from sim_backend.world import GridWorld, PolygonWorld, StartPose, World, WorldError

__all__ = [
    "ROBOT_RADIUS_M",
    "builtin_names",
    "load_world",
    "map_server_values",
    "polygon_world_to_json",
]

_JSON_EXT = (".json",)
_YAML_EXT = (".yaml", ".yml")
_JSON_KEYS = ("name", "boundary", "obstacles", "start")
_YAML_REQUIRED = ("image", "resolution", "origin", "negate", "occupied_thresh", "free_thresh")
_MODES = ("trinary", "scale", "raw")


class _FileError(Exception):
    """A problem in the file; ``load_world`` prefixes the path and re-raises as WorldError."""


def load_world(spec: str | os.PathLike[str]) -> World:
    """Load a built-in world by name or a world file by path; see the module docstring.

    Built-in names win over files of the same name (write ``./fig1`` for such a file), so a
    stray file in the working directory cannot change what ``fig1`` means.
    """
    text = os.fspath(spec)
    if not text.strip():
        raise WorldError(
            "empty world name: give a built-in world (" + ", ".join(builtin_names()) + ")"
            " or a .json/.yaml file"
        )
    if is_builtin_name(text):
        return builtin_world(text)
    path = Path(text)
    suffix = path.suffix.lower()
    try:
        try:
            exists = path.exists()
        except (OSError, ValueError) as exc:
            raise _FileError(f"cannot access the file ({exc})") from None
        if not exists:
            if suffix:
                raise _FileError("no such file")
            raise _FileError(
                "not a built-in world (" + ", ".join(builtin_names()) + ") and no such file"
            )
        if path.is_dir():
            raise _FileError("is a directory, not a world file")
        if not suffix:
            raise _FileError(
                "no file extension: expected .json (polygon world)"
                " or .yaml/.yml (ROS map_server map)"
            )
        if suffix in _JSON_EXT:
            world: World = _load_polygon_json(path)
        elif suffix in _YAML_EXT:
            world = _load_map_server(path)
        else:
            raise _FileError(
                f"unknown extension {path.suffix!r}: expected .json (polygon world)"
                " or .yaml/.yml (ROS map_server map)"
            )
    except (_FileError, WorldError) as exc:
        raise WorldError(_one_line(f"{text}: {exc}")) from exc
    except shapely.errors.GEOSException as exc:
        raise WorldError(_one_line(f"{text}: the geometry cannot be processed ({exc})")) from exc
    return world


def _one_line(message: str) -> str:
    return " ".join(message.split())


def _read_bytes(path: Path, what: str = "file") -> bytes:
    try:
        return path.read_bytes()
    except IsADirectoryError:
        raise _FileError(f"the {what} is a directory") from None
    except OSError as exc:
        raise _FileError(f"cannot read the {what} ({exc.strerror or exc})") from None


def _decode(data: bytes) -> str:
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise _FileError(f"not UTF-8 text (byte {exc.start})") from None


def _type_name(value: object) -> str:
    names = {dict: "an object", list: "a list", str: "a string", bool: "a boolean"}
    if value is None:
        return "null"
    for t, n in names.items():
        if isinstance(value, t):
            return n
    if isinstance(value, int | float):
        return "a number"
    return type(value).__name__


def _number(value: object, what: str) -> float:
    """A finite float; booleans are refused although Python counts them as ints."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise _FileError(f"{what} must be a number, got {_type_name(value)} {_show(value)}")
    try:
        out = float(value)
    except OverflowError:
        out = math.inf
    if not math.isfinite(out):
        raise _FileError(f"{what} must be a finite number, got {_show(value)}")
    return out


def _show(value: object) -> str:
    text = json.dumps(value) if isinstance(value, str) else repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


# ---------------------------------------------------------------------------------------------
# Polygon JSON
# ---------------------------------------------------------------------------------------------


def _no_duplicate_keys(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in pairs:
        if key in out:
            raise _FileError(f"duplicate key {key!r}")
        out[key] = value
    return out


def _load_polygon_json(path: Path) -> PolygonWorld:
    text = _decode(_read_bytes(path))
    try:
        doc = json.loads(text, object_pairs_hook=_no_duplicate_keys)
    except json.JSONDecodeError as exc:
        raise _FileError(
            f"line {exc.lineno} column {exc.colno}: invalid JSON ({exc.msg})"
        ) from None
    except RecursionError:
        raise _FileError("invalid JSON (nested too deeply)") from None
    if not isinstance(doc, dict):
        raise _FileError(f"the top level must be a JSON object, got {_type_name(doc)}")
    unknown = [k for k in doc if k not in _JSON_KEYS]
    if unknown:
        raise _FileError(f"unknown key {unknown[0]!r} (expected {', '.join(_JSON_KEYS)})")
    missing = [k for k in ("boundary", "start") if k not in doc]
    if missing:
        raise _FileError(f"missing key {missing[0]!r}")
    name = doc.get("name", path.stem)
    if not isinstance(name, str) or not name.strip():
        raise _FileError(f"'name' must be a non-empty string, got {_type_name(name)} {_show(name)}")
    boundary = _vertices(doc["boundary"], "boundary")
    obstacles_doc = doc.get("obstacles", [])
    if not isinstance(obstacles_doc, list):
        raise _FileError(f"'obstacles' must be a list of polygons, got {_type_name(obstacles_doc)}")
    obstacles = [_vertices(o, f"obstacle {i}") for i, o in enumerate(obstacles_doc)]
    start = _json_start(doc["start"])
    world = PolygonWorld(name, boundary, obstacles, start, source=str(path))
    world.check_start(ROBOT_RADIUS_M)
    return world


def _vertices(value: object, what: str) -> list[tuple[float, float]]:
    """Type-check a polygon and refuse flat ones; whether it is simple is PolygonWorld's job."""
    if not isinstance(value, list):
        raise _FileError(f"{what}: must be a list of [x, y] vertices, got {_type_name(value)}")
    if len(value) < 3:
        raise _FileError(f"{what}: a polygon needs at least 3 vertices, got {len(value)}")
    out = []
    for i, v in enumerate(value):
        if not isinstance(v, list) or len(v) != 2:
            raise _FileError(f"{what} vertex {i}: must be an [x, y] pair, got {_show(v)}")
        out.append((_number(v[0], f"{what} vertex {i} x"), _number(v[1], f"{what} vertex {i} y")))
    # A flat polygon would otherwise be reported as "self-intersecting", which misleads.
    # Scale first: differences of coordinates near the float limit would overflow.
    xy = np.asarray(out)
    scale = float(np.abs(xy).max()) or 1.0
    spread = np.linalg.svd(xy / scale - xy[0] / scale, compute_uv=False)
    if spread[1] <= 1e-9 * max(1e-300, float(spread[0])):
        raise _FileError(f"{what}: degenerate polygon with zero area (all vertices on one line)")
    return out


def _json_start(value: object) -> StartPose:
    if not isinstance(value, dict):
        raise _FileError(f"'start' must be an object with x, y, theta, got {_type_name(value)}")
    unknown = [k for k in value if k not in ("x", "y", "theta")]
    if unknown:
        raise _FileError(f"start: unknown key {unknown[0]!r} (expected x, y, theta)")
    for key in ("x", "y"):
        if key not in value:
            raise _FileError(f"start: missing key {key!r}")
    return StartPose(
        _number(value["x"], "start x"),
        _number(value["y"], "start y"),
        _number(value.get("theta", 0.0), "start theta"),
    )


def polygon_world_to_json(world: PolygonWorld) -> dict[str, Any]:
    """The polygon JSON document for ``world``, so a generated world can be saved and edited."""
    return {
        "name": world.name,
        "boundary": np.asarray(world.boundary, dtype=float).tolist(),
        "obstacles": [np.asarray(o, dtype=float).tolist() for o in world.obstacles],
        "start": {"x": world.start.x, "y": world.start.y, "theta": world.start.theta},
    }


# ---------------------------------------------------------------------------------------------
# ROS map_server
# ---------------------------------------------------------------------------------------------


def map_server_values(
    gray: np.ndarray, negate: bool, occupied_thresh: float, free_thresh: float, mode: str
) -> np.ndarray:
    """The OccupancyGrid values map_server would publish for 8-bit grey pixels (same layout).

    ``trinary``: 100 occupied, 0 free, -1 unknown. ``scale``: as trinary but the cells between
    the thresholds get 1..99, scaled linearly. ``raw``: the (negated) pixel value itself, where
    map_server passes 0..100 through and anything above means unknown (-1 here).
    """
    v = np.asarray(gray, dtype=float)
    if negate:
        v = 255.0 - v
    if mode == "raw":
        raw = np.rint(v).astype(np.int16)
        return np.where(raw <= 100, raw, -1).astype(np.int8)
    p = (255.0 - v) / 255.0
    out = np.full(v.shape, -1, dtype=np.int8)
    if mode == "scale":
        ratio = (p - free_thresh) / (occupied_thresh - free_thresh)
        out = np.rint(1.0 + 98.0 * np.clip(ratio, 0.0, 1.0)).astype(np.int8)
    out[p > occupied_thresh] = 100
    out[p < free_thresh] = 0
    return out


def _load_map_server(path: Path) -> GridWorld:
    """A GridWorld from a map_server YAML and its image.

    Only cells map_server calls certainly free (value 0) become free space. Unknown cells are
    made occupied because in a map built by SLAM they are the region the sensor never saw, i.e.
    outside the mapped building or inside walls and furniture; leaving them free would let the
    simulated robot drive out of the map into space with no walls. Cells of intermediate
    probability (``scale``/``raw``) are made occupied for the same reason: a simulated world
    needs a definite wall wherever the map is not sure the floor is clear.
    """
    text = _decode(_read_bytes(path))
    try:
        doc = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        problem = getattr(exc, "problem", None) or str(exc)
        where = f"line {mark.line + 1} column {mark.column + 1}: " if mark is not None else ""
        raise _FileError(f"{where}invalid YAML ({problem})") from None
    except RecursionError:
        raise _FileError("invalid YAML (nested too deeply)") from None
    if doc is None:
        raise _FileError("the file is empty; expected a map_server YAML mapping")
    if not isinstance(doc, dict):
        raise _FileError(f"the top level must be a YAML mapping, got {_type_name(doc)}")
    missing = [k for k in _YAML_REQUIRED if k not in doc]
    if missing:
        raise _FileError("missing key " + ", ".join(repr(k) for k in missing))

    image_name = doc["image"]
    if not isinstance(image_name, str) or not image_name.strip():
        raise _FileError(
            f"'image' must be a file name, got {_type_name(image_name)} {_show(image_name)}"
        )
    resolution = _yaml_number(doc, "resolution")
    if resolution <= 0:
        raise _FileError(f"'resolution' must be a positive number, got {_show(doc['resolution'])}")
    origin = _yaml_origin(doc["origin"])
    negate = doc["negate"]
    if isinstance(negate, bool) or negate in (0, 1):
        negate = bool(negate)
    else:
        raise _FileError(f"'negate' must be 0, 1, true or false, got {_show(negate)}")
    occ = _threshold(doc, "occupied_thresh")
    free = _threshold(doc, "free_thresh")
    if free >= occ:
        raise _FileError(f"'free_thresh' ({free:g}) must be less than 'occupied_thresh' ({occ:g})")
    mode = doc.get("mode", "trinary")
    if mode not in _MODES:
        raise _FileError(f"unknown 'mode' {_show(mode)} (expected trinary, scale or raw)")
    name = doc.get("name", path.stem)
    if not isinstance(name, str) or not name.strip():
        raise _FileError(f"'name' must be a non-empty string, got {_type_name(name)} {_show(name)}")
    start = _yaml_start(doc["start"]) if "start" in doc else None

    image_path = Path(image_name)
    if not image_path.is_absolute():
        image_path = path.parent / image_path
    gray = _read_gray(image_path, image_name)
    values = map_server_values(gray, negate, occ, free, mode)
    occupied = np.flipud(values != 0)  # image row 0 is the top; GridWorld's is the bottom
    auto_start = start is None
    if start is None:
        start = _max_clearance_start(occupied, resolution, origin)
    world = GridWorld(name, occupied, resolution, origin, start, source=str(path))
    try:
        world.check_start(ROBOT_RADIUS_M)
    except WorldError as exc:
        if auto_start:
            raise _FileError(f"no free cell leaves room for the robot: {exc}") from None
        raise
    junction = _junction_start(world) if auto_start else None
    if junction is not None:
        world = GridWorld(name, occupied, resolution, origin, junction, source=str(path))
    return world


def _yaml_num(value: object, what: str) -> float:
    """Like ``_number``, but a numeric string counts, as it does for ROS's yaml-cpp.

    PyYAML follows YAML 1.1, which reads ``5e-2`` (no dot) as a string; map_server would take
    it as 0.05, so refusing it would reject maps that work in ROS.
    """
    if isinstance(value, str):
        try:
            parsed = float(value.strip())
        except ValueError:
            raise _FileError(f"{what} must be a number, got a string {_show(value)}") from None
        return _number(parsed, what)
    return _number(value, what)


def _yaml_number(doc: dict[str, Any], key: str) -> float:
    return _yaml_num(doc[key], f"'{key}'")


def _threshold(doc: dict[str, Any], key: str) -> float:
    value = _yaml_number(doc, key)
    if not 0.0 <= value <= 1.0:
        raise _FileError(f"'{key}' must be between 0 and 1, got {_show(doc[key])}")
    return value


def _yaml_origin(value: object) -> tuple[float, float]:
    if not isinstance(value, list) or len(value) != 3:
        raise _FileError(f"'origin' must be a list [x, y, yaw], got {_show(value)}")
    x = _yaml_num(value[0], "'origin' x")
    y = _yaml_num(value[1], "'origin' y")
    yaw = _yaml_num(value[2], "'origin' yaw")
    if abs(yaw) > 1e-9:
        raise _FileError(f"'origin' yaw is {yaw:g} rad: rotated maps are not supported, use yaw 0")
    return (x, y)


def _yaml_start(value: object) -> StartPose:
    if not isinstance(value, list) or len(value) not in (2, 3):
        raise _FileError(f"'start' must be a list [x, y] or [x, y, theta], got {_show(value)}")
    nums = [_yaml_num(v, f"'start' {k}") for v, k in zip(value, ("x", "y", "theta"), strict=False)]
    return StartPose(*nums)


@contextmanager
def _image_errors(shown: str, image_path: Path) -> Iterator[None]:
    """Turn Pillow's many failure modes (OSError, SyntaxError, ValueError, ...) into one line."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error", Image.DecompressionBombWarning)
            yield
    except FileNotFoundError:
        raise _FileError(f"image {shown!r} not found (looked for {image_path})") from None
    except IsADirectoryError:
        raise _FileError(f"image {shown!r} is a directory ({image_path})") from None
    except PermissionError:
        raise _FileError(f"image {shown!r} cannot be read: permission denied") from None
    except UnidentifiedImageError:
        raise _FileError(
            f"image {shown!r} is not an image Pillow can read ({image_path})"
        ) from None
    except (
        OSError,
        SyntaxError,
        ValueError,
        EOFError,
        MemoryError,
        Image.DecompressionBombError,
        Image.DecompressionBombWarning,
    ) as exc:
        raise _FileError(f"image {shown!r} is damaged or unreadable ({exc})") from None


def _read_gray(image_path: Path, shown: str) -> np.ndarray:
    """8-bit grey levels as map_server computes them: the plain mean of the colour channels.

    Pillow's ``convert('L')`` weights green more (ITU-R 601 luma), which would move coloured
    pixels across thresholds compared with ROS; alpha is left out, as ROS leaves it out of
    the mean. 16-bit images are scaled to 8 bits, as map_server's image libraries do.
    """
    with _image_errors(shown, image_path), Image.open(image_path) as img:
        img.load()
        mode = img.mode
        if mode in ("L", "LA"):
            arr = np.asarray(img.getchannel("L"), dtype=float)
        elif mode == "1":
            arr = np.asarray(img.convert("L"), dtype=float)
        elif mode.startswith("I"):
            wide = np.asarray(img if mode == "I" else img.convert("I"), dtype=float)
            arr = np.clip(wide, 0, 65535) / 257.0
        elif mode == "F":
            raise _FileError(f"image {shown!r} has floating-point pixels; expected 8 or 16 bits")
        else:
            rgb = np.asarray(img.convert("RGB"), dtype=float)
            arr = rgb.mean(axis=2)
    if arr.ndim != 2 or arr.size == 0:
        raise _FileError(f"image {shown!r} has no pixels")
    return arr


#: A map with no start begins at a junction of the ground truth's GVG this clear of walls: a
#: corridor's, where the doors off it are near enough for the sonar to see, not the middle of
#: the largest room (the farthest free cell), whose door a ring 3 m off cannot resolve. Started
#: there, on a floor of two rooms off a corridor the robot mapped its room and called it
#: complete (2 places of 10, seeds 1-3); started at the corridor's junction, all of it.
JUNCTION_START_CLEARANCE_M = (0.5, 1.5)


def _junction_start(world: World) -> StartPose | None:
    """Where a map with no start begins: the meet point of most edges whose clearance is in
    ``JUNCTION_START_CLEARANCE_M``, the one nearest the middle of all of them among equals;
    None if there is none (the farthest free cell, as given, stands)."""
    meets = compute_gvg(world).meet_points
    lo, hi = JUNCTION_START_CLEARANCE_M
    fit = [m for m in meets if lo <= m.clearance_m <= hi]
    if not fit:
        return None
    cx = sum(m.x for m in meets) / len(meets)
    cy = sum(m.y for m in meets) / len(meets)
    best = max(fit, key=lambda m: (m.degree, -math.hypot(m.x - cx, m.y - cy)))
    return StartPose(float(best.x), float(best.y), 0.0)


def _max_clearance_start(
    occupied: np.ndarray, resolution: float, origin: tuple[float, float]
) -> StartPose:
    """The centre of the free cell farthest from any occupied cell (first such in row order).

    The map names no start, and the farthest-from-walls cell is the one place sure to fit the
    robot; the grid is padded with occupied cells because GridWorld treats the outside as
    occupied. Ties go to the lowest row, then column, so the choice is deterministic.
    """
    free = np.pad(~occupied, 1, constant_values=False)
    clearance = ndimage.distance_transform_edt(free)[1:-1, 1:-1]
    row, col = np.unravel_index(int(np.argmax(clearance)), clearance.shape)
    x = origin[0] + (int(col) + 0.5) * resolution
    y = origin[1] + (int(row) + 0.5) * resolution
    return StartPose(float(x), float(y), 0.0)
