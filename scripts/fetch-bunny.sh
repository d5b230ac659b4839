#!/usr/bin/env bash
# Fetch the Stanford bunny from the npm package `bunny` (1.0.1, M. Lysenko) into target/bunny/:
# `index.js` holds `exports.positions=[[x,y,z],…]` and `exports.cells=[[a,b,c],…]`, which
# `cargo xtask bench voxelize --mesh target/bunny/index.js` reads. Not committed: it is the
# scan's data, fetched when wanted. Needs npm and network access.
set -euo pipefail
cd "$(dirname "$0")/.."
mkdir -p target/bunny
cd target/bunny
npm pack --silent bunny@1.0.1 >/dev/null
tar xzf bunny-1.0.1.tgz --strip-components=1 package/index.js
echo "target/bunny/index.js"
