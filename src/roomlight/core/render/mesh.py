"""Mitsuba triangle meshes from numpy arrays: the one place a ``mi.Mesh`` is assembled for the
scenes' objects (benchmark objects, photo objects, synthetic rooms' parts).

The 2.5D emitter's mesh is not built here: :mod:`roomlight.core.render.scene` keeps its topology and
updates only its vertex positions and emission during a fit.
"""

from __future__ import annotations

import numpy as np

__all__ = ["mitsuba_mesh"]


def mitsuba_mesh(name: str, vertices, faces, bsdf, normals=None, uvs=None, emitter=None):
    """A ``mi.Mesh`` called ``name``.

    Args:
        vertices: (V, 3) positions in the scene's frame (metres).
        faces: (F, 3) vertex indices.
        bsdf: a Mitsuba BSDF dict, or an already loaded BSDF object.
        normals: optional (V, 3) shading normals (unit length); without them Mitsuba shades flat.
        uvs: optional (V, 2) texture coordinates.
        emitter: optional loaded ``area`` emitter object.
    """
    from roomlight.core.render.variant import mitsuba

    mi = mitsuba()
    vertices = np.asarray(vertices, np.float32)
    faces = np.asarray(faces, np.uint32)
    props = mi.Properties()
    props["bsdf"] = mi.load_dict(bsdf) if isinstance(bsdf, dict) else bsdf
    if emitter is not None:
        props["emitter"] = emitter
    mesh = mi.Mesh(name, len(vertices), len(faces), props,
                   has_vertex_normals=normals is not None, has_vertex_texcoords=uvs is not None)
    params = mi.traverse(mesh)
    params["vertex_positions"] = mi.Float(vertices.ravel())
    if normals is not None:
        params["vertex_normals"] = mi.Float(np.asarray(normals, np.float32).ravel())
    if uvs is not None:
        params["vertex_texcoords"] = mi.Float(np.asarray(uvs, np.float32).ravel())
    params["faces"] = mi.UInt(faces.ravel())
    params.update()
    return mesh
