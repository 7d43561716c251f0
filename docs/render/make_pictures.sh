#!/usr/bin/env bash
# Regenerates the pictures of docs/render/README.md with the release binary:
#
#     cargo build --release -p tessd && bash docs/render/make_pictures.sh
#
# Every picture is 960x540 (`tessd render ... --json`); the script prints one line per picture
# with the figures the README's captions quote (cracks detected / filled, covered pixels, time).
# Runs without a GPU (lavapipe): about three minutes on 2 cores, most of it the two --raycast
# pictures; the first run on a machine takes longer while the shaders compile. The parts are
# shared parts: the tessd-brep documents of core/tessellate/tests/data/ (OCCT's bottle, 71
# faces, and CrankArm.brep, 53 faces), and the M6 countersunk screw's STEP file
# (shared/data/brep), exported on the fly with `python -m tessd.brep export` in .venv-cad.
set -euo pipefail
cd "$(dirname "$0")/../.."
TESSD="${TESSD_BIN:-${CARGO_TARGET_DIR:-target}/release/tessd}"
DATA=core/tessellate/tests/data
OUT=docs/render
SIZE=960x540

# render NAME PART [tessd render options...]
render() {
    local name=$1 part=$2
    shift 2
    "$TESSD" render "$DATA/$part.json" "$OUT/$name.png" --size "$SIZE" --json "$@" 2>/dev/null |
        python3 -c '
import json, sys
r = json.load(sys.stdin)
c = r.get("cracks")
cracks = "cracks %s: %d detected, %d filled" % (c["mode"], c["detected"], c["filled"]) if c else "no crack pass"
print("%s.png: %s, %s, %d of %d pixels covered, %d grid cells, %.0f ms" % (sys.argv[1], r["method"],
      cracks, r["covered"], r["pixels"], r["grid"]["cells"], r["timings_ms"]["total"]))' "$name"
}

# The STEP part, exported as the render tests do.
SHARED="${TESSD_SHARED_DATA:-../shared/data}"
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
PYTHONPATH=python .venv-cad/bin/python -m tessd.brep export \
    "$SHARED/brep/M6-1x12-countersunk-screw.step" "$TMP/M6_screw.json" 2>/dev/null
ln -sf "$TMP/M6_screw.json" "$DATA/.M6_screw.json"
trap 'rm -rf "$TMP" "$DATA/.M6_screw.json"' EXIT

for part in bottle CrankArm .M6_screw; do
    name=$(echo "${part#.}" | tr '[:upper:]' '[:lower:]')
    render "${name}_none" "$part" --cracks none
    render "${name}_image" "$part" --cracks image
    render "${name}_object" "$part" --cracks object
    render "${name}_raycast" "$part" --raycast
    render "${name}_face_ids" "$part" --shading face-ids
done
# A close-up of the bottle's neck (a cylinder) where it meets the shoulder and the thread: the
# cracks left open, then filled.
CLOSEUP=(--eye=11.07,-7.52,57.17 --target=6.39,-2.83,49.68)
render closeup_none bottle --cracks none "${CLOSEUP[@]}"
render closeup_object bottle --cracks object "${CLOSEUP[@]}"
# Meshes side by side: the Stanford bunny's LOD chain from the USD stage `tessd lod` writes,
# one 320x320 panel per LOD variant, one camera (Gooch shading).
"$TESSD" lod "$SHARED/mesh/stanford_bunny.obj" --levels 10%,2%,0.5% --out "$TMP/bunny_lods.usda" \
    >/dev/null
"$TESSD" render "$TMP/bunny_lods.usda" "$OUT/bunny_lods.png" --size 320x320 --shading gooch \
    --eye=-0.1,0.25,0.35 --target=-0.02,0.1,0 --up=0,1,0 --json 2>/dev/null | python3 -c '
import json, sys
r = json.load(sys.stdin)
print("bunny_lods.png: %s, %dx%d, %.0f ms" % (", ".join("%s %d triangles" % (p["label"], p["triangles"])
      for p in r["panels"]), r["width"], r["height"], r["timings_ms"]["total"]))'
ls -l "$OUT"/*.png
