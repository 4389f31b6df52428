#!/usr/bin/env bash
# What the viewer and its browser tests need outside Python, installed only when missing:
#   - three.js, pinned, from npm into build/web (inlined into each viewer page when it is written);
#   - a headless Chromium (Debian package "chromium") for the browser tests.
# Idempotent, and never fatal: without them `roomlight view` says how to install three.js and the
# browser tests are skipped with the reason.
set -uo pipefail
THREE_VERSION="${THREE_VERSION:-0.187.0}"
here="$(cd "$(dirname "$0")/.." && pwd)"
dest="$here/build/web"
have="$(sed -n 's/.*"version": *"\([^"]*\)".*/\1/p' "$dest/node_modules/three/package.json" 2>/dev/null | head -1)"
if [ "$have" != "$THREE_VERSION" ]; then
  if command -v npm >/dev/null 2>&1; then
    echo "roomlight: installing three@$THREE_VERSION into build/web (npm)"
    mkdir -p "$dest"
    npm install --prefix "$dest" --no-save --no-audit --no-fund --loglevel=error "three@$THREE_VERSION" >/dev/null \
      || echo "roomlight: npm could not install three@$THREE_VERSION; 'roomlight view' will not work" >&2
  else
    echo "roomlight: npm not found; install Node.js to let 'roomlight view' inline three.js" >&2
  fi
fi
if ! command -v chromium >/dev/null 2>&1 && ! command -v chromium-browser >/dev/null 2>&1; then
  . "$here/scripts/apt_install.sh"
  apt_install chromium "the browser tests; without it they are skipped" || true
fi
exit 0
