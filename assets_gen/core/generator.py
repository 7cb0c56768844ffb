"""The generator contract: a parameter dataclass plus a writer, built only through
:meth:`Generator.build`, so validation, input paths, staging and the manifest are done once for
every generator and every caller (CLI, recipe, tests)."""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

from assets_gen.core.output import staged_output, write_manifest
from assets_gen.core.params import GeneratorError, Params


@dataclass
class Job:
    """What a writer gets. ``params`` has its input paths resolved (read from them); ``given`` is
    the parameters as the caller wrote them (what the manifest records). Files go into ``stage``;
    ``out_dir`` is where they end up (for paths written into files)."""
    params: Any
    given: Any
    seed: int
    stage: Path
    out_dir: Path
    preview: bool
    notes: dict[str, Any] = field(default_factory=dict)

    def note(self, **facts: Any) -> None:
        """Record derived facts (a front radius, the sun) in the manifest beside the parameters."""
        self.notes.update(facts)


#: A writer: writes a job's files into ``job.stage`` and returns their names.
Writer = Callable[[Job], list[str]]


@dataclass(frozen=True)
class Generator:
    """One ``assets-gen`` subcommand: ``name``, a one-line ``summary``, its ``params`` dataclass,
    its ``write`` function, the long ``--help`` text, and whether it can write PNG previews."""
    name: str
    summary: str
    params: type[Params]
    write: Writer
    description: str = ""
    previews: bool = False

    @property
    def module(self) -> str:
        """The module that holds the writer (what a recipe's rebuild hash starts from)."""
        return self.write.__module__

    def build(self, params: Params | None = None, seed: int = 0, out_dir: str | Path | None = None, *,
              base: str | Path | None = None, preview: bool = True) -> list[str]:
        """Validate ``params`` (default: all defaults), write the files for ``seed`` plus the manifest
        ``<name>.json`` into ``out_dir`` (default ``assets/<name>``) and return their paths.
        Relative input paths resolve against ``base`` (default: the working folder). Nothing is
        left behind on failure: the output folder is made only when the files move in."""
        given = self.params() if params is None else params
        if not isinstance(given, self.params):
            raise TypeError(f"{self.name} takes {self.params.__name__}, not {type(given).__name__}")
        if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
            raise GeneratorError(f"seed must be a non-negative integer, got {seed!r}")
        resolved = given.resolved(Path(base)) if base is not None else given
        resolved.validate()
        out_dir = Path(out_dir) if out_dir is not None else Path("assets") / self.name
        with staged_output(out_dir) as stage:
            job = Job(resolved, given, seed, stage, out_dir, preview and self.previews)
            names = self.write(job)
            manifest = f"{self.name}.json"
            write_manifest(stage / manifest, self.name, {**given.as_dict(), **job.notes}, seed, names)
        return [str(out_dir / n) for n in [*names, manifest]]
