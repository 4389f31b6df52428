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
. "$(dirname "$0")/apt_install.sh"
# Not fatal when it fails: a CUDA-only machine does not need it, and the README says what to do.
apt_install libllvm19 "Mitsuba's CPU backend; or install LLVM 16+ and set DRJIT_LIBLLVM_PATH, see docs/troubleshooting.md" || true
