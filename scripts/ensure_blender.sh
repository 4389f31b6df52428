#!/usr/bin/env bash
# Blender as a Python module (PyPI "bpy", CPython 3.11 only) in its own environment, .venv-blender,
# for the test that renders an exported light with Cycles against Mitsuba. bpy pins numpy 1.x, so it
# does not go into .venv. Idempotent, and never fatal: without it that test is skipped with the reason.
set -uo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
venv="$here/.venv-blender"
BPY_SPEC="${BPY_SPEC:-bpy==5.0.1}"
if [ -x "$venv/bin/python" ] && "$venv/bin/python" -c "import bpy" >/dev/null 2>&1; then
  exit 0
fi
py="$(command -v python3.11 || true)"
if [ -z "$py" ]; then
  echo "roomlight: no python3.11, so no Blender module (bpy); the Blender export test will be skipped" >&2
  exit 0
fi
echo "roomlight: installing $BPY_SPEC into .venv-blender (about 370 MB)"
"$py" -m venv "$venv" && "$venv/bin/python" -m pip install -q "$BPY_SPEC" >/dev/null 2>&1 \
  || echo "roomlight: could not install $BPY_SPEC; the Blender export test will be skipped" >&2
exit 0
