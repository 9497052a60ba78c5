#!/usr/bin/env bash
# Fetches the Stanford bunny and writes it as an OBJ that `ngi render --scene <path>` and load_mesh take:
#   $NGI_ASSET_DIR/bunny.obj       (default: ${XDG_CACHE_HOME:-~/.cache}/ngi/assets/bunny.obj: a user directory, so a
#                                  read-only checkout or an installed ngi works too)
# Source: the npm package "bunny" (public domain; a Stanford scan's `positions` and `cells`: 1,839 vertices,
# 3,674 triangles), installed with npm into $NGI_ASSET_DIR/npm and converted with node. The OBJ is scaled so the
# bunny stands 40 m tall on y = 0 (x and z centred on 0): the size of the procedural mesh families and of the
# voxel "sculpture", so ambient-occlusion distances mean the same on it. Triangles are wound counter-clockwise
# seen from outside (flipped if the package's are not).
# Idempotent: an existing bunny.obj is kept (delete it to refetch). Non-fatal: without node/npm or without the
# registry (offline), it says so on stderr and exits 0 with nothing written; nothing in the build or the tests
# needs the bunny. Prints the OBJ's path on stdout when it exists.
set -uo pipefail
cd "$(dirname "$0")/.."
assets=${NGI_ASSET_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/ngi/assets}
out=$assets/bunny.obj
version=1.0.1  # pinned: the same bunny (and the same OBJ bytes) everywhere
if [[ -s "$out" ]]; then echo "$out"; exit 0; fi
if ! command -v npm >/dev/null || ! command -v node >/dev/null; then
    echo "fetch_bunny: node/npm not installed: skipped (apt-get install nodejs npm)" >&2
    exit 0
fi
mkdir -p "$assets/npm" || exit 0
if ! timeout 300 npm install --prefix "$assets/npm" --no-audit --no-fund --no-save --loglevel=error --fetch-retries=1 \
        "bunny@$version" >"$assets/npm/install.log" 2>&1; then
    echo "fetch_bunny: npm install bunny@$version failed (offline?): skipped ($assets/npm/install.log)" >&2
    exit 0
fi
if ! node - "$assets/npm/node_modules/bunny" "$out.tmp" "$version" <<'EOF'
const [pkg, out, version] = process.argv.slice(2);
const { positions, cells } = require(pkg);
let lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
for (const p of positions) for (let k = 0; k < 3; ++k) { lo[k] = Math.min(lo[k], p[k]); hi[k] = Math.max(hi[k], p[k]); }
const s = 40 / (hi[1] - lo[1]);                     // 40 m tall
const o = [-(lo[0] + hi[0]) / 2, -lo[1], -(lo[2] + hi[2]) / 2];   // centred on x = z = 0, standing on y = 0
const v = positions.map(p => p.map((c, k) => (c + o[k]) * s));
// Outward winding: the signed volume of the (nearly closed) scan is positive when its triangles are.
let vol = 0;
for (const [a, b, c] of cells) {
  const [p, q, r] = [v[a], v[b], v[c]];
  vol += p[0] * (q[1] * r[2] - q[2] * r[1]) - p[1] * (q[0] * r[2] - q[2] * r[0]) + p[2] * (q[0] * r[1] - q[1] * r[0]);
}
const lines = [`# The Stanford bunny (npm package "bunny" ${version}, public domain; tools/fetch_bunny.sh):`,
               `# ${v.length} vertices, ${cells.length} triangles, scaled to 40 m tall, standing on y = 0, in metres.`];
for (const p of v) lines.push(`v ${p.map(c => c.toFixed(5)).join(' ')}`);
for (const [a, b, c] of cells) lines.push(vol >= 0 ? `f ${a + 1} ${b + 1} ${c + 1}` : `f ${a + 1} ${c + 1} ${b + 1}`);
require('fs').writeFileSync(out, lines.join('\n') + '\n');
EOF
then
    rm -f "$out.tmp"
    echo "fetch_bunny: converting the package to OBJ failed: skipped" >&2
    exit 0
fi
mv "$out.tmp" "$out" && echo "$out"
