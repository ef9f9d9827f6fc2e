"""``tslam bench can --json``: the figures come out as one JSON object, progress on stderr."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from tslam.programs.bench_can import _age, decode_rate

TSLAM = Path(sys.executable).with_name("tslam")


def test_bench_prints_decode_rate_and_latency():
    proc = subprocess.run(
        [str(TSLAM), "bench", "can", "--json", "--frames", "500", "--seconds", "1"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    result = json.loads(proc.stdout)
    assert result["frames_decoded_per_s"] > 0
    assert 0 < result["latency_ms_median"] <= result["latency_ms_p99"]
    for run in result["latency"].values():
        assert run["samples"] > 0 and run["median_ms"] <= run["p99_ms"] <= run["max_ms"]
    assert "latency over slcan" in proc.stderr


def test_bench_refuses_silly_sizes():
    proc = subprocess.run(
        [str(TSLAM), "bench", "can", "--frames", "3"], capture_output=True, text=True, timeout=120
    )
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1 and "--frames" in proc.stderr


def test_probe_values_date_themselves():
    # Value index 7 was taken at t0 + k * interval for the latest k = 7 (mod 1000) before 'seen'.
    t0, interval = 100.0, 0.001
    seen = t0 + 2007 * interval + 0.0004
    assert abs(_age(1.0 + 7 * 0.005, seen, t0, interval) - 0.0004) < 1e-9
    assert abs(_age(1.0 + 6 * 0.005, seen, t0, interval) - 0.0014) < 1e-9


def test_decode_rate_is_positive():
    assert decode_rate(200) > 0
