#!/usr/bin/env bash
# The converged references of `lgh bench quality --equal-time` (issue 36), made on a machine
# with a GPU: for each scene, the mean of REF_FRAMES brute-force frames of REF_VPLS VPLs each
# (`--reference-device gpu --references-only`), written as OUT_DIR/NAME.exr with its first
# half beside it (NAME.half.exr), and OUT_DIR/references.json with each reference's file,
# time and convergence (the FLIP of its first half against it). A 2-core CPU needs hours
# for references converged to the issue's criterion (a tenth of the smallest error in the
# table); a GPU should need minutes.
#
# Usage: scripts/gpu-references.sh [OUT_DIR]   (default gpu-references)
# Environment: SIZE (320x180, the benchmark's), REF_FRAMES (32), REF_VPLS (100000),
# STEP_TIMEOUT (seconds per scene, 120), SCENES (the six of the equal-time table; Sponza and
# the conference room need LGH_SCENES), LGH_BIN (a built `lgh` instead of building one),
# PACK (1: the EXRs packed into OUT_DIR/references.tar). An existing NAME.exr is read, not
# made again.
#
# Then, on the machine that runs the sweep (the same --size), in the same scene order:
#   lgh bench quality --equal-time SCENES... --reference OUT_DIR/NAME.exr ...
# A scene that fails or runs out of time is recorded as {"error": ...} and the rest go on.
set -uo pipefail
cd "$(dirname "$0")/.."
out=$(realpath -m "${1:-gpu-references}")
size=${SIZE:-320x180}
frames=${REF_FRAMES:-32}
vpls=${REF_VPLS:-100000}
step_timeout=${STEP_TIMEOUT:-120}
scenes=${SCENES:-"builtin:cornell scenes/test/two-rooms.toml scenes/test/clutter.toml scenes/test/colonnade.toml scenes/sponza.toml scenes/conference.toml"}

if [[ -n "${LGH_BIN:-}" ]]; then
    lgh=$LGH_BIN
else
    cargo build --release -p lgh-cli || exit 1
    lgh=target/release/lgh
fi
mkdir -p "$out"
entries=()
for scene in $scenes; do
    name=$(basename "${scene#builtin:}" .toml)
    echo "== $name" >&2
    start=$SECONDS
    json="$out/$name.json"
    if timeout "$step_timeout" "$lgh" bench quality --equal-time "$scene" --size "$size" \
        --reference-frames "$frames" --reference-vpls "$vpls" --reference-device gpu \
        --reference "$out/$name.exr" --references-only --json >"$json" && [[ -s "$json" ]]; then
        entry=$(cat "$json")
    else
        entry="{\"error\": \"failed or ran past ${step_timeout} s\"}"
    fi
    rm -f "$json"
    secs=$((SECONDS - start))
    echo "   $secs s" >&2
    entries+=("{\"scene\": \"$name\", \"seconds\": $secs, \"result\": $entry}")
done
{
    echo "{"
    echo "  \"size\": \"$size\", \"reference_frames\": $frames, \"reference_vpls\": $vpls,"
    echo "  \"scenes\": [$(IFS=,; echo "${entries[*]}")]"
    echo "}"
} >"$out/references.json.tmp"
mv "$out/references.json.tmp" "$out/references.json"
# PACK=1: the EXRs in one tar (a lent GPU brings back at most 8 files).
if [[ "${PACK:-0}" == 1 ]]; then
    (cd "$out" && shopt -s nullglob && exrs=(*.exr) && ((${#exrs[@]})) &&
        tar -cf references.tar "${exrs[@]}" && rm -f "${exrs[@]}")
fi
echo "wrote $out" >&2
