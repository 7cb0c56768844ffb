"""The machine's memory, the budget that the footprint estimate and the image reader both check
against (a module of its own so the image reader, which assets-gen uses too, imports nothing more)."""
from __future__ import annotations

import os


def machine_memory() -> int:
    """This machine's physical memory in bytes."""
    return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
