"""The 2.5D area light (paper §3.1; docs/conventions.md): an emissive triangle mesh from (radiance, depth).

Vertices sit at p = D(u, v) * omega(u, v) for every pixel centre. The quad grid between
neighbouring pixels is split into two triangles; a duplicated seam column (u = 1 + 0.5/W,
resolved by the texture's ``repeat`` wrap) keeps texture coordinates continuous, and the two
open rings next to the poles are closed by triangle fans around pole vertices placed at the
centroid of their ring (one pole duplicate per fan triangle, so each gets its own u).

Faces are oriented **inward** (normal = (p1 - p0) x (p2 - p0) points towards the capture point
for a star-shaped depth map) because Mitsuba's area emitters are one-sided.

Topology and UVs depend only on (H, W) and are cached; positions are a differentiable function
of the depth map, and the radiance map is used unchanged as the emissive texture.

Vertex layout for an H x W panorama (N = H (W + 1) + 2W vertices, F = 2 H W faces):
    [0, H (W+1))            grid vertex (i, j) at index i (W+1) + j, j = W duplicates j = 0
    [H (W+1), H (W+1) + W)  north pole duplicates, one per column gap
    [H (W+1) + W, N)        south pole duplicates
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import torch

from roomlight.errors import ShapeError
from roomlight.core.geometry.equirect import check_equirect_shape, pixel_directions

__all__ = ["AreaLightTopology", "area_light_topology", "area_light_vertices", "AreaLightMesh", "build_area_light"]


@dataclass(frozen=True)
class AreaLightTopology:
    """Fixed part of a 2.5D area light at one resolution.

    Attributes:
        height, width: panorama size H, W.
        faces: (F, 3) int64 vertex indices, F = 2 H W, oriented inward.
        uv: (N, 2) float32 texture coordinates (v = 0 at the top image row, Mitsuba's
            in-memory convention); u may reach 1 + 0.5/W on the seam column.
        pixel_of_grid_vertex: (H (W+1),) int64 flat pixel index i W + (j mod W) of each grid vertex.
    """

    height: int
    width: int
    faces: torch.Tensor
    uv: torch.Tensor
    pixel_of_grid_vertex: torch.Tensor

    @property
    def vertex_count(self) -> int:
        return self.height * (self.width + 1) + 2 * self.width

    @property
    def face_count(self) -> int:
        return 2 * self.height * self.width


@lru_cache(maxsize=16)
def area_light_topology(height: int, width: int) -> AreaLightTopology:
    """Build (once per resolution) the faces, UVs and gather indices of the emitter mesh."""
    check_equirect_shape(height, width, "2.5D area light")
    h, w = height, width
    cols = w + 1
    ii, jj = torch.meshgrid(torch.arange(h), torch.arange(cols), indexing="ij")
    grid = (ii * cols + jj)  # (H, W+1) vertex ids
    pixel = (ii * w + torch.remainder(jj, w)).reshape(-1)

    # Quads between rows i, i+1 and columns j, j+1: a=(i,j) b=(i,j+1) c=(i+1,j) d=(i+1,j+1).
    a = grid[:-1, :-1].reshape(-1)
    b = grid[:-1, 1:].reshape(-1)
    c = grid[1:, :-1].reshape(-1)
    d = grid[1:, 1:].reshape(-1)
    # (a, c, b) and (b, c, d) turn inward: d omega/d phi x d omega/d theta points outward.
    quads = torch.cat([torch.stack([a, c, b], 1), torch.stack([b, c, d], 1)])

    north0 = h * cols
    south0 = north0 + w
    j = torch.arange(w)
    north = north0 + j
    south = south0 + j
    fan_n = torch.stack([north, grid[0, :-1], grid[0, 1:]], 1)
    fan_s = torch.stack([south, grid[-1, 1:], grid[-1, :-1]], 1)
    faces = torch.cat([quads, fan_n, fan_s]).to(torch.int64)

    u = (torch.arange(cols, dtype=torch.float64) + 0.5) / w
    v = (torch.arange(h, dtype=torch.float64) + 0.5) / h
    vv, uu = torch.meshgrid(v, u, indexing="ij")
    uv_grid = torch.stack([uu, vv], -1).reshape(-1, 2)
    # Pole duplicates take u between their two ring vertices and the ring's own v, so the cap
    # shows the first/last row (a texture lookup at v = 0 would wrap to the opposite pole).
    pole_u = (j.to(torch.float64) + 1.0) / w
    uv_n = torch.stack([pole_u, torch.full_like(pole_u, 0.5 / h)], 1)
    uv_s = torch.stack([pole_u, torch.full_like(pole_u, 1.0 - 0.5 / h)], 1)
    uv = torch.cat([uv_grid, uv_n, uv_s]).to(torch.float32)
    return AreaLightTopology(h, w, faces, uv, pixel)


@lru_cache(maxsize=16)
def _unit_directions(height: int, width: int, dtype: torch.dtype, device: str) -> torch.Tensor:
    return pixel_directions(height, width, dtype=dtype, device=device).reshape(-1, 3)


def area_light_vertices(depth: torch.Tensor) -> torch.Tensor:
    """Vertex positions of the 2.5D area light, differentiable in ``depth``.

    Args:
        depth: (H, W) radial distance from the capture point (scene units, e.g. metres), > 0.
    Returns:
        (N, 3) positions in the capture frame (y up), N = H (W+1) + 2W, in the order of
        :class:`AreaLightTopology`.
    """
    if depth.dim() == 3 and depth.shape[0] == 1:
        depth = depth[0]
    if depth.dim() != 2:
        raise ShapeError(f"area light: expected depth of shape (H, W), got {tuple(depth.shape)}")
    h, w = depth.shape
    topo = area_light_topology(h, w)
    dirs = _unit_directions(h, w, depth.dtype, str(depth.device))
    points = depth.reshape(-1, 1) * dirs  # (H W, 3)
    grid = points.index_select(0, topo.pixel_of_grid_vertex.to(depth.device))
    north = points[:w].mean(0, keepdim=True).expand(w, 3)
    south = points[-w:].mean(0, keepdim=True).expand(w, 3)
    return torch.cat([grid, north, south])


@dataclass
class AreaLightMesh:
    """An emissive mesh: geometry plus the texture it shows.

    Attributes:
        vertices: (N, 3) positions (scene units), differentiable.
        faces: (F, 3) int64, inward-facing.
        uv: (N, 2) float32 texture coordinates.
        texture: (H, W, 3) linear radiance (W / (sr m^2) or relative units), differentiable.
    """

    vertices: torch.Tensor
    faces: torch.Tensor
    uv: torch.Tensor
    texture: torch.Tensor

    @property
    def resolution(self) -> tuple[int, int]:
        return tuple(self.texture.shape[:2])


def build_area_light(radiance: torch.Tensor, depth: torch.Tensor) -> AreaLightMesh:
    """Lift a panorama (radiance (H, W, 3), depth (H, W)) into a 2.5D area light.

    Both inputs stay in the autograd graph: ``vertices`` depends on ``depth`` and ``texture`` is
    ``radiance`` itself.
    """
    if radiance.dim() != 3 or radiance.shape[-1] != 3:
        raise ShapeError(f"area light: expected radiance of shape (H, W, 3), got {tuple(radiance.shape)}")
    if radiance.shape[:2] != depth.shape[-2:]:
        raise ShapeError(
            f"area light: radiance is {tuple(radiance.shape[:2])} but depth is {tuple(depth.shape[-2:])}; "
            "resample one to the other's resolution"
        )
    verts = area_light_vertices(depth)
    topo = area_light_topology(*radiance.shape[:2])
    return AreaLightMesh(verts, topo.faces.to(verts.device), topo.uv.to(verts.device), radiance)
