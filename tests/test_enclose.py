"""A 2.5D light pushed out behind a scene: every point ends up inside, nothing else moves."""

import numpy as np
import torch

from roomlight.core.emitter.enclose import enclosing_depth
from roomlight.core.geometry.equirect import pixel_directions, sample_equirect


def box_depth(h, half=(2.0, 1.3, 1.6)):
    d = pixel_directions(h, 2 * h, dtype=torch.float64).numpy()
    return 1.0 / (np.abs(d) / np.asarray(half)).max(-1)


def test_points_inside_the_light_leave_it_unchanged():
    depth = box_depth(32)
    rng = np.random.default_rng(0)
    pts = rng.uniform(-1, 1, (2000, 3)) * [1.0, 0.65, 0.8]  # inside half the 4 x 2.6 x 3.2 m box
    out, moved = enclosing_depth(depth, pts, margin=0.03)
    assert moved == 0.0
    np.testing.assert_array_equal(out, depth.astype(np.float32))


def test_points_outside_or_on_the_light_end_up_inside_it_with_the_margin():
    h = 32
    depth = box_depth(h)
    rng = np.random.default_rng(1)
    # A second, larger box (a floor 0.4 m lower, a wall 1 m farther): points on its surface, some on
    # the light's own walls (coincident), some beyond them.
    dirs = rng.normal(size=(5000, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    far = 1.0 / (np.abs(dirs) / np.array([3.0, 1.7, 1.6])).max(-1)
    pts = dirs * far[:, None]
    out, moved = enclosing_depth(depth, pts, margin=0.03, dilate=1)
    assert moved > 0.9  # the walls the two boxes share are pushed out by the margin too
    # Every point is inside the new surface, wherever the bilinear lookup lands.
    d_at = sample_equirect(torch.from_numpy(out)[None, None].double(), torch.from_numpy(pts))[0, 0].numpy()
    assert (d_at >= np.linalg.norm(pts, axis=1)).all()
    # The light only moves out, and no farther than the points' box and the margin (plus one texel).
    assert (out >= depth.astype(np.float32)).all()
    outer = box_depth(h, (3.0, 1.7, 1.6))
    # The outer box's depth over each texel's 5 x 5 neighbours' centres bounds it over the texel and
    # its 3 x 3 neighbours' whole cells (where the points spread to).
    near = np.pad(outer, ((2, 2), (0, 0)), mode="edge")
    reach = np.max([np.roll(near[2 + dy:2 + dy + h], dx, axis=1) for dy in range(-2, 3) for dx in range(-2, 3)], 0)
    assert (out <= np.maximum(depth, 1.07 * reach)).all()  # the 3 % margin and the depth spread within a texel
