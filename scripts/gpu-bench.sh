#!/usr/bin/env bash
# The GPU benchmarks of issue 35 in one command, on a machine with a GPU (a Vulkan, Metal or
# DX12 driver): builds lgh, then renders the default scene and Sponza (when $LGH_SCENES names
# the shared scenes) at 1280x720 with 100K and 1M VPLs as the viewer does (VPLs regenerated
# and the hierarchy rebuilt every frame, the viewer's settings, k = 4), with the lighting loop
# on the GPU, and writes one JSON file: the adapter, and per case the median ms per frame and
# per pass (the GPU pass from its timestamps where the adapter has them), plus `lgh bench
# render --device gpu` (the paper's Tables 2 and 3) on the default scene.
#
# Usage: scripts/gpu-bench.sh [OUT.json]   (default gpu-bench.json)
# Environment: SIZE (1280x720), VPLS ("100000 1000000"), FRAMES (12), LGH_SCENES.
# Takes about 2 minutes after the build on a current GPU and 16 cores; lavapipe's times are
# no measure of a GPU (use SIZE=160x90 VPLS=10000 FRAMES=3 there to check the script).
set -euo pipefail
cd "$(dirname "$0")/.."
out=$(realpath -m "${1:-gpu-bench.json}")
size=${SIZE:-1280x720}
vpls=${VPLS:-"100000 1000000"}
frames=${FRAMES:-12}

cargo build --release -p lgh-cli
lgh=target/release/lgh
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

scenes=("builtin:cornell")
names=("cornell")
if [[ -n "${LGH_SCENES:-}" && -f "$LGH_SCENES/sponza/sponza.obj" ]]; then
    scenes+=("scenes/sponza.toml")
    names+=("sponza")
else
    echo "LGH_SCENES does not name the shared scenes: Sponza skipped" >&2
fi

# The paper's tables with the loop on the GPU (its JSON names the adapter).
"$lgh" bench render --device gpu --size "$size" --vpls "${vpls// /,}" --runs 3 \
    --interleave 1,4 --json >"$tmp/tables.json"

cases=()
for i in "${!scenes[@]}"; do
    for n in $vpls; do
        f="$tmp/${names[$i]}-$n.json"
        echo "view ${names[$i]} $size $n VPLs" >&2
        # The viewer's frame, headless: 4 shadow samples, the rest at its interactive start.
        "$lgh" view "${scenes[$i]}" --headless --device gpu --size "$size" --vpls "$n" \
            --shadow-samples 4 --frames "$frames" --light-speed 2 --stats "$f"
        cases+=("{\"scene\": \"${names[$i]}\", \"vpls\": $n, \"view\": $(cat "$f")}")
    done
done

{
    echo "{"
    echo "  \"size\": \"$size\","
    echo "  \"tables\": $(cat "$tmp/tables.json"),"
    echo "  \"cases\": ["
    for j in "${!cases[@]}"; do
        sep=","
        [[ $j -eq $((${#cases[@]} - 1)) ]] && sep=""
        echo "    ${cases[$j]}$sep"
    done
    echo "  ]"
    echo "}"
} >"$out.tmp"
mv "$out.tmp" "$out"
echo "wrote $out" >&2
