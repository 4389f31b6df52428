"""Every method roomlight can recover a light with, and every reference it is scored against.

One :class:`Method` record per name says what the fitters, benchmarks, reports and the command line
need to know about it: which light it produces, how it makes it, which trained model it needs, where
it runs, and how the report describes it. The registry's order is the row order of every table
(baselines, then the priors, then the references); a benchmark that runs a subset keeps that order.

=================  ======================================================================
``naive-paste``    no light: the object rendered alone and pasted (photo benchmark's floor)
``constant-colour`` a uniform light of the input view's mean colour (crop benchmark's floor)
``mirrored-crop``  the input view mirrored and stretched around the sphere (crop benchmark)
``direct-envmap``  free log radiance as an env map, smoothness prior
``direct-sphere``  free log radiance on a sphere proxy enclosing all objects (+20 %)
``direct-al``      free log radiance + log depth, 2.5D area light, smoothness prior
``veni``           z + exposure of VENI, the rotation-equivariant env-map prior (radiance at infinity)
``prior-envmap``   the prior's latent, its radiance shown at infinity (env-map-prior comparison)
``veni-d``         z + exposure of VENI+D, the same with depth, through the 2.5D area light
``prior-samples``  ``prior`` from the paper's start (latent samples), on photos
``prior-zero``     ``prior`` from z = 0, on photos
``prior-view``     ``prior`` from the view encoder's start, on photos
``prior``          z + log-exposure (+ white balance) through the 2.5D area light (the paper's method)
``estimate``       ``roomlight estimate``: the view encoder's room from one image, no depth (crops, photos)
``estimate-refine`` the same, then fitted to the image's own pixels (``--refine``)
``estimate-depth-optional`` the same read by the prior's depth-optional view encoder, no depth at all
``prior-mean``     the prior's mean room, z = 0: nothing from the image (a reference)
``prior-ceiling``  the prior's best latent for the whole true room (its capacity; a reference)
``oracle-envmap``  the true room's panorama shown at infinity (a reference)
``oracle``         the true room's panorama as a 2.5D area light (a reference)
=================  ======================================================================
"""

from __future__ import annotations

from dataclasses import dataclass

from roomlight.errors import RoomlightError

__all__ = ["Method", "METHODS", "ESTIMATE_ROWS", "method", "methods_for", "default_run", "method_names", "method_order", "needs_prior",
           "is_reference", "check_methods", "FIT", "PHOTO", "CROPS"]

#: Where a method runs: ``roomlight fit`` / ``bench run`` (a scene description's view) ...
FIT = "fit"
#: ... ``roomlight fit-photo`` / ``bench run-photos`` (a photograph) ...
PHOTO = "photo"
#: ... and ``bench run-crops`` (the field's protocol: one perspective crop of a panorama, no depth).
CROPS = "crops"


