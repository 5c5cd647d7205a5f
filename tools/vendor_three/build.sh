#!/usr/bin/env bash
# Rebuild the vendored three.js viewer bundle from the npm registry (versions pinned in package.json).
set -euo pipefail
cd "$(dirname "$0")"
npm install --no-audit --no-fund
data=../../brainpainter/data
npx esbuild entry.js --bundle --minify --format=iife --legal-comments=none --target=es2020 \
    --outfile="$data/three-viewer.min.js"
version=$(node -p 'JSON.parse(require("fs").readFileSync("node_modules/three/package.json")).version')
{ echo "three.js $version (https://threejs.org), bundled by tools/vendor_three/build.sh into"
  echo "three-viewer.min.js together with its GLTFLoader and OrbitControls (examples/jsm)."
  echo; cat node_modules/three/LICENSE; } > "$data/three-viewer.LICENSE.txt"
