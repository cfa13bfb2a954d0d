#!/usr/bin/env bash
# The test command: installs lavapipe (Mesa's software Vulkan) when no Vulkan driver is present,
# names the adapter in the log, then runs every test with GPU tests required to find an adapter.
set -euo pipefail
cd "$(dirname "$0")/.."

if ! ls /usr/share/vulkan/icd.d/lvp_icd*.json >/dev/null 2>&1; then
    echo "== installing lavapipe (mesa-vulkan-drivers)"
    SUDO=""
    [ "$(id -u)" -ne 0 ] && SUDO="sudo"
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq mesa-vulkan-drivers >/dev/null
fi

# nv-flip (FLIP in `chambre converge`) compiles NVIDIA's C++ implementation.
if ! command -v c++ >/dev/null 2>&1; then
    echo "== installing a C++ compiler (g++)"
    SUDO=""
    [ "$(id -u)" -ne 0 ] && SUDO="sudo"
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq g++ >/dev/null
fi

# The interactive preview's test (tests/window.rs) opens its window on Xvfb and types into it
# with xdotool.
if ! command -v Xvfb >/dev/null 2>&1 || ! command -v xdotool >/dev/null 2>&1; then
    echo "== installing Xvfb and xdotool"
    SUDO=""
    [ "$(id -u)" -ne 0 ] && SUDO="sudo"
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq xvfb xdotool >/dev/null
fi

# tests/export.rs renders `chambre export --mitsuba` scenes with Mitsuba 3 (pinned, into
# target/mitsuba-site) on the CPU; without it those tests fail.
mitsuba_env=$(tools/install_mitsuba.sh)   # an assignment, so that a failed install stops here
eval "$mitsuba_env"
export CHAMBRE_REQUIRE_MITSUBA=1

export CHAMBRE_REQUIRE_GPU=1
# The loader's complaint about a missing XDG_RUNTIME_DIR on headless machines is noise.
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"

# Dependencies point one way (docs/architecture.md): no import circle between files or modules.
python3 tools/check_imports.py
# Small functions: none over 120 lines outside unit-test modules (its own test first).
python3 tools/test_check_function_length.py
python3 tools/check_function_length.py
cargo build --release --bins
echo "== GPU adapters"
./target/release/chambre info
# docs/shards.md's Slurm array on a real slurmctld and slurmd (installs slurm-wlm and munge).
echo "== Slurm"
tools/test_slurm.sh
python3 tools/test_bench_tables.py   # BENCHMARKS.md's tables from the bench reports
cargo test --release
