"""Command line of the generators: ``python -m omnikin.runtime.protocol``.

Prints the C header, rewrites the generated tables of a Markdown page, or checks that a
committed header / page is up to date (exit status 1 when stale, 2 on an error)::

    python -m omnikin.runtime.protocol --header > firmware/omnikin_wheel/omnikin_protocol.h
    python -m omnikin.runtime.protocol --update-doc docs/protocol.md
    python -m omnikin.runtime.protocol --check-header firmware/omnikin_wheel/omnikin_protocol.h
    python -m omnikin.runtime.protocol --check-doc docs/protocol.md
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ...errors import ProtocolError
from .c_header import HEADER_COMMAND, generate_header
from .markdown import DOC_COMMAND, update_doc


def main(argv=None) -> int:
    """Run the command line with ``argv`` (default: ``sys.argv[1:]``); returns the exit status."""
    ap = argparse.ArgumentParser(
        prog="python -m omnikin.runtime.protocol",
        description="Generate the firmware header or the documentation tables from protocol.yaml.",
    )
    g = ap.add_mutually_exclusive_group(required=True)
    g.add_argument("--header", action="store_true", help="print the C header (omnikin_protocol.h)")
    g.add_argument("--update-doc", metavar="MD", help="rewrite the generated blocks of this Markdown file")
    g.add_argument("--check-doc", metavar="MD", help="exit 1 if the generated blocks of this file are stale")
    g.add_argument("--check-header", metavar="H", help="exit 1 if this header differs from the generated one")
    args = ap.parse_args(argv)
    try:
        if args.header:
            sys.stdout.write(generate_header())
            return 0
        path = Path(args.update_doc or args.check_doc or args.check_header)
        text = path.read_text(encoding="utf-8")
        new = generate_header() if args.check_header else update_doc(text)
        if args.update_doc:
            if new != text:
                path.write_text(new, encoding="utf-8")
            return 0
        if new != text:
            print(
                f"{path} is stale; regenerate it ({DOC_COMMAND if args.check_doc else HEADER_COMMAND})", file=sys.stderr
            )
            return 1
        return 0
    except UnicodeDecodeError as exc:
        print(f"error: {path}: not UTF-8 text (byte {exc.start})", file=sys.stderr)
        return 2
    except (OSError, ProtocolError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
