#!/usr/bin/env bash
# Make sure Mitsuba's CPU (LLVM) backend can start: Dr.Jit >= 1.5 needs libLLVM >= 16.
# Idempotent: does nothing when a suitable libLLVM is present or DRJIT_LIBLLVM_PATH is set.
set -euo pipefail
if [ -n "${DRJIT_LIBLLVM_PATH:-}" ] && [ -e "${DRJIT_LIBLLVM_PATH}" ]; then
  exit 0
fi
if ldconfig -p 2>/dev/null | grep -Eq 'libLLVM(-|\.so\.)(1[6-9]|[2-9][0-9])'; then
  exit 0
fi
for d in /usr/lib/llvm-1[6-9]/lib /usr/lib/llvm-2[0-9]/lib; do
  if ls "$d"/libLLVM*.so* >/dev/null 2>&1; then exit 0; fi
done
if ! command -v apt-get >/dev/null 2>&1; then
  echo "roomlight: no libLLVM >= 16 found and no apt-get: install LLVM 16+ and set DRJIT_LIBLLVM_PATH (see README, 'Troubleshooting')." >&2
  exit 0   # not fatal: a CUDA-only machine does not need it
fi
SUDO=""
if [ "$(id -u)" != "0" ]; then
  if command -v sudo >/dev/null 2>&1; then SUDO="sudo -n"; else
    echo "roomlight: libllvm19 is needed for Mitsuba's CPU backend; run 'apt-get install libllvm19' as root." >&2
    exit 0
  fi
fi
echo "roomlight: installing libllvm19 for Mitsuba's CPU backend"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get install -y -q libllvm19 >/dev/null 2>&1 || {
  $SUDO apt-get update -q >/dev/null && $SUDO apt-get install -y -q libllvm19 >/dev/null
}