@dataclass(frozen=True)
class Method:
    """What one method is.

    Attributes:
        name: the name on the command line, in result files and in tables.
        light: the light it produces: ``mesh`` (2.5D area light), ``envmap`` (light at infinity),
            ``sphere`` (a sphere proxy around the objects), or None (no light: a compositing baseline).
        source: how it makes that light: ``latent`` (a trained model's latent fitted to the image),
            ``pixels`` (free per-pixel maps fitted to the image, or the image's pixels rearranged),
            ``truth-latent`` (the model's latent fitted to the true room: nothing from the image),
            ``mean`` (the model's mean room: nothing from the image), ``truth`` (the true room itself),
            or ``paste`` (no light at all).
        model: the model family it fits: ``prior`` (the panoramic VAE, ``--model``), ``veni`` or
            ``veni-d`` (loaded by name, ``--set veni_model=`` / ``veni_d_model=``), or None.
        runs: where it runs (:data:`FIT`, :data:`PHOTO`, :data:`CROPS`).
        default: whether a benchmark runs it when no ``--methods`` are given ...
        default_in: ... in these places only (None: wherever it runs).
        init: for photo variants of ``prior``, the fixed start of the latent fit (``fit-photo --init``).
        text: one sentence for a report's reader.
        label: (family, representation) for the cost table.
    """

    name: str
    light: str | None
    source: str
    model: str | None
    runs: frozenset
    default: bool
    text: str
    label: tuple[str, str] = ("", "")
    init: str | None = None
    default_in: frozenset | None = None

    def is_default_in(self, where: str) -> bool:
        """Whether a benchmark of ``where`` runs it when no ``--methods`` are given."""
        return self.default and where in (self.default_in if self.default_in is not None else self.runs)

    @property
    def needs_prior(self) -> bool:
        """Whether it fits the latent of a trained model (rather than free maps or the truth)."""
        return self.model is not None

    @property
    def is_reference(self) -> bool:
        """Whether it takes nothing from the image: a reference or floor, never the best of a table."""
        return self.source not in ("latent", "pixels")

    @property
    def loads_own_model(self) -> bool:
        """Whether it fits a model it loads by name (VENI, VENI+D) unless ``--model`` gives one of its kind."""
        return self.model in ("veni", "veni-d")

    def takes_model_option(self, model_given: bool) -> bool:
        """Whether a command must load its ``--model`` (or the bundled prior) for this method: the prior's
        methods always, the VENI ones only when ``--model`` is given."""
        return self.needs_prior and (not self.loads_own_model or model_given)

    @property
    def fitted_as(self) -> str:
        """The method whose fit it runs (``prior`` for its start variants, else itself)."""
        return "prior" if self.init is not None else self.name


_BOTH = frozenset({FIT, PHOTO})
_FIT = frozenset({FIT})
_PHOTO = frozenset({PHOTO})
_CROPS = frozenset({CROPS})

#: The registry, in table order.
METHODS: tuple[Method, ...] = (
    Method("naive-paste", None, "paste", None, _PHOTO, True,
           "not a light: the object rendered under a uniform light and pasted over the photograph"),
    Method("constant-colour", "envmap", "pixels", None, _CROPS, True,
           "a uniform light of the input view's mean colour"),
    Method("mirrored-crop", "envmap", "pixels", None, _CROPS, True,
           "the input view stretched over the front half of the sphere and mirrored onto the back half"),
    Method("direct-envmap", "envmap", "pixels", None, _BOTH, True,
           "an env map (the light at infinity) optimised pixel by pixel with a smoothness term",
           ("Smoothness", "env map")),
    Method("direct-sphere", "sphere", "pixels", None, _FIT, True,
           "a panorama on a sphere around the objects (a sphere proxy), optimised pixel by pixel",
           ("Smoothness", "sphere proxy")),
    Method("direct-al", "mesh", "pixels", None, _FIT, True,
           "a 2.5D area light (radiance and depth) optimised pixel by pixel with a smoothness term",
           ("Smoothness", "2.5D AL")),
    Method("veni", "envmap", "latent", "veni", _BOTH, False,
           "VENI, a rotation-equivariant env-map prior, its latent (and an exposure) optimised; light at infinity",
           ("VENI", "env map")),
    Method("prior-envmap", "envmap", "latent", "prior", _BOTH, True,
           "the learned prior's decoding shown as an env map (its depth ignored)",
           ("roomlight prior", "env map")),
    Method("veni-d", "mesh", "latent", "veni-d", _BOTH, False,
           "VENI+D, VENI with a depth output, its latent optimised; its decoding is a 2.5D area light",
           ("VENI+D", "2.5D AL")),
    Method("prior-samples", "mesh", "latent", "prior", _PHOTO, False,
           "the prior's fit from the paper's start (the best of a few latent samples)", init="samples"),
    Method("prior-zero", "mesh", "latent", "prior", _PHOTO, False,
           "the prior's fit from the latent z = 0", init="zero"),
    Method("prior-view", "mesh", "latent", "prior", _PHOTO, False,
           "the prior's fit from its view encoder's guess", init="view"),
    Method("prior", "mesh", "latent", "prior", _BOTH, True,
           "the learned prior's latent (and an exposure) optimised; its decoding is a 2.5D area light",
           ("roomlight prior", "2.5D AL")),
    Method("estimate", "mesh", "latent", "prior", _CROPS | _PHOTO, True,
           "roomlight estimate: the prior's view encoder reads the image alone (no depth) and decodes its room",
           default_in=_CROPS),
    Method("estimate-refine", "mesh", "latent", "prior", _CROPS | _PHOTO, True,
           "roomlight estimate --refine: the same, then the room fitted to the image's own pixels",
           default_in=_CROPS),
    Method("estimate-depth-optional", "mesh", "latent", "prior", _CROPS | _PHOTO, False,
           "roomlight estimate --depth-optional-encoder: the prior's depth-optional view encoder reads the image "
           "with no depth at all"),
    Method("prior-mean", "mesh", "mean", "prior", _CROPS, True,
           "not a fit: the prior's mean room (z = 0), the same for every image"),
    Method("prior-ceiling", "mesh", "truth-latent", "prior", _PHOTO, True,
           "not a fit to the photograph: the prior's best latent for the whole true room (its capacity)"),
    Method("oracle-envmap", "envmap", "truth", None, _PHOTO, True,
           "not a fit: the true room's panorama shown at infinity"),
    Method("oracle", "mesh", "truth", None, _BOTH, True,
           "not a fit: the ground-truth emitter re-rendered, the noise floor of the metrics"),
)

