"""The daemon's configuration: the examples shipped in deploy/ load, and every mistake is one
line naming the key, exit code 2, before anything opens or moves."""

from __future__ import annotations

from pathlib import Path

import pytest

from hal.registry import parse_spec
from tslam.daemon.config import ConfigError, load_config, parse_config
from tslam.programs.cli import main

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = sorted((ROOT / "deploy" / "examples").glob("*.toml"))
GOOD = {"robot": "r1", "storage": "store", "backend": {"backend": "sim", "world": "fig12"}}


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.name)
def test_shipped_examples_load(path, tmp_path):
    # The robot examples name files under /etc that exist on a robot, not here.
    text = path.read_text()
    for src, dst in (
        ("/etc/tslam/zenoh/robot-peer.json5", str(ROOT / "deploy/zenoh/robot-peer.json5")),
        ("/etc/tslam/nomad-1.credentials", str(ROOT / "deploy/zenoh/credentials.example")),
        ("/etc/tslam/nomad-2.credentials", str(ROOT / "deploy/zenoh/credentials.example")),
    ):
        text = text.replace(src, dst)
    local = tmp_path / path.name
    local.write_text(text)
    cfg = load_config(local)
    name, _ = parse_spec(cfg.backend)
    assert name in ("sim", "nomad200", "composed")
    assert cfg.link_enabled and (cfg.link.listen or cfg.link.connect)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"robot": "bad name!"}, "robot must be 1-64 letters"),
        ({"rate_hz": 0}, "rate_hz must be between 0.5 and 200"),
        ({"rate_hz": "fast"}, "rate_hz must be a number"),
        ({"watchdog_s": 0.1}, "watchdog_s must be at least two control periods"),
        ({"backend": {"world": "fig12"}}, '[backend] needs backend = "NAME"'),
        ({"bogus": 1}, "unknown key(s) bogus"),
        ({"sim": {"time_scale": -1}}, "sim.time_scale must be between 0 and"),
        ({"sim": {"speed": 2}}, "unknown key(s) sim.speed"),
        ({"link": {"mode": "mesh"}}, "link mode 'mesh' is not one of"),
        ({"link": {"listen": "tcp/127.0.0.1:1"}}, "link.listen must be a list"),
        ({"link": {"config_file": "/nonexistent.json5"}}, "link.config_file names no file"),
        ({"link": {"user": "alice"}}, "user and password must be given together"),
    ],
)
def test_mistakes_name_the_key(change, message):
    raw = {**GOOD, **change}
    with pytest.raises(ConfigError) as err:
        parse_config(raw, "robot.toml")
    assert message in str(err.value)
    assert str(err.value).startswith("robot.toml")


def test_sim_table_only_with_the_sim_backend():
    raw = {**GOOD, "backend": {"backend": "nomad200", "port": "/dev/null"}, "sim": {}}
    with pytest.raises(ConfigError, match=r"\[sim\] applies to backend = \"sim\" only"):
        parse_config(raw)


def test_cli_reports_a_bad_file_in_one_line(tmp_path, capsys):
    bad = tmp_path / "robot.toml"
    bad.write_text('robot = "r1"\nstorage = \n')
    assert main(["daemon", "--config", str(bad)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "not valid TOML" in err[0]
    assert main(["daemon", "--config", str(tmp_path / "missing.toml")]) == 2
    assert "cannot read" in capsys.readouterr().err


def test_unknown_backend_is_refused_before_anything_opens(tmp_path, capsys):
    cfg = tmp_path / "robot.toml"
    cfg.write_text(
        f'robot = "r1"\nstorage = "{tmp_path / "s"}"\n[backend]\nbackend = "warpdrive"\n'
        "[link]\nenabled = false\n"
    )
    assert main(["daemon", "--config", str(cfg)]) == 2
    err = capsys.readouterr().err
    assert "no backend named 'warpdrive'" in err and "Traceback" not in err
