"""``tslam bench serial``: the physical limit from the frame sizes, and a short measured run."""

from __future__ import annotations

import json

import pytest

from tslam.programs.bench_serial import cycle_bytes, physical_limits
from tslam.programs.cli import main


def test_frame_sizes_of_one_control_cycle():
    frames = cycle_bytes(sonar_pos=False)
    # gs: 01 02 00 07 0a 5c; vm: 6 payload bytes; each state reply: 16 sonar bytes, 3 bumper,
    # 8 configuration, 6 velocity and the 7-byte tail, in a 6-byte frame.
    assert frames == {
        "gs_request": 6,
        "gs_reply": 46,
        "vm_request": 12,
        "vm_reply": 46,
        "total": 110,
    }
    limits = physical_limits(sonar_pos=False)
    assert limits["bits_per_cycle"] == 1100
    assert limits["control_hz_limit"]["9600"] == pytest.approx(9600 / 1100, abs=1e-3)
    with_pos = cycle_bytes(sonar_pos=True)
    assert with_pos["gs_reply"] == 46 + 16 * 36


def test_bench_prints_round_trips_and_rates(capsys):
    code = main(["bench", "serial", "--json", "--samples", "20", "--cycles", "20"])
    out, err = capsys.readouterr()
    result = json.loads(out)
    assert code == 0 and "bench serial:" in err
    assert 0 < result["rtt_ms_median"] <= result["rtt_ms_p99"]
    assert result["samples"] == 20
    assert result["control_hz_measured_pty"] > 0
    assert result["control_hz_limit_9600"] == pytest.approx(8.727, abs=1e-3)


def test_bench_refuses_tiny_runs(capsys):
    assert main(["bench", "serial", "--samples", "1"]) == 2
    assert "--samples" in capsys.readouterr().err
