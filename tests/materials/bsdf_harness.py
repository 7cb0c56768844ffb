"""Monte Carlo checks of a material's eval_pdf/sample pair, run through the same Warp functions
the integrator calls, on parameter rows laid out by the material's own declaration."""
from __future__ import annotations

from functools import lru_cache
from typing import Any

import numpy as np
import warp as wp

from renderer.materials import REGISTRY, device_layout, first_rows, kind_id, material, resolve
from renderer.materials.bsdf import BSDF, MAX_SLOTS, SPECULAR, Slots
from renderer.sampling.warps import uniform_sphere


def constant_rows(name: str, values: dict[str, Any]) -> tuple[np.ndarray, int]:
    """Slot rows (MAX_SLOTS, 3) and flags of a material with constant values, as the upload lays
    them out (declaration order, defaults, derived values): what load_bsdf would fill in."""
    layout, flags = device_layout(material(name, **values))
    rows = np.zeros((MAX_SLOTS, 3), dtype=np.float32)
    for j, (_, v) in enumerate(layout):
        if v is not None:
            rows[j] = np.broadcast_to(np.asarray(v, dtype=np.float32), (3,))
    return rows, flags


def layer_table(name: str, values: dict[str, Any]) -> tuple[wp.array, int, int]:
    """The layer table of a scene holding only this material: (rows, first, count), as the upload
    lays it out (a dummy row 0, the energy tables if it uses them, then the material's rows;
    count 0 without a stack)."""
    desc = material(name, **values)
    rows_of = getattr(REGISTRY[name], "layer_rows", None)
    mine = rows_of(resolve(desc)[0], None) if rows_of is not None else np.zeros((0, 4), np.float32)
    lead = np.concatenate(first_rows([desc]))
    rows = np.concatenate([lead, mine])
    return wp.array(rows, dtype=wp.vec4, device="cpu"), len(lead), len(mine)


def _bsdf_inputs(name: str, values: dict[str, Any]) -> list:
    rows, flags = constant_rows(name, values)
    return [Slots(*rows.ravel().tolist()), int(flags), kind_id(name), *layer_table(name, values)]


def _unit(wo) -> wp.vec3:
    wo = np.asarray(wo, dtype=np.float64)
    return wp.vec3(*(wo / np.linalg.norm(wo)))


@wp.func
def bsdf_from_rows(p: Slots, flags: int, kind: int, layers: wp.array(dtype=wp.vec4), first: int,
                   count: int) -> BSDF:
    """A BSDF as load_bsdf fills it, from constant slot rows and a layer table (rgb3: no spectral table)."""
    b = BSDF()
    b.kind = kind
    b.p = p
    b.flags = flags
    b.layers = layers
    b.layer_first = first
    b.layer_count = count
    return b


@lru_cache(maxsize=None)
def _kernel(name: str, funcs: tuple | None = None):
    mod = REGISTRY[name]
    eval_pdf, sample = funcs or (mod.eval_pdf, mod.sample)

    @wp.kernel(module="unique")
    def check(p: Slots, flags: int, kind: int, layers: wp.array(dtype=wp.vec4), first: int,
              count: int, wo: wp.vec3, seed: int, out: wp.array(dtype=wp.vec3, ndim=2)):
        i = wp.tid()
        rng = wp.rand_init(seed, i)
        b = bsdf_from_rows(p, flags, kind, layers, first, count)
        # uniform-sphere estimates of the integrals of pdf and of f |cos|
        wi = uniform_sphere(wp.vec2(wp.randf(rng), wp.randf(rng)))
        inv = 4.0 * 3.14159265358979
        e = wp.static(eval_pdf)(b, wo, wi)
        out[i, 0] = wp.vec3(e.pdf * inv, 0.0, 0.0)
        out[i, 1] = e.f * (wp.abs(wi[2]) * inv)
        s = wp.static(sample)(b, wo, wp.vec3(wp.randf(rng), wp.randf(rng), wp.randf(rng)))
        w = wp.vec3(0.0)
        err = float(0.0)
        if s.pdf > 0.0:
            w = s.weight
            if (s.flags & SPECULAR) == 0:
                # the sample's pdf and weight must agree with eval_pdf for the direction it picked
                es = wp.static(eval_pdf)(b, wo, s.wi)
                fe = es.f * (wp.abs(s.wi[2]) / s.pdf)
                err = (wp.abs(es.pdf - s.pdf) / wp.max(s.pdf, 1.0e-6)
                       + wp.length(fe - s.weight) / wp.max(wp.length(s.weight), 1.0e-6))
        out[i, 2] = w
        out[i, 3] = wp.vec3(err, float(s.flags), wp.where(s.pdf > 0.0, 1.0, 0.0))

    return check


