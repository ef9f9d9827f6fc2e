"""The hal contract suite run against the simulator, through the registry as a user would."""

from __future__ import annotations

from hal.contract import BackendContract
from hal.registry import create_backend
from sim_backend.backend import SimBackend
from tests.conftest import box_world


class TestSimContract(BackendContract):
    free_ahead_m = 5.0

    def make_backend(self):
        return SimBackend(box_world(), seed=3)


class TestSimContractFromUrl(BackendContract):
    """Same contract, backend created from a URL naming a built-in world."""

    free_ahead_m = 0.6

    def make_backend(self):
        return create_backend("sim://fig12?seed=5&drift=none")
