#!/usr/bin/env bash
# Rebuilds three-bundle.min.js (the three.js parts the scene page uses, one IIFE that
# defines window.FATHOM_THREE) from the npm registry's three and esbuild packages.
# Run from this folder; commit the result with three's LICENSE when the version changes.
set -euo pipefail
cd "$(dirname "$0")"
work=$(mktemp -d)
cp entry.js "$work/"
(cd "$work" && npm init -y >/dev/null && npm install --no-audit --no-fund three@0.187.0 esbuild@0.28.2 >/dev/null &&
  npx esbuild entry.js --bundle --minify --format=iife --global-name=FATHOM_THREE \
    --legal-comments=none --outfile=three-bundle.min.js)
cp "$work/three-bundle.min.js" "$work/node_modules/three/LICENSE" .
rm -rf "$work"
