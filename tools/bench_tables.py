#!/usr/bin/env python3
"""The tables of BENCHMARKS.md from the JSON reports of tools/bench.sh (bench/*.json) and
tools/bench_gpu.sh (bench/gpu/*.json). Python's standard library only.

  python3 tools/bench_tables.py BENCH_DIR                      # print every table it can make
  python3 tools/bench_tables.py BENCH_DIR --update BENCHMARKS.md

Each table of BENCHMARKS.md sits between `<!-- bench:NAME -->` and `<!-- /bench:NAME -->`.
--update rewrites the blocks whose reports are in BENCH_DIR, each with the command that made
it, the commit, the date and the machine above its table, and leaves the others as they are
(it names both kinds on standard error). The commit comes from BENCH_DIR/commit.txt and the
CPU's model from BENCH_DIR/cpu.txt, which tools/bench.sh writes beside the reports.
"""
import json
import os
import sys

import bench_gpu_table

BVH_LABELS = {"bvh2": "BVH2", "cwbvh": "CWBVH", "wide": "wide (CPU)",
              "packets": "wide, packets of 16 (CPU)",
              "stream": "wide, streams of 8 in flight (CPU)"}
QUERIES = {"closest_hit": "closest", "any_hit": "any"}
FERMAT_SCENES = ["sphere", "torus", "ellipsoid", "cylinder", "teapot"]
FERMAT_SIZES = ["640x480", "1280x960", "2560x1920"]


class BenchError(Exception):
    """Bad input: the file (and line) at fault and why."""


def load(folder, name):
    """The JSON report `name` in `folder`, or None when it is not there."""
    path = os.path.join(folder, name)
    if not os.path.exists(path):
        return None
    try:
        with open(path) as f:
            return json.load(f)
    except json.JSONDecodeError as e:
        raise BenchError(f"{path}:{e.lineno}: not JSON: {e.msg}") from e


def read_text(folder, name, default):
    path = os.path.join(folder, name)
    if not os.path.exists(path):
        return default
    with open(path) as f:
        return f.read().strip() or default


def adapter_name(adapter):
    """The adapter with its driver, without the limits chambre appends after ': '."""
    return adapter.split("): max ")[0] + ")" if "): max " in adapter else adapter


def command_line(command):
    """The command as a reader runs it: `chambre` for the binary's path."""
    words = command.split()
    if words and os.path.basename(words[0]) == "chambre":
        words[0] = "chambre"
    return " ".join(words)


def provenance(folder, reports):
    """The lines above a table: each command, then commit, date, CPU and adapter of the run."""
    commands = " and ".join(f"`{command_line(r['command'])}`" for r in reports)
    machine = reports[0]["machine"]
    cpu = read_text(folder, "cpu.txt", "CPU model not recorded")
    commit = read_text(folder, "commit.txt", "unknown")
    return [f"{commands}", "",
            f"Commit `{commit}`, {machine['date_utc']}; {machine['cpu_threads']} CPU threads "
            f"({cpu}); adapter: {adapter_name(machine['adapter'])}.", ""]


def fmt(value, digits=2):
    return "-" if value is None else f"{value:.{digits}f}"


def exponent(value):
    """A float as Rust's `{:e}` writes it (chambre's own tables): `1.700087e6`."""
    mantissa, power = f"{value:.6e}".split("e")
    return f"{mantissa}e{int(power)}"


def spread(s, digits=1):
    """A median with its range: `12.3 (11.9–12.8)`."""
    return f"{s['median']:.{digits}f} ({s['min']:.{digits}f}–{s['max']:.{digits}f})"


def table(header, rows):
    out = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    out += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return out


def rays_rows(report):
    """`bench rays`: every set, query, backend and BVH, with the checksum they must share."""
    reads = {r["set"]: r["bytes_per_ray"] for r in report["cwbvh_reads"]}
    rows = []
    for r in report["results"]:
        rate = r["mrays_per_s"]
        gbs = "-"
        if r["bvh"] == "cwbvh" and r["query"] == "closest_hit" and r["set"] in reads:
            gbs = f"{reads[r['set']] * rate['median'] / 1e3:.0f}"
        rows.append([r["set"], QUERIES[r["query"]], r["backend"], BVH_LABELS[r["bvh"]],
                     spread(rate, 2), gbs, r["checksum"]["hits"],
                     exponent(r["checksum"]["sum_t"])])
    return table(["rays", "query", "backend", "BVH", "Mrays/s median (min–max)",
                  "GB/s read", "hits", "sum of t"], rows)