def bsdf_moments(name: str, values: dict[str, Any], wo, n: int = 400_000, seed: int = 1,
                 funcs: tuple | None = None) -> dict[str, np.ndarray]:
    """Estimates of ∫pdf, ∫f|cos| (uniform sampling), E[sample weight] (importance sampling),
    its non-delta part, the largest sample/eval_pdf inconsistency (meaningless for materials whose
    f is an estimate) and the lobe flags seen, for a material with the
    given constant parameter values (defaults for the rest). ``funcs``: an (eval_pdf, sample) pair
    of Warp functions of (BSDF, wo, wi or u) to check instead of the material's own (e.g. its
    lobes without the radiance scaling of refraction)."""
    out = wp.zeros((n, 4), dtype=wp.vec3, device="cpu")
    wp.launch(_kernel(name, funcs), dim=n, inputs=[*_bsdf_inputs(name, values), _unit(wo), seed, out], device="cpu")
    o = out.numpy().astype(np.float64)   # float32 sums of 1e5+ weights drift by 1e-3
    ok = o[:, 3, 2] > 0
    nonspec = ok & ((o[:, 3, 1].astype(int) & SPECULAR) == 0)
    return {"pdf_integral": o[:, 0, 0].mean(), "albedo_uniform": o[:, 1].mean(axis=0),
            "albedo_sampled": o[:, 2].mean(axis=0), "max_inconsistency": o[:, 3, 0].max(),
            "albedo_sampled_nonspecular": np.where(nonspec[:, None], o[:, 2], 0.0).mean(axis=0),
            "albedo_sampled_stderr": o[:, 2].std(axis=0) / np.sqrt(n),
            "albedo_uniform_stderr": o[:, 1].std(axis=0) / np.sqrt(n),
            "lobe_flags": set(o[ok, 3, 1].astype(int).tolist())}


@lru_cache(maxsize=None)
def _chi2_kernels(name: str):
    mod = REGISTRY[name]

    @wp.kernel(module="unique")
    def draw(p: Slots, flags: int, kind: int, layers: wp.array(dtype=wp.vec4), first: int,
              count: int, wo: wp.vec3, seed: int, out: wp.array(dtype=wp.vec4)):
        i = wp.tid()
        rng = wp.rand_init(seed, i)
        b = bsdf_from_rows(p, flags, kind, layers, first, count)
        s = wp.static(mod.sample)(b, wo, wp.vec3(wp.randf(rng), wp.randf(rng), wp.randf(rng)))
        ok = 0.0
        if s.pdf > 0.0 and (s.flags & SPECULAR) == 0:
            ok = 1.0
        out[i] = wp.vec4(s.wi[0], s.wi[1], s.wi[2], ok)

    @wp.kernel(module="unique")
    def density(p: Slots, flags: int, kind: int, layers: wp.array(dtype=wp.vec4), first: int,
              count: int, wo: wp.vec3, dirs: wp.array(dtype=wp.vec3),
                out: wp.array(dtype=float)):
        i = wp.tid()
        out[i] = wp.static(mod.eval_pdf)(bsdf_from_rows(p, flags, kind, layers, first, count), wo, dirs[i]).pdf

    return draw, density


