"""Command-line options made from a generator's parameter dataclass, so every subcommand gets its
parameters, ``--seed``, ``--out`` and (where it has previews) ``--preview`` from one place."""
from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path
from typing import Any

from assets_gen.core.generator import Generator
from assets_gen.core.params import Params, kind


class HelpFormatter(argparse.RawDescriptionHelpFormatter, argparse.ArgumentDefaultsHelpFormatter):
    """Descriptions as written (they hold formulas and tables) and every option's default."""


def add_param_arguments(parser: argparse.ArgumentParser, cls: type[Params]) -> None:
    """One ``--option`` per field of the parameter dataclass ``cls``, defaults and units from it."""
    for f in dataclasses.fields(cls):
        flag = "--" + f.name.replace("_", "-")
        kw: dict[str, Any] = {"default": f.default, "help": f.metadata["help"], "dest": f.name}
        if "choices" in f.metadata:
            kw["choices"] = f.metadata["choices"]
        if kind(f) is bool:
            kw["action"] = argparse.BooleanOptionalAction
        elif kind(f) is tuple:
            kw.update(nargs=len(f.default), type=float, metavar=tuple("XYZW"[:len(f.default)]))
        else:
            kw["type"] = kind(f)
        parser.add_argument(flag, **kw)


def params_from_args(args: argparse.Namespace, cls: type[Params]) -> Params:
    """The parameter dataclass from parsed options."""
    return cls(**{f.name: getattr(args, f.name) for f in dataclasses.fields(cls)})


def add_generator_parser(subparsers: Any, gen: Generator) -> argparse.ArgumentParser:
    """The subcommand of ``gen``; running it builds with the parsed options and returns the paths."""
    p = subparsers.add_parser(gen.name, help=gen.summary, description=gen.description or gen.summary,
                              formatter_class=HelpFormatter)
    add_param_arguments(p, gen.params)
    p.add_argument("--seed", type=int, default=0, help="random seed; the same seed gives the same bytes")
    p.add_argument("--out", type=Path, default=Path("assets") / gen.name, help="output folder")
    if gen.previews:
        p.add_argument("--preview", action=argparse.BooleanOptionalAction, default=True,
                       help="also write a small PNG preview")
    p.set_defaults(run=lambda a: gen.build(params_from_args(a, gen.params), a.seed, a.out,
                                           preview=getattr(a, "preview", False)))
    return p
