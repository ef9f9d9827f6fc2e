"""The dependency direction of ARCHITECTURE.md, checked with import-linter."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
LINT = Path(sys.executable).with_name("lint-imports")


def lint(cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [str(LINT), "--config", "pyproject.toml", "--no-cache"],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=120,
        env={"PYTHONPATH": str(cwd), "PATH": "/usr/bin:/bin"},
    )


@pytest.fixture(scope="module")
def lint_available():
    if not LINT.exists():
        pytest.fail("import-linter is not installed (pip install -e '.[test]')")


def test_the_tree_keeps_every_contract(lint_available):
    result = lint(ROOT)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "broken" in result.stdout and "0 broken" in result.stdout


@pytest.mark.parametrize(
    ("path", "source", "contract"),
    [
        ("hal/_probe.py", "import sim_backend.world\n", "hal depends on nothing of ours"),
        ("tslam/core/_probe.py", "import time\n", "the tslam core is pure"),
        ("tslam/core/_probe.py", "import sim_backend\n", "the tslam core is pure"),
        ("sim_backend/_probe.py", "import tslam.programs\n", "sim_backend sits on hal"),
    ],
)
def test_a_violation_is_caught(lint_available, tmp_path, path, source, contract):
    for pkg in ("hal", "drivers", "sim_backend", "tslam"):
        shutil.copytree(ROOT / pkg, tmp_path / pkg, ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copy(ROOT / "pyproject.toml", tmp_path / "pyproject.toml")
    (tmp_path / path).write_text(source)
    result = lint(tmp_path)
    assert result.returncode != 0
    assert f"{contract}" in result.stdout and "BROKEN" in result.stdout
