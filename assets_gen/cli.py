"""``assets-gen SUBCOMMAND ...``: one subcommand per generator module.

Each module named in :data:`GENERATORS` defines ``register(subparsers)``, which adds its
subcommand with ``set_defaults(run=callable)``; the callable takes the parsed arguments and
returns the list of files written.
"""
from __future__ import annotations

import argparse
import importlib
import sys

from assets_gen.common import GeneratorError

#: Generator modules, in the order ``--help`` lists them.
GENERATORS: tuple[str, ...] = ("seashell", "sunglasses", "umbrella", "palm", "sky", "dunes", "ripples", "grains", "maps", "recipe")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="assets-gen", description=__doc__.splitlines()[0],
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    sub = parser.add_subparsers(dest="command", metavar="SUBCOMMAND")
    for name in GENERATORS:
        importlib.import_module(f"assets_gen.{name}").register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "run", None):
        parser.print_help()
        return 0 if args.command is None and GENERATORS else 2
    try:
        for path in args.run(args):
            print(path)
    except GeneratorError as e:
        print(f"assets-gen {args.command}: error: {e}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
