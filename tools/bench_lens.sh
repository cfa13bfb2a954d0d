#!/usr/bin/env bash
# What a real lens costs against the thin lens: scenes/double_gauss.toml rendered through its
# prescription and through the thin lens of the same focal length and f-number (the same scene
# with `lens` replaced), side by side, RUNS times each on the CPU path; the median render times
# (chambre's own report) and their ratio.
#   tools/bench_lens.sh [RUNS] [extra render args...]
set -euo pipefail
cd "$(dirname "$0")/.."
runs=${1:-3}
shift || true
bin=${CHAMBRE_BIN:-target/release/chambre}
thin=scenes/.bench_thin_lens.toml
trap 'rm -f "$thin"' EXIT
focal=$("$bin" lens scenes/lenses/dgauss_50mm.dat | awk '/^focal length/ {print $3}')
number=$("$bin" lens scenes/lenses/dgauss_50mm.dat | awk '/^f-number/ {sub("f/", "", $2); print $2}')
sed "s|^lens = .*|focal_length = $focal\nf_number = $number|" scenes/double_gauss.toml > "$thin"
seconds() { "$bin" render "$1" --backend cpu -o /tmp/bench_lens.pfm "${@:2}" 2>&1 |
  sed -n 's/.* spp in \([0-9.]*\) s.*/\1/p'; }
median() { sort -g | awk '{v[NR] = $1} END {print v[int((NR + 1) / 2)]}'; }
real=(); thin_times=()
for _ in $(seq "$runs"); do
  real+=("$(seconds scenes/double_gauss.toml "$@")")
  thin_times+=("$(seconds "$thin" "$@")")
done
r=$(printf '%s\n' "${real[@]}" | median)
t=$(printf '%s\n' "${thin_times[@]}" | median)
echo "| real lens (double Gauss, f/$number) | thin lens (f = $focal mm) | real / thin |"
echo "|---|---|---|"
echo "| $r s | $t s | $(awk -v a="$r" -v b="$t" 'BEGIN {printf "%.2fx", a / b}') |"
