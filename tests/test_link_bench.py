"""``tslam bench link --json``, run small: the keys are there and the figures are sane (no
timing asserted: the figures depend on the machine)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

TSLAM = Path(sys.executable).with_name("tslam")


def test_bench_link_prints_its_figures():
    proc = subprocess.run(
        [str(TSLAM), "bench", "link", "--json", "--events", "40", "--event-hz", "200",
         "--nodes", "30", "--fetches", "2", "--world", "fig12"],
        capture_output=True,
        text=True,
        timeout=300,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    r = json.loads(proc.stdout)
    assert 0 < r["latency_ms_p50"] <= r["latency_ms_p99"] <= r["latency_ms_max"]
    assert r["events_received"] == r["events_sent"] == 40
    snap = r["snapshot"]
    assert snap["nodes"] == 30 and snap["bytes"] > 30 * 50 and snap["fetch_ms_p50"] > 0
    mc = r["map_changes"]
    assert mc["changes"] >= mc["gvg_nodes"] and mc["bytes_per_s_mean"] > 0
    assert mc["bytes_per_s_peak"] >= mc["bytes_per_s_mean"]
    assert r["map_changes_bytes_per_s"] == mc["bytes_per_s_mean"]
    assert "exploration model" in proc.stderr


def test_bench_link_refuses_silly_sizes():
    proc = subprocess.run(
        [str(TSLAM), "bench", "link", "--events", "3"], capture_output=True, text=True, timeout=120
    )
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1 and "--events" in proc.stderr