def chi2_pvalue(name: str, values: dict[str, Any], wo, n: int = 200_000, z_bins: int = 12, phi_bins: int = 24,
                sub: int = 16, seed: int = 3) -> float:
    """Pearson chi-square p-value that ``sample``'s directions follow ``eval_pdf``'s density:
    counts in equal-solid-angle (cos θ, φ) cells against the pdf integrated over each cell on a
    stratified sub x sub grid. Cells expecting fewer than 5 samples are pooled into one."""
    from scipy.stats import chi2

    draw, density = _chi2_kernels(name)
    inputs = [*_bsdf_inputs(name, values), _unit(wo)]
    out = wp.zeros(n, dtype=wp.vec4, device="cpu")
    wp.launch(draw, dim=n, inputs=[*inputs, seed, out], device="cpu")
    s = out.numpy()
    s = s[s[:, 3] > 0]
    zi = np.clip(((s[:, 2] + 1) / 2 * z_bins).astype(int), 0, z_bins - 1)
    fi = np.clip(((np.arctan2(s[:, 1], s[:, 0]) % (2 * np.pi)) / (2 * np.pi) * phi_bins).astype(int), 0, phi_bins - 1)
    observed = np.bincount(zi * phi_bins + fi, minlength=z_bins * phi_bins).astype(np.float64)
    # cell integrals of the pdf: z and φ are uniform in solid angle, so a midpoint grid is fair
    zz = -1 + (np.arange(z_bins * sub) + 0.5) * 2 / (z_bins * sub)
    ff = (np.arange(phi_bins * sub) + 0.5) * 2 * np.pi / (phi_bins * sub)
    Z, F = np.meshgrid(zz, ff, indexing="ij")
    r = np.sqrt(np.maximum(0, 1 - Z ** 2))
    dirs = np.stack([r * np.cos(F), r * np.sin(F), Z], -1).reshape(-1, 3).astype(np.float32)
    pdf = wp.zeros(len(dirs), dtype=float, device="cpu")
    wp.launch(density, dim=len(dirs), inputs=[*inputs, wp.array(dirs, dtype=wp.vec3, device="cpu"), pdf],
              device="cpu")
    cell_area = 4 * np.pi / (z_bins * phi_bins * sub * sub)
    integral = (pdf.numpy().reshape(z_bins, sub, phi_bins, sub) * cell_area).sum(axis=(1, 3)).ravel()
    expected = integral / integral.sum() * observed.sum()
    big = expected >= 5
    obs = np.append(observed[big], observed[~big].sum())
    exp = np.append(expected[big], expected[~big].sum())
    keep = exp > 0
    stat = ((obs[keep] - exp[keep]) ** 2 / exp[keep]).sum()
    return float(chi2.sf(stat, keep.sum() - 1))


@lru_cache(maxsize=None)
def _mean_f_kernel(name: str):
    mod = REGISTRY[name]

    @wp.kernel(module="unique")
    def mean_f(p: Slots, flags: int, kind: int, layers: wp.array(dtype=wp.vec4), first: int, count: int,
               wo: wp.array(dtype=wp.vec3), wi: wp.array(dtype=wp.vec3), seed: int,
               out: wp.array(dtype=wp.vec3, ndim=2)):
        i, j = wp.tid()
        b = bsdf_from_rows(p, flags, kind, layers, first, count)
        rng = wp.rand_init(seed, i * 65536 + j)
        b.wavelength_u = wp.randf(rng)
        out[i, j] = wp.static(mod.eval_pdf)(b, wo[i], wi[i]).f

    return mean_f


def mean_f(name: str, values: dict[str, Any], pairs: list[tuple], n: int = 4000, seed: int = 5):
    """Mean and standard error over n per-sample seeds (``wavelength_u``) of a stochastic f(wo, wi),
    for each (wo, wi) pair: materials whose eval_pdf is an estimate (the layered ones)."""
    wo = wp.array(np.array([_unit(a) for a, _ in pairs], dtype=np.float32), dtype=wp.vec3, device="cpu")
    wi = wp.array(np.array([_unit(c) for _, c in pairs], dtype=np.float32), dtype=wp.vec3, device="cpu")
    out = wp.zeros((len(pairs), n), dtype=wp.vec3, device="cpu")
    wp.launch(_mean_f_kernel(name), dim=(len(pairs), n), inputs=[*_bsdf_inputs(name, values), wo, wi, seed, out],
              device="cpu")
    o = out.numpy().astype(np.float64)
    return o.mean(axis=1), o.std(axis=1) / np.sqrt(n)


@lru_cache(maxsize=None)
def _cell_kernel(name: str):
    mod = REGISTRY[name]

    @wp.kernel(module="unique")
    def cells(p: Slots, flags: int, kind: int, layers: wp.array(dtype=wp.vec4), first: int, count: int,
              wo: wp.vec3, seed: int, out: wp.array(dtype=wp.vec4, ndim=2)):
        i = wp.tid()
        rng = wp.rand_init(seed, i)
        b = bsdf_from_rows(p, flags, kind, layers, first, count)
        b.wavelength_u = wp.randf(rng)
        s = wp.static(mod.sample)(b, wo, wp.vec3(wp.randf(rng), wp.randf(rng), wp.randf(rng)))
        v = float(0.0)
        if s.pdf > 0.0 and (s.flags & SPECULAR) == 0:
            v = (s.weight[0] + s.weight[1] + s.weight[2]) / 3.0
        out[i, 0] = wp.vec4(s.wi[0], s.wi[1], s.wi[2], v)
        wu = uniform_sphere(wp.vec2(wp.randf(rng), wp.randf(rng)))
        f = wp.static(mod.eval_pdf)(b, wo, wu).f
        out[i, 1] = wp.vec4(wu[0], wu[1], wu[2], (f[0] + f[1] + f[2]) / 3.0 * wp.abs(wu[2]) * 4.0 * 3.14159265358979)

    return cells


