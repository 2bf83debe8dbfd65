#!/usr/bin/env bash
# Checks the system tools `make setup` needs; names the Debian package of each missing one.
# Usage: tools/check_system.sh <python-interpreter>
set -u
python=${1:-python3.11}
missing=()

need() {  # need <command> <debian package>
  command -v "$1" >/dev/null 2>&1 || missing+=("$1 (Debian package: $2)")
}

need cmake cmake
need make make
need cc gcc
need c++ g++
if ! command -v "$python" >/dev/null 2>&1; then
  missing+=("$python (Debian package: python3.11)")
else
  if ! "$python" -c 'import sys; sys.exit(sys.version_info[:2] != (3, 11))' 2>/dev/null; then
    missing+=("Python 3.11 as $python (it does not run as Python 3.11; Debian package: python3.11)")
  else
  "$python" -c 'import venv, ensurepip' >/dev/null 2>&1 \
    || missing+=("venv/ensurepip for $python (Debian package: python3.11-venv)")
  include=$("$python" -c 'import sysconfig; print(sysconfig.get_paths()["include"])' 2>/dev/null)
  [ -f "$include/Python.h" ] || missing+=("Python.h for $python (Debian package: python3.11-dev)")
  fi
fi

if [ ${#missing[@]} -gt 0 ]; then
  echo "make setup: missing system tools:" >&2
  for m in "${missing[@]}"; do echo "  - $m" >&2; done
  echo "Install them (for example: sudo apt-get install cmake make gcc g++ python3.11 python3.11-venv python3.11-dev) and run make setup again." >&2
  exit 1
fi
