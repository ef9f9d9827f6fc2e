"""``tslam emulate DEVICE``: a simulated robot behind a real wire protocol."""

from __future__ import annotations

import argparse


def add_parser(sub: argparse._SubParsersAction) -> None:
    from tslam.programs import emulate_can_sonar, emulate_nomad200

    p = sub.add_parser("emulate", help="serve a device's wire protocol from the simulated robot")
    esub = p.add_subparsers(dest="emulate_command", required=True, metavar="DEVICE")
    emulate_nomad200.add_parser(esub)
    emulate_can_sonar.add_parser(esub)