def _cell_of(d: np.ndarray, z_bins: int, phi_bins: int) -> np.ndarray:
    zi = np.clip(((d[:, 2] + 1) / 2 * z_bins).astype(int), 0, z_bins - 1)
    fi = np.clip(((np.arctan2(d[:, 1], d[:, 0]) % (2 * np.pi)) / (2 * np.pi) * phi_bins).astype(int), 0, phi_bins - 1)
    return zi * phi_bins + fi


def weighted_cells_pvalue(name: str, values: dict[str, Any], wo, n: int = 200_000, z_bins: int = 8,
                          phi_bins: int = 12, seed: int = 9) -> float:
    """Chi-square p-value that ``sample``'s non-delta directions, weighted by their sample weights,
    put the same reflected energy into each (cos θ, φ) cell as ``eval_pdf``'s f |cos| integrated by
    uniform sampling: the check for a sampler whose exact density has no closed form (pbrt's
    layered BSDF), where direction counts cannot be compared with eval_pdf's approximate pdf."""
    from scipy.stats import chi2

    out = wp.zeros((n, 2), dtype=wp.vec4, device="cpu")
    wp.launch(_cell_kernel(name), dim=n, inputs=[*_bsdf_inputs(name, values), _unit(wo), seed, out], device="cpu")
    o = out.numpy()
    m = z_bins * phi_bins
    stats = []
    for k in range(2):
        c = _cell_of(o[:, k, :3], z_bins, phi_bins)
        v = o[:, k, 3]
        s1 = np.bincount(c, weights=v, minlength=m) / n
        s2 = np.bincount(c, weights=v * v, minlength=m) / n
        stats.append((s1, (s2 - s1 ** 2) / n))
    (a, va), (b, vb) = stats
    keep = (va + vb) > 0
    keep &= (a + b) > 1e-3 * (a + b).sum()
    stat = ((a[keep] - b[keep]) ** 2 / (va[keep] + vb[keep])).sum()
    return float(chi2.sf(stat, keep.sum()))


@lru_cache(maxsize=None)
def _f_kernel(name: str):
    mod = REGISTRY[name]

    @wp.kernel(module="unique")
    def f(p: Slots, flags: int, kind: int, layers: wp.array(dtype=wp.vec4), first: int, count: int,
          wo: wp.array(dtype=wp.vec3), wi: wp.array(dtype=wp.vec3), out: wp.array(dtype=wp.vec3)):
        i = wp.tid()
        out[i] = wp.static(mod.eval_pdf)(bsdf_from_rows(p, flags, kind, layers, first, count), wo[i], wi[i]).f

    return f


def bsdf_values(name: str, values: dict[str, Any], wo: np.ndarray, wi: np.ndarray) -> np.ndarray:
    """f(wo[i], wi[i]) of a material with constant parameter values, (n, 3)."""
    out = wp.zeros(len(wo), dtype=wp.vec3, device="cpu")
    wp.launch(_f_kernel(name), dim=len(wo), inputs=[*_bsdf_inputs(name, values), wp.array(wo, dtype=wp.vec3),
                                                    wp.array(wi, dtype=wp.vec3), out], device="cpu")
    return out.numpy()


def random_pairs(seed: int, n: int = 4000) -> tuple[np.ndarray, np.ndarray]:
    """n pairs (wo, wi) of directions uniform on the sphere, float32."""
    v = np.random.default_rng(seed).standard_normal((2, n, 3))
    v = (v / np.linalg.norm(v, axis=2, keepdims=True)).astype(np.float32)
    return v[0], v[1]


def assert_reciprocal(name: str, values: dict[str, Any], eta: float, seed: int = 1) -> None:
    """f(wo, wi) = f(wi, wo) for reflection; with radiance scaled by 1/η'² on refraction,
    f(wi, wo) = η'² f(wo, wi) for transmission (η' the index ratio seen from wo, eta the inside
    over the outside index)."""
    wo, wi = random_pairs(seed)
    forward = bsdf_values(name, values, wo, wi).astype(np.float64)
    backward = bsdf_values(name, values, wi, wo).astype(np.float64)
    crossing = (wo[:, 2] * wi[:, 2] < 0)[:, None]
    etap = np.where(wo[:, 2] > 0, eta, 1 / eta)[:, None]
    expect = np.where(crossing, forward * etap ** 2, forward)
    assert np.any(forward > 0)
    # atol: float32 half vectors near grazing and near the critical angle (the bare dielectric
    # misses by as much there); f peaks at O(1)
    np.testing.assert_allclose(backward, expect, rtol=2e-3, atol=1e-5)
