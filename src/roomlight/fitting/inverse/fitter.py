"""Fitting the illumination of a scene view by analysis-by-synthesis (paper §3.4).

Each iteration decodes the light model, renders the fitted view through Mitsuba (prb, max depth
4) with a fresh seed, and minimises L_img + lambda_rep L_rep + regularisers with Adam and a
global gradient-norm clip.

Best iterate. Single-iteration losses are Monte-Carlo estimates with independent noise, so
the smallest of them mostly picks a lucky seed. Every ``eval_every`` iterations (and after
the last one) the current parameters are instead re-evaluated with one *fixed* seed: all
candidates then see the same random numbers (common random numbers), their differences reflect
the parameters rather than the noise, and the best of them under this fixed-seed objective
is kept.

Rendering window. The loss only sees masked pixels, so by default each step renders just the
mask's bounding box grown by :data:`CROP_MARGIN_PX` (a film crop of the same camera): the
masked pixels get the same estimate as in the full frame, and the time that the other pixels
would cost (mostly camera rays that hit the emitter directly, which are expensive for a
2.5D mesh light and free for an env map) is not spent. ``FitConfig.crop_to_mask = False``
renders the whole frame.

Non-finite values. A step whose loss or gradient has a NaN/inf is skipped (the parameters
and Adam's moments are untouched), counted, and recorded in the history; many in a row stop
the fit with an error naming the iteration.
"""

from __future__ import annotations

import copy
import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import torch

from roomlight.errors import RoomlightError
from roomlight.fitting.inverse.config import FitConfig
from roomlight.fitting.inverse.lights import LightModel
from roomlight.fitting.inverse.objective import image_loss
from roomlight.fitting.inverse.repulsion import repulsion_penalty
from roomlight.core.light import Light

__all__ = ["FitResult", "Fitter", "MAX_NONFINITE_IN_A_ROW", "CROP_MARGIN_PX", "mask_window"]

MAX_NONFINITE_IN_A_ROW = 20
EVAL_SEED_OFFSET = 1_000_003  # the fixed best-iterate seed never coincides with a training seed
#: Pixels kept around the mask's bounding box: at least the radius of Mitsuba's widest default
#: pixel filter (gaussian, 2 px), so that no masked pixel loses filter support at the window's edge.
CROP_MARGIN_PX = 4


def mask_window(mask: torch.Tensor, margin: int = CROP_MARGIN_PX) -> tuple[int, int, int, int] | None:
    """(x0, y0, width, height) of the (H, W) mask's bounding box grown by ``margin`` pixels and
    clipped to the image; None when that is the whole image (or the mask is empty)."""
    rows = torch.nonzero(mask.any(1)).flatten()
    cols = torch.nonzero(mask.any(0)).flatten()
    if rows.numel() == 0:
        return None
    h, w = mask.shape
    y0, y1 = max(int(rows[0]) - margin, 0), min(int(rows[-1]) + 1 + margin, h)
    x0, x1 = max(int(cols[0]) - margin, 0), min(int(cols[-1]) + 1 + margin, w)
    if (x0, y0, x1, y1) == (0, 0, w, h):
        return None
    return x0, y0, x1 - x0, y1 - y0


@dataclass
class FitResult:
    """What a fit recovered (or, for the benchmark's oracle, the true light in the same shape).

    Attributes:
        method: the method's name.
        light: the recovered light: radiance (H, 2H, 3) linear (exposure applied), depth (H, 2H)
            metres or None, its kind; its frame is the identity (the light sits at the fitted
            scene's origin).
        history: one dict per iteration (loss terms, seconds, skipped flags, fixed-seed checks).
        best_iteration: iteration whose parameters were kept; None when nothing was fitted (an oracle).
        best_loss: their fixed-seed objective.
        seconds: the fit's duration.
        nonfinite_steps: skipped non-finite steps; None when nothing was fitted.
        config: the fit's settings.
    """

    method: str
    light: Light
    history: list[dict] = field(default_factory=list)
    best_iteration: int | None = 0
    best_loss: float = float("inf")
    seconds: float = 0.0
    nonfinite_steps: int | None = 0
    config: dict = field(default_factory=dict)

    @property
    def radiance(self) -> torch.Tensor:
        """(H, 2H, 3) float32 linear radiance, CPU."""
        return self.light.radiance

    @property
    def depth(self) -> torch.Tensor | None:
        """(H, 2H) float32 radial depth in metres, or None (env map, sphere proxy)."""
        return self.light.depth

    @property
    def emitter_kind(self) -> str:
        """``mesh``, ``envmap`` or ``sphere:R`` (accepted by EmitterScene)."""
        return self.light.kind


