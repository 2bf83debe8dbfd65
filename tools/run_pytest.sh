#!/usr/bin/env bash
# Runs pytest; exit code 5 (no tests collected) fails loudly instead of passing silently.
set -u
python=$1; shift
"$python" -m pytest "$@"
rc=$?
if [ $rc -eq 5 ]; then
  echo "pytest collected no tests: treating as failure" >&2
  exit 1
fi
exit $rc
