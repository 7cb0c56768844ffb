"""Kernels compile once per run: point Warp's cache at the repository's cache folder."""
import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
os.environ.setdefault("WARP_CACHE_PATH", str(ROOT / ".warp-cache"))
sys.path.insert(0, str(Path(__file__).parent))
