"""Create a backend from configuration, by name or URL, importing it only when chosen.

Backends are registered as ``"module.path:ClassName"`` strings: by the ``tslam.backends``
entry-point group of installed packages, or at run time with ``register_backend``. Nothing
is imported until ``create_backend`` picks one, so a laptop without pyserial or python-can
can still run the simulator.

Specs:

- ``"sim"`` or ``{"backend": "sim", "world": "fig14", "seed": 3}``;
- a URL ``"sim://fig14?seed=3&drift=paper"``: the scheme names the backend, the part after
  ``//`` becomes the option ``target`` and the query adds options (as strings; the backend
  converts and checks them).
"""

from __future__ import annotations

import importlib
from collections.abc import Mapping
from importlib.metadata import entry_points
from typing import Any
from urllib.parse import parse_qsl, urlsplit

from hal.errors import BackendNotFoundError, ConfigurationError
from hal.interfaces import Backend

ENTRY_POINT_GROUP = "tslam.backends"

_registered: dict[str, str] = {}


def register_backend(name: str, target: str) -> None:
    """Register ``target`` ("module:Class") under ``name``; later registrations win."""
    if ":" not in target:
        raise ValueError(f"backend target must look like 'module:Class', got {target!r}")
    _registered[name] = target


def available_backends() -> dict[str, str]:
    """Every known backend name and where it lives (nothing is imported)."""
    found = {ep.name: ep.value for ep in entry_points(group=ENTRY_POINT_GROUP)}
    found.update(_registered)
    return dict(sorted(found.items()))


def parse_spec(spec: str | Mapping[str, Any]) -> tuple[str, dict[str, Any]]:
    """Split a spec into the backend name and its options."""
    if isinstance(spec, Mapping):
        options = dict(spec)
        name = options.pop("backend", None)
        if not isinstance(name, str) or not name:
            raise ConfigurationError("backend configuration needs a 'backend' name")
        return name, options
    if not isinstance(spec, str) or not spec.strip():
        raise ConfigurationError(f"backend spec must be a name or URL, got {spec!r}")
    spec = spec.strip()
    if "://" not in spec:
        return spec, {}
    parts = urlsplit(spec)
    options: dict[str, Any] = {}
    target = parts.netloc + parts.path
    if target:
        options["target"] = target
    try:
        pairs = parse_qsl(parts.query, keep_blank_values=True, strict_parsing=bool(parts.query))
    except ValueError as exc:
        raise ConfigurationError(f"{spec}: malformed query string ({exc})") from None
    for key, value in pairs:
        if key in options:
            raise ConfigurationError(f"{spec}: option '{key}' given twice")
        options[key] = value
    return parts.scheme, options


def backend_class(name: str) -> type[Backend]:
    """Import and return the class registered under ``name``."""
    known = available_backends()
    if name not in known:
        raise BackendNotFoundError(
            f"no backend named '{name}' (available: {', '.join(known) or 'none'})"
        )
    module_name, _, attr = known[name].partition(":")
    try:
        module = importlib.import_module(module_name)
    except ImportError as exc:
        raise BackendNotFoundError(
            f"backend '{name}' could not be imported from {module_name}: {exc}"
        ) from exc
    cls = getattr(module, attr, None)
    if not (isinstance(cls, type) and issubclass(cls, Backend)):
        raise BackendNotFoundError(f"backend '{name}': {known[name]} is not a hal Backend class")
    return cls


def create_backend(spec: str | Mapping[str, Any], **overrides: Any) -> Backend:
    """Build an unconfigured backend; nothing is opened and nothing moves until ``configure``."""
    name, options = parse_spec(spec)
    options.update(overrides)
    cls = backend_class(name)
    from_config = getattr(cls, "from_config", None)
    if from_config is None:
        raise BackendNotFoundError(f"backend '{name}' has no from_config(options) constructor")
    return from_config(options)
