#!/usr/bin/env bash
# Builds the seed corpus of every fuzz target under OUT/<target>/ from the repository's data (data/, tests/data/,
# fuzz/seeds/) and, when present, the shared data beside the repository (../shared/data). The shared files are
# copied at run time into the build directory, never into the repository.
#   bash fuzz/build_corpus.sh OUT
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
OUT="$1"
SHARED="${STRATA_SHARED_DATA:-$ROOT/../shared/data}"
mkdir -p "$OUT"
for t in hanim obj bvh gltf makehuman makehuman_pack binding muscle scenario; do mkdir -p "$OUT/$t"; cp "$ROOT"/fuzz/seeds/$t/* "$OUT/$t/"; done

cp "$ROOT"/data/default_skeleton.x3d "$ROOT"/tests/data/*.xml "$OUT/hanim/"
# Multi-file targets read their files joined by NUL bytes (fuzz/fuzz_common.h).
{ cat "$ROOT/data/part_joints.json"; printf '\0'; cat "$ROOT/data/binding_overrides.json"; } > "$OUT/binding/shipped.bin"
cp "$ROOT"/data/scenarios/*.json "$OUT/scenario/"
cp "$ROOT"/data/makehuman_body.bin "$OUT/makehuman_pack/shipped.bin"
{ cat "$ROOT/data/muscles.json"; printf '\0'; printf '{"gain": 1.5, "muscles": {"l_biceps": 2}}'; } > "$OUT/muscle/shipped.bin"

if [ -d "$SHARED" ]; then
  # X3D files up to 100 KB: the 220 KB ones (Joe, StandardHumanoid) slow the whole run to ~5 inputs/s against
  # ~160 without them; their features (skin, interpolators, routes) are in the smaller seeds, and the loader tests
  # read them whole.
  find "$SHARED/hanim_x3d" -name '*.x3d' -size -100k -exec cp {} "$OUT/hanim/" \; 2>/dev/null || true
  # Captures cut to their hierarchy and first 5 frames: the 390 KB CMU walk fuzzes at ~16 inputs/s whole (the
  # mutations are spent on frame numbers) and at hundreds per second cut, with the same code reached.
  for f in "$SHARED"/cmu_mocap_bvh/*.bvh; do
    [ -f "$f" ] || continue
    awk 'BEGIN{m=0} /^Frames:/{print "Frames: 5"; m=1; next} {if(m>=1){ if(m>1 && ++n>5) exit; if(/^Frame Time/) m=2 } print}' \
      "$f" > "$OUT/bvh/$(basename "$f" .bvh)_5frames.bvh"
  done
  cp "$SHARED"/gltf_khronos_samples/*.glb "$SHARED"/gltf_khronos_samples/*.gltf "$OUT/gltf/" 2>/dev/null || true
  # The MakeHuman files are 1.7 + 0.1 + 0.9 MB; libFuzzer cuts inputs at 1 MiB, so the joined trio would only
  # ever be seen truncated. The OBJ target gets the first 64 KiB of base.obj (a valid prefix: vertices, then
  # faces referencing them appear later, so it parses to "no faces"), the MakeHuman target its own small seed.
  if [ -f "$SHARED/makehuman_hm08/base.obj" ]; then
    head -c 65536 "$SHARED/makehuman_hm08/base.obj" | sed '$d' > "$OUT/obj/makehuman_base_head.obj"
  fi
else
  echo "build_corpus.sh: no shared data at $SHARED; seeds from the repository only" >&2
fi
for t in hanim obj bvh gltf makehuman binding muscle scenario; do echo "$t: $(ls "$OUT/$t" | wc -l) seeds"; done
