"""pbrt-v4's ``--stats``: what a render did, printed at its end in pbrt's indented layout, from
counts that already exist (the scene description, the integrator's race-free per-row ray and
dropped-sample counters, the device arrays, the clock at each phase). Nothing is counted on the
device for this, so a render with ``--stats`` is the same render.

Rays are split into camera rays (one per sample, exact) and the rest (bounce, shadow and
subsurface rays, which the integrator counts together)."""
from __future__ import annotations

from collections import Counter
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from renderer.scene.description import SceneDescription
    from renderer.session import RenderSession
    from renderer.settings import RenderSettings


def _kinds(counts: Counter) -> str:
    return ", ".join(f"{k} {n}" for k, n in sorted(counts.items())) or "none"


def device_bytes(session: RenderSession) -> int:
    """Bytes of the device arrays the scene and film hold (Warp arrays report their allocation); 0
    for a cluster's driver, which holds none."""
    ds = getattr(session, "ds", None)
    if ds is None:
        return 0
    arrays = list(ds.keep) + [getattr(session.film, n) for n in vars(session.film)]
    seen, total = set(), 0
    for a in arrays:
        cap = getattr(a, "capacity", None)
        if isinstance(cap, int) and id(a) not in seen:
            seen.add(id(a))
            total += cap
    return total


def scene_lines(desc: SceneDescription) -> list[tuple[str, str]]:
    placed = Counter()
    for inst in desc.instance_sets:
        for s in inst.shapes:
            placed[s] += len(inst.transforms)
    triangles = sum(len(desc.meshes[desc.shapes[s].mesh].indices) * n for s, n in placed.items())
    lights = Counter(d.kind for d in desc.lights) + Counter(
        s.area_light.kind for s in desc.shapes if s.area_light is not None)
    return [("Shapes (distinct meshes)", f"{len(desc.shapes)} ({len(desc.meshes)})"),
            ("Shape instances placed", str(sum(placed.values()))),
            ("Triangles placed", str(triangles)),
            ("Materials", _kinds(Counter(m.kind for m in desc.materials))),
            ("Textures", str(len(desc.textures))),
            ("Lights", _kinds(lights))]


def report(desc: SceneDescription, settings: RenderSettings, session: RenderSession, phases: dict[str, float],
           passes: int) -> str:
    """The statistics block: scene, integrator, rays, memory and time per phase (seconds)."""
    st = session.stats
    samples = st.spp * st.width * st.height
    sections: list[tuple[str, list[tuple[str, str]]]] = [
        ("Scene", scene_lines(desc)),
        ("Integrator", [("Sampler", settings.sampler.name),
                        ("Samples per pixel", str(st.spp)), ("Passes", str(passes)),
                        ("Maximum depth", str(settings.max_depth))]),
        ("Rays", [("Camera rays (one per sample)", str(samples)),
                  ("Bounce, shadow and subsurface rays", f"{max(0.0, st.rays - samples):.0f}"),
                  ("Rays per camera ray", f"{st.rays / max(samples, 1):.3f}"),
                  ("Samples dropped (NaN, Inf, negative)", str(st.bad_samples))]),
        ("Memory", [("Peak resident", f"{st.peak_memory_mb:.1f} MiB"),
                    ("Device arrays (scene and film)", f"{device_bytes(session) / 2**20:.1f} MiB")]),
        ("Time", [(name, f"{sec:.3f} s") for name, sec in phases.items()]
         + [("Samples per second", f"{st.samples_per_second:.4g}"), ("Rays per second", f"{st.rays_per_second:.4g}")]),
    ]
    out = ["Statistics:"]
    for title, rows in sections:
        out.append(f"  {title}")
        out += [f"    {name:<44}{value}" for name, value in rows]
    return "\n".join(out)
