#!/usr/bin/env bash
# The raster preview's figures of BENCHMARKS.md (tools/bench.sh runs this part too): the Fermat
# reflections against the ray tracer, then the preview's frame times and shadows. Tables go to
# standard output, JSON reports to bench/ (or $OUT).
# Usage: tools/bench_preview.sh   (each `bench fermat` times 5 rounds after a warm-up)
# CHAMBRE_BIN=path/to/chambre runs a binary built elsewhere (a GPU machine without cargo);
# OUT=bench/gpu puts the reports where tools/bench_tables.py takes a GPU machine's (default bench).
set -euo pipefail
cd "$(dirname "$0")/.."
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
chambre="${CHAMBRE_BIN:-./target/release/chambre}"
if [ -z "${CHAMBRE_BIN:-}" ]; then
    cargo build --release --bin chambre
fi
out="${OUT:-bench}"
mkdir -p "$out"
git rev-parse --short HEAD > "$out/commit.txt" 2>/dev/null || echo unknown > "$out/commit.txt"
lscpu 2>/dev/null | sed -n 's/^Model name: *//p' > "$out/cpu.txt" || true
echo "# chambre bench (preview), $(date -u +%Y-%m-%d), $(nproc) cores, $(uname -m)"
echo
# Fermat reflections in the preview against the ray tracer, by subdivision: a sphere, a
# torus, an ellipsoid, a cylinder and the teapot's 32 Bézier patches.
"$chambre" bench fermat --json "$out/fermat.json"
for mirror in torus ellipsoid cylinder teapot; do
    "$chambre" bench fermat --scene "scenes/fermat_$mirror.toml" --json "$out/fermat_$mirror.json"
done
# The same comparison on frames 4, 16 and 64 times larger: how each frame grows with its pixels
# once past its fixed costs (the reference at 16 spp: FLIP is not this run's question).
for mirror in sphere teapot; do
    for size in 640x480 1280x960 2560x1920; do
        "$chambre" bench fermat --scene "scenes/fermat_$mirror.toml" --subdivisions 4 \
            -D render.width="${size%x*}" -D render.height="${size#*x}" --reference-spp 16 \
            --runs 3 --json "$out/fermat_${mirror}_$size.json"
    done
done
# The teapot's 32 searches one a dispatch, as before they were batched (BENCHMARKS.md).
"$chambre" bench fermat --scene scenes/fermat_teapot.toml --subdivisions 1,4,16 \
    --searches-per-dispatch 1 --json "$out/fermat_teapot_unbatched.json"
# The curved shapes' tessellation tolerance traded against time and FLIP.
for mirror in sphere teapot; do
    for tolerance in 0.125 0.25 0.5 1 2; do
        "$chambre" bench fermat --scene "scenes/fermat_$mirror.toml" --subdivisions 4 \
            --tessellation-tolerance "$tolerance" \
            --json "$out/fermat_${mirror}_tolerance_$tolerance.json"
    done
done
# Mirrors reflecting themselves (--self-reflections), their own triangles cut for each
# tolerance, traded against time and FLIP (without: the tables above).
for mirror in torus teapot; do
    for tolerance in 0.5 1 2 4; do
        "$chambre" bench fermat --scene "scenes/fermat_$mirror.toml" --subdivisions 4 \
            --self-reflections "$tolerance" \
            --json "$out/fermat_${mirror}_self_$tolerance.json"
    done
done
echo
# The raster preview's frame time, beside the ray-traced frames of `bench frame`.
for scene in architecture tabletop spheres bunny; do
    "$chambre" preview "scenes/$scene.toml" -o "$out/preview_$scene.png" --frames 5 2>&1 \
        | grep -v '^note:'
done
echo
# The preview without and with shadows: frame time, the maps' drawing, FLIP.
"$chambre" bench preview --json "$out/preview.json"
