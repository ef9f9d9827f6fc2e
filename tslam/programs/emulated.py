"""A Nomad 200 driver talking to ``tslam emulate nomad200`` in another process, for one run.

The emulator serves a pty in lockstep mode, so a run goes through the whole real path (driver,
pyserial, termios, a pty, the protocol, the emulator, the simulator) across processes and still
repeats exactly, seed for seed. (``tslam sim --backend nomad200-emulated`` hosts the same
emulator on a thread instead, to score against the true pose: see ``sim_backends``.)
"""

from __future__ import annotations

import contextlib
import json
import selectors
import subprocess
import sys
import time
from collections.abc import Iterator, Sequence
from typing import Any

from drivers.nomad200.device import Nomad200Backend
from tslam.programs.cli import UserError

STARTUP_TIMEOUT_S = 120.0
STOP_TIMEOUT_S = 5.0


def emulator_command(
    world: str, seed: int, drift: str, extra: Sequence[str] = (), *, lockstep: bool = True
) -> list[str]:
    """The command line that starts the emulator on a pty."""
    cmd = [sys.executable, "-m", "tslam.programs.cli", "emulate", "nomad200"]
    cmd += ["--world", world, "--seed", str(seed), "--drift", drift, "--pty"]
    if lockstep:
        cmd.append("--lockstep")
    return [*cmd, *extra]


def read_ready_line(proc: subprocess.Popen[str], timeout_s: float) -> dict[str, Any]:
    """The emulator's JSON line, or UserError with what it said on stderr if it failed."""
    assert proc.stdout is not None
    deadline = time.monotonic() + timeout_s
    with selectors.DefaultSelector() as sel:
        sel.register(proc.stdout, selectors.EVENT_READ)
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                raise UserError(f"the Nomad 200 emulator did not start within {timeout_s:g} s")
            if sel.select(left):
                line = proc.stdout.readline()
                if line:
                    try:
                        return json.loads(line)
                    except json.JSONDecodeError:
                        raise UserError(f"the emulator printed {line.strip()!r}") from None
                break  # EOF: it exited
    err = proc.stderr.read() if proc.stderr is not None else ""
    proc.wait(STOP_TIMEOUT_S)
    last = err.strip().splitlines()[-1] if err.strip() else f"exit code {proc.returncode}"
    raise UserError(f"the Nomad 200 emulator failed: {last.removeprefix('tslam: error: ')}")


def stop_process(proc: subprocess.Popen[str]) -> None:
    """SIGTERM, a bounded wait, then SIGKILL."""
    if proc.poll() is None:
        proc.terminate()
        try:
            proc.wait(STOP_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(STOP_TIMEOUT_S)
    for stream in (proc.stdout, proc.stderr):
        if stream is not None:
            stream.close()


@contextlib.contextmanager
def emulated_nomad200(
    world: str,
    seed: int = 0,
    drift: str = "paper",
    *,
    emulator_args: Sequence[str] = (),
    startup_timeout_s: float = STARTUP_TIMEOUT_S,
    **opts: Any,
) -> Iterator[Nomad200Backend]:
    """Start the emulator (pty, lockstep), yield an unconfigured driver for it, clean up.

    ``opts`` are driver options (``drivers.nomad200.settings``) over the defaults used here:
    lockstep and the sonars' "pos" attachments (exact firing stamps; free on a pty).
    ``emulator_args`` go to ``tslam emulate nomad200`` (fault options, say).
    """
    proc = subprocess.Popen(
        emulator_command(world, seed, drift, emulator_args),
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    backend: Nomad200Backend | None = None
    try:
        ready = read_ready_line(proc, startup_timeout_s)
        options = {"port": ready["port"], "lockstep": True, "sonar_pos": True, **opts}
        backend = Nomad200Backend.from_config(options)
        yield backend
    finally:
        try:
            if backend is not None:
                backend.close()
        finally:
            stop_process(proc)
