#!/usr/bin/env bash
# MuJoCo Warp on a CUDA GPU: an export's scene beside a baseline scene through benchmarks/sim_bench.py
# (counts, CPU MuJoCo on one core, Warp at batch 1, 1024 and 8192 with and without CUDA-graph
# capture, each batch's world 0 against CPU MuJoCo, the stages and --profile's kernels at 8192),
# on a GPU machine that has Python 3.12 and JAX but neither MuJoCo nor Warp nor a package registry.
#
# The wheels travel with the working tree, which may carry 64 MiB a call, and Warp's wheel alone is
# 142 MiB: it travels in three equal parts, three calls in a row each leaving its part on the machine
# (its disk stays while it is held between calls), the last one installing and running:
#
#   here:    bash benchmarks/gpu_check.sh prepare EXPORT_DIR BASELINE_EXPORT_DIR
#            (.gpu/1, .gpu/2, .gpu/3, each at most 58 MiB; .gpu/ ignored through .git/info/exclude)
#   device:  carry .gpu/1:  bash benchmarks/gpu_check.sh stash .gpu/1
#            carry .gpu/2:  bash benchmarks/gpu_check.sh stash .gpu/2
#            carry .gpu/3:  bash benchmarks/gpu_check.sh stash .gpu/3 && bash benchmarks/gpu_check.sh run
#
# `run` writes sim_bench.txt and sim_bench.json to $OUT (or ./gpu_check_out), and where the export
# holds the tail on the quadruped (robot/quadruped/scene_go1.xml) host_tail_8192.txt and .json: its
# MuJoCo Warp rate at batch 8192 (benchmarks/host_bench.py --warp-scene); arguments after `run`
# go to sim_bench.py (e.g. --gpu-batches 8192,32768). The versions are the lock's
# (requirements/lock.txt).
set -euo pipefail

repo=$(cd "$(dirname "$0")/.." && pwd)
stash=${GPU_CHECK_STASH:-/tmp/gpu_check}
group_mib=58
wheels="mujoco mujoco-core mujoco-mjx mujoco-warp warp-lang glfw PyOpenGL"

pinned() {  # NAME==VERSION from the lock
    local line
    line=$(grep -i "^$1==" "$repo/requirements/lock.txt") || { echo "gpu_check: $1 is not in requirements/lock.txt" >&2; exit 2; }
    echo "$line"
}

scene_tar() {  # EXPORT_DIR NAME: the export's robot folder without the ROS 2 package, as NAME/robot
    local export=$1 name=$2
    [ -f "$export/robot/scene.xml" ] || { echo "gpu_check: $export/robot/scene.xml not found" >&2; exit 2; }
    mkdir -p "$work/scenes/$name"
    cp -r "$export/robot" "$work/scenes/$name/"
    rm -rf "$work/scenes/$name/robot/ros2"
}

