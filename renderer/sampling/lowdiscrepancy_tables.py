"""Host-side tables for the low-discrepancy samplers, all derived from library data, never typed in:
Sobol generator matrices from the Joe–Kuo direction numbers scipy ships, primes by a sieve, and the
GF(2) inverse that finds which global Sobol index lands in a given pixel."""
from __future__ import annotations

import importlib.util
from functools import lru_cache
from itertools import permutations
from pathlib import Path

import numpy as np

#: Output bits of a Sobol sample, and so the columns of each generator matrix (indices < 2^32).
SOBOL_BITS = 32


def _direction_numbers() -> tuple[np.ndarray, np.ndarray]:
    """scipy's Joe–Kuo table: primitive polynomials (as bit masks) and initial m_k per dimension.
    The file is found without importing ``scipy.stats`` (0.6 CPU-s of imports, in every render)."""
    spec = importlib.util.find_spec("scipy.stats")
    if spec is None or not spec.submodule_search_locations:
        raise ImportError("scipy is needed for the Sobol direction numbers (pip install scipy)")
    data = np.load(Path(spec.submodule_search_locations[0]) / "_sobol_direction_numbers.npz")
    return data["poly"], data["vinit"]


@lru_cache(maxsize=None)
def sobol_matrices(n_dims: int) -> np.ndarray:
    """(n_dims, 32) uint32: column j of dimension d is the direction number V_j (MSB first), so a
    point is the XOR of the columns of its index's set bits (Bratley–Fox recurrence)."""
    poly, vinit = _direction_numbers()
    if n_dims > len(poly):
        raise ValueError(f"scipy's table has {len(poly)} Sobol dimensions, not {n_dims}")
    out = np.zeros((n_dims, SOBOL_BITS), dtype=np.uint32)
    for d in range(n_dims):
        s = int(poly[d]).bit_length() - 1            # the polynomial's degree
        m = [int(v) for v in vinit[d][:s]] if s else [1] * SOBOL_BITS   # dimension 0: van der Corput
        for k in range(len(m), SOBOL_BITS):
            new = m[k - s] ^ (m[k - s] << s)
            for i in range(1, s):
                if (int(poly[d]) >> (s - i)) & 1:
                    new ^= m[k - i] << i
            m.append(new)
        out[d] = [m[k] << (SOBOL_BITS - 1 - k) for k in range(SOBOL_BITS)]
    return out


def sobol_byte_tables(matrices: np.ndarray) -> np.ndarray:
    """(n_dims, 4, 256) uint32: entry [d, k, x] is the XOR of dimension d's columns 8k..8k+7
    selected by the bits of x, so a point is four table lookups XORed instead of one XOR per set
    bit of its index (the same bits: XOR is associative)."""
    cols = np.asarray(matrices, dtype=np.uint32).reshape(len(matrices), 4, 8)
    bits = (np.arange(256)[:, None] >> np.arange(8)) & 1                  # (256, 8)
    picked = np.where(bits[None, None].astype(bool), cols[:, :, None, :], np.uint32(0))
    return np.bitwise_xor.reduce(picked, axis=3).astype(np.uint32)


@lru_cache(maxsize=None)
def primes(n: int) -> np.ndarray:
    """The first ``n`` primes (int32), by a sieve of Eratosthenes."""
    limit = max(16, int(n * (np.log(n + 2) + np.log(np.log(n + 3))) + 10))
    sieve = np.ones(limit, dtype=bool)
    sieve[:2] = False
    for p in range(2, int(limit ** 0.5) + 1):
        if sieve[p]:
            sieve[p * p::p] = False
    return np.flatnonzero(sieve)[:n].astype(np.int32)


def four_way_permutations() -> np.ndarray:
    """(24, 4) int32: every permutation of the base-4 digits 0..3 (ZSobol permutes Morton digits)."""
    return np.array(list(permutations(range(4))), dtype=np.int32)


def _gf2_inverse(cols: list[int], n: int) -> list[int]:
    """Columns of the inverse of the n x n GF(2) matrix whose column j is the bit mask ``cols[j]``."""
    rows = [sum(((cols[j] >> i) & 1) << j for j in range(n)) | (1 << (n + i)) for i in range(n)]
    for c in range(n):
        pivot = next(r for r in range(c, n) if (rows[r] >> c) & 1)
        rows[c], rows[pivot] = rows[pivot], rows[c]
        for r in range(n):
            if r != c and (rows[r] >> c) & 1:
                rows[r] ^= rows[c]
    inv_rows = [r >> n for r in rows]
    return [sum(((inv_rows[i] >> j) & 1) << i for i in range(n)) for j in range(n)]


@lru_cache(maxsize=None)
def sobol_pixel_inverse(m: int) -> np.ndarray:
    """(max(2m, 1),) uint32 columns of M^-1, where M maps the low 2m bits b of a Sobol index to the
    pixel (x | y << m) that dimensions 0 and 1 put its point in on a 2^m x 2^m grid. Any 2^2m
    consecutive aligned indices cover every pixel once (the (0,2)-sequence property), so M inverts."""
    if m == 0:
        return np.zeros(1, dtype=np.uint32)
    C = sobol_matrices(2)
    cols = [int(C[0, j] >> (SOBOL_BITS - m)) | (int(C[1, j] >> (SOBOL_BITS - m)) << m) for j in range(2 * m)]
    return np.array(_gf2_inverse(cols, 2 * m), dtype=np.uint32)
