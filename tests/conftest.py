"""Kernels compile once per run: point Warp's cache at the repository's cache folder."""
import os
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
os.environ.setdefault("WARP_CACHE_PATH", str(ROOT / ".warp-cache"))
sys.path.insert(0, str(Path(__file__).parent))


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """``make test`` runs on pytest-xdist workers with ``--dist loadgroup``: each test file stays on
    one worker (its kernels compile once, not on every worker that draws one of its tests), and the
    tests that start a local Ray instance share one worker, so two instances never start at once."""
    for item in items:
        if item.get_closest_marker("xdist_group") is None:
            path = Path(str(item.fspath)).relative_to(ROOT)
            group = "ray" if path.parts[:2] == ("tests", "cluster") else path.as_posix()
            item.add_marker(pytest.mark.xdist_group(group))