prepare() {
    [ $# -eq 2 ] || { echo "usage: gpu_check.sh prepare EXPORT_DIR BASELINE_EXPORT_DIR" >&2; exit 2; }
    local python="${PYTHON:-$repo/.venv/bin/python}" specs="" name
    work=$(mktemp -d)
    trap 'rm -rf "$work"' EXIT
    for name in $wheels; do specs="$specs $(pinned "$name")"; done
    # shellcheck disable=SC2086
    "$python" -m pip download -q --no-deps --only-binary=:all: --python-version 3.12 \
        --implementation cp --platform manylinux_2_28_x86_64 --platform manylinux_2_27_x86_64 \
        --platform manylinux_2_17_x86_64 --platform manylinux2014_x86_64 -d "$work/wheels" $specs
    scene_tar "$1" scene
    scene_tar "$2" baseline
    tar -C "$work/scenes" -cJf "$work/scenes.tar.xz" scene baseline
    rm -rf "$repo/.gpu"
    mkdir -p "$repo/.gpu/1" "$repo/.gpu/2" "$repo/.gpu/3"
    mkdir -p "$repo/.git/info"
    grep -qx '/.gpu/' "$repo/.git/info/exclude" 2>/dev/null || echo '/.gpu/' >>"$repo/.git/info/exclude"
    local warp
    warp=$(basename "$work"/wheels/warp_lang-*.whl)
    split -n 3 -d -a 2 "$work/wheels/$warp" "$work/$warp.part-"
    mv "$work/$warp.part-00" "$work"/wheels/mujoco_mjx-*.whl "$repo/.gpu/1/"
    mv "$work/$warp.part-01" "$work"/wheels/mujoco_core-*.whl "$repo/.gpu/2/"
    rm "$work/wheels/$warp"
    mv "$work/$warp".part-* "$work"/wheels/*.whl "$work/scenes.tar.xz" "$repo/.gpu/3/"
    local group size
    for group in 1 2 3; do
        size=$(du -sm "$repo/.gpu/$group" | cut -f1)
        echo "  .gpu/$group: ${size} MiB: $(ls "$repo/.gpu/$group" | tr '\n' ' ')"
        [ "$size" -le "$group_mib" ] || { echo "gpu_check: .gpu/$group is over $group_mib MiB" >&2; exit 2; }
    done
}

stash_part() {
    [ $# -eq 1 ] && [ -d "$1" ] || { echo "usage: gpu_check.sh stash .gpu/N (a carried folder)" >&2; exit 2; }
    mkdir -p "$stash"
    cp "$1"/* "$stash/"
    echo "stashed $(ls "$1" | wc -l) file(s) in $stash: $(du -sm "$stash" | cut -f1) MiB there now"
}

run() {
    local out=${OUT:-$repo/gpu_check_out} first base
    mkdir -p "$out"
    cd "$stash"
    for first in *.part-00; do
        [ -e "$first" ] || continue
        base=${first%.part-00}
        for part in "$base".part-01 "$base".part-02; do
            [ -f "$part" ] || { echo "gpu_check: $part missing: stash every .gpu/N first" >&2; exit 2; }
        done
        cat "$base".part-* >"$base" && rm "$base".part-*
    done
    python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade \
        --target /tmp/site "$stash"/*.whl
    mkdir -p "$stash/scenes"
    tar -C "$stash/scenes" -xJf "$stash/scenes.tar.xz"
    cd "$repo"
    export PYTHONPATH="/tmp/site:$repo${PYTHONPATH:+:$PYTHONPATH}" PYTHONUNBUFFERED=1
    nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader | tee "$out/gpu.txt"
    python3 benchmarks/sim_bench.py "$stash/scenes/scene" --scene robot/scene.xml \
        --baseline "$stash/scenes/baseline/robot/scene.xml" --no-mjx --warp-cpu-batch 0 \
        --cpu-seconds 2 --gpu-batches 1,1024,8192 --profile --json "$out/sim_bench.json" "$@" \
        2>&1 | tee "$out/sim_bench.txt"
    local quad="$stash/scenes/scene/robot/quadruped/scene_go1.xml"
    if [ -f "$quad" ]; then
        python3 benchmarks/host_bench.py "$stash/scenes/scene" --warp-scene "$quad" \
            --warp-batch 8192 --json "$out/host_tail_8192.json" 2>&1 | tee "$out/host_tail_8192.txt"
    else
        echo "gpu_check: no robot/quadruped/scene_go1.xml in the export (built without the" \
            "quadruped extra): no host+tail rate" | tee "$out/host_tail_8192.txt"
    fi
}

case "${1:-}" in
    prepare) shift; prepare "$@" ;;
    stash) shift; stash_part "$@" ;;
    run) shift; run "$@" ;;
    *) echo "usage: gpu_check.sh prepare EXPORT_DIR BASELINE_EXPORT_DIR | stash .gpu/N | run [sim_bench args]" >&2; exit 2 ;;
esac
