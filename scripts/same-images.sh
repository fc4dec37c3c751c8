#!/usr/bin/env bash
# Renders the same set of images with two lgh binaries and checks that every one is
# pixel-identical (max_abs 0): the check of a change that must not change the arithmetic.
#
#   scripts/same-images.sh OLD_LGH NEW_LGH
#
# Covers every method, the main flag variants, interleaving, sequences with TAA, the
# built-in scenes and, when LGH_SCENES names the shared scenes, the scene files of scenes/.
set -u
old=$1; new=$2
here=$(cd "$(dirname "$0")/.." && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
render_all() {
  bin=$1; out=$2; mkdir -p "$out/seq"
  r() { name=$1; shift; "$bin" render "$@" --quiet --out "$out/$name.exr" 2>/dev/null || echo "FAIL $name ($bin)"; }
  small=(--size 96x54 --vpls 2000)
  for m in brute brute-unshadowed lgh lgh-unshadowed slc slc-clamped; do r "cornell-$m" --method "$m" "${small[@]}"; done
  r lgh-il4 --interleave 4 "${small[@]}"
  r lgh-il2-k1 --interleave 2 --shadow-samples 1 "${small[@]}"
  r lgh-paper --shadow-target centroid --jitter-at candidate --construction gather --grid-emission mean-normal "${small[@]}"
  r lgh-s0 --start-level 0 --shadow-from-level 0 --alpha 2 --normal-bins "${small[@]}"
  r lgh-scatter --construction scatter --filter none --levels 4 "${small[@]}"
  r slc-ism --method slc --ism "${small[@]}"
  r slc-il1 --method slc --interleave 1 --shadow-samples 0 --error-bound 0.001 "${small[@]}"
  r default-indirect --component indirect --size 96x54
  r default-direct --component direct --size 96x54
  for m in pt-slc pt-uniform pt-clamped; do r "emitter-$m" builtin:emitter-room --method "$m" --size 64x36 --spp 4; done
  if [ -n "${LGH_SCENES:-}" ]; then
    for s in "$here"/scenes/*.toml; do
      n=$(basename "$s" .toml)
      for m in lgh lgh-unshadowed slc slc-clamped; do r "$n-$m" "$s" --method "$m" --size 128x72 --vpls 5000; done
      r "$n-lgh-il4" "$s" --interleave 4 --size 128x72 --vpls 5000
      r "$n-brute" "$s" --method brute --size 48x27 --vpls 500
    done
  fi
  "$bin" render builtin:cornell-moving-block --frames 0..3 --taa --size 64x36 --vpls 1000 --quiet --out "$out/seq/f_####.exr"
  "$bin" render builtin:cornell-moving-light --frames 0..3 --taa --taa-target indirect --method slc --size 64x36 --vpls 1000 --quiet --out "$out/seq/g_####.exr"
}
render_all "$old" "$work/old"
render_all "$new" "$work/new"
n=0; bad=0
for f in $(cd "$work/old" && find . -name '*.exr' | sort); do
  n=$((n + 1))
  if ! "$new" diff "$work/new/$f" "$work/old/$f" --json 2>/dev/null | grep -q '"max_abs":0.0,'; then
    echo "differs: $f"; bad=$((bad + 1))
  fi
done
echo "$n images compared, $bad differ"
[ "$bad" -eq 0 ]
