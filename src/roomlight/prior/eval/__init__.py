"""Evaluating the prior: metrics, the encoder / latent-fit benchmark, samples and figures.

- :mod:`roomlight.prior.eval.metrics`   PSNR, SSIM (LDR), HDR PSNR, AbsRel, the LDR tone mapping
- :func:`evaluate_prior`, :func:`report_markdown`, :func:`write_report`   ``roomlight eval-prior``
- :func:`load_lpips`              LPIPS only with local weights
- :func:`compare_reports`         two evaluations room by room, with bootstrap intervals
- :mod:`roomlight.prior.eval.samples`   prior samples, latent interpolation, probe renders
- :mod:`roomlight.prior.eval.figures`   the samples figure and interpolation strips
"""

from __future__ import annotations

from roomlight.prior.eval.compare import compare_reports, comparison_markdown
from roomlight.prior.eval.lpips import load_lpips
from roomlight.prior.eval.metrics import abs_rel, log_average_luminance, peak_error_stops, psnr, psnr_hdr, ssim, to_ldr
from roomlight.prior.eval.prior import evaluate_prior, panorama_metrics, report_markdown, write_report
from roomlight.prior.eval.samples import decode_latents, interpolate_latents, probe_layout, render_probes, sample_latents

__all__ = ["abs_rel", "log_average_luminance", "peak_error_stops", "psnr", "psnr_hdr", "ssim", "to_ldr", "evaluate_prior",
           "panorama_metrics", "report_markdown", "write_report", "load_lpips", "decode_latents",
           "interpolate_latents", "probe_layout", "render_probes", "sample_latents", "compare_reports",
           "comparison_markdown"]
