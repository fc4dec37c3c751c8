#!/usr/bin/env bash
# The GPU benchmarks of issue 35 in one command, on a machine with a GPU (a Vulkan, Metal or
# DX12 driver): builds lgh, then renders the default scene and Sponza (when $LGH_SCENES names
# the shared scenes) at 1280x720 with 100K and 1M VPLs as the viewer does (VPLs regenerated
# and the hierarchy rebuilt every frame, the viewer's settings, k = 4), with the lighting loop
# on the GPU, and writes one JSON file: the adapter, and per case the median ms per frame and
# per pass (the GPU pass from its timestamps where the adapter has them), the same frame on
# the CPU for comparison, the hierarchy build of each scene's VPLs on the GPU and on the CPU
# (`lgh bench build --device gpu|cpu`), plus `lgh bench render --device gpu` (the paper's
# Tables 2 and 3) on the default scene.
#
# Usage: scripts/gpu-bench.sh [OUT.json]   (default gpu-bench.json)
# Environment: SIZE (1280x720), VPLS ("100000 1000000"), FRAMES (12), CPU_FRAMES (4; 0 skips
# the CPU comparison), STEP_TIMEOUT (seconds per step, 100), LGH_SCENES, LGH_BIN (a built
# `lgh` to use instead of building one, for machines without cargo).
# Each step that fails or runs out of time is recorded as {"error": ...} and the rest go on.
# Each scene also runs its first VPL count with the camera moving (the A and D keys
# alternating), where the still camera's G-buffer and edge resolve are made every frame,
# and with one hierarchy per normal bin (the render's default; VPLs split on the GPU).
# Takes about 2 minutes after the build on a current GPU and 16 cores; lavapipe's times are
# no measure of a GPU (use SIZE=160x90 VPLS=10000 FRAMES=3 there to check the script).
set -uo pipefail
cd "$(dirname "$0")/.."
out=$(realpath -m "${1:-gpu-bench.json}")
size=${SIZE:-1280x720}
vpls=${VPLS:-"100000 1000000"}
frames=${FRAMES:-12}
cpu_frames=${CPU_FRAMES:-4}
step_timeout=${STEP_TIMEOUT:-100}

if [[ -n "${LGH_BIN:-}" ]]; then
    lgh=$LGH_BIN
else
    cargo build --release -p lgh-cli || exit 1
    lgh=target/release/lgh
fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# step NAME COMMAND...: runs COMMAND (which writes $tmp/NAME.json) under the step timeout,
# and leaves {"error": ...} there when it fails.
step() {
    local name=$1
    shift
    echo "== $name" >&2
    local start=$SECONDS
    if ! timeout "$step_timeout" "$@" || [[ ! -s "$tmp/$name.json" ]]; then
        echo "{\"error\": \"step failed or ran past ${step_timeout} s\"}" >"$tmp/$name.json"
    fi
    echo "   $((SECONDS - start)) s" >&2
}

scenes=("builtin:cornell")
names=("cornell")
if [[ -n "${LGH_SCENES:-}" && -f "$LGH_SCENES/sponza/sponza.obj" ]]; then
    scenes+=("scenes/sponza.toml")
    names+=("sponza")
else
    echo "LGH_SCENES does not name the shared scenes: Sponza skipped" >&2
fi

