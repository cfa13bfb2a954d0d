#!/usr/bin/env bash
# Reproduces every figure of BENCHMARKS.md: runs each `chambre bench` part, side by side on the
# backends found, and writes the tables (bench/results.md) and the JSON reports (bench/*.json).
# Usage: tools/bench.sh [RUNS]   (default 3 timed runs after a warm-up for each figure)
# CHAMBRE_BIN=path/to/chambre runs a binary built elsewhere (a GPU machine without cargo).
set -euo pipefail
cd "$(dirname "$0")/.."
runs="${1:-3}"
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
chambre="${CHAMBRE_BIN:-./target/release/chambre}"
if [ -z "${CHAMBRE_BIN:-}" ]; then
    cargo build --release --bin chambre
fi
mkdir -p bench
# What tools/bench_tables.py prints above each table besides the reports' own fields.
git rev-parse --short HEAD > bench/commit.txt 2>/dev/null || echo unknown > bench/commit.txt
lscpu 2>/dev/null | sed -n 's/^Model name: *//p' > bench/cpu.txt || true
{
    echo "# chambre bench, $(date -u +%Y-%m-%d), $(nproc) cores, $(uname -m)"
    echo
    # Beside the adapter's dispatch shape, two fixed ones (rays per invocation).
    "$chambre" bench frame --runs "$runs" --gpu-rays-per-invocation 64,4 --json bench/frame.json
    echo
    # Motion blur: the bunny moving half a unit while the shutter is open, against the same
    # scene standing still (its row in the table above).
    "$chambre" bench frame --runs "$runs" --scenes bunny -D 'shapes[0].velocity=[0.5,0.0,0.0]' \
        -D 'camera.shutter=[0.0,1.0]' --json bench/frame_motion.json
    echo
    "$chambre" bench motion --size 768 --runs "$runs" --json bench/motion.json
    echo
    # The raster preview: Fermat reflections, frame times, shadows.
    CHAMBRE_BIN="$chambre" tools/bench_preview.sh
    echo
    "$chambre" bench rays --runs "$runs" --json bench/rays.json
    echo
    # The throughput issue's real-GPU target is stated at 1920x1080.
    "$chambre" bench rays --width 1920 --height 1080 --runs "$runs" --json bench/rays_1080p.json
    echo
    "$chambre" bench build --runs "$runs" --json bench/build.json
    echo
    "$chambre" bench scale --runs "$runs" --json bench/scale.json --plot bench/scale.svg
    echo
    "$chambre" bench samplers --json bench/samplers.json
    echo
    "$chambre" bench precision --size 128 --json bench/precision.json
    echo
    "$chambre" bench precision --mesh scenes/meshes/checker_light.obj --size 128 \
        --camera-height 0.1 --json bench/precision_grazing.json
    echo
    "$chambre" converge scenes/bokeh.toml -D render.width=120 -D render.height=80 \
        --reference-spp 4096 --max-spp 256 --samplers random,stratified,poisson,interleaved,sobol \
        --backends cpu,gpu --csv bench/converge_bokeh.csv --plot bench/converge_bokeh.svg
    # The scenes shipped to stress the trade (scenes/converge/), on the CPU path.
    for scene in defocus_tilt soft_shadows mirror_corridor checkerboard; do
        echo
        echo "converge: scenes/converge/$scene.toml"
        "$chambre" converge "scenes/converge/$scene.toml" --reference-spp 2048 --max-spp 128 \
            --samplers random,stratified,sobol --csv "bench/converge_$scene.csv"
    done
    # The lens target: the defocus scene at equal time, medians of 3 renders.
    echo
    echo "converge, lens samplers at equal time: scenes/converge/defocus_tilt.toml"
    "$chambre" converge scenes/converge/defocus_tilt.toml --reference-spp 4096 --max-spp 256 \
        --samplers random,stratified,sobol --runs 3 --csv bench/converge_lens_defocus_tilt.csv \
        --plot bench/converge_lens_defocus_tilt.svg
    # Adaptive against uniform sampling on the same scenes: Sobol patterns (progressive, so a
    # pixel that stops keeps a stratified prefix), medians of 3 renders.
    for scene in defocus_tilt soft_shadows mirror_corridor checkerboard; do
        echo
        echo "converge, adaptive: scenes/converge/$scene.toml"
        "$chambre" converge "scenes/converge/$scene.toml" --reference-spp 4096 --max-spp 256 \
            --samplers sobol --noise-targets 0.1,0.05,0.02 --runs 3 \
            --csv "bench/converge_adaptive_$scene.csv" \
            --plot "bench/converge_adaptive_$scene.svg"
    done
    # The same with a later first decision, where FLIP parity was looked for.
    for scene in defocus_tilt mirror_corridor checkerboard; do
        echo
        echo "converge, adaptive, --min-spp 64: scenes/converge/$scene.toml"
        "$chambre" converge "scenes/converge/$scene.toml" --reference-spp 4096 --max-spp 256 \
            --samplers sobol --noise-targets 0.005,0.002,0.001 --min-spp 64 --runs 3 \
            --csv "bench/converge_adaptive_min64_$scene.csv"
    done
    # The path tracer by max_depth, against Mitsuba 3's path integrator where it is installed
    # (CHAMBRE_MITSUBA_SITE from tools/install_mitsuba.sh).
    echo
    echo "path tracer by max_depth: scenes/cornell_box.toml"
    python3 tools/bench_path.py --chambre "$chambre" --runs "$runs" --rounds 5 --out bench
} | tee bench/results.md
# The plots BENCHMARKS.md shows.
cp bench/scale.svg docs/images/scale.svg
cp bench/converge_bokeh.svg docs/images/converge_bokeh.svg
cp bench/converge_adaptive_defocus_tilt.svg docs/images/converge_adaptive_defocus_tilt.svg
cp bench/converge_lens_defocus_tilt.svg docs/images/converge_lens_defocus_tilt.svg
# The tables of BENCHMARKS.md made anew from the reports (the others are left as they are).
python3 tools/bench_tables.py bench --update BENCHMARKS.md
