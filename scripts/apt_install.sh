#!/usr/bin/env bash
# Shared by the setup scripts (sourced, not run): apt_install PACKAGE PURPOSE
# Installs a Debian package as root, or through password-less sudo, refreshing the package lists
# only when the first attempt fails (they are often stale on a fresh machine). Returns 0 when the
# package was installed, 1 otherwise, after saying why on stderr; never exits the caller.
apt_install() {
  local pkg="$1" purpose="$2" sudo=""
  if ! command -v apt-get >/dev/null 2>&1; then
    echo "roomlight: no apt-get; install $pkg yourself ($purpose)" >&2
    return 1
  fi
  if [ "$(id -u)" != "0" ]; then
    if command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then sudo="sudo -n"; else
      echo "roomlight: $pkg is needed ($purpose); run 'apt-get install $pkg' as root" >&2
      return 1
    fi
  fi
  echo "roomlight: installing $pkg ($purpose)"
  export DEBIAN_FRONTEND=noninteractive
  if $sudo apt-get install -y -q "$pkg" >/dev/null 2>&1; then return 0; fi
  if $sudo apt-get update -q >/dev/null 2>&1 && $sudo apt-get install -y -q "$pkg" >/dev/null 2>&1; then return 0; fi
  echo "roomlight: could not install $pkg ($purpose)" >&2
  return 1
}
