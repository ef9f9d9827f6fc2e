"""Reading backend options with errors that name the backend, the key and the problem.

Options arrive as strings from URLs (``sim://fig14?seed=3``) or typed values from TOML; both
go through the same checks so a typo never becomes a silent default.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from typing import Any

from hal.errors import ConfigurationError


class Options:
    """Typed, validated access to a backend's option mapping."""

    def __init__(self, backend: str, options: Mapping[str, Any]) -> None:
        self.backend = backend
        self._values = dict(options)
        self._read: set[str] = set()

    def _raw(self, key: str, default: Any) -> Any:
        self._read.add(key)
        return self._values.get(key, default)

    def _fail(self, key: str, what: str, got: Any) -> ConfigurationError:
        return ConfigurationError(f"{self.backend}: option '{key}' {what}, got {got!r}")

    def str(self, key: str, default: str | None = None) -> str:
        v = self._raw(key, default)
        if v is None:
            raise ConfigurationError(f"{self.backend}: option '{key}' is required")
        if not isinstance(v, str):
            raise self._fail(key, "must be a string", v)
        return v

    def choice(self, key: str, choices: Iterable[str], default: str) -> str:
        v = self.str(key, default)
        allowed = list(choices)
        if v not in allowed:
            raise self._fail(key, f"must be one of {', '.join(allowed)}", v)
        return v

    def int(self, key: str, default: int, lo: int | None = None, hi: int | None = None) -> int:
        v = self._raw(key, default)
        try:
            if isinstance(v, bool) or (isinstance(v, float) and not v.is_integer()):
                raise ValueError
            out = int(v)
        except (TypeError, ValueError):
            raise self._fail(key, "must be an integer", v) from None
        self._range(key, out, lo, hi)
        return out

    def float(
        self, key: str, default: float, lo: float | None = None, hi: float | None = None
    ) -> float:
        v = self._raw(key, default)
        try:
            if isinstance(v, bool):
                raise ValueError
            out = float(v)
        except (TypeError, ValueError):
            raise self._fail(key, "must be a number", v) from None
        if not math.isfinite(out):
            raise self._fail(key, "must be a finite number", v)
        self._range(key, out, lo, hi)
        return out

    def bool(self, key: str, default: bool) -> bool:
        v = self._raw(key, default)
        if isinstance(v, bool):
            return v
        if isinstance(v, str) and v.lower() in ("1", "true", "yes", "on"):
            return True
        if isinstance(v, str) and v.lower() in ("0", "false", "no", "off"):
            return False
        raise self._fail(key, "must be true or false", v)

    def _range(self, key: str, v: float, lo: float | None, hi: float | None) -> None:
        if lo is not None and v < lo:
            raise self._fail(key, f"must be at least {lo}", v)
        if hi is not None and v > hi:
            raise self._fail(key, f"must be at most {hi}", v)

    def finish(self) -> None:
        """Refuse keys nobody read: they are typos or options of another backend."""
        unknown = sorted(set(self._values) - self._read)
        if unknown:
            known = ", ".join(sorted(self._read))
            raise ConfigurationError(
                f"{self.backend}: unknown option(s) {', '.join(unknown)} (known: {known})"
            )
