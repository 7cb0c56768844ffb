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


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption("--device", default="cpu", help="the Warp device every render of the tests uses by default "
                     "(make gpu-check: cuda); tests that name a device keep it")


@pytest.fixture(autouse=True, scope="session")
def _default_device(pytestconfig: pytest.Config):
    """With ``--device cuda``, the renderer's entry points default to that device instead of the CPU,
    so the same physics tests (furnaces, energy, determinism, resume) run on a GPU."""
    device = pytestconfig.getoption("--device")
    if device == "cpu":
        yield
        return
    import inspect

    import renderer.api
    import renderer.session

    saved = []
    for fn in (renderer.api.render, renderer.api.open_session, renderer.session.RenderSession.__init__):
        names = [p.name for p in inspect.signature(fn).parameters.values()
                 if p.default is not inspect.Parameter.empty and p.kind is p.POSITIONAL_OR_KEYWORD]
        saved.append((fn, fn.__defaults__))
        fn.__defaults__ = tuple(device if n == "device" else d for n, d in zip(names[-len(fn.__defaults__):],
                                                                                  fn.__defaults__))
    yield
    for fn, defaults in saved:
        fn.__defaults__ = defaults
