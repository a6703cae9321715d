"""``omnikin presets``: the robots shipped with omnikin (:data:`omnikin.presets.PRESET_NAMES`)."""

from __future__ import annotations

import argparse

from ..presets import PRESET_NAMES
from .common import console, print_json


def add_parser(sub, robot_help: str) -> None:
    """Add ``presets`` to ``sub``."""
    sp = sub.add_parser(
        "presets",
        help="list the shipped robots",
        description="List the robots shipped with omnikin.",
        epilog="examples:\n  omnikin presets\n  omnikin presets --json",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sp.add_argument("--json", action="store_true", help="machine-readable output")
    sp.set_defaults(func=run)


def run(args) -> int:
    """The table of the presets (or ``--json``); status 0."""
    from rich.table import Table

    table = Table(title="omnikin presets (omnikin show NAME)", title_justify="left")
    for col in ("name", "wheels", "Campion type", "holonomic", "reference"):
        table.add_column(col)
    out = []
    from ..io.robot_file import load_preset

    for name in PRESET_NAMES:
        r = load_preset(name)  # the shipped files, whatever the current folder holds
        m = r.mobility
        ref = r.references[0] if r.references else ""
        out.append(
            {
                "name": name,
                "wheels": len(r.wheels),
                "campion_type": list(m.campion_type),
                "holonomic": m.holonomic,
                "reference": ref,
            }
        )
        table.add_row(
            name,
            str(len(r.wheels)),
            str(m.campion_type),
            "yes" if m.holonomic else "no",
            ref[:70] + ("..." if len(ref) > 70 else ""),
        )
    if args.json:
        print_json(out)
    else:
        console().print(table)
    return 0
