"""Reflectance models written out from their published formulas, to check Mitsuba's BSDFs against.

Directions are unit 3-vectors in the local shading frame (normal +z); ``wi`` points away from the
surface towards where the light comes from (Mitsuba's convention), and every function returns the
BSDF value times cos(theta_o), which is what Mitsuba's ``BSDF.eval`` returns.

- Fresnel: exact unpolarised reflectance of a dielectric (relative index eta) and of a conductor
  (complex index eta + i k) (Born & Wolf).
- GGX (Trowbridge-Reitz) normal distribution D and Smith's separable masking G1 (Walter et al. 2007).
- Burley's "principled" model (Burley 2012) as Mitsuba documents its ``principled`` plugin: a GGX
  specular lobe with alpha = roughness^2 whose Fresnel term blends the dielectric one (eta from
  ``specular``) with Schlick's towards base_color by ``metallic``, plus the Burley diffuse and
  retro-reflection lobes weighted by 1 - metallic.
"""

from __future__ import annotations

import math

import numpy as np


def direction(theta_deg: float, phi_deg: float = 0.0) -> np.ndarray:
    """Unit vector at polar angle theta from +z, azimuth phi from +x."""
    t, p = math.radians(theta_deg), math.radians(phi_deg)
    return np.array([math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)])


def half_vector(wi, wo) -> np.ndarray:
    h = np.asarray(wi, float) + np.asarray(wo, float)
    return h / np.linalg.norm(h)


def reflect(wi) -> np.ndarray:
    """Mirror direction of wi about the normal +z."""
    return np.array([-wi[0], -wi[1], wi[2]], float)


def fresnel_dielectric(cos_i, eta):
    """Unpolarised reflectance of light arriving from outside at cos_i >= 0 on a medium of relative index
    eta (eta < 1: from the denser side, 1 beyond the critical angle). Works on arrays."""
    c = np.asarray(cos_i, float)
    sin2_t = (1.0 - c * c) / (eta * eta)
    cos_t = np.sqrt(np.clip(1.0 - sin2_t, 0.0, None))
    with np.errstate(divide="ignore", invalid="ignore"):
        rs = (c - eta * cos_t) / (c + eta * cos_t)
        rp = (eta * c - cos_t) / (eta * c + cos_t)
    return np.where(sin2_t >= 1.0, 1.0, 0.5 * (rs * rs + rp * rp))


def fresnel_conductor(cos_i: float, eta, k) -> np.ndarray:
    """Unpolarised reflectance of a conductor of complex index eta + i k (per channel)."""
    n = np.asarray(eta, float) + 1j * np.asarray(k, float)
    c = float(cos_i)
    cos_t = np.sqrt(1.0 - (1.0 - c * c) / (n * n))
    rs = (c - n * cos_t) / (c + n * cos_t)
    rp = (n * c - cos_t) / (n * c + cos_t)
    return 0.5 * (np.abs(rs) ** 2 + np.abs(rp) ** 2)


def conductor_f0(eta, k) -> np.ndarray:
    """Normal-incidence reflectance of a conductor: ((n - 1)^2 + k^2) / ((n + 1)^2 + k^2)."""
    eta, k = np.asarray(eta, float), np.asarray(k, float)
    return ((eta - 1) ** 2 + k ** 2) / ((eta + 1) ** 2 + k ** 2)


def ggx_d(cos_h, alpha):
    """GGX normal distribution at a microfacet normal cos_h from +z."""
    c2 = np.asarray(cos_h, float) ** 2
    return alpha * alpha / (math.pi * (c2 * (alpha * alpha - 1.0) + 1.0) ** 2)


def smith_g1(v, m, alpha):
    """Smith's GGX masking of direction v (..., 3) seen over microfacet normal m (..., 3)."""
    v, m = np.asarray(v, float), np.asarray(m, float)
    c = np.abs(v[..., 2])
    tan2 = (1.0 - c * c) / np.maximum(c * c, 1e-300)
    g = 2.0 / (1.0 + np.sqrt(1.0 + alpha * alpha * tan2))
    # a facet seen from its back side masks everything
    return np.where(np.sum(v * m, -1) * v[..., 2] > 0, g, 0.0)


