"""Sampling the prior, interpolating latents, and lighting probe spheres with decoded rooms.

- :func:`sample_latents` draws z ~ N(0, temperature^2 I) from a seeded generator;
- :func:`decode_latents` decodes them in batches into linear radiance and depth;
- :func:`interpolate_latents` walks between two latents (spherical by default: a straight
  line between two N(0, I) draws passes through atypically short latents, a great-circle arc
  keeps the norm in the typical shell);
- :func:`probe_layout` + :func:`render_probes` place glossy spheres at several positions inside
  a decoded room and render them lit by its 2.5D area light (paper Fig. 3), which shows that the
  illumination depends on position.
"""

from __future__ import annotations

import math

import torch

from roomlight.errors import RoomlightError

__all__ = ["sample_latents", "decode_latents", "interpolate_latents", "probe_layout", "render_probes",
           "CAMERA_TARGET"]

#: The probe camera sits at the capture point and looks along -z, slightly down.
CAMERA_TARGET = (0.0, -0.35, -1.0)


def sample_latents(n: int, latent_dim: int, seed: int = 0, temperature: float = 1.0) -> torch.Tensor:
    """(n, latent_dim) float32 draws from N(0, temperature^2 I); deterministic per seed."""
    g = torch.Generator().manual_seed(int(seed))
    return torch.randn(n, latent_dim, generator=g) * float(temperature)


@torch.no_grad()
def decode_latents(model, z: torch.Tensor, batch_size: int = 8) -> tuple[torch.Tensor, torch.Tensor]:
    """Decode (N, D) latents: radiance (N, 3, H, W) linear and depth (N, 1, H, W), on the CPU."""
    device = next(model.parameters()).device
    model.eval()
    rads, deps = [], []
    for i in range(0, z.shape[0], batch_size):
        r, d = model.decode(z[i:i + batch_size].to(device))
        rads.append(r.cpu())
        deps.append(d.cpu())
    return torch.cat(rads), torch.cat(deps)


def interpolate_latents(z0: torch.Tensor, z1: torch.Tensor, steps: int, mode: str = "slerp") -> torch.Tensor:
    """(steps, D) latents from ``z0`` to ``z1`` inclusive (both (D,)).

    ``slerp`` interpolates direction along the great circle and the norm linearly; ``lerp`` is
    the straight line. Both return exactly z0 and z1 at the ends.
    """
    if steps < 2:
        raise RoomlightError(f"interpolate_latents: need at least 2 steps, got {steps}")
    t = torch.linspace(0.0, 1.0, steps, dtype=torch.float64)[:, None]
    a, b = z0.double().flatten(), z1.double().flatten()
    if mode == "lerp":
        out = (1 - t) * a + t * b
    elif mode == "slerp":
        na, nb = a.norm(), b.norm()
        ua, ub = a / na.clamp_min(1e-12), b / nb.clamp_min(1e-12)
        omega = torch.arccos((ua * ub).sum().clamp(-1.0, 1.0))
        if float(omega) < 1e-6:  # (anti-)parallel within rounding: the straight line is the arc
            out = (1 - t) * a + t * b
        else:
            so = torch.sin(omega)
            u = (torch.sin((1 - t) * omega) / so) * ua + (torch.sin(t * omega) / so) * ub
            out = u * ((1 - t) * na + t * nb)
        out[0], out[-1] = a, b
    else:
        raise RoomlightError(f"interpolate_latents: mode must be 'slerp' or 'lerp', got {mode!r}")
    return out.to(z0.dtype)


def probe_layout(depth: torch.Tensor, n: int = 3, spread_deg: float = 22.0, fractions=(0.3, 0.5, 0.7),
                 radius_ratio: float = 0.12) -> list[tuple[tuple[float, float, float], float]]:
    """Sphere centres and radii inside a decoded room, all in view of the probe camera.

    Probe i lies in direction (azimuth offset from -z in [-spread, spread], 18 degrees below the
    horizon) at ``fractions[i]`` of the smallest depth within 20 degrees of that direction, with
    radius ``radius_ratio`` times its distance, so it never touches the emitter mesh.

    Args:
        depth: (H, W) decoded radial depth (scene units).
    Returns:
        list of ((x, y, z), radius).
    """
    from roomlight.core.geometry.equirect import pixel_directions, uv_to_direction

    h, w = depth.shape[-2:]
    dirs = pixel_directions(h, w, dtype=torch.float64)
    dep = depth.reshape(h, w).double()
    out = []
    for i in range(n):
        az = math.radians(-spread_deg + (2 * spread_deg * i / (n - 1) if n > 1 else spread_deg))
        el = math.radians(-18.0)
        u = torch.tensor(az / (2 * math.pi), dtype=torch.float64) % 1.0
        v = torch.tensor(0.5 - el / math.pi, dtype=torch.float64)
        d = uv_to_direction(u, v)
        near = (dirs @ d) > math.cos(math.radians(20.0))
        dist = float(dep[near].min()) * fractions[i % len(fractions)]
        c = (d * dist).tolist()
        out.append(((c[0], c[1], c[2]), radius_ratio * dist))
    return out


def render_probes(radiance: torch.Tensor, depth: torch.Tensor, probes, material_name: str = "glossy",
                  resolution: int = 160, spp: int = 32, fov_deg: float = 65.0, seed: int = 0) -> torch.Tensor:
    """Render spheres lit by the 2.5D area light of (radiance, depth), seen from the capture point.

    Args:
        radiance: (H, W, 3) linear radiance; depth: (H, W) radial depth (scene units).
        probes: list of ((x, y, z), radius) from :func:`probe_layout`.
        material_name: a :mod:`roomlight.core.render.materials` name (``glossy`` shows reflections).
        resolution: square image size in pixels.
    Returns:
        (resolution, resolution, 3) float32 linear image (the room's mesh shows behind the probes).
    """
    from roomlight.core.render.camera import perspective_sensor
    from roomlight.core.render.materials import material
    from roomlight.core.render.scene import EmitterScene

    h, w = radiance.shape[:2]
    objects = {f"probe_{i}": {"type": "sphere", "center": list(c), "radius": float(r),
                              "bsdf": material(material_name)} for i, (c, r) in enumerate(probes)}
    sensor = perspective_sensor((0.0, 0.0, 0.0), CAMERA_TARGET, (0.0, 1.0, 0.0), fov_deg, resolution, resolution)
    scene = EmitterScene("mesh", (h, w), objects=objects, sensor=sensor,
                         integrator={"type": "path", "max_depth": 4})
    scene.set_emitter(radiance.float().cpu(), depth.float().cpu().reshape(h, w))
    return scene.render(spp=spp, seed=seed)