class Fitter:
    """Runs the optimisation of one light model against one view.

    Args:
        light: the light model (its ``kind`` fixes the emitter of ``escene``).
        escene: an EmitterScene of the fitted view (objects + sensor) for ``light.kind``.
        target: (H, W, 3) linear target image; mask: (H, W) bool object pixels.
        points: (M, 3) object surface points for the repulsion term, or None.
        config: the settings.
        sensor_dict: the view's sensor as a Mitsuba dict (needed with ``window``).
        window: (x0, y0, width, height) of the image region to render while fitting (see
            :func:`mask_window`), or None for the whole frame.

    ``target`` and ``mask`` attributes hold the fitted window; ``full_target`` and ``full_mask``
    the whole frame (for previews, rendered with the scene's own sensor).
    """

    def __init__(self, light: LightModel, escene, target: torch.Tensor, mask: torch.Tensor,
                 points: torch.Tensor | None, config: FitConfig, sensor_dict: dict | None = None,
                 window: tuple[int, int, int, int] | None = None):
        self.light, self.escene, self.config = light, escene, config
        self.full_target, self.full_mask = target.float(), mask.bool()
        # Without a pixel to match, a fit renders nothing; it is left to terms a subclass adds (a photo
        # without objects: the light seen through its pixels).
        self.renders = bool(self.full_mask.any())
        if not self.renders and not self.fits_without_pixels():
            raise RoomlightError("fit: the mask selects no pixel of the target image")
        self.window = window
        if window is None:
            self.sensor = 0  # the scene's own sensor: the whole frame
            self.target, self.mask = self.full_target, self.full_mask
        else:
            if sensor_dict is None:
                raise RoomlightError("Fitter: a rendering window needs the view's sensor dict")
            self.sensor = escene.cropped_sensor(sensor_dict, window)
            self.target, self.mask = self.in_window(self.full_target), self.in_window(self.full_mask)
        self.points = points if (points is not None and light.has_depth and config.lambda_rep > 0) else None
        params = [p for p in light.parameters() if p.requires_grad]
        self.params = params
        self.optimizer = torch.optim.Adam(params, lr=config.lr, betas=tuple(config.betas))
        self.generator = torch.Generator().manual_seed(config.seed)

    def in_window(self, image: torch.Tensor) -> torch.Tensor:
        """The part of a whole-frame (H, W, ...) image inside the rendering window (all of it without one)."""
        if self.window is None:
            return image
        x0, y0, w, h = self.window
        return image[y0:y0 + h, x0:x0 + w]

    def fits_without_pixels(self) -> bool:
        """Whether the objective has terms beyond the image's (so an empty mask still fits something)."""
        return False

    # ------------------------------------------------------------------ objective
    def terms(self, image: torch.Tensor | None, radiance, depth, mask) -> dict[str, torch.Tensor]:
        """Every term of the objective and their weighted ``total``; ``image`` None (nothing rendered,
        see ``renders``) makes the image term zero."""
        c = self.config
        if image is None:
            t = {"img": torch.zeros((), dtype=radiance.dtype, device=radiance.device)}
        else:
            t = image_loss(image, self.target, mask, c.tau, c.c_max, c.lambda_log, c.log_eps)
        if self.points is not None and depth is not None:
            t["rep"] = repulsion_penalty(depth, self.points, c.margin)
            t["total"] = t["img"] + c.lambda_rep * t["rep"]
        else:
            t["total"] = t["img"]
        for name, value in self.light.regularizers().items():
            t[name] = value
            t["total"] = t["total"] + value
        return t

    def _mask_subset(self) -> torch.Tensor:
        frac = self.config.pixel_subset
        if frac >= 1.0:
            return self.mask
        keep = torch.rand(self.mask.shape, generator=self.generator) < frac
        sub = self.mask & keep
        return sub if bool(sub.any()) else self.mask

    def evaluate_terms(self) -> dict[str, float]:
        """Every term of the objective of the current parameters at the fixed seed (no gradients)."""
        c = self.config
        with torch.no_grad():
            rad, depth = self.light.emitter()
            img = None
            if self.renders:
                self.escene.set_emitter(rad, depth)
                self.escene.set_parameters(self.light.scene_values())
                img = self.escene.render(spp=c.eval_spp or c.spp, seed=c.seed + EVAL_SEED_OFFSET, sensor=self.sensor)
            return {k: float(v) for k, v in self.terms(img, rad, depth, self.mask).items()}

    def evaluate(self) -> float:
        """The objective of the current parameters at the fixed seed (no gradients)."""
        return self.evaluate_terms()["total"]

    def update(self) -> float:
        """Apply the gradients now in the parameters: global-norm clip, then one Adam step.
        Returns the gradient norm before clipping."""
        gnorm = float(torch.nn.utils.clip_grad_norm_(self.params, self.config.grad_clip))
        self.optimizer.step()
        return gnorm

    # ------------------------------------------------------------------ one step
    def step(self, it: int) -> dict:
        """One optimisation step at iteration ``it``: render, loss, backward, clip, Adam.

        A step whose loss or gradient is non-finite leaves the parameters and Adam's moments
        as they were and is flagged ``skipped_nonfinite``. Returns the iteration's record: the
        loss terms, ``grad_norm``, ``seconds`` and the light's own description.
        """
        from roomlight.core.render.bridge import render_differentiable

        c = self.config
        t0 = time.perf_counter()
        record: dict = {}
        self.optimizer.zero_grad(set_to_none=True)
        rad, depth = self.light.emitter()
        seed = c.seed + 2 * it
        img = None
        if self.renders:
            img = render_differentiable(self.escene, rad, depth, spp=c.spp, seed=seed, seed_grad=seed + 1,
                                        sensor=self.sensor, extra=self.light.scene_values())
        terms = self.terms(img, rad, depth, self._mask_subset())
        loss = terms["total"]
        ok = bool(torch.isfinite(loss))
        if ok:
            loss.backward()
            ok = all(p.grad is None or bool(torch.isfinite(p.grad).all()) for p in self.params)
        if ok:
            gnorm = self.update()
        else:
            # Skip: parameters and Adam's moments stay as they were.
            self.optimizer.zero_grad(set_to_none=True)
            gnorm = float("nan")
            record["skipped_nonfinite"] = True
        record.update({k: float(v.detach()) for k, v in terms.items()})
        record.update({"grad_norm": gnorm, "seconds": time.perf_counter() - t0, **self.light.describe()})
        return record

    # ------------------------------------------------------------------ loop and bookkeeping
    def run(self, progress: bool = True, history_path: Path | None = None, state_path: Path | None = None,
            checkpoint_every: int = 0, state_tag: dict | None = None) -> FitResult:
        """All iterations of :meth:`step`, with the fixed-seed best-iterate checks, the history
        (``history_path``: one JSON line per iteration), the progress bar and the non-finite
        guard; ends with the best parameters loaded into the light.

        With ``state_path``, the state of the fit is saved there every ``checkpoint_every``
        iterations (:mod:`roomlight.fitting.inverse.checkpoint`), and a state found there when the run
        starts is restored first, so the run continues where an interrupted one stopped.
        ``state_tag`` (JSON-friendly) describes what is fitted; a saved state with another tag is refused.
        """
        from roomlight.fitting.inverse.checkpoint import load_fit_state, save_fit_state

        c = self.config
        best = (float("inf"), -1, None)
        history: list[dict] = []
        nonfinite = 0
        in_a_row = 0
        start = 0
        if state_path is not None and Path(state_path).is_file():
            restored = load_fit_state(state_path, self, state_tag)
            start, best, history = restored["next_iteration"], restored["best"], restored["history"]
            nonfinite, in_a_row = restored["nonfinite"], restored["in_a_row"]
        log = open(history_path, "w") if history_path else None
        if log:
            for record in history:
                log.write(json.dumps(record) + "\n")
            log.flush()
        bar = None
        if progress:
            from roomlight.core.progress import progress_bar

            bar = progress_bar(total=c.iterations, initial=start, desc="fit", unit="it")
        t_start = time.perf_counter()
        try:
            for it in range(start, c.iterations + 1):
                record: dict = {"iteration": it}
                if it % max(c.eval_every, 1) == 0 or it == c.iterations:
                    value = self.evaluate()
                    record["fixed_seed_loss"] = value
                    if math.isfinite(value) and value < best[0]:
                        best = (value, it, copy.deepcopy(self.light.state_dict()))
                if it < c.iterations:
                    record.update(self.step(it))
                    if record.get("skipped_nonfinite"):
                        nonfinite += 1
                        in_a_row += 1
                        if in_a_row >= MAX_NONFINITE_IN_A_ROW:
                            raise RoomlightError(
                                f"fit: {in_a_row} consecutive iterations (up to {it}) gave a non-finite loss or "
                                "gradient; lower the learning rate or check the target image and scene")
                    else:
                        in_a_row = 0
                history.append(record)
                if log:
                    log.write(json.dumps(record) + "\n")
                    log.flush()
                if bar and it < c.iterations:
                    bar.set_postfix(loss=f"{record['total']:.4g}", best=f"{best[0]:.4g}@{best[1]}")
                    bar.update()
                if state_path is not None and checkpoint_every > 0 and it < c.iterations \
                        and (it + 1) % checkpoint_every == 0:
                    save_fit_state(state_path, self, it + 1, best, history, nonfinite, in_a_row, state_tag)
        finally:
            if bar:
                bar.close()
            if log:
                log.close()
        if best[2] is not None:
            self.light.load_state_dict(best[2])
        with torch.no_grad():
            rad, depth = self.light.emitter()
        return FitResult(method="", light=Light(rad, depth, self.escene_kind()), history=history,
                         best_iteration=best[1], best_loss=best[0], seconds=time.perf_counter() - t_start,
                         nonfinite_steps=nonfinite, config=c.to_dict())

    def escene_kind(self) -> str:
        return str(self.escene.kind)
