#!/usr/bin/env bash
# Installs what tests/export.rs renders with: Mitsuba 3 and Dr.Jit (pinned, from PyPI) into
# target/mitsuba-site, out of the system's Python, and a libLLVM for Dr.Jit's CPU backend (the
# `llvm_ad_rgb` variant; Debian's libllvm19). Prints the two variables the test reads:
#
#   eval "$(tools/install_mitsuba.sh)"   # sets CHAMBRE_MITSUBA_SITE and DRJIT_LIBLLVM_PATH
#
# Does nothing that is already done: a second run takes a second.
set -euo pipefail
cd "$(dirname "$0")/.."

MITSUBA_VERSION=3.9.1
DRJIT_VERSION=1.5.0
site="$PWD/target/mitsuba-site"
python="${PYTHON:-python3}"
SUDO=""
[ "$(id -u)" -ne 0 ] && SUDO="sudo"

# Dr.Jit's LLVM backend loads libLLVM at run time. Dr.Jit 1.5's kernels use llvm.maximum and
# llvm.minimum, which LLVM 16's x86 backend cannot compile ("Cannot select: fmaximum"): 19.
llvm() {
    ls /usr/lib/x86_64-linux-gnu/libLLVM.so.19.1 /usr/lib/x86_64-linux-gnu/libLLVM-19.so.1 \
        2>/dev/null | head -n 1
}
if [ -z "$(llvm)" ]; then
    echo "== installing libllvm19 (Dr.Jit's CPU backend)" >&2
    $SUDO apt-get update -qq >&2
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq libllvm19 >/dev/null
fi

# One folder per Python version: the wheels are built for one.
tag=$("$python" -c 'import sys; print(f"cp{sys.version_info[0]}{sys.version_info[1]}")')
stamp="$site/.installed-$tag-mitsuba-$MITSUBA_VERSION-drjit-$DRJIT_VERSION"
if [ ! -e "$stamp" ]; then
    echo "== installing mitsuba $MITSUBA_VERSION and drjit $DRJIT_VERSION into $site" >&2
    rm -rf "$site"
    "$python" -m pip install --quiet --disable-pip-version-check --no-warn-script-location --root-user-action=ignore \
        --target "$site" "mitsuba==$MITSUBA_VERSION" "drjit==$DRJIT_VERSION" >&2
    touch "$stamp"
fi

echo "export CHAMBRE_MITSUBA_SITE='$site'"
echo "export DRJIT_LIBLLVM_PATH='$(llvm)'"
