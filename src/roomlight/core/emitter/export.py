"""Writing an emitter to disk so other tools (and ``mi.load_file``) can use it.

A bundle directory holds:

- ``radiance.exr``  the panorama's radiance (R, G, B, float32) in roomlight's convention; it is
                    also the mesh's emissive texture, so it holds no extra channels;
- ``depth.exr``     its radial depth in metres (channel Z), when there is one;
- ``emitter.ply``   the 2.5D area light / sphere-proxy mesh (positions + uv), not for env maps;
- ``envmap.exr``    env maps only: the radiance resampled to Mitsuba's pole-to-pole rows;
- ``scene.xml``     a Mitsuba 3 scene holding the emitter with id ``emitter``;
- ``preview.png``   tone-mapped radiance above colour-mapped depth.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import torch

from roomlight.core.emitter.area_light import build_area_light
from roomlight.core.emitter.envmap import envmap_data
from roomlight.core.emitter.sphere import sphere_depth

__all__ = ["scene_xml", "export_emitter"]

_AREA_XML = """<scene version="3.0.0">
    <!-- roomlight {kind} emitter: a closed, inward-facing mesh textured with the panorama -->
    <integrator type="path">
        <integer name="max_depth" value="{max_depth}"/>
    </integrator>
    <shape type="ply" id="emitter">
        <string name="filename" value="emitter.ply"/>
        <boolean name="face_normals" value="true"/>
        <!-- a black delta BSDF: the light source reflects nothing (see EMITTER_BSDF) -->
        <bsdf type="conductor">
            <rgb name="specular_reflectance" value="0, 0, 0"/>
        </bsdf>
        <emitter type="area">
            <texture type="bitmap" name="radiance">
                <string name="filename" value="radiance.exr"/>
                <boolean name="raw" value="true"/>
                <string name="filter_type" value="bilinear"/>
                <string name="wrap_mode" value="repeat"/>
            </texture>
        </emitter>
    </shape>
</scene>
"""

_ENV_XML = """<scene version="3.0.0">
    <!-- roomlight env-map emitter: the panorama at infinity (rows resampled pole to pole) -->
    <integrator type="path">
        <integer name="max_depth" value="{max_depth}"/>
    </integrator>
    <emitter type="envmap" id="emitter">
        <string name="filename" value="envmap.exr"/>
    </emitter>
</scene>
"""


def scene_xml(kind: str, max_depth: int = 4) -> str:
    """Text of ``scene.xml`` for an emitter kind name (``mesh``, ``sphere`` or ``envmap``)."""
    template = _ENV_XML if kind == "envmap" else _AREA_XML
    return template.format(kind=kind, max_depth=max_depth)


def export_emitter(out_dir, radiance: torch.Tensor, depth: torch.Tensor | None, kind="mesh",
                   metadata: dict | None = None) -> dict[str, Path]:
    """Write an emitter bundle (see module docstring) and return the paths written.

    Args:
        radiance: (H, W, 3) linear radiance.
        depth: (H, W) radial depth in metres (required for ``mesh``; a sphere uses its radius).
        kind: ``mesh``, ``envmap``, ``sphere:R`` or an EmitterKind.
    """
    from roomlight.core.io import save_png, write_exr, write_ply
    from roomlight.core.io.preview import colorize_depth, tonemap_gamma
    from roomlight.core.light import parse_emitter_kind

    k = parse_emitter_kind(kind)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    rad = radiance.detach().float().cpu()
    h, w = rad.shape[:2]
    if k.name == "sphere":
        depth = sphere_depth(h, w, k.radius)
    paths: dict[str, Path] = {}
    channels = {"R": rad[..., 0].numpy(), "G": rad[..., 1].numpy(), "B": rad[..., 2].numpy()}
    paths["radiance"] = out / "radiance.exr"
    write_exr(paths["radiance"], channels, half=False)
    if depth is not None:
        paths["depth"] = out / "depth.exr"
        write_exr(paths["depth"], {"Z": depth.detach().float().cpu().numpy()}, half=False)
    if k.name == "envmap":
        env = envmap_data(rad)[:, 1:-1]  # Mitsuba adds the wrap columns itself when loading
        paths["envmap"] = out / "envmap.exr"
        write_exr(paths["envmap"], {"R": env[..., 0].numpy(), "G": env[..., 1].numpy(), "B": env[..., 2].numpy()},
                  half=False)
    else:
        mesh = build_area_light(rad, depth.detach().float().cpu())
        paths["mesh"] = out / "emitter.ply"
        write_ply(paths["mesh"], mesh.vertices.numpy(), mesh.faces.numpy(), uv=mesh.uv.numpy())
    paths["scene"] = out / "scene.xml"
    paths["scene"].write_text(scene_xml(k.name))
    preview = tonemap_gamma(rad.numpy())
    if depth is not None:
        preview = np.concatenate([preview, colorize_depth(depth.detach().float().cpu().numpy())], axis=0)
    paths["preview"] = out / "preview.png"
    save_png(paths["preview"], preview)
    if metadata is not None:
        import json

        paths["metadata"] = out / "emitter.json"
        paths["metadata"].write_text(json.dumps({"kind": str(k), "resolution": [h, w], **metadata}, indent=2))
    return paths
