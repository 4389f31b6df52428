"""LPIPS (Zhang et al. 2018), only when the package and its weights are already on this machine.

LPIPS needs the ``lpips`` package and the ImageNet weights of its AlexNet backbone, which
torchvision downloads on first use. roomlight never downloads weights implicitly: the metric is
computed only if ``lpips`` imports and the backbone file is already in torch's hub cache;
otherwise :func:`load_lpips` returns None and a reason that the reports print.
"""

from __future__ import annotations

from pathlib import Path

import torch

__all__ = ["ALEXNET_WEIGHTS", "load_lpips"]

#: File name torchvision uses for the AlexNet ImageNet weights in ``$TORCH_HOME/hub/checkpoints``.
ALEXNET_WEIGHTS = "alexnet-owt-7be5be79.pth"


def load_lpips(device: str | torch.device = "cpu"):
    """``(fn, None)`` with ``fn(pred, target) -> (B,)`` on [0, 1] LDR images, or ``(None, reason)``."""
    try:
        import lpips  # noqa: F401
    except ImportError:
        return None, "LPIPS not computed: the `lpips` package is not installed (pip install lpips)"
    weights = Path(torch.hub.get_dir()) / "checkpoints" / ALEXNET_WEIGHTS
    if not weights.exists():
        return None, (f"LPIPS not computed: its AlexNet weights are not available locally ({weights} is missing; "
                      "they are not downloaded automatically)")
    import lpips

    net = lpips.LPIPS(net="alex", verbose=False).to(device).eval()

    @torch.no_grad()
    def fn(pred: torch.Tensor, target: torch.Tensor) -> torch.Tensor:
        # LPIPS expects RGB in [-1, 1].
        return net(pred.float() * 2 - 1, target.float() * 2 - 1).flatten().double().cpu()

    return fn, None
