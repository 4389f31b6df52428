"""Finding the pinned three.js that ``make setup`` installs, and inlining it into one HTML page.

The viewer page must work offline from a single file, so three.js and the viewer's own module
travel inside it as text; a small loader turns each into a ``blob:`` URL, rewrites the import
specifiers to those URLs, and imports the viewer. three.js is not kept in this repository:
``make setup`` runs ``npm install`` into ``build/web`` (version ``THREE_VERSION``), and
``ROOMLIGHT_THREE_DIR`` can point at another copy of the npm package.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

__all__ = ["THREE_VERSION", "three_dir", "module_scripts"]

THREE_VERSION = "0.187.0"  #: keep in step with scripts/ensure_web.sh, which installs it
_REPO = Path(__file__).resolve().parents[3]

# (name, path inside the npm package, {import specifier: name of the module it refers to})
_MODULES = [
    ("three-core", "build/three.core.js", {}),
    ("three", "build/three.module.js", {"./three.core.js": "three-core"}),
    ("orbit", "examples/jsm/controls/OrbitControls.js", {"three": "three"}),
]

_LOADER = """<script>
(function () {
  var order = %s, urls = {};
  order.forEach(function (m) {
    var text = document.getElementById('module-' + m.name).textContent;
    Object.keys(m.imports).forEach(function (spec) {
      text = text.split("from '" + spec + "'").join("from '" + urls[m.imports[spec]] + "'");
    });
    urls[m.name] = URL.createObjectURL(new Blob([text], {type: 'text/javascript'}));
  });
  import(urls[order[order.length - 1].name]).catch(function (e) {
    document.body.insertAdjacentHTML('beforeend', '<pre style="color:#f66;position:absolute;bottom:0">' + e + '</pre>');
  });
})();
</script>"""


def three_dir() -> Path:
    """The three.js npm package folder; raises FileNotFoundError saying how to install it."""
    candidates = [Path(os.environ["ROOMLIGHT_THREE_DIR"])] if os.environ.get("ROOMLIGHT_THREE_DIR") else []
    candidates += [_REPO / "build" / "web" / "node_modules" / "three", Path.cwd() / "node_modules" / "three"]
    for c in candidates:
        if (c / "build" / "three.core.js").is_file():
            return c
    raise FileNotFoundError(
        f"three.js {THREE_VERSION} was not found (looked in {', '.join(str(c) for c in candidates)}); "
        f"run 'make setup', or 'npm install --prefix build/web three@{THREE_VERSION}', "
        "or set ROOMLIGHT_THREE_DIR to an installed 'three' npm package")


def _script(name: str, text: str) -> str:
    # the text sits in a non-executed script element; only "</script" could end it early
    safe = text.replace("</script", "<\\/script")
    return f'<script type="text/plain" id="module-{name}">{safe}</script>'


def module_scripts(app_js: str) -> str:
    """HTML holding three.js, OrbitControls and ``app_js`` (which imports ``three`` and the controls)."""
    root = three_dir()
    parts, order = [], []
    for name, rel, imports in _MODULES:
        parts.append(_script(name, (root / rel).read_text(encoding="utf-8")))
        order.append({"name": name, "imports": imports})
    parts.append(_script("app", app_js))
    order.append({"name": "app", "imports": {"three": "three", "three/addons/controls/OrbitControls.js": "orbit"}})
    return "\n".join(parts) + "\n" + _LOADER % json.dumps(order)
