#!/usr/bin/env python3
"""The tables of tools/bench_gpu.sh from the JSON reports in one folder: chambre's ray queries,
frames and scale beside Mitsuba 3's on the same GPU, with the ratios the GPU-frames targets are
stated in. Python's standard library only.

  python3 tools/bench_gpu_table.py OUT_DIR
"""
import json
import os
import sys

FRAMES = ["dragon", "cornell_direct", "thin_lens", "tabletop", "bunny", "mirrors",
          "cornell_path", "interior"]


def load(folder, name):
    path = os.path.join(folder, name)
    if not os.path.exists(path):
        return None
    with open(path) as f:
        return json.load(f)


def fmt(value, digits=1):
    return "-" if value is None else f"{value:,.{digits}f}"


def ratio(a, b):
    return "-" if a is None or b is None or b == 0 else f"{a / b:.2f}x"


def gpu_rays(report, set_name, query):
    """chambre's GPU CWBVH rate (Mrays/s median) for a ray set and query."""
    if report is None:
        return None
    names = {"closest": "closest_hit", "any": "any_hit"}
    for r in report["report"]["results"]:
        if (r["set"] == set_name and r["query"] == names[query]
                and str(r["bvh"]).lower() == "cwbvh" and "gpu" in r["backend"]
                and "checks:" not in r["backend"]):
            return r["mrays_per_s"]["median"]
    return None


def rays_table(folder):
    chambre = load(folder, "rays_1080p.json")
    peers = {s: load(folder, f"mitsuba_rays_{s}.json") for s in ("coherent", "incoherent")}
    size = "1920x1080 x 8 frames"
    if chambre is not None:
        config = chambre["report"]["config"]
        size = f"{config['camera']['width']}x{config['camera']['height']} x {config['frames']} frames"
    out = [f"## Ray queries: the dragon, {size} (Mrays/s, medians)", "",
           "| rays | query | chambre CWBVH | Mitsuba 3 | chambre / Mitsuba |", "|---|---|---|---|---|"]
    for set_name in ("coherent", "incoherent"):
        for query in ("closest", "any"):
            c = gpu_rays(chambre, set_name, query)
            peer = peers[set_name]
            m = peer[query]["mrays_per_s"] if peer else None
            out.append(f"| {set_name} | {query} | {fmt(c)} | {fmt(m)} | {ratio(c, m)} |")
    return out


def frame_runs(report):
    result = report["report"]["results"][0]
    return result, {r["backend"]: r for r in result["runs"]}


def frames_table(folder):
    out = ["## Frames (ms, medians; `frame` includes the image's read-back, as Mitsuba's does)", "",
           "| scene | size x spp | megakernel frame | wavefront frame (traced) | Mitsuba 3 | "
           "best chambre / Mitsuba time |", "|---|---|---|---|---|---|"]
    for name in FRAMES:
        report = load(folder, f"frame_{name}.json")
        if report is None:
            continue
        result, runs = frame_runs(report)
        mega, wave = runs.get("gpu-mega"), runs.get("gpu-wave")
        peer = load(folder, f"mitsuba_frame_{name}.json")
        m = peer["median_s"] * 1e3 if peer else None
        best = min(r["frame_ms"]["median"] for r in (mega, wave) if r)
        wave_text = "-" if wave is None else \
            f"{fmt(wave['frame_ms']['median'])} ({fmt(wave['traced_ms']['median'])})"
        out.append(f"| {name} | {result['width']}x{result['height']} x {result['spp']} | "
                   f"{fmt(mega['frame_ms']['median']) if mega else '-'} | {wave_text} | "
                   f"{fmt(m)} | {ratio(best, m)} |")
    return out


