#!/usr/bin/env bash
# chambre's CPU path against Embree 3 on the very same rays, side by side in one run.
#
# Installs Debian's libembree-dev and a C++ compiler where missing, builds tools/embree/
# (Embree's one-ray and 16-wide packet APIs on rays read from files), has chambre write its
# mesh and ray sets (`chambre bench rays --write-rays`), then alternates the two benchmarks
# ROUNDS times (chambre, Embree, chambre, Embree, ...: a shared machine's load falls on both),
# each with RUNS timed runs after a warm-up, and summarises: the median over the rounds of each
# one's median Mrays/s, the median of the rounds' ratios, whether both found the same hits.
#
# Usage: tools/bench_embree.sh [ROUNDS] [RUNS]   (default 2 rounds of 5 runs)
# FRAMES (default 8) and SIZE (default 1024) set the camera's rays, SIZE x SIZE x FRAMES;
# BVH (default all of chambre's CPU variants) is passed to `--bvh`; CHAMBRE_BIN runs a binary
# built elsewhere; CHAMBRE_BASE, a second chambre binary (a baseline: before a change), is
# measured too, just before the first in each round. Writes bench/embree/ (the JSON reports and
# summary.md).
set -euo pipefail
cd "$(dirname "$0")/.."
rounds="${1:-2}"
runs="${2:-5}"
frames="${FRAMES:-8}"
size="${SIZE:-1024}"
bvh="${BVH:-bvh2,cwbvh,wide,packets,stream}"
SUDO=""
[ "$(id -u)" -ne 0 ] && SUDO="sudo"

if [ ! -f /usr/include/embree3/rtcore.h ] || ! command -v c++ >/dev/null; then
    echo "== installing libembree-dev and g++" >&2
    $SUDO apt-get update -qq >&2
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq libembree-dev g++ >/dev/null
fi
embree_version=$(dpkg-query -W -f='${Version}' libembree-dev 2>/dev/null || echo unknown)

out=bench/embree
mkdir -p "$out" target/embree
tool=target/embree/bench_embree
if [ ! -x "$tool" ] || [ tools/embree/bench_embree.cpp -nt "$tool" ]; then
    echo "== building $tool" >&2
    c++ -O2 -std=c++17 -Wall -Wextra -o "$tool" tools/embree/bench_embree.cpp \
        -lembree3 -lpthread
fi

chambre="${CHAMBRE_BIN:-./target/release/chambre}"
if [ -z "${CHAMBRE_BIN:-}" ]; then
    cargo build --release --bin chambre
fi
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
camera=(--width "$size" --height "$size" --frames "$frames")
"$chambre" bench rays "${camera[@]}" --write-rays target/embree/rays >&2

rm -f "$out"/chambre_*.json "$out"/base_*.json "$out"/embree_*.json "$out"/load_*.txt
for round in $(seq 1 "$rounds"); do
    if [ -n "${CHAMBRE_BASE:-}" ]; then
        "$CHAMBRE_BASE" bench rays --backends cpu --bvh "$bvh" "${camera[@]}" --runs "$runs" \
            --json "$out/base_$round.json" >&2
    fi
    uptime > "$out/load_chambre_$round.txt"
    "$chambre" bench rays --backends cpu --bvh "$bvh" "${camera[@]}" --runs "$runs" \
        --json "$out/chambre_$round.json" >&2
    uptime > "$out/load_embree_$round.txt"
    "$tool" target/embree/rays --runs "$runs" --json "$out/embree_$round.json" >&2
done

python3 - "$out" "$rounds" "$embree_version" \
    "$(git rev-parse --short HEAD)$(git diff --quiet HEAD -- src || echo ' (with uncommitted changes to src/)')" \
    "$chambre bench rays --backends cpu --bvh $bvh ${camera[*]} --runs $runs" \
    "$tool target/embree/rays --runs $runs" <<'PY' | tee "$out/summary.md"
import json, os, platform, statistics, subprocess, sys

out, rounds, embree_version, commit, chambre_cmd, embree_cmd = sys.argv[1:]
rounds = int(rounds)
chambre = [json.load(open(f"{out}/chambre_{r}.json")) for r in range(1, rounds + 1)]
base = [json.load(open(f"{out}/base_{r}.json")) for r in range(1, rounds + 1)
        if os.path.exists(f"{out}/base_{r}.json")]
embree = [json.load(open(f"{out}/embree_{r}.json")) for r in range(1, rounds + 1)]
loads = [open(f"{out}/load_{who}_{r}.txt").read().split("load average:")[1].strip()
         for r in range(1, rounds + 1) for who in ("chambre", "embree")]
model = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo")
              if l.startswith("model name")), platform.processor())
flags = next((l.split(":", 1)[1].split() for l in open("/proc/cpuinfo")
              if l.startswith("flags")), [])
