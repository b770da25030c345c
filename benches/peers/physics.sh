#!/usr/bin/env bash
# Physical motion against closed forms, haptloop beside MuJoCo (issue 19;
# see physics.py). Uses the virtual environment run.sh creates in
# benches/peers/.venv (made here the same way if it is missing), builds
# haptloop in release and prints one markdown table. Not part of .ci/run.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
venv="$here/.venv"
if [ ! -x "$venv/bin/python" ]; then
  python3 -m venv "$venv"
fi
"$venv/bin/pip" install --quiet --disable-pip-version-check -r "$here/requirements.txt"
(cd "$here/../.." && cargo build --release --quiet)
exec "$venv/bin/python" "$here/physics.py" "$@"
