#!/usr/bin/env bash
# The GPU comparison in one command, sized for a lent GPU machine (a few minutes on an H100 or
# H200): chambre's ray queries and frames, and Mitsuba 3 (`cuda_ad_rgb`, OptiX) on the same rays
# and on `chambre export --mitsuba` exports of the same scenes, side by side in one run; then
# the table with ratios (tools/bench_gpu_table.py) and every JSON report in $OUT.
#
#   CHAMBRE_BIN=path/to/chambre PEER=.peer OUT=out tools/bench_gpu.sh [RUNS]
#
# CHAMBRE_BIN: a release binary built elsewhere (default: target/release/chambre, built here).
# PEER: a folder holding ../shared/peers-gpu's Mitsuba bundle and mitsuba_peer.py (copied into
#   an ignored folder of the checkout, which a device call carries); unset: chambre alone.
# OUT: where the reports go (default bench/gpu). RUNS: timed runs of each figure (default 5).
set -euo pipefail
cd "$(dirname "$0")/.."
runs="${1:-5}"
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
chambre="${CHAMBRE_BIN:-./target/release/chambre}"
out="${OUT:-bench/gpu}"
if [ -z "${CHAMBRE_BIN:-}" ]; then
    cargo build --release --bin chambre
fi
mkdir -p "$out"
started=$(date +%s)
stamp() { echo "== $1 ($(($(date +%s) - started)) s)"; }

stamp "adapter"
"$chambre" info | tee "$out/adapter.txt"
git rev-parse --short HEAD > "$out/commit.txt" 2>/dev/null || echo unknown > "$out/commit.txt"
lscpu 2>/dev/null | sed -n 's/^Model name: *//p' > "$out/cpu.txt" || true

# A scene's film must have its image's aspect (within 0.1%): these 36 mm films keep the
# scenes' horizontal field of view at 1:1 and 16:9.
square="-D camera.film=[36.0,36.0]"
wide="-D camera.film=[36.0,20.25]"
# The benchmark set: (name, scene, overrides, export flags), the sizes the issue states its
# targets at. The export flags say how Mitsuba renders the same frame (docs/mitsuba.md): the
# dragon's camera rays alone (`depth`, as its ambient-only frame is); `--approximate` where the
# scene has what Mitsuba lacks (ambient light, Phong lobes, lens tilt, blades), written as the
# nearest it has: the same rays' work, not the same image.
frames=(
    "dragon|dragon||--integrator depth"
    "cornell_direct|cornell_direct|-D render.width=1024 -D render.height=1024 -D render.spp=64|"
    "thin_lens|thin_lens|-D render.width=1024 -D render.height=1024 -D render.spp=64 $square|--approximate"
    "tabletop|tabletop|-D render.width=1920 -D render.height=1080 $wide|--approximate"
    "bunny|bunny|-D render.width=1920 -D render.height=1080 $wide|--approximate"
    "mirrors|mirrors|-D render.width=1920 -D render.height=1080 $wide|--approximate"
    "cornell_path|cornell_box|-D render.width=1024 -D render.height=1024 -D render.spp=64 -D render.integrator=\"path\" -D render.max_depth=4|"
    "interior|interior|-D render.width=1024 -D render.height=1024 -D render.spp=64 -D camera.film_shift=[0.0,0.0] -D camera.position=[0.0,1.0,3.9] -D camera.look_at=[0.0,1.0,0.0]|"
)

stamp "chambre: ray queries (the dragon, 1920x1080 and 1024x1024 x 8 frames)"
"$chambre" bench rays --backends gpu --bvh cwbvh --width 1920 --height 1080 --runs "$runs" \
    --json "$out/rays_1080p.json"
"$chambre" bench rays --backends gpu --bvh cwbvh --runs "$runs" --json "$out/rays_1024.json"

for entry in "${frames[@]}"; do
    IFS='|' read -r name scene overrides _ <<< "$entry"
    stamp "chambre: frame $name"
    # shellcheck disable=SC2086
    "$chambre" bench frame --backends gpu --no-general --scenes "$scene" $overrides \
        --runs "$runs" --json "$out/frame_$name.json"
done

stamp "chambre: scale (the dragon and 4 and 12 copies beside it, 512x512 camera rays)"
"$chambre" bench scale --backends gpu --prefixes 1000000000 --copies 4,12 --size 512 --runs "$runs" \
    --pad-mib 64,128,256,512 --json "$out/scale.json"
# The same copies far apart (no camera ray reaches them): the BVH and buffers of 4 and 12
# dragons with one dragon's work.
"$chambre" bench scale --backends gpu --prefixes 1000000000 --copies 4,12 --size 512 --runs "$runs" \
    --copy-spacing 50 --json "$out/scale_far.json"

if [ -n "${PEER:-}" ]; then
    stamp "Mitsuba 3: unpacking"
    site=/tmp/mitsuba-site
    mkdir -p "$site"
    tar xJf "$PEER"/mitsuba-*.tar.xz -C "$site"
    export PYTHONPATH="$site" MI_VARIANT="${MI_VARIANT:-cuda_ad_rgb}"
    peer=(python3 "$PEER/mitsuba_peer.py")
    gunzip -c scenes/meshes/dragon_vrip.obj.gz > /tmp/dragon.obj
    stamp "Mitsuba 3: ray queries"
    "${peer[@]}" rays /tmp/dragon.obj "$out/mitsuba_rays_coherent.json" --runs "$runs"
    "${peer[@]}" rays /tmp/dragon.obj "$out/mitsuba_rays_incoherent.json" --runs "$runs" --incoherent
    for copies in 1 4 12; do
        "${peer[@]}" rays /tmp/dragon.obj "$out/mitsuba_scale_$copies.json" --width 512 \
            --height 512 --frames 1 --runs "$runs" --copies "$copies"
    done
    for entry in "${frames[@]}"; do
        IFS='|' read -r name scene overrides export_flags <<< "$entry"
        stamp "Mitsuba 3: frame $name"
        # shellcheck disable=SC2086
        "$chambre" export "scenes/$scene.toml" --mitsuba "$out/mitsuba_$name.xml" $overrides \
            $export_flags
        "${peer[@]}" render "$out/mitsuba_$name.xml" "/tmp/mitsuba_$name.exr" \
            "$out/mitsuba_frame_$name.json" --runs "$runs"
    done
fi

stamp "table"
python3 tools/bench_gpu_table.py "$out" | tee "$out/table.md"
stamp "done"
