"""Torch <-> Dr.Jit bridge: render an :class:`EmitterScene` as a differentiable torch op.

``render_differentiable`` writes the radiance texture and (for 2.5D emitters) the vertex
positions into the scene inside a ``drjit.wrap``-ed function and calls ``mi.render`` with the
scene parameters, so a torch loss on the returned image back-propagates through Dr.Jit's
AD (the ``prb`` integrator's adjoint pass) to ``radiance`` and ``depth``.
"""

from __future__ import annotations

import torch

from roomlight.core.render.scene import EmitterScene

__all__ = ["render_differentiable"]


def render_differentiable(escene: EmitterScene, radiance: torch.Tensor, depth: torch.Tensor | None = None,
                          spp: int = 16, seed: int = 0, seed_grad: int | None = None,
                          spp_grad: int | None = None, sensor: int | object = 0,
                          extra: dict[str, torch.Tensor] | None = None) -> torch.Tensor:
    """Differentiable render of ``escene`` lit by (radiance, depth).

    Args:
        escene: the scene; its emitter kind decides how depth is used.
        radiance: (H, W, 3) linear radiance (moved to the variant's device: CPU for LLVM, GPU
            for CUDA; gradients flow back to the original tensor).
        depth: (H, W) radial depth in scene units (ignored by ``envmap``/``sphere``).
        spp: samples per pixel of the primal render.
        seed: primal seed; vary it per optimisation step to decorrelate the noise.
        seed_grad: seed of the adjoint pass (default ``seed + 1``). Mitsuba requires it to differ
            from ``seed`` so that the gradient's noise is independent of the primal's.
        spp_grad: samples per pixel of the adjoint pass (default ``spp``).
        sensor: index of the scene's sensor to render, or a Mitsuba sensor object (e.g. a cropped copy).
        extra: more differentiable scene parameters by their ``mi.traverse`` key, e.g. an object's
            ``"obj.bsdf.base_color.value"`` (3,) or ``"obj.bsdf.roughness.value"`` (1,); see
            :meth:`EmitterScene.parameter_value` for the accepted types.
    Returns:
        (H_img, W_img, 3) float32 linear image on the variant's device, attached to torch's
        autograd graph.
    """
    import drjit as dr

    from roomlight.core.render.variant import serial_backward, torch_device

    mi = escene.mi
    seed_grad = seed + 1 if seed_grad is None else seed_grad
    # drjit.wrap hands tensors over through DLPack: they must live where the variant computes.
    device = torch_device()
    radiance = radiance.float().to(device)
    depth = depth.float().to(device) if depth is not None else None
    tex = escene.texture_value(radiance)
    verts = escene.vertex_value(depth)
    extra = {k: v.float().to(device) for k, v in (extra or {}).items()}

    @dr.wrap(source="torch", target="drjit")
    def _render(tex_dr, verts_dr, extra_dr):
        for key, value in extra_dr.items():
            escene.params[key] = escene.parameter_value(key, value)
        escene.write_emitter_values(tex_dr, verts_dr.array if verts_dr is not None else None)
        return mi.render(escene.scene, escene.params, spp=spp, seed=seed, seed_grad=seed_grad,
                         spp_grad=spp_grad or spp, sensor=sensor)

    img = _render(tex, verts, extra)
    if img.requires_grad and serial_backward():
        _serialise_adjoint(img, [t for t in (tex, verts, *extra.values()) if t is not None and t.requires_grad])
    return img[..., :3]


def _serialise_adjoint(image: torch.Tensor, inputs: list[torch.Tensor]) -> None:
    """Run the adjoint pass of ``image`` on one Dr.Jit worker, then give the workers back.

    Tensor hooks bracket it: the hook on the image's gradient runs just before the wrapped render's
    backward (one worker), the hooks on its inputs' gradients just after (all workers again), so
    every other render keeps its workers. See :func:`roomlight.core.render.variant.serial_backward`.
    """
    import drjit as dr

    from roomlight.core.render.variant import worker_count

    workers = worker_count()

    def one(g):
        dr.set_thread_count(1)
        return g

    def back(g):
        dr.set_thread_count(workers)
        return g

    image.register_hook(one)
    for t in inputs:
        t.register_hook(back)