def frame_rows(report):
    """`bench frame`: a row per scene, a column per backend (ms, and its speed-up over `cpu`)."""
    backends = []
    for result in report["results"]:
        for run in result["runs"]:
            if run["backend"] not in backends:
                backends.append(run["backend"])
    rows = []
    for result in report["results"]:
        runs = {run["backend"]: run for run in result["runs"]}
        cpu = runs.get("cpu")
        cells = []
        for backend in backends:
            run = runs.get(backend)
            if run is None:
                cells.append("-")
                continue
            ms = run["frame_ms"]["median"]
            text = f"{ms:.1f}"
            if cpu is not None and backend != "cpu":
                text += f" ({cpu['frame_ms']['median'] / ms:.2f}x)"
            cells.append(text)
        rows.append([result["scene"], f"{result['width']}x{result['height']} x {result['spp']}",
                     result["triangles"]] + cells)
    return table(["scene", "size x spp", "triangles"] + [f"{b} ms" for b in backends], rows)


def build_rows(report):
    rows = [[r["preset"], spread(r["build_ms"]), r["nodes"], r["depth"], f"{r['sah_cost']:.1f}",
             f"{r['memory_bytes'] / 2**20:.1f}"] for r in report["results"]]
    return table(["preset", "build ms", "nodes", "depth", "SAH cost", "BVH MiB"], rows)


def scale_rows(report):
    rows = []
    for r in report["results"]:
        if r.get("gpu_mrays_per_s"):
            gpu = f"{r['gpu_mrays_per_s']['median']:.2f}"
        else:
            gpu = "refused (binding limit)" if r.get("gpu_refused") else "-"
        rss = r.get("peak_rss_bytes")
        rows.append([r["triangles"], f"{r['build_ms']:.1f}", f"{r['wide_build_ms']:.1f}",
                     r["bvh_nodes"], f"{r['scene_bytes'] / 2**20:.1f}",
                     "-" if rss is None else f"{rss / 2**20:.0f}", BVH_LABELS[r["cpu_bvh"]],
                     f"{r['cpu_mrays_per_s']['median']:.2f}", BVH_LABELS[r["gpu_bvh"]], gpu,
                     r["checksum"]["hits"]])
    return table(["triangles", "build ms", "wide BVHs ms", "BVH nodes", "scene MiB",
                  "peak RSS MiB", "CPU BVH", "CPU Mrays/s", "GPU BVH", "GPU Mrays/s", "hits"],
                 rows)


def motion_rows(report):
    results = report["results"]
    one = results[0]["mrays_per_s"]["median"]
    rows = [[r["slices"], spread(r["build_ms"]), spread(r["mrays_per_s"], 2),
             f"{r['mrays_per_s']['median'] / one:.2f}x", r["hits"]] for r in results]
    return table(["BVH slices", "build ms", "Mrays/s", f"vs {results[0]['slices']} slice",
                  "hits"], rows)


def samplers_rows(report):
    spps = sorted({r["spp"] for r in report["results"]})
    samplers = []
    for r in report["results"]:
        if r["sampler"] not in samplers:
            samplers.append(r["sampler"])
    cell = {(r["sampler"], r["spp"]): r for r in report["results"]}
    rows = [[s] + [f"{cell[s, n]['rmse']:.4f} ({cell[s, n]['cpu_ms']:.0f} ms)"
                   if (s, n) in cell else "-" for n in spps] for s in samplers]
    return table(["lens sampler"] + [f"{n} spp" for n in spps], rows)


def preview_rows(report):
    rows = []
    for r in report["rows"]:
        if not r["shadows"]:
            shadows = "no"
        elif r["area_shadow_samples"] == 1:
            shadows = "yes"
        else:
            n = r["area_shadow_samples"]
            shadows = f"yes, area lights {n}x{n} cubes"
        maps = "-" if r["shadow_maps"] == 0 else \
            f"{r['shadow_maps']} of {r['shadow_map_side']}² in {r['shadow_maps_ms']:.1f} ms"
        rows.append([r["scene"], f"{r['width']}x{r['height']}", r["lights"], shadows,
                     spread(r["frame_ms"], 2), maps, f"{r['flip']:.4f}"])
    return table(["scene", "size", "lights", "shadows", "preview frame (ms)",
                  "shadow maps, drawn once", f"FLIP vs {report['reference_spp']} spp"], rows)