_BY_NAME = {m.name: m for m in METHODS}

#: The rows that are ``roomlight estimate`` rather than a fit (photo and crop benchmarks): name ->
#: (whether it refines, ``--refine``; how it reads a photograph without depth: ``guess`` or ``withheld``,
#: ``--depth-optional-encoder``).
ESTIMATE_ROWS = {"estimate": (False, "guess"), "estimate-refine": (True, "guess"),
                 "estimate-depth-optional": (False, "withheld")}


def method(name: str) -> Method:
    """The method called ``name``; a one-line error naming the known ones otherwise."""
    try:
        return _BY_NAME[name]
    except KeyError:
        raise RoomlightError(f"unknown method {name!r}; choose one of {', '.join(_BY_NAME)}") from None


def methods_for(where: str, *, fitted: bool | None = None, default: bool | None = None) -> tuple[str, ...]:
    """Names of the methods that run in ``where`` (:data:`FIT`, :data:`PHOTO` or :data:`CROPS`), in table order.

    ``fitted``: True keeps only methods fitted to the image, False only the references;
    ``default``: True keeps only those a benchmark runs without ``--methods``.
    """
    return tuple(m.name for m in METHODS if where in m.runs
                 and (fitted is None or fitted != m.is_reference)
                 and (default is None or default == m.is_default_in(where)))


def default_run(where: str) -> tuple[str, ...]:
    """The methods a benchmark runs without ``--methods``, in the order it runs them: the paper's method
    first and the simplest baseline last (the reverse of the table), so that a run stopped early has the
    rows that matter most. The VENI rows load models of their own and are asked for by name."""
    return tuple(reversed(methods_for(where, fitted=True, default=True)))


def method_names() -> tuple[str, ...]:
    """Every name, in table order."""
    return tuple(_BY_NAME)


def method_order() -> tuple[str, ...]:
    """The row order of every table (unknown names follow, sorted: see ``ordered``)."""
    return method_names()


def needs_prior(name: str) -> bool:
    """Whether ``name`` fits a trained model's latent; False for names not in the registry."""
    m = _BY_NAME.get(name)
    return m is not None and m.needs_prior


def is_reference(name: str) -> bool:
    """Whether ``name`` is a reference (takes nothing from the image); False for unknown names."""
    m = _BY_NAME.get(name)
    return m is not None and m.is_reference


def check_methods(names, allowed, option: str = "--methods") -> tuple[str, ...]:
    """``names`` as a tuple, refused with one line naming the ``allowed`` ones if any is not among them."""
    names = tuple(names)
    bad = [n for n in names if n not in allowed]
    if bad:
        raise RoomlightError(f"{option}: unknown method(s) {', '.join(bad)}; choose from {', '.join(allowed)}")
    return names
