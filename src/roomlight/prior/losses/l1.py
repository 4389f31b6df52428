"""Pixel-wise L1 loss (paper eq. 3, terms L1^L and L1^D)."""

from __future__ import annotations

import torch

from roomlight.errors import ShapeError

__all__ = ["l1_loss"]


def check_same_shape(pred: torch.Tensor, target: torch.Tensor, what: str) -> None:
    """Raise :class:`ShapeError` unless ``pred`` and ``target`` have the same shape."""
    if pred.shape != target.shape:
        raise ShapeError(
            f"{what}: prediction {tuple(pred.shape)} and target {tuple(target.shape)} must have "
            "the same shape"
        )


def l1_loss(pred: torch.Tensor, target: torch.Tensor) -> torch.Tensor:
    """Mean absolute error over every element (batch, channels and pixels).

    Args:
        pred, target: tensors of the same shape, e.g. (B, 3, H, W) z-scored radiance or
            (B, 1, H, W) z-scored log depth.
    Returns:
        scalar tensor.
    """
    check_same_shape(pred, target, "l1_loss")
    return (pred - target).abs().mean()
