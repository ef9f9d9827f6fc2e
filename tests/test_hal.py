"""hal: the registry, option checking and the lifecycle's failure paths."""

from __future__ import annotations

import subprocess
import sys

import pytest

from hal import (
    BackendNotFoundError,
    ConfigurationError,
    LifecycleError,
    Options,
    State,
    available_backends,
    create_backend,
    parse_spec,
    register_backend,
)
from hal.interfaces import Encoders
from hal.types import Odometry
from sim_backend.backend import SimBackend


def test_url_names_the_backend_and_carries_its_options():
    name, opts = parse_spec("sim://fig12?seed=3&drift=none")
    assert name == "sim" and opts == {"target": "fig12", "seed": "3", "drift": "none"}
    assert parse_spec("sim") == ("sim", {})
    assert parse_spec({"backend": "sim", "seed": 2}) == ("sim", {"seed": 2})


def test_registry_creates_an_unconfigured_sim_backend():
    b = create_backend("sim://fig12?seed=3&drift=none")
    assert isinstance(b, SimBackend) and b.state is State.UNCONFIGURED
    assert b.seed == 3 and b.params.drift == "none" and b.world.name.startswith("fig12")
    assert "sim" in available_backends()


def test_backends_are_imported_only_when_chosen():
    code = (
        "import sys, hal; hal.available_backends(); hal.parse_spec('sim://fig1');"
        "assert 'sim_backend' not in sys.modules, sorted(m for m in sys.modules if 'sim' in m)"
    )
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=60
    )
    assert result.returncode == 0, result.stderr


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        ("nosuch://x", "no backend named 'nosuch'"),
        ("sim://fig12?seed=abc", "option 'seed' must be an integer, got 'abc'"),
        ("sim://fig12?drift=wild", "option 'drift' must be one of none, paper, severe"),
        ("sim://fig12?sede=1", "unknown option(s) sede"),
        ("sim://fig12?beam_deg=nan", "option 'beam_deg' must be a finite number"),
        ("sim://nosuchworld", "nosuchworld"),
        ({"seed": 1}, "needs a 'backend' name"),
        ("", "must be a name or URL"),
    ],
)
def test_bad_configuration_names_what_is_wrong(spec, message):
    with pytest.raises(ConfigurationError) as err:
        create_backend(spec)
    assert message in str(err.value)


def test_registered_target_must_be_a_backend_class():
    register_backend("not-a-backend", "hal.types:Odometry")
    with pytest.raises(BackendNotFoundError, match="not a hal Backend class"):
        create_backend("not-a-backend")
    register_backend("missing-module", "no_such_module_xyz:Thing")
    with pytest.raises(BackendNotFoundError, match="could not be imported"):
        create_backend("missing-module")


def test_options_types_and_ranges():
    o = Options("x", {"a": "2", "b": "0.5", "c": "yes", "d": 3.5})
    assert o.int("a", 0) == 2 and o.float("b", 0.0) == 0.5 and o.bool("c", False) is True
    with pytest.raises(ConfigurationError, match="option 'd' must be an integer"):
        o.int("d", 0)
    with pytest.raises(ConfigurationError, match="must be at most 1"):
        Options("x", {"p": "2"}).float("p", 0.0, hi=1.0)


class _FlakyEncoders(Encoders):
    """Fails half-way through configure, like a port that opens and then refuses settings."""

    backend_name = "flaky"

    def __init__(self) -> None:
        super().__init__()
        self.closed = 0

    @property
    def clock(self):
        raise NotImplementedError

    def _on_configure(self) -> None:
        raise ConfigurationError("flaky: the device refused its settings")

    def _on_close(self) -> None:
        self.closed += 1

    def _odometry(self) -> Odometry:
        return Odometry(0.0, 0.0, 0.0, 0.0, 0.0)


def test_failed_configure_releases_the_link_and_stays_unconfigured():
    b = _FlakyEncoders()
    with pytest.raises(ConfigurationError, match="refused its settings"):
        b.configure()
    assert b.state is State.UNCONFIGURED and b.closed == 1
    with pytest.raises(LifecycleError, match="cannot read odometry while unconfigured"):
        b.odometry()
