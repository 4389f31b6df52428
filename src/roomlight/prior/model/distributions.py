"""The VAE posterior q(z | x) = N(mean, diag exp(logvar)) (paper §3.2)."""

from __future__ import annotations

import torch

__all__ = ["DiagonalGaussian"]


class DiagonalGaussian:
    """Diagonal Gaussian over the latent, parameterised by mean and log-variance.

    Attributes:
        mean: (B, D) posterior mean.
        logvar: (B, D) log-variance, already clamped by the encoder.
    """

    def __init__(self, mean: torch.Tensor, logvar: torch.Tensor):
        if mean.shape != logvar.shape:
            raise ValueError(f"mean {tuple(mean.shape)} and logvar {tuple(logvar.shape)} differ")
        self.mean = mean
        self.logvar = logvar

    @property
    def std(self) -> torch.Tensor:
        """(B, D) standard deviation exp(logvar / 2)."""
        return torch.exp(0.5 * self.logvar)

    @property
    def var(self) -> torch.Tensor:
        """(B, D) variance exp(logvar)."""
        return torch.exp(self.logvar)

    def sample(self, generator: torch.Generator | None = None) -> torch.Tensor:
        """Reparameterised sample mean + std * eps, eps ~ N(0, I): (B, D), differentiable.

        ``generator`` makes the noise reproducible; it must live on the tensors' device.
        """
        eps = torch.randn(
            self.mean.shape, generator=generator, dtype=self.mean.dtype, device=self.mean.device
        )
        return self.mean + self.std * eps

    def mode(self) -> torch.Tensor:
        """(B, D) the most likely latent, i.e. the mean."""
        return self.mean

    def kl(self) -> torch.Tensor:
        """(B,) closed-form KL(q || N(0, I)) summed over the latent dimensions (nats)."""
        return 0.5 * torch.sum(self.mean**2 + self.var - 1.0 - self.logvar, dim=1)

    def __repr__(self) -> str:
        return f"DiagonalGaussian(shape={tuple(self.mean.shape)})"
