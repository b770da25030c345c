#!/usr/bin/env bash
# haptloop against MuJoCo on the project's mechanisms (see README.md here).
# Creates a virtual environment in benches/peers/.venv, installs MuJoCo into
# it, builds haptloop in release (whose `export mjcf` writes the MuJoCo
# models) and runs compare.py; arguments go to compare.py
# (`bash benches/peers/run.sh --help`). Not part of .ci/run.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
venv="$here/.venv"
if [ ! -x "$venv/bin/python" ]; then
  python3 -m venv "$venv"
fi
"$venv/bin/pip" install --quiet --disable-pip-version-check -r "$here/requirements.txt"
(cd "$here/../.." && cargo build --release --quiet)
exec "$venv/bin/python" "$here/compare.py" "$@"
