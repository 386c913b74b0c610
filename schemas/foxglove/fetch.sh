#!/usr/bin/env bash
# Regenerates the Foxglove JSON schemas in this folder from the npm package
# @foxglove/schemas (MIT, see LICENSE). Needs npm and node. Run from anywhere:
#   bash schemas/foxglove/fetch.sh
# The output is committed; the build never runs this script.
set -euo pipefail
version=2.1.0
here="$(cd "$(dirname "$0")" && pwd)"
names=(SceneUpdate SceneEntity SceneEntityDeletion ArrowPrimitive CubePrimitive
  SpherePrimitive CylinderPrimitive LinePrimitive TriangleListPrimitive TextPrimitive
  ModelPrimitive FrameTransforms FrameTransform Log Time Duration Pose Vector3 Point3
  Quaternion Color KeyValuePair)
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
cd "$tmp"
npm pack --silent "@foxglove/schemas@$version" >/dev/null
tar xzf "foxglove-schemas-$version.tgz"
# package/jsonschema.js exports one JSON schema object per Foxglove message type.
node -e '
const fs = require("fs");
const s = require(process.cwd() + "/package/jsonschema.js");
const [out, ...names] = process.argv.slice(1);
for (const n of names) {
  if (!(n in s)) { console.error("missing schema " + n); process.exit(1); }
  fs.writeFileSync(out + "/" + n + ".json", JSON.stringify(s[n], null, 2) + "\n");
}' "$here" "${names[@]}"
echo "wrote ${#names[@]} schemas of @foxglove/schemas@$version to $here"
