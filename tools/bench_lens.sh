#!/usr/bin/env bash
# What a real lens costs against the thin lens: scenes/double_gauss.toml rendered through its
# prescription and through the thin lens of the same focal length and f-number (the same scene
# with `lens` replaced), side by side, RUNS times each on the CPU path; the median render times
# (chambre's own report) and their ratio; then `chambre converge` on both at 120 x 80 (Sobol,
# up to 64 spp, each against its own 1024 spp reference): the error each reaches and the time it
# takes, so that the trade (noise from rays the glass blocks against the thin lens) is measured.
# Then the spectral mode against the same lens traced at its reference line alone:
# scenes/spectral_singlet.toml with `camera.spectral` true and false, the same two measures.
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
# Side by side, RUNS times: the median render times of scene $1 and of scene $2 (each with the
# `--set` of $3 and $4, or none) and their ratio, as a table row.
side_by_side() {
  local first=() second=() a b
  for _ in $(seq "$runs"); do
    first+=("$(seconds "$1" ${3:+--set "$3"} "${extra[@]}")")
    second+=("$(seconds "$2" ${4:+--set "$4"} "${extra[@]}")")
  done
  a=$(printf '%s\n' "${first[@]}" | median)
  b=$(printf '%s\n' "${second[@]}" | median)
  echo "| $a s | $b s | $(awk -v a="$a" -v b="$b" 'BEGIN {printf "%.2fx", a / b}') |"
}
extra=("$@")
echo "| real lens (double Gauss, f/$number) | thin lens (f = $focal mm) | real / thin |"
echo "|---|---|---|"
side_by_side scenes/double_gauss.toml "$thin"

converge_row() {
  "$bin" converge "$1" --set render.width=120 --set render.height=80 ${3:+--set "$3"} --samplers sobol \
    --backends cpu --max-spp 64 --reference-spp 1024 --csv "/tmp/bench_lens_$2.csv" --no-plot 2>&1 |
    awk -F'|' '/^\| cpu sobol \| -?[0-9]/ {gsub(/ /, "", $0); print $4 "|" $6 "|" $8; exit}'
}
echo
echo "| camera | spp | relMSE | wall ms | relMSE x time (lower is better) |"
echo "|---|---|---|---|---|"
for pair in "real lens:scenes/double_gauss.toml" "thin lens:$thin"; do
  name=${pair%%:*}; scene=${pair#*:}
  IFS='|' read -r spp rel ms <<< "$(converge_row "$scene" "${name// /_}")"
  echo "| $name | $spp | $rel | $ms | $(awk -v a="$rel" -v b="$ms" 'BEGIN {printf "%.3e", a * b}') |"
done

spectral=scenes/spectral_singlet.toml
echo
echo "| spectral (N-BK7 singlet, f/5) | reference line only | spectral / reference |"
echo "|---|---|---|"
side_by_side "$spectral" "$spectral" "" camera.spectral=false
echo
echo "| camera | spp | relMSE | wall ms | relMSE x time (lower is better) |"
echo "|---|---|---|---|---|"
for pair in "spectral:camera.spectral=true" "reference line only:camera.spectral=false"; do
  name=${pair%%:*}; set=${pair#*:}
  IFS='|' read -r spp rel ms <<< "$(converge_row "$spectral" "${name// /_}" "$set")"
  echo "| $name | $spp | $rel | $ms | $(awk -v a="$rel" -v b="$ms" 'BEGIN {printf "%.3e", a * b}') |"
done
