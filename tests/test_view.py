"""``roomlight view``: the page's data against the bundle, and the page itself in headless Chromium.

Browser checks use a panorama whose answer is known without the viewer: a box room (depth from
the example room) that is red behind the capture point (z > 0) and blue in front (z < 0). Looking
along -z the room is blue; a mirror ball's centre reflects +z, so it is red; a probe at the capture
point sees exactly the env map, and one moved towards the red wall sees more red.
Set ROOMLIGHT_SAVE_SCREENSHOTS=DIR to keep the screenshots (the README's image comes from there).
"""

from __future__ import annotations

import base64
import json
import os
import re
import shutil

import numpy as np
import pytest
import torch
from click.testing import CliRunner

from helpers_browser import screenshot
from roomlight.cli.main import cli
from roomlight.core.emitter.export import export_emitter
from roomlight.core.examples import example_room
from roomlight.core.geometry.equirect import pixel_directions
from roomlight.core.io import read_ply

pytest.importorskip("roomlight.viewer")
from roomlight.viewer import three_dir  # noqa: E402

try:
    three_dir()
except FileNotFoundError as e:
    pytest.skip(f"three.js is not installed: {e}", allow_module_level=True)

SIZE = (900, 500)  # wide enough that the panel (left, 310 px) does not cover the insets
# insets: 240 x 120 px each, 8 px from the top and right edges; balls at x = -1.1 (mirror) and +1.1 (diffuse)
LEFT, RIGHT, TOP, IW, IH = 900 - 2 * 248, 900 - 248, 8, 240, 120


def _page_data(html: str) -> dict:
    m = re.search(r'<script type="application/json" id="roomlight-data">(.*?)</script>', html, re.S)
    return json.loads(m.group(1).replace("<\\/", "</"))


def _view(bundle, tmp_path, name="page.html"):
    out = tmp_path / name
    res = CliRunner().invoke(cli, ["view", str(bundle), "--out", str(out), "--cube-size", "64"])
    assert res.exit_code == 0, res.output
    return out


@pytest.fixture(scope="module")
def red_blue(tmp_path_factory):
    _, depth = example_room(32)
    z = pixel_directions(32, 64, dtype=torch.float64)[..., 2]
    rad = torch.where((z > 0)[..., None], torch.tensor([0.8, 0.05, 0.05]), torch.tensor([0.05, 0.05, 0.8]))
    out = tmp_path_factory.mktemp("redblue") / "emitter"
    export_emitter(out, rad.float(), depth, "mesh")
    return out


def test_page_holds_the_bundle_and_nothing_from_the_network(red_blue, tmp_path):
    page = _view(red_blue, tmp_path)
    html = page.read_text()
    assert not re.search(r'<(script|link|img)[^>]+(src|href)=', html), "the page must not load files"
    data = _page_data(html)
    ply = read_ply(red_blue / "emitter.ply")
    pos = np.frombuffer(base64.b64decode(data["mesh"]["positions"]), "<f4").reshape(-1, 3)
    np.testing.assert_array_equal(pos, ply["vertices"])
    faces = np.frombuffer(base64.b64decode(data["mesh"]["faces"]), "<u4").reshape(-1, 3)
    np.testing.assert_array_equal(faces, ply["faces"])
    rgba = np.frombuffer(base64.b64decode(data["radiance"]), "<f2").reshape(32, 64, 4)
    assert set(np.unique(rgba[..., 3])) == {1.0}
    assert np.isin(rgba[..., :3], np.float16([0.8, 0.05])).all()  # half floats keep these values closely
    assert (rgba[..., 0] > rgba[..., 2]).sum() == 32 * 32  # half the columns face +z
    lo, hi = np.array(data["bounds"])
    assert np.all(lo < data["probe"]) and np.all(np.array(data["probe"]) < hi)


def _region(img, x0, y0, w, h):
    return img[y0:y0 + h, x0:x0 + w].astype(np.float64)


def _ball(img, inset_x, which):
    """Pixels of the mirror (0) or diffuse (1) ball's central disc in an inset."""
    cx = inset_x + int(IW / 2 + (-1.1 if which == 0 else 1.1) / 3.75 * IW / 2)
    return _region(img, cx - 12, TOP + IH // 2 - 12, 24, 24)


@pytest.mark.slow
def test_viewer_renders_the_light_and_the_probe_follows_it(red_blue, tmp_path):
    page = _view(red_blue, tmp_path)
    at_origin = screenshot(page, tmp_path / "origin.png", "probe=0,0,0&exposure=0", SIZE)
    main = _region(at_origin, 340, 160, 540, 320)  # below the insets, right of the panel
    assert main.mean() > 20, "the emissive mesh should fill the view"
    assert main[..., 2].mean() > 3 * main[..., 0].mean(), "looking along -z shows the blue half"
    for inset in (LEFT, RIGHT):
        mirror, diffuse = _ball(at_origin, inset, 0), _ball(at_origin, inset, 1)
        assert mirror[..., 0].mean() > 2 * mirror[..., 2].mean(), "a mirror ball's centre reflects +z (red)"
        assert diffuse[..., 0].mean() > diffuse[..., 2].mean(), "its facing side is lit mostly by the red half"
    # at the capture point the 2.5D light and the env map are the same light
    np.testing.assert_allclose(_region(at_origin, LEFT, TOP, IW, IH), _region(at_origin, RIGHT, TOP, IW, IH),
                               atol=6)

    moved = screenshot(page, tmp_path / "moved.png", "probe=0,0,1.2&exposure=0", SIZE)
    left0, left1 = _region(at_origin, LEFT, TOP, IW, IH), _region(moved, LEFT, TOP, IW, IH)
    assert np.abs(left1 - left0).mean() > 2, "moving the probe must change its reflection"
    # the mirror ball (left half of the inset): its red cap grows as the red wall comes closer
    near, far = _region(moved, LEFT, TOP, IW // 2, IH), _region(at_origin, LEFT, TOP, IW // 2, IH)
    assert (near[..., 0] > near[..., 2] + 40).sum() > 1.2 * (far[..., 0] > far[..., 2] + 40).sum(), \
        "near the red wall the mirror ball shows more red"
    np.testing.assert_allclose(_region(moved, RIGHT, TOP, IW, IH), _region(at_origin, RIGHT, TOP, IW, IH), atol=1,
                               err_msg="the env map does not depend on where the probe is")


@pytest.mark.slow
def test_viewer_screenshot_of_the_example_room(tmp_path):
    rad, depth = example_room(64)
    bundle = tmp_path / "example"
    export_emitter(bundle, rad, depth, "mesh")
    page = _view(bundle, tmp_path)
    shot = tmp_path / "viewer.png"
    img = screenshot(page, shot, "probe=0.6,-0.55,-1.5&radius=0.3&camera=-0.4,0.1,0.4&target=0.6,-0.55,-1.5", (1000, 600))
    assert (img.max(-1) > 30).mean() > 0.5
    if os.environ.get("ROOMLIGHT_SAVE_SCREENSHOTS"):
        shutil.copy(shot, os.path.join(os.environ["ROOMLIGHT_SAVE_SCREENSHOTS"], "viewer.png"))