def dragon_rate(folder):
    """The dragon frame's camera-ray rate against the ray-query kernel's on the same rays."""
    report = load(folder, "frame_dragon.json")
    rays = load(folder, "rays_1024.json")
    if report is None:
        return []
    result, runs = frame_runs(report)
    camera_rays = result["width"] * result["height"] * result["spp"]
    query = gpu_rays(rays, "coherent", "closest")
    out = [f"## The dragon frame's camera rays against the ray-query kernel ({result['width']}x"
           f"{result['height']} x {result['spp']})", "",
           "| measure | Mrays/s | of the ray-query kernel's |", "|---|---|---|",
           f"| ray-query kernel, coherent closest hit | {fmt(query)} | 100% |"]
    for backend in ("gpu-mega", "gpu-wave"):
        run = runs.get(backend)
        if run is None:
            continue
        for label, key in (("frame, read-back included", "frame_ms"), ("frame until traced", "traced_ms")):
            rate = camera_rays / run[key]["median"] / 1e3
            share = "-" if not query else f"{100 * rate / query:.0f}%"
            out.append(f"| {backend} {label} | {fmt(rate, 2)} | {share} |")
    closest = next((s for s in result.get("stages", []) if s["kernel"] == "wf_closest"), None)
    if closest and closest["ms"] > 0:
        rate = camera_rays / closest["ms"] / 1e3
        share = "-" if not query else f"{100 * rate / query:.0f}%"
        out.append(f"| wf_closest kernel alone (profiled) | {fmt(rate, 2)} | {share} |")
    return out


def stages_table(folder):
    out = ["## Where a wavefront frame's device time goes (one profiled render)", "",
           "| scene | kernel | ms | share |", "|---|---|---|---|"]
    any_stage = False
    for name in FRAMES:
        report = load(folder, f"frame_{name}.json")
        if report is None:
            continue
        stages = report["report"]["results"][0].get("stages", [])
        total = sum(s["ms"] for s in stages) or 1.0
        for s in stages:
            any_stage = True
            out.append(f"| {name} | {s['kernel']} | {s['ms']:.2f} | {100 * s['ms'] / total:.0f}% |")
    return out if any_stage else []


def scale_table(folder):
    report = load(folder, "scale.json")
    if report is None:
        return []
    far = load(folder, "scale_far.json")
    out = ["## Scale: 512x512 camera rays on the dragon and copies beside it (Mrays/s)", "",
           "| scene | triangles | chambre | chambre's share of one dragon's rate | Mitsuba 3 | "
           "Mitsuba's share |", "|---|---|---|---|---|---|"]
    rate = lambda r: r["gpu_mrays_per_s"]["median"] if r.get("gpu_mrays_per_s") else None
    rows = report["report"]["results"]
    plain = [r for r in rows if r.get("padding_bytes", 0) == 0]
    first = rate(plain[0]) if plain else None
    peer_first = None
    for copies, r in zip([1, 4, 12], plain):
        c = rate(r)
        peer = load(folder, f"mitsuba_scale_{copies}.json")
        m = peer["closest"]["mrays_per_s"] if peer else None
        peer_first = peer_first or m
        share = "-" if not (c and first) else f"{100 * c / first:.0f}%"
        peer_share = "-" if not (m and peer_first) else f"{100 * m / peer_first:.0f}%"
        label = "the dragon" if copies == 1 else f"{copies} dragons, 1.1 widths apart"
        out.append(f"| {label} | {r['triangles']:,} | {fmt(c)} | {share} | {fmt(m)} | {peer_share} |")
    for r in rows:
        if r.get("padding_bytes", 0):
            c = rate(r)
            share = "-" if not (c and first) else f"{100 * c / first:.0f}%"
            label = f"the dragon, primitives padded by {r['padding_bytes'] >> 20} MiB unread"
            out.append(f"| {label} | {r['triangles']:,} | {fmt(c)} | {share} | - | - |")
    if far:
        far_plain = [r for r in far["report"]["results"] if r.get("padding_bytes", 0) == 0]
        for copies, r in zip([1, 4, 12], far_plain):
            if copies == 1:
                continue
            c = rate(r)
            share = "-" if not (c and first) else f"{100 * c / first:.0f}%"
            label = f"{copies} dragons, 50 widths apart (no ray reaches the others)"
            out.append(f"| {label} | {r['triangles']:,} | {fmt(c)} | {share} | - | - |")
    return out


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    folder = sys.argv[1]
    adapter = open(os.path.join(folder, "adapter.txt")).read().strip() \
        if os.path.exists(os.path.join(folder, "adapter.txt")) else "unknown"
    commit = open(os.path.join(folder, "commit.txt")).read().strip() \
        if os.path.exists(os.path.join(folder, "commit.txt")) else "unknown"
    lines = [f"# chambre against Mitsuba 3 on one GPU", "",
             f"Adapter: {adapter}", f"Commit: {commit}", ""]
    for table in (rays_table, frames_table, dragon_rate, stages_table, scale_table):
        rows = table(folder)
        if rows:
            lines += rows + [""]
    print("\n".join(lines))


if __name__ == "__main__":
    main()