def fermat_accuracy(row):
    return [f"{row['drawn']}/{row['features']}", fmt(row["corner_max_px"], 3),
            fmt(row["displacement_median_px"], 3), fmt(row["displacement_p99_px"], 3),
            fmt(row["displacement_max_px"], 3), fmt(row["flip_reflector"], 4)]


FERMAT_ACCURACY = ["features drawn", "corners: max (px)", "median (px)", "p99 (px)", "max (px)",
                   "FLIP of the mirror"]


def fermat_subdivision_rows(report):
    """One `bench fermat` report: a row per subdivision."""
    rows = [[r["subdivision"], f"{r['reflected_triangles']} ({r['reflected_drawn']})",
             f"{r['preview_ms']['median']:.2f}", f"{r['speedup']['median']:.1f}x"]
            + fermat_accuracy(r) for r in report["rows"]]
    return table(["subdivision", "reflected triangles (drawn)", "preview (ms)",
                  "ray-traced / preview"] + FERMAT_ACCURACY, rows)


def fermat_scene_rows(reports):
    """The five Fermat scenes at subdivision 4 (the 16x16 floor), a row each."""
    rows = []
    for name, report in reports:
        row = next((r for r in report["rows"] if r["subdivision"] == 4), None)
        if row is None:
            continue
        rows.append([name, f"{row['preview_ms']['median']:.2f}",
                     f"{report['ray_traced_gpu_ms']['median']:.2f}",
                     f"{row['speedup']['median']:.1f}x"] + fermat_accuracy(row))
    return table(["mirror", "preview (ms)", "ray-traced 1 spp (ms)", "ray-traced / preview"]
                 + FERMAT_ACCURACY, rows)


def fermat_size_rows(reports):
    rows = []
    for name, report in reports:
        row = report["rows"][0]
        rows.append([name, f"{report['width']}x{report['height']}",
                     f"{row['preview_ms']['median']:.2f}", f"{row['stages']['main_ms']:.2f}",
                     f"{report['ray_traced_gpu_ms']['median']:.2f}",
                     f"{report['ray_traced_gpu_read_ms']['median']:.2f}",
                     f"{row['speedup']['median']:.1f}x"])
    return table(["mirror", "size", "preview (ms)", "main pass alone (ms)",
                  "ray-traced, finished on the device (ms)", "with the image read back (ms)",
                  "ray-traced / preview"], rows)


def single(file, render):
    """A block made from one report."""
    def make(folder):
        report = load(folder, file)
        if report is None:
            return None
        return provenance(folder, [report]) + render(report["report"])
    return make


def fermat_scenes(folder):
    reports = []
    for name in FERMAT_SCENES:
        report = load(folder, "fermat.json" if name == "sphere" else f"fermat_{name}.json")
        if report is not None:
            reports.append((name, report))
    if not reports:
        return None
    return provenance(folder, [r for _, r in reports]) + \
        fermat_scene_rows([(n, r["report"]) for n, r in reports])


def fermat_sizes(folder):
    reports = []
    for name in ("sphere", "teapot"):
        for size in FERMAT_SIZES:
            report = load(folder, f"fermat_{name}_{size}.json")
            if report is not None:
                reports.append((name, report))
    if not reports:
        return None
    return provenance(folder, [r for _, r in reports]) + \
        fermat_size_rows([(n, r["report"]) for n, r in reports])


def gpu_frames(folder):
    """tools/bench_gpu.sh's frames: one report per scene, one table."""
    reports = [load(folder, f"frame_{name}.json") for name in bench_gpu_table.FRAMES]
    reports = [r for r in reports if r is not None]
    if not reports:
        return None
    merged = {"results": [res for r in reports for res in r["report"]["results"]]}
    return provenance(folder, reports[:1]) + frame_rows(merged)


