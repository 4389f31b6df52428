"""Procedural rooms, windows: portal sampling and the sky model."""

import numpy as np
import pytest

pytestmark = pytest.mark.mitsuba


def _portal(mi, sky):
    from roomlight.datagen.synth.portal import portal_emitter
    from roomlight.datagen.synth.spec import Window

    # A 1.2 x 1.0 m window in the wall x = 2 (room side x < 2), reveal 0.25 m.
    w = Window(origin=(2.0, 1.0, -0.6), edge_a=(0.0, 0.0, 1.2), edge_b=(0.0, 1.0, 0.0), normal=(-1.0, 0.0, 0.0),
               depth=0.25)
    return w, portal_emitter(mi, w, sky)


def _flat_sky(L=100.0, sun=None, sun_dir=(1.0, 0.0, 0.0)):
    from roomlight.datagen.synth.spec import Sky

    return Sky(kind="clear", zenith=(L, L, L), horizon=(L, L, L), exponent=1.0, ground=(L, L, L),
               sun=sun, sun_dir=sun_dir, sun_illuminance=0.0 if sun is None else 8e4)


def _sample_portal(mi, emitter, p, n=1 << 18, seed=0):
    import drjit as dr

    rng = np.random.default_rng(seed)
    it = dr.zeros(mi.Interaction3f, n)
    it.p = mi.Point3f(*[np.full(n, v, np.float32) for v in p])
    u = rng.random((2, n)).astype(np.float32)
    ds, w = emitter.sample_direction(it, mi.Point2f(u[0], u[1]))
    pdf = emitter.pdf_direction(it, ds)
    return np.asarray(w[1], np.float64), np.asarray(ds.pdf, np.float64), np.asarray(pdf, np.float64)


def _window_solid_angle(p, w, k=400):
    from roomlight.datagen.synth.portal import portal_quad

    o, a, b = portal_quad(w)
    s = (np.arange(k) + 0.5) / k
    q = o + s[:, None, None] * a + s[None, :, None] * b
    v = q - np.asarray(p)
    r = np.linalg.norm(v, axis=-1)
    cos = np.abs(v @ (np.cross(a, b) / np.linalg.norm(np.cross(a, b)))) / r
    return float((cos / r ** 2).sum() * np.linalg.norm(np.cross(a, b)) / k ** 2)


def test_portal_sampling_matches_the_window_solid_angle(mi):
    """E[weight] of the portal's direction sampling = L * solid angle of the window opening,
    and pdf_direction reproduces the sampling pdf (the MIS contract)."""
    w, em = _portal(mi, _flat_sky(100.0))
    for p in [(0.5, 1.2, 0.3), (1.6, 0.4, -1.5)]:
        weight, pdf_s, pdf_e = _sample_portal(mi, em, p)
        assert weight.mean() == pytest.approx(100.0 * _window_solid_angle(p, w), rel=0.01)
        ok = pdf_s > 0
        assert np.allclose(pdf_s[ok], pdf_e[ok], rtol=1e-4)


def test_portal_sun_strategy_gives_the_sun_illuminance(mi):
    """Only the sun shines (sky 0): E[weight] = L_sun * sun solid angle when the sun's cone
    passes through the window."""
    from roomlight.datagen.synth.sky import sun_solid_angle

    L_sun = 1e8
    sun_dir = tuple(np.array([1.0, 0.3, 0.0]) / np.hypot(1.0, 0.3))
    _, em = _portal(mi, _flat_sky(0.0, sun=(L_sun,) * 3, sun_dir=sun_dir))
    weight, _, _ = _sample_portal(mi, em, (0.5, 1.0, 0.0))
    assert weight.mean() == pytest.approx(L_sun * sun_solid_angle(0.5), rel=0.02)


def test_sky_model_is_the_same_in_numpy_and_in_the_portal(mi):
    import drjit as dr

    from roomlight.datagen.synth.sky import sample_sky, sky_radiance

    rng = np.random.default_rng(5)
    sky = None
    while sky is None or sky.sun is None or not any(sky.skyline):
        sky = sample_sky(rng, "clear")
    _, em = _portal(mi, sky)
    d = rng.normal(size=(4096, 3))
    d[:64] = np.asarray(sky.sun_dir) + 0.002 * rng.normal(size=(64, 3))  # some inside the sun disk
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    ref = np.stack(sky_radiance(sky, d[:, 0], d[:, 1], d[:, 2]), -1)
    got = em._radiance(mi.Vector3f(*[d[:, k].astype(np.float32) for k in range(3)]))
    dr.eval(got)
    got = np.stack([np.asarray(got[k]) for k in range(3)], -1)
    close = np.isclose(got, ref, rtol=2e-3, atol=1e-3).all(-1)
    assert close.mean() > 0.995  # float32 vs float64 may flip the odd direction on a disk/bin edge
    assert (ref[:64].max(-1) > 1e6).any()