isa = "AVX-512" if "avx512f" in flags else "AVX2" if "avx2" in flags else "SSE"
sys.path.insert(0, "tools")
from bench_tables import BVH_LABELS as bvh_label

def rows(report, key):
    return {key(r): r for r in report}

def chambre_key(r):
    return (r["set"], "closest" if r["query"] == "closest_hit" else "any", r["bvh"])

def embree_key(r):
    return (r["set"], r["query"], r["api"])

c_rows = [rows(c["report"]["results"], chambre_key) for c in chambre]
b_rows = [rows(c["report"]["results"], chambre_key) for c in base]
e_rows = [rows(e["results"], embree_key) for e in embree]
med = statistics.median
print(f"chambre against Embree {embree_version}, {chambre[0]['machine']['date_utc']}, commit "
      f"{commit}: {os.cpu_count()} cores ({model}, {isa}), {chambre[0]['machine']['cpu_threads']} "
      f"chambre threads, {embree[0]['threads']} Embree threads, Embree's 16-wide packets "
      f"{'native' if embree[0]['native_ray16'] else 'emulated'}; {rounds} rounds alternating "
      f"chambre and Embree, each the median of {embree[0]['runs']} runs after a warm-up; "
      f"load averages (1, 5, 15 min) before each: {'; '.join(loads)}\n")
if base:
    print(f"- chambre (base): `{os.environ['CHAMBRE_BASE']}`, the same arguments, just before "
          "chambre in each round")
print(f"- chambre: `{chambre_cmd}`\n- Embree: `{embree_cmd}` (tools/embree/bench_embree.cpp, "
      f"built by tools/bench_embree.sh)\n")
print("Mrays/s: the median over the rounds of each round's median (the rounds' medians' range "
      "beside it); a ratio is the median of the rounds' ratios. Embree's packets of 16 take the "
      "camera's rays as 4x4 pixels, the incoherent rays sixteen consecutive ones; \"coherent "
      "flag\": RTC_INTERSECT_CONTEXT_FLAG_COHERENT, the others the context's default flags.\n")
apis = ["one ray", "packets of 16", "packets of 16, coherent flag"]
print("| rays | query | tracer | Mrays/s | rounds' range | / Embree one ray | / Embree 16 | "
      "/ Embree 16, coherent flag | hits | mean t |")
print("|---|---|---|---|---|---|---|---|---|---|")

def speed(r):
    return r["mrays_per_s"]["median"] if "mrays_per_s" in r else r["median"]

def checksum(r):
    return (r["checksum"]["hits"], r["checksum"]["sum_t"]) if "checksum" in r \
        else (r["hits"], r["sum_t"])

problems = []
for s in ("coherent", "incoherent"):
    for q in ("closest", "any"):
        embree_apis = [a for a in apis if (s, q, a) in e_rows[0]]
        lines = [(f"Embree, {a}", [e[(s, q, a)] for e in e_rows]) for a in embree_apis]
        for b in [k[2] for k in c_rows[0] if k[0] == s and k[1] == q]:
            if b_rows:
                lines.append((f"chambre (base), {bvh_label[b]}", [c[(s, q, b)] for c in b_rows]))
            lines.append((f"chambre, {bvh_label[b]}", [c[(s, q, b)] for c in c_rows]))
        reference = lines[0][1][0]
        for name, rs in lines:
            m = [speed(r) for r in rs]
            ratios = []
            for a in apis:
                if a not in embree_apis:
                    ratios.append("-")
                    continue
                base = [e[(s, q, a)] for e in e_rows]
                ratios.append(f"{med([x / speed(b) for x, b in zip(m, base)]):.2f}x")
            hits, sum_t = checksum(rs[0])
            mean_t = f"{sum_t / hits:.7f}" if q == "closest" and hits else "-"
            print(f"| {s} | {q} | {name} | {med(m):.2f} | {min(m):.2f}-{max(m):.2f} | "
                  f"{' | '.join(ratios)} | {hits} | {mean_t} |")
            # The same hits as Embree's one-ray API: counts within 0.01% of the rays, mean
            # distances within 1e-5 relative.
            e_hits, e_sum = checksum(reference)
            if abs(hits - e_hits) > 1e-4 * rs[0]["rays"]:
                problems.append(f"{s} {q} {name}: {hits} hits, Embree one ray {e_hits}")
            if q == "closest" and hits and e_hits and \
                    abs(sum_t / hits - e_sum / e_hits) > 1e-5 * (e_sum / e_hits):
                problems.append(f"{s} {q} {name}: mean t {sum_t / hits}, Embree {e_sum / e_hits}")
print()
if problems:
    print("NOT THE SAME HITS:\n" + "\n".join(f"- {p}" for p in problems))
    sys.exit(1)
print("Every tracer found the same hits as Embree's one-ray API: counts within 0.01% of the "
      "rays, mean distances within 1e-5 (relative).")
PY