def gpu_peers(folder):
    """tools/bench_gpu.sh's comparison with Mitsuba 3 (tools/bench_gpu_table.py's tables)."""
    peer = load(folder, "mitsuba_rays_coherent.json")
    first = load(folder, "rays_1080p.json")
    if peer is None or first is None:
        return None
    lines = provenance(folder, [first])
    lines[0] = "`CHAMBRE_BIN=... PEER=... tools/bench_gpu.sh`, whose first command is " + lines[0]
    for make in (bench_gpu_table.rays_table, bench_gpu_table.frames_table,
                 bench_gpu_table.dragon_rate, bench_gpu_table.stages_table,
                 bench_gpu_table.scale_table):
        rows = make(folder)
        if rows:
            # The GPU script's own headings become bold lines inside the block.
            lines += [f"**{rows[0].lstrip('# ')}**"] + rows[1:] + [""]
    return lines[:-1]


def on_gpu(make):
    """A block made from the reports of a GPU machine, in BENCH_DIR/gpu."""
    return lambda folder: make(os.path.join(folder, "gpu"))


# The 2-core machine's tables from BENCH_DIR (tools/bench.sh); a GPU machine's from
# BENCH_DIR/gpu (tools/bench_gpu.sh, and `OUT=bench/gpu tools/bench_preview.sh`).
BLOCKS = {
    "rays": single("rays.json", rays_rows),
    "frame": single("frame.json", frame_rows),
    "frame-motion": single("frame_motion.json", frame_rows),
    "motion": single("motion.json", motion_rows),
    "build": single("build.json", build_rows),
    "scale": single("scale.json", scale_rows),
    "samplers": single("samplers.json", samplers_rows),
    "preview": single("preview.json", preview_rows),
    "fermat": fermat_scenes,
    "fermat-sphere": single("fermat.json", fermat_subdivision_rows),
    "fermat-sizes": fermat_sizes,
    "gpu-rays-1080p": on_gpu(single("rays_1080p.json", rays_rows)),
    "gpu-rays": on_gpu(single("rays_1024.json", rays_rows)),
    "gpu-frames": on_gpu(gpu_frames),
    "gpu-scale": on_gpu(single("scale.json", scale_rows)),
    "gpu-fermat": on_gpu(fermat_scenes),
    "gpu-fermat-sizes": on_gpu(fermat_sizes),
    "gpu-peers": on_gpu(gpu_peers),
}


def render_all(folder):
    """Every block the reports in `folder` make, as (name, lines)."""
    out = []
    for name, make in BLOCKS.items():
        lines = make(folder)
        if lines is not None:
            out.append((name, lines))
    return out


def update(text, path, folder):
    """`text` with each block whose reports are in `folder` made anew; (text, made, kept)."""
    lines = text.split("\n")
    out, made, kept = [], [], []
    i = 0
    while i < len(lines):
        line = lines[i]
        out.append(line)
        i += 1
        if not (line.startswith("<!-- bench:") and line.endswith(" -->")):
            continue
        name = line[len("<!-- bench:"):-len(" -->")]
        if name not in BLOCKS:
            raise BenchError(f"{path}:{i}: unknown table `{name}` (known: {', '.join(BLOCKS)})")
        end = f"<!-- /bench:{name} -->"
        try:
            close = lines.index(end, i)
        except ValueError:
            raise BenchError(f"{path}:{i}: table `{name}` has no closing `{end}`") from None
        fresh = BLOCKS[name](folder)
        if fresh is None:
            out += lines[i:close]
            kept.append(name)
        else:
            out += fresh
            made.append(name)
        out.append(end)
        i = close + 1
    return "\n".join(out), made, kept


def write_atomically(path, text):
    temporary = path + ".tmp"
    with open(temporary, "w") as f:
        f.write(text)
    os.replace(temporary, path)


def main(argv):
    if len(argv) not in (2, 4) or (len(argv) == 4 and argv[2] != "--update"):
        sys.exit(__doc__)
    folder = argv[1]
    try:
        if len(argv) == 2:
            for name, lines in render_all(folder):
                print(f"<!-- bench:{name} -->\n" + "\n".join(lines) + f"\n<!-- /bench:{name} -->\n")
            return
        path = argv[3]
        with open(path) as f:
            text, made, kept = update(f.read(), path, folder)
        write_atomically(path, text)
        print(f"{path}: made anew from {folder}: {', '.join(made) or 'none'}; "
              f"kept (no report): {', '.join(kept) or 'none'}", file=sys.stderr)
    except BenchError as e:
        sys.exit(f"error: {e}")
    except (KeyError, TypeError, IndexError) as e:
        sys.exit(f"error: a report in {folder} lacks a field or has the wrong shape: {e!r}")


if __name__ == "__main__":
    main(sys.argv)
