#!/usr/bin/env python3
"""What each bounce of chambre's path tracer costs and buys, against Mitsuba 3's `path`
integrator on the same scene (llvm_ad_rgb on the CPU; Python's standard library only).

  python3 tools/bench_path.py [--chambre BIN] [--runs N] [--rounds R] [--out DIR]

On the path-traced Cornell box (`scenes/cornell_box.toml`, its light's triangles reflecting
too) at 64 x 64 and 256 spp: a reference from chambre at max_depth 32 and 4096 spp; then for each
max_depth, chambre's render time (its own report: the render, not the scene's loading) and
relMSE against the reference, and the same for Mitsuba (`chambre export --mitsuba`, then
tools/mitsuba_render.py time: kernels compiled once, each render waited for; the relMSE of its
last run). R rounds alternate the two, N runs each after a warm-up, so that a shared machine's
load falls on both: the seconds are the medians of all runs, the ratio the median of the
rounds' ratios (their range beside it). Writes DIR/path.json and prints the table
BENCHMARKS.md shows. Mitsuba comes from CHAMBRE_MITSUBA_SITE (`eval "$(tools/install_mitsuba.sh)"`)
or PYTHONPATH; without it the Mitsuba columns say so.
"""
import argparse
import json
import os
import re
import statistics
import struct
import subprocess
import sys
import time

SCENE = "scenes/cornell_box.toml"
FRAMING = ["render.integrator=\"path\"", "render.width=64", "render.height=64"]
DEPTHS = [0, 1, 2, 3, 4, 6, 8]
SPP = 256
REFERENCE = {"spp": 4096, "max_depth": 32}


def read_pfm(path):
    """(width, height, [r, g, b, ...]) of a colour PFM, top row first."""
    with open(path, "rb") as f:
        data = f.read()
    parts = data.split(b"\n", 3)
    if parts[0].strip() != b"PF":
        raise SystemExit(f"{path}: not a colour PFM")
    width, height = map(int, parts[1].split())
    scale = float(parts[2])
    fmt = "<" if scale < 0 else ">"
    values = struct.unpack(fmt + "f" * (3 * width * height), parts[3][: 12 * width * height])
    rows = [values[3 * width * y: 3 * width * (y + 1)] for y in range(height)]
    return width, height, [v for row in reversed(rows) for v in row]


def rel_mse(image, reference):
    """Mean of (x - r)^2 / (r^2 + 0.01) over pixels and channels (`chambre::metrics`)."""
    return sum((x - r) ** 2 / (r * r + 0.01) for x, r in zip(image, reference)) / len(image)


def sets(pairs):
    return [a for p in pairs for a in ("--set", p)]


def chambre_render(binary, out, spp, max_depth, seed):
    """The render's seconds as chambre reports them (`... spp in X s`)."""
    args = [binary, "render", SCENE, "--backend", "cpu", "-o", out, *sets(FRAMING),
            *sets([f"render.spp={spp}", f"render.max_depth={max_depth}", f"render.seed={seed}",
                   "render.rr_depth=5"])]
    run = subprocess.run(args, capture_output=True, text=True)
    if run.returncode != 0:
        raise SystemExit(f"chambre render failed: {run.stderr}")
    found = re.search(r"spp in ([0-9.]+) s", run.stderr)
    if not found:
        raise SystemExit(f"no render time in chambre's report: {run.stderr}")
    return float(found.group(1))


def with_mitsuba_site():
    """The environment with CHAMBRE_MITSUBA_SITE on Python's path, for Mitsuba's runs."""
    env = dict(os.environ)
    site = env.get("CHAMBRE_MITSUBA_SITE")
    if site:
        env["PYTHONPATH"] = os.pathsep.join(p for p in (site, env.get("PYTHONPATH")) if p)
    return env


def mitsuba_available():
    try:
        subprocess.run([sys.executable, "-c", "import mitsuba"], check=True,
                       capture_output=True, env=with_mitsuba_site())
        return True
    except subprocess.CalledProcessError:
        return False