def microfacet_reflection(wi, wo, alpha, fresnel) -> np.ndarray:
    """F(wi . h) D(h) G1(wi) G1(wo) / (4 cos_i): a GGX reflection lobe times cos_o; ``fresnel(cos)``."""
    h = half_vector(wi, wo)
    g = smith_g1(wi, h, alpha) * smith_g1(wo, h, alpha)
    return np.asarray(fresnel(float(np.dot(wi, h))), float) * ggx_d(h[2], alpha) * g / (4.0 * wi[2])


def schlick_weight(cos) -> float:
    return float(np.clip(1.0 - cos, 0.0, 1.0)) ** 5


def principled(base_color, roughness: float, metallic: float, wi, wo, specular: float = 0.5) -> np.ndarray:
    """Burley's principled BRDF (no sheen, clearcoat, transmission or tint) times cos_o, per channel."""
    base = np.asarray(base_color, float)
    eta = 2.0 / (1.0 - math.sqrt(0.08 * specular)) - 1.0  # F0 = 0.08 specular: eta 1.5 at specular 0.5
    alpha = max(0.001, roughness ** 2)

    def fresnel(cos_d):
        schlick = base + (1.0 - base) * schlick_weight(cos_d)
        return (1.0 - metallic) * fresnel_dielectric(cos_d, eta) + metallic * schlick

    spec = microfacet_reflection(wi, wo, alpha, fresnel)
    fi, fo = schlick_weight(wi[2]), schlick_weight(wo[2])
    rr = 2.0 * roughness * float(np.dot(half_vector(wi, wo), wo)) ** 2
    diffuse = (1.0 - 0.5 * fi) * (1.0 - 0.5 * fo)
    retro = rr * (fo + fi + fo * fi * (rr - 1.0))
    return spec + (1.0 - metallic) * wo[2] * base / math.pi * (diffuse + retro)


def rough_interface(cos_i: float, eta: float, alpha: float, n=(400, 64)) -> tuple[float, float]:
    """(reflected, transmitted) fractions of light arriving at cos_i on a rough GGX interface of relative
    index eta, single scattering with Smith masking of the outgoing direction: E over visible normals m
    of F G1(w_r, m) and of (1 - F) G1(w_t, m). A midpoint rule over the normals, drawn by the inverse of
    the GGX (D cos) distribution's CDF, tan^2 theta_m = alpha^2 xi / (1 - xi)."""
    xi = (np.arange(n[0]) + 0.5) / n[0]
    phi = (np.arange(n[1]) + 0.5) / n[1] * 2.0 * math.pi
    x, p = np.meshgrid(xi, phi, indexing="ij")
    cos_m = 1.0 / np.sqrt(1.0 + alpha * alpha * x / (1.0 - x))
    sin_m = np.sqrt(1.0 - cos_m ** 2)
    m = np.stack([sin_m * np.cos(p), sin_m * np.sin(p), cos_m], -1)
    wi = np.array([math.sqrt(max(0.0, 1.0 - cos_i * cos_i)), 0.0, cos_i])
    c = m @ wi
    # visible-normal density G1(wi, m) (wi . m)+ D(m) / cos_i over the drawing density D(m) cos_m
    weight = np.where(c > 0, smith_g1(wi, m, alpha) * c / cos_i / cos_m, 0.0)
    f = fresnel_dielectric(np.clip(c, 0.0, 1.0), eta)
    w_r = 2.0 * c[..., None] * m - wi
    reflected = np.mean(weight * f * smith_g1(w_r, m, alpha) * (w_r[..., 2] > 0))
    cos_t2 = 1.0 - (1.0 - c * c) / (eta * eta)
    w_t = -wi / eta + (c / eta - np.sqrt(np.clip(cos_t2, 0.0, None)))[..., None] * m
    transmitted = np.mean(weight * (1.0 - f) * smith_g1(w_t, m, alpha) * (cos_t2 > 0))
    return float(reflected), float(transmitted)