cases=()
for i in "${!scenes[@]}"; do
    for n in $vpls; do
        name="${names[$i]}-$n"
        # The viewer's frame, headless: 4 shadow samples, the rest at its interactive start.
        view=("$lgh" view "${scenes[$i]}" --headless --size "$size" --vpls "$n"
            --shadow-samples 4 --light-speed 2)
        step "$name-gpu" "${view[@]}" --device gpu --frames "$frames" --stats "$tmp/$name-gpu.json"
        cpu="null"
        if [[ "$cpu_frames" -gt 0 ]]; then
            step "$name-cpu" "${view[@]}" --device cpu --frames "$cpu_frames" \
                --stats "$tmp/$name-cpu.json"
            cpu=$(cat "$tmp/$name-cpu.json")
        fi
        cases+=("{\"scene\": \"${names[$i]}\", \"vpls\": $n, \"camera\": \"still\", \"view\": $(cat "$tmp/$name-gpu.json"), \"view_cpu\": $cpu}")
    done
    # A moving camera (the viewer's A and D keys, one a frame, alternating): the G-buffer,
    # the tile bounds and the edge resolve are made again every frame.
    n=${vpls%% *}
    name="${names[$i]}-$n-moving"
    keys=$(printf 'a,d,%.0s' $(seq "$frames") | cut -d, -f"1-$frames")
    step "$name-gpu" "$lgh" view "${scenes[$i]}" --headless --size "$size" --vpls "$n" \
        --shadow-samples 4 --light-speed 2 --keys "$keys" --device gpu --frames "$frames" \
        --stats "$tmp/$name-gpu.json"
    cases+=("{\"scene\": \"${names[$i]}\", \"vpls\": $n, \"camera\": \"moving\", \"view\": $(cat "$tmp/$name-gpu.json"), \"view_cpu\": null}")
    # The same with the temporal filter of the shadow ratio (on the GPU, in the frame's
    # submission).
    name="${names[$i]}-$n-moving-taa"
    step "$name-gpu" "$lgh" view "${scenes[$i]}" --headless --size "$size" --vpls "$n" \
        --shadow-samples 4 --light-speed 2 --keys "$keys" --taa --device gpu --frames "$frames" \
        --stats "$tmp/$name-gpu.json"
    cases+=("{\"scene\": \"${names[$i]}\", \"vpls\": $n, \"camera\": \"moving, taa\", \"view\": $(cat "$tmp/$name-gpu.json"), \"view_cpu\": null}")
    # One hierarchy per normal bin (the render's default), the VPLs split on the GPU.
    name="${names[$i]}-$n-bins"
    step "$name-gpu" "$lgh" view "${scenes[$i]}" --headless --size "$size" --vpls "$n" \
        --shadow-samples 4 --light-speed 2 --normal-bins=true --device gpu --frames "$frames" \
        --stats "$tmp/$name-gpu.json"
    cases+=("{\"scene\": \"${names[$i]}\", \"vpls\": $n, \"camera\": \"still, normal bins\", \"view\": $(cat "$tmp/$name-gpu.json"), \"view_cpu\": null}")
done

# The hierarchy build of the VPLs of each scene, 100K and 1M, on the GPU and on the CPU
# (the restriction; `lgh bench build`, Table 1 of the paper): per step and per GPU pass.
builds=()
for i in "${!scenes[@]}"; do
    for dev in gpu cpu; do
        name="build-${names[$i]}-$dev"
        step "$name" sh -c '"$0" bench build --device "$1" --lights "$2" --runs 5 --scene "$3" \
            --json >"$4"' "$lgh" "$dev" "${vpls// /,}" "${scenes[$i]}" "$tmp/$name.json"
        builds+=("{\"scene\": \"${names[$i]}\", \"device\": \"$dev\", \"build\": $(cat "$tmp/$name.json")}")
    done
done

# The paper's tables with the loop on the GPU (its JSON names the adapter).
step tables sh -c "\"$lgh\" bench render --device gpu --size $size --vpls ${vpls// /,} \
    --runs 3 --interleave 1,4 --json >\"$tmp/tables.json\""
# The same on Sponza with 4 x 4 interleaving: the loop's cost without shadows, with 1 and
# with 4 shadow samples.
sponza_tables=null
if [[ " ${names[*]} " == *" sponza "* ]]; then
    step tables-sponza sh -c "\"$lgh\" bench render scenes/sponza.toml --device gpu \
        --size $size --vpls ${vpls// /,} --runs 2 --interleave 4 --json \
        >\"$tmp/tables-sponza.json\""
    sponza_tables=$(cat "$tmp/tables-sponza.json")
fi

{
    echo "{"
    echo "  \"size\": \"$size\","
    echo "  \"tables\": $(cat "$tmp/tables.json"),"
    echo "  \"tables_sponza\": $sponza_tables,"
    echo "  \"builds\": [$(IFS=,; echo "${builds[*]}")],"
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
