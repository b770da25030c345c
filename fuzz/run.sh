#!/usr/bin/env bash
# Fuzz scene loading + validation + compilation with libFuzzer (cargo-fuzz,
# nightly toolchain). Usage: fuzz/run.sh [SECONDS] [extra libFuzzer flags]
# New corpus entries go to fuzz/corpus/scene (git-ignored); the seeds are the
# built-in scenes and the malformed-scene corpus, read-only. A crash leaves
# its input in fuzz/artifacts/scene/: copy it into tests/data/fuzz-regressions/
# (the test `every_fuzz_regression_loads_or_fails_cleanly` replays them).
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-60}"
shift || true
if ! cargo fuzz --version >/dev/null 2>&1; then
  cargo install cargo-fuzz --locked
fi
mkdir -p fuzz/corpus/scene
cargo +nightly fuzz run scene fuzz/corpus/scene scenes tests/data/bad-scenes \
  -- -max_total_time="$seconds" -max_len=16384 -rss_limit_mb=2048 "$@"
