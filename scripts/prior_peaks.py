"""Does a prior keep the light sources? Brightest pixel / median luminance of held-out panoramas,
their encoder-pass reconstructions, and samples.

Run: .venv/bin/python scripts/prior_peaks.py MODEL_OR_RUN DATA_DIR [N_SAMPLES]
(DATA_DIR/test/*.exr are the held-out panoramas, as written by `roomlight synth`.)
"""

import sys
from pathlib import Path

import numpy as np
import torch

from roomlight.prior.data.dataset import load_training_pair
from roomlight.prior.eval.metrics import peak_contrast
from roomlight.prior.model.runs import load_run_model


def main() -> None:
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    torch.set_num_threads(2)
    model = load_run_model(sys.argv[1])
    files = sorted(Path(sys.argv[2], "test").glob("*.exr"))
    if not files:
        sys.exit(f"no panoramas in {Path(sys.argv[2], 'test')}")
    inputs, recons = [], []
    with torch.no_grad():
        for f in files:
            rad, dep, _ = load_training_pair(f, model.config.resolution)
            pred, _ = model.decode(model.encode(rad[None], dep[None]).mode())
            inputs.append(float(peak_contrast(rad[None])[0]))
            recons.append(float(peak_contrast(pred)[0]))
        n = int(sys.argv[3]) if len(sys.argv) > 3 else 64
        z = torch.randn(n, model.config.latent_dim, generator=torch.Generator().manual_seed(0))
        samples = peak_contrast(model.decode(z)[0]).numpy()
    inputs, recons = np.array(inputs), np.array(recons)
    print(f"{len(files)} held-out panoramas: input median {np.median(inputs):.1f}x; reconstruction median "
          f"{np.median(recons):.1f}x (p10 {np.percentile(recons, 10):.1f}, p90 {np.percentile(recons, 90):.1f}); "
          f"peak above 10x: reconstructions {np.mean(recons > 10):.0%}, inputs {np.mean(inputs > 10):.0%}")
    print(f"{n} samples (seed 0): median {np.median(samples):.1f}x (p10 {np.percentile(samples, 10):.1f}, "
          f"p90 {np.percentile(samples, 90):.1f}); peak above 10x: {np.mean(samples > 10):.0%}")


if __name__ == "__main__":
    main()
