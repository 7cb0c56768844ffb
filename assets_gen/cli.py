"""``assets-gen SUBCOMMAND ...``: one subcommand per registered generator, plus ``recipe``."""
from __future__ import annotations

import argparse
import sys
import warnings

from assets_gen import recipe
from assets_gen.core import GeneratorError
from assets_gen.core.options import add_generator_parser
from assets_gen.registry import GENERATORS


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="assets-gen", description=__doc__.splitlines()[0],
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    sub = parser.add_subparsers(dest="command", metavar="SUBCOMMAND")
    for gen in GENERATORS:
        add_generator_parser(sub, gen)
    recipe.add_parser(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    # colour-science warns at import that matplotlib (plotting, unused here) is missing: the user
    # of the command should see only its own messages
    warnings.filterwarnings("ignore", message='"Matplotlib" related API features are not available')
    if not getattr(args, "run", None):
        parser.print_help()
        return 0 if args.command is None else 2
    from renderer.errors import RenderError

    try:
        for path in args.run(args):
            print(path)
    # RenderError: the renderer's parser, ray caster or image reader on a scene or file we were
    # given (it names the file and line); OSError and MemoryError: the machine (a full disk, too
    # little memory), not the command. Each is one line, never a traceback.
    except (GeneratorError, RenderError, OSError) as e:
        print(f"assets-gen {args.command}: error: {e}", file=sys.stderr)
        return 2
    except MemoryError:
        print(f"assets-gen {args.command}: error: not enough memory for these parameters", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
