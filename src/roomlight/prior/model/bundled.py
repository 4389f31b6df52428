"""Models shipped inside the package, by name: what ``--model NAME`` means when NAME is not a path.

=========  ======================================================================================
``prior``  the bundled prior (``assets/prior``): what every prior method uses without ``--model``
``lite``   the earlier, smaller prior (latent 128; ``assets/prior-lite``, with its view encoder)
``veni``   VENI, the rotation-equivariant env-map prior, trained like the bundled prior
``veni-d`` VENI+D, the same with a depth output, fitted as a 2.5D area light
=========  ======================================================================================

A name whose weights this installation does not hold is an error that says so.
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["ASSETS", "BUNDLED_MODELS", "bundled_model_path"]

#: The package's assets folder.
ASSETS = Path(__file__).resolve().parents[2] / "assets"

#: Name -> folder under :data:`ASSETS`.
BUNDLED_MODELS = {"prior": "prior", "lite": "prior-lite", "veni": "veni", "veni-d": "veni-d"}


def bundled_model_path(name: str) -> Path | None:
    """The folder of the bundled model ``name`` when it is installed (holds weights), else None."""
    folder = BUNDLED_MODELS.get(name)
    if folder is None:
        return None
    path = ASSETS / folder
    return path if (path / "model.safetensors").is_file() else None
