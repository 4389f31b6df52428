"""What each candidate prior costs: decode latency, latent-fit step, scene-fit iteration, training rate.

For every candidate architecture (random weights: none of these timings depends on the weights):

- parameters;
- decode ms: one latent -> (radiance, depth), batch 1, no gradient (what a viewer or a sample costs);
- latent fit ms/it: one step of ``fit-pano`` / ``eval-prior``'s latent fit at batch 16 (decode, the
  four-channel loss, backward to z);
- scene fit s/it: one iteration of ``roomlight fit --method prior`` on the built-in example scene at the
  fast preset's size (render 128x128 at 16 spp through the 2.5D light, backward through the decoder);
- training panoramas/s: full training steps at batch 32 (forward, the training loss, backward, AdamW).

Prints a Markdown table of medians (after one warm-up). Pause other heavy jobs while it runs.
Run: .venv/bin/python benchmarks/bench_prior_candidates.py [--candidates lite,lite-l256,...] [--repeats 5]
     [--no-scene-fit]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import torch

sys.path.insert(0, str(Path(__file__).resolve().parent))

#: Candidate name -> (preset, overrides of its ModelConfig).
CANDIDATES = {
    "lite": ("lite", {}),
    "lite-l256": ("lite", {"latent_dim": 256}),
    "lite-l512": ("lite", {"latent_dim": 512}),
    "lite-w24-l256": ("lite", {"ch": 24, "latent_dim": 256}),
    "small": ("small", {}),
    "small-l512": ("small", {"latent_dim": 512}),
    "lite-128x256": ("lite", {"resolution": (128, 256)}),
    "default": ("default", {}),
}


from bench_model import median_time  # noqa: E402  (warm-up, then the median of repeats)


def make_model(name: str):
    from roomlight.prior.model import ModelConfig, Normalization, PanoVAE, get_preset

    preset, overrides = CANDIDATES[name]
    cfg = get_preset(preset).override(**overrides) if overrides else get_preset(preset)
    assert isinstance(cfg, ModelConfig)
    torch.manual_seed(0)
    norm = Normalization(torch.tensor([0.95, 0.76, 0.61, 0.61]), torch.tensor([0.64, 0.60, 0.59, 0.52]))
    return PanoVAE(cfg, normalization=norm)


def decode_ms(model, repeats: int) -> float:
    z = torch.randn(1, model.config.latent_dim)
    with torch.no_grad():
        return 1e3 * median_time(lambda: model.decode(z), repeats)


def latent_fit_ms(model, repeats: int, batch: int = 16) -> float:
    h, w = model.config.resolution
    target = torch.randn(batch, 4, h, w)
    z = torch.zeros(batch, model.config.latent_dim, requires_grad=True)
    opt = torch.optim.Adam([z], lr=0.01)

    def step():
        opt.zero_grad()
        loss = (model.decoder(z) - target).square().mean()
        loss.backward()
        opt.step()

    return 1e3 * median_time(step, repeats)


def training_rate(model, repeats: int, batch: int = 32) -> float:
    from roomlight.prior.losses import vae_loss

    h, w = model.config.resolution
    rad = torch.rand(batch, 3, h, w) * 4
    depth = 1.0 + torch.rand(batch, 1, h, w) * 4
    x = model.normalization.normalize(rad, depth)
    opt = torch.optim.AdamW(model.parameters(), lr=1e-4)
    model.train()

    def step():
        opt.zero_grad()
        x_hat, post = model.forward_normalized(x)
        terms = vae_loss(x_hat, x, post.mean, post.logvar, 10**6, model.normalization, target_radiance=rad)
        terms["total"].backward()
        opt.step()

    t = median_time(step, repeats)
    model.eval()
    return batch / t


def scene_fit_s(model, iterations: int) -> float:
    from bench_fit import build_scene, time_method

    with tempfile.TemporaryDirectory() as tmp:
        scene = build_scene(Path(tmp), 128, 128)
        return time_method(scene, "prior", model, 16, iterations)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--candidates", default=",".join(CANDIDATES))
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--no-scene-fit", action="store_true", help="skip the rendering fit (the slowest column)")
    args = ap.parse_args()
    names = [n.strip() for n in args.candidates.split(",") if n.strip()]
    unknown = [n for n in names if n not in CANDIDATES]
    if unknown:
        ap.error(f"unknown candidates {unknown}; choose from {', '.join(CANDIDATES)}")
    if not args.no_scene_fit:
        from roomlight.core.render.variant import ensure_variant

        ensure_variant()
    print(f"torch threads {torch.get_num_threads()}, medians of {args.repeats}")
    print("| candidate | resolution | latent | params | decode ms (batch 1) | latent fit ms/it (batch 16) "
          "| scene fit s/it | training panoramas/s (batch 32) |")
    print("|---|---|---:|---:|---:|---:|---:|---:|")
    for name in names:
        model = make_model(name).eval()
        for p in model.parameters():
            p.requires_grad_(False)
        dec = decode_ms(model, args.repeats)
        fit = latent_fit_ms(model, args.repeats)
        scene = float("nan") if args.no_scene_fit else scene_fit_s(model, args.repeats)
        for p in model.parameters():
            p.requires_grad_(True)
        rate = training_rate(model, max(2, args.repeats // 2))
        cfg = model.config
        n = sum(p.numel() for p in model.parameters())
        print(f"| {name} | {cfg.resolution[0]}×{cfg.resolution[1]} | {cfg.latent_dim} | {n / 1e6:.2f} M | {dec:.1f} "
              f"| {fit:.0f} | {scene:.3f} | {rate:.1f} |", flush=True)


if __name__ == "__main__":
    main()
