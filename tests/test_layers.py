"""The package's import graph: a strict layer order between subpackages, and no cycle between modules.

Every import counts, at module level or inside a function, because a function-level import is
still a dependency (it only defers the cost). The layers are documented in docs/architecture.md;
a subpackage may import from any layer below its own, never from its own layer's siblings or
from above.
"""

from __future__ import annotations

import ast
from pathlib import Path

import roomlight

PACKAGE = Path(roomlight.__file__).parent

#: The groups that hold the pipeline's stages; their subpackages and modules are the layer units, and the
#: group packages themselves only describe what they hold (they import nothing).
GROUPS = ("core", "prior", "fitting", "datagen", "evaluation")

#: Top to bottom. Names are top-level modules or subpackages of ``roomlight``, or a group's subpackages
#: and modules (``core.io``).
LAYERS = [
    ["cli"],
    ["demo", "evaluation.experiments"],
    ["prior.viewenc"],
    ["prior.train", "parallax"],
    ["viewer"],
    ["evaluation.photobench"],
    ["export"],
    ["fitting.insert"],
    ["prior.eval", "evaluation.bench", "evaluation.crops", "datagen.synth", "datagen.prepare"],
    ["evaluation.harness"],
    ["fitting.photo"],
    ["fitting.inverse", "prior.data"],
    ["fitting.scene", "prior.latent_fit", "prior.model", "core.examples"],
    ["prior.losses"],
    ["core.render"],
    ["core.emitter"],
    ["core.io"],
    ["core.light"],
    ["core.geometry"],
    ["core.color", "core.config", "core.progress", "core.cluster", "core.stats", "core.cpu", "fitting.methods"],
    ["errors"],
]


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _modules() -> dict[str, Path]:
    return {_module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def _imports(name: str, path: Path, modules: dict[str, Path]) -> set[str]:
    """roomlight modules imported anywhere in one file (a ``from pkg import mod`` names ``pkg.mod``)."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            targets = [f"{target}.{a.name}" if f"{target}.{a.name}" in modules else target for a in node.names]
        else:
            continue
        out.update(t for t in targets if t.startswith("roomlight.") and t != name)
    return out


def _graph() -> dict[str, set[str]]:
    modules = _modules()
    return {name: _imports(name, path, modules) for name, path in modules.items()}


def _unit(module: str) -> str:
    """The layer unit of a module: its subpackage or top-level module; inside a group, the group's
    subpackage or module (``roomlight.core.io.exr`` -> ``core.io``)."""
    parts = module.split(".")
    return ".".join(parts[1:3]) if parts[1] in GROUPS and len(parts) > 2 else parts[1]


def test_the_groups_only_describe_what_they_hold():
    for group in GROUPS:
        tree = ast.parse((PACKAGE / group / "__init__.py").read_text())
        assert ast.get_docstring(tree), f"roomlight.{group} has no docstring"
        assert all(isinstance(n, ast.Expr) for n in tree.body), f"roomlight.{group}/__init__.py does more than describe"


def test_every_subpackage_and_top_level_module_has_a_layer():
    units = {_unit(m) for m in _modules() if m != "roomlight" and m.split(".")[1:] not in ([g] for g in GROUPS)}
    placed = {u for layer in LAYERS for u in layer}
    assert units - {"assets"} == placed, (
        f"not in LAYERS: {sorted(units - placed)}; in LAYERS but gone: {sorted(placed - units)}")


def test_no_import_goes_up_or_sideways_a_layer():
    rank = {u: i for i, layer in enumerate(LAYERS) for u in layer}
    bad = []
    for module, targets in _graph().items():
        if module == "roomlight" or module.split(".")[1:] in ([g] for g in GROUPS):
            continue
        for target in targets:
            a, b = _unit(module), _unit(target)
            if a != b and rank[b] <= rank[a]:
                bad.append(f"{module} -> {target} ({a} is not above {b})")
    assert not bad, "imports against the layer order:\n" + "\n".join(sorted(bad))


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan)."""
    index, low, stack, on, out = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_no_import_cycle_between_modules():
    # Imports through a package (``from roomlight.core.io import save_png``) count as edges to the
    # package's __init__, which imports its modules: a module that imports its own package
    # therefore shows up as a cycle, as it should (it only works by import order).
    assert _cycles(_graph()) == []


def test_the_cycle_finder_finds_cycles():
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert _cycles({"a": {"b"}, "b": set()}) == []
