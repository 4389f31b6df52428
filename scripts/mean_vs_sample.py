"""How well a prior decodes its encoder's posterior mean, against posterior samples.

Run: .venv/bin/python scripts/mean_vs_sample.py MODEL [--data data/rooms64b] [--split train] [--limit 32]
         [--samples 2] [--seed 0]

Prints the mean absolute error of the reconstruction in the model's normalised space (radiance
channels, and depth when the model decodes it) for (a) the posterior mean, (b) posterior samples,
and, for VENI / VENI+D, (c) the mean with the field's per-image inputs taken from a sample, which
isolates those inputs. A VAE whose decoder is smooth over the posterior decodes its mean at least as
well as a sample; a much larger error for the mean means the decoder relies on the sampling noise
(docs/model.md, VENI). MODEL is anything ``--model`` accepts.
"""

from __future__ import annotations

import argparse
import sys

import torch

from roomlight.errors import RoomlightError


def _errors(model, x: torch.Tensor, x_hat: torch.Tensor) -> tuple[float, float | None]:
    """(radiance L1, depth L1 or None) between x and x_hat (B, C, H, W), normalised space."""
    rad = float((x_hat[:, :3] - x[:, :3]).abs().mean())
    dep = float((x_hat[:, 3:4] - x[:, 3:4]).abs().mean()) if getattr(model, "has_depth", True) else None
    return rad, dep


def _veni_decode(model, z_waves: torch.Tensor, z_image: torch.Tensor) -> torch.Tensor:
    """VENI's decoding (B, C, H, W) with its plane waves from ``z_waves`` and its per-image inputs from ``z_image``."""
    out = model.field(z_waves, model.directions, image=model.field.image_invariants(z_image))   # (B, H W, C)
    height, width = model.config.resolution
    return out.transpose(1, 2).reshape(z_waves.shape[0], -1, height, width)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("model")
    p.add_argument("--data", default="data/rooms64b")
    p.add_argument("--split", default="train", choices=["train", "val", "test"])
    p.add_argument("--limit", type=int, default=32)
    p.add_argument("--samples", type=int, default=2)
    p.add_argument("--seed", type=int, default=0)
    args = p.parse_args(argv)

    from roomlight.prior.model.families import is_veni
    from roomlight.prior.model.runs import load_run_model
    from roomlight.prior.viewenc.trainer import load_panoramas

    try:
        model = load_run_model(args.model, device="cpu").eval()
        rad, dep, _ = load_panoramas(args.data, args.split, tuple(model.config.resolution), limit=args.limit,
                                     note=lambda *a: None)
    except RoomlightError as e:
        sys.exit(f"error: {e}")
    x = model.normalization.normalize(rad, dep)
    gen = torch.Generator().manual_seed(args.seed)
    rows = []
    with torch.no_grad():
        post = model.encode_normalized(x)
        mean = post.mode()
        rows.append(("posterior mean", _errors(model, x, model.decode_normalized(mean))))
        samples = [post.sample(gen) for _ in range(args.samples)]
        for i, z in enumerate(samples):
            rows.append((f"posterior sample {i + 1}", _errors(model, x, model.decode_normalized(z))))
        if is_veni(model):
            rows.append(("mean, per-image inputs of sample 1", _errors(model, x, _veni_decode(model, mean, samples[0]))))
        std = float(post.std.median())
    print(f"{args.model}: {x.shape[0]} panoramas of {args.data} ({args.split}); median posterior std {std:.3f}\n")
    print("| decoded latent | L1 radiance | L1 depth |\n|---|---:|---:|")
    for name, (r, d) in rows:
        print(f"| {name} | {r:.3f} | {'—' if d is None else f'{d:.3f}'} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
