#!/usr/bin/env bash
# Reproduces every figure of BENCHMARKS.md: runs each `chambre bench` part, side by side on the
# backends found, and writes the tables (bench/results.md) and the JSON reports (bench/*.json).
# Usage: tools/bench.sh [RUNS]   (default 3 timed runs after a warm-up for each figure)
set -euo pipefail
cd "$(dirname "$0")/.."
runs="${1:-3}"
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
cargo build --release --bin chambre
mkdir -p bench
chambre=./target/release/chambre
{
    echo "# chambre bench, $(date -u +%Y-%m-%d), $(nproc) cores, $(uname -m)"
    echo
    "$chambre" bench frame --runs "$runs" --json bench/frame.json
    echo
    "$chambre" bench rays --runs "$runs" --json bench/rays.json
    echo
    "$chambre" bench build --runs "$runs" --json bench/build.json
    echo
    "$chambre" bench scale --runs "$runs" --json bench/scale.json --plot bench/scale.svg
    echo
    "$chambre" bench samplers --json bench/samplers.json
} | tee bench/results.md
# The plot BENCHMARKS.md shows.
cp bench/scale.svg docs/images/scale.svg