def mitsuba_render(binary, out_dir, max_depth, runs):
    """Mitsuba's render seconds (one a run) and its last image, on chambre's export."""
    xml = os.path.join(out_dir, f"path_mitsuba_{max_depth}.xml")
    export = [binary, "export", SCENE, "--mitsuba", xml, *sets(FRAMING),
              *sets([f"render.spp={SPP}", f"render.max_depth={max_depth}", "render.rr_depth=5"])]
    subprocess.run(export, check=True, capture_output=True)
    pfm = os.path.join(out_dir, f"path_mitsuba_{max_depth}.pfm")
    run = subprocess.run([sys.executable, "tools/mitsuba_render.py", "time", xml, str(runs), pfm],
                         check=True, capture_output=True, text=True, env=with_mitsuba_site())
    return json.loads(run.stdout.strip().splitlines()[-1])["seconds"], read_pfm(pfm)[2]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--chambre", default="target/release/chambre")
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--out", default="bench")
    args = parser.parse_args()
    os.makedirs(args.out, exist_ok=True)
    reference_pfm = os.path.join(args.out, "path_reference.pfm")
    started = time.time()
    chambre_render(args.chambre, reference_pfm, REFERENCE["spp"], REFERENCE["max_depth"], 1)
    reference = read_pfm(reference_pfm)[2]
    peer = mitsuba_available()
    rows = []
    for depth in DEPTHS:
        pfm = os.path.join(args.out, f"path_chambre_{depth}.pfm")
        chambre_render(args.chambre, pfm, SPP, depth, 100)  # warm-up
        seconds, errors, m_seconds, ratios = [], [], [], []
        for _ in range(args.rounds):
            ours = []
            for run in range(args.runs):
                ours.append(chambre_render(args.chambre, pfm, SPP, depth, 2 + len(seconds)))
                seconds.append(ours[-1])
                errors.append(rel_mse(read_pfm(pfm)[2], reference))
            if peer:
                theirs, image = mitsuba_render(args.chambre, args.out, depth, args.runs)
                m_seconds += theirs
                ratios.append(statistics.median(ours) / statistics.median(theirs))
        row = {"max_depth": depth, "chambre_s": statistics.median(seconds),
               "chambre_rel_mse": statistics.median(errors)}
        if peer:
            row["mitsuba_s"] = statistics.median(m_seconds)
            row["mitsuba_rel_mse"] = rel_mse(image, reference)
            row["ratio"] = statistics.median(ratios)
            row["ratio_range"] = [min(ratios), max(ratios)]
        rows.append(row)
        print(json.dumps(row), file=sys.stderr, flush=True)
    report = {"scene": SCENE, "overrides": FRAMING, "spp": SPP, "reference": REFERENCE,
              "runs": args.runs, "rounds": args.rounds, "rows": rows, "mitsuba": peer,
              "seconds": time.time() - started}
    with open(os.path.join(args.out, "path.json"), "w") as f:
        json.dump(report, f, indent=1)
    print(table(report))


def table(report):
    lines = ["| max_depth | chambre (s) | relMSE | Mitsuba 3 (s) | relMSE | time, chambre / Mitsuba (rounds) |",
             "|---|---|---|---|---|---|"]
    for r in report["rows"]:
        if "mitsuba_s" in r:
            low, high = r["ratio_range"]
            peer = (f"{r['mitsuba_s']:.3f} | {r['mitsuba_rel_mse']:.2e} | "
                    f"{r['ratio']:.2f}x ({low:.2f}–{high:.2f})")
        else:
            peer = "- | - | Mitsuba not installed"
        lines.append(f"| {r['max_depth']} | {r['chambre_s']:.3f} | "
                     f"{r['chambre_rel_mse']:.2e} | {peer} |")
    return "\n".join(lines)


if __name__ == "__main__":
    main()
