#!/usr/bin/env bash
# Rebuilds three.bundle.js, the three.js the viewer inlines into view.html,
# from three's npm package at the pinned version, with esbuild (pinned too):
# one classic script (an IIFE defining the global `THREE`, OrbitControls and ConvexGeometry
# included), so the page needs no module loading, no server and no network.
# Run it only to move to another three.js version (change THREE below), then
# commit three.bundle.js and LICENSE together. Needs node and npm.
set -euo pipefail
THREE=0.187.0
ESBUILD=0.28.2
here="$(cd "$(dirname "$0")" && pwd)"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cd "$work"
npm init -y >/dev/null
npm install --no-audit --no-fund --save-exact "three@$THREE" "esbuild@$ESBUILD" >/dev/null
cp "$here/entry.js" .
npx esbuild entry.js --bundle --format=iife --global-name=THREE --minify \
  --legal-comments=none --target=es2020 --outfile=three.bundle.js
{
  echo "/* three.js $THREE (https://threejs.org), MIT licence: see LICENSE beside this file."
  echo "   Built by build.sh from the npm package three@$THREE with esbuild@$ESBUILD. */"
  cat three.bundle.js
} >"$here/three.bundle.js"
cp node_modules/three/LICENSE "$here/LICENSE"
echo "wrote $here/three.bundle.js ($(wc -c <"$here/three.bundle.js") bytes) and LICENSE"
