"""The contract every hal backend must honour, as a reusable pytest suite.

A backend's tests subclass ``BackendContract`` and provide ``make_backend``: a fresh,
unconfigured backend placed where it can drive forward ``free_ahead_m`` metres without
touching anything. Tests for interfaces the backend does not provide are skipped, so a
sonar-only board runs the same suite. Time passes through the backend's own clock, so the
suite runs unchanged against a simulator, an emulator or a robot on blocks.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from hal.errors import CommandError, LifecycleError
from hal.interfaces import Backend, Drive, Encoders, SonarRing
from hal.lifecycle import State
from hal.types import Twist


class BackendContract:
    """Mix into a ``Test...`` class and implement ``make_backend``."""

    #: How far the robot may drive straight ahead in the test set-up.
    free_ahead_m: float = 1.0
    #: How long to let motion run in the tests, in seconds of the backend's clock.
    motion_s: float = 1.5

    def make_backend(self) -> Backend:
        raise NotImplementedError

    @pytest.fixture
    def backend(self):
        b = self.make_backend()
        yield b
        b.close()

    @pytest.fixture
    def active(self, backend):
        backend.configure()
        backend.activate()
        return backend

    def _need(self, backend: Backend, *kinds: type) -> None:
        missing = [k.__name__ for k in kinds if not isinstance(backend, k)]
        if missing:
            pytest.skip(f"backend does not provide {', '.join(missing)}")

    # ------------------------------------------------------------------ lifecycle
    def test_starts_unconfigured_and_refuses_everything(self, backend):
        assert backend.state is State.UNCONFIGURED
        if isinstance(backend, Drive):
            with pytest.raises(LifecycleError):
                backend.command(Twist(0.1, 0.0, 0.0))
            with pytest.raises(LifecycleError):
                backend.status()
        if isinstance(backend, Encoders):
            with pytest.raises(LifecycleError):
                backend.odometry()
        if isinstance(backend, SonarRing):
            with pytest.raises(LifecycleError):
                backend.scan()

    def test_configured_but_inactive_refuses_motion_and_allows_reads(self, backend):
        backend.configure()
        assert backend.state is State.INACTIVE
        if isinstance(backend, Drive):
            with pytest.raises(LifecycleError):
                backend.command(Twist(0.1, 0.0, 0.0))
            backend.stop()  # stopping is always allowed while the link is open
            assert backend.status().stamp_s >= 0.0
        if isinstance(backend, Encoders):
            assert math.isfinite(backend.odometry().x_m)
        if isinstance(backend, SonarRing):
            assert len(backend.scan()) == backend.n_transducers

    def test_transitions_out_of_order_are_refused(self, backend):
        with pytest.raises(LifecycleError):
            backend.activate()
        backend.configure()
        with pytest.raises(LifecycleError):
            backend.configure()
        with pytest.raises(LifecycleError):
            backend.deactivate()
        backend.activate()
        with pytest.raises(LifecycleError):
            backend.activate()

    def test_close_is_final_and_idempotent(self, active):
        active.close()
        active.close()
        assert active.state is State.CLOSED
        with pytest.raises(LifecycleError):
            active.configure()
        if isinstance(active, Encoders):
            with pytest.raises(LifecycleError):
                active.odometry()
        if isinstance(active, Drive):
            active.stop()  # harmless once closed: closing already stopped the robot

    def test_context_manager_activates_and_closes(self):
        b = self.make_backend()
        with b as entered:
            assert entered is b
            assert b.state is State.ACTIVE
        assert b.state is State.CLOSED

    # ------------------------------------------------------------------ drive + encoders
    def test_forward_command_moves_the_robot(self, active):
        self._need(active, Drive, Encoders)
        before = active.odometry()
        speed = min(0.2, active.limits.v_mps, self.free_ahead_m / (2 * self.motion_s))
        active.command(Twist(speed, 0.0, 0.0))
        active.clock.sleep(self.motion_s)
        after = active.odometry()
        moved = math.hypot(after.x_m - before.x_m, after.y_m - before.y_m)
        assert after.stamp_s > before.stamp_s
        assert 0.2 * speed * self.motion_s < moved <= speed * self.motion_s * 1.05 + 0.01
        assert after.distance_m - before.distance_m == pytest.approx(moved, rel=0.05, abs=0.01)
        assert active.status().motors_on

    def test_stop_halts_motion(self, active):
        self._need(active, Drive, Encoders)
        active.command(Twist(0.15, 0.0, 0.0))
        active.clock.sleep(0.5)
        active.stop()
        active.clock.sleep(2.0)  # let deceleration finish
        a = active.odometry()
        active.clock.sleep(1.0)
        b = active.odometry()
        assert math.hypot(b.x_m - a.x_m, b.y_m - a.y_m) < 1e-3

    def test_deactivate_stops_the_robot(self, active):
        self._need(active, Drive, Encoders)
        active.command(Twist(0.15, 0.0, 0.0))
        active.clock.sleep(0.5)
        active.deactivate()
        active.clock.sleep(2.0)
        a = active.odometry()
        active.clock.sleep(1.0)
        b = active.odometry()
        assert math.hypot(b.x_m - a.x_m, b.y_m - a.y_m) < 1e-3

    def test_non_finite_command_is_refused_and_stops(self, active):
        self._need(active, Drive, Encoders)
        active.command(Twist(0.15, 0.0, 0.0))
        active.clock.sleep(0.5)
        with pytest.raises(CommandError):
            active.command(Twist(math.nan, 0.0, 0.0))
        active.clock.sleep(2.0)
        a = active.odometry()
        active.clock.sleep(1.0)
        b = active.odometry()
        assert math.hypot(b.x_m - a.x_m, b.y_m - a.y_m) < 1e-3

    def test_commands_beyond_limits_are_clamped(self, active):
        self._need(active, Drive, Encoders)
        lim = active.limits
        active.command(Twist(0.0, 100.0 * lim.steer_radps, 0.0))
        active.clock.sleep(self.motion_s)
        turned = abs(active.odometry().heading_rad)
        assert 0.0 < turned <= lim.steer_radps * self.motion_s * 1.1 + 1e-3

    def test_turret_turns_the_sonar_poses(self, active):
        self._need(active, Drive, SonarRing)
        yaw0 = active.scan().yaw_rad.copy()
        active.command(Twist(0.0, 0.0, active.limits.turret_radps))
        # Long enough for every transducer to fire again after the turret moved.
        active.clock.sleep(max(self.motion_s, 2.5))
        active.stop()
        yaw1 = active.scan().yaw_rad
        dyaw = np.angle(np.exp(1j * (yaw1 - yaw0)))
        assert np.all(dyaw > math.radians(5.0))

    # ------------------------------------------------------------------ sonar ring
    def test_scan_is_well_formed(self, active):
        self._need(active, SonarRing)
        active.clock.sleep(1.2)
        s = active.scan()
        n = active.n_transducers
        assert len(s) == n and s.x_m.shape == s.y_m.shape == s.yaw_rad.shape == (n,)
        assert s.stamps_s.shape == (n,)
        assert np.all(s.stamps_s <= active.clock.now() + 1e-9)
        r = s.ranges_m[s.echo]
        assert np.all((r >= s.min_range_m) & (r <= s.max_range_m))
        assert s.echo.any(), "a ring in a room hears at least one wall"
        radius = np.hypot(s.x_m, s.y_m)
        assert np.all(radius > 0.05) and np.all(radius < 0.5)
        # Each transducer looks outward from where it sits on the ring.
        bearing = np.arctan2(s.y_m, s.x_m)
        assert np.all(np.abs(np.angle(np.exp(1j * (s.yaw_rad - bearing)))) < math.radians(1.0))
        one = s.reading(int(np.argmax(s.echo)))
        assert one.range_m is not None and one.range_m == pytest.approx(
            float(s.ranges_m[int(np.argmax(s.echo))])
        )

    def test_scan_stamps_advance(self, active):
        self._need(active, SonarRing)
        a = active.scan().stamps_s.copy()
        active.clock.sleep(1.5)
        b = active.scan().stamps_s
        assert np.all(b > a)
