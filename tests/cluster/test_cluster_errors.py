"""Cluster renders that cannot start say why, with exit code 2: an address nothing listens on,
cluster options without ``--ray``, and Ray not installed (the message says how to install it)."""
from __future__ import annotations

import socket
import sys

import pytest

from renderer.cli import main
from cluster_scenes import write_cluster_scene as write_scene


def free_port() -> int:
    """A local port nothing listens on (bound, then released)."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.mark.parametrize("form", ["ray://127.0.0.1:{port}", "127.0.0.1:{port}"])
def test_unreachable_address_fails_clearly(tmp_path, capsys, form):
    pytest.importorskip("ray")
    address = form.format(port=free_port())
    assert main([str(write_scene(tmp_path)), "-o", str(tmp_path / "o.exr"), "--ray", address, "--quiet"]) == 2
    assert f"cannot reach the Ray cluster at {address}" in capsys.readouterr().err
    assert not (tmp_path / "o.exr").exists()


@pytest.mark.parametrize("args, needle", [
    (["--ray", "not-an-address"], "Ray address must be"),
    (["--ray-chunk", "4"], "--ray-chunk and --ray-workers need --ray"),
    (["--ray", "--wavefront"], "Ray workers use their device's"),
])
def test_bad_cluster_options(tmp_path, capsys, args, needle):
    assert main([str(write_scene(tmp_path)), "-o", str(tmp_path / "o.exr"), *args, "--quiet"]) == 2
    assert needle in capsys.readouterr().err


def test_ray_chunk_must_be_positive(tmp_path, capsys):
    with pytest.raises(SystemExit) as e:
        main([str(write_scene(tmp_path)), "--ray", "--ray-chunk", "0"])
    assert e.value.code == 2 and "at least 1" in capsys.readouterr().err


def test_without_ray_the_message_says_how_to_install_it(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "ray", None)          # import ray now raises ImportError
    assert main([str(write_scene(tmp_path)), "-o", str(tmp_path / "o.exr"), "--ray", "--quiet"]) == 2
    assert "pip install 'summertime[cluster]'" in capsys.readouterr().err
