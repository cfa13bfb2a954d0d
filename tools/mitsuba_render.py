"""Mitsuba 3 on `chambre export --mitsuba` scenes, for tests/export.rs (no numpy needed).

  python3 tools/mitsuba_render.py render SCENE.xml SEED OUT.pfm [SCENE.xml SEED OUT.pfm ...]
      renders each scene with the sampler's own sample count and seed SEED, and writes the
      linear RGB image as PFM.
  python3 tools/mitsuba_render.py load SCENE.xml [SCENE.xml ...]
      loads each scene and prints one JSON line about it: what it holds, as Mitsuba read it.
  python3 tools/mitsuba_render.py time SCENE.xml RUNS OUT.pfm
      renders the scene once to compile its kernels, then RUNS times (seeds 1..RUNS, each
      waited for), prints one JSON line with each run's seconds, and writes the last image.

Variant: MI_VARIANT (default llvm_ad_rgb, which needs DRJIT_LIBLLVM_PATH to name a libLLVM,
16 or newer, where Dr.Jit does not find one). Mitsuba comes from PYTHONPATH
(tools/install_mitsuba.sh installs it into target/mitsuba-site).
"""
import json
import os
import sys


def mitsuba():
    import mitsuba as mi
    mi.set_variant(os.environ.get("MI_VARIANT", "llvm_ad_rgb"))
    return mi


def render(args):
    mi = mitsuba()
    if len(args) % 3:
        sys.exit("render takes SCENE.xml SEED OUT.pfm triples")
    for xml, seed, out in zip(args[0::3], args[1::3], args[2::3]):
        scene = mi.load_file(xml)
        image = mi.render(scene, seed=int(seed))
        mi.Bitmap(image).write(out)


def time_renders(args):
    import time
    mi = mitsuba()
    if len(args) != 3:
        sys.exit("time takes SCENE.xml RUNS OUT.pfm")
    xml, runs, out = args[0], int(args[1]), args[2]
    import drjit as dr
    scene = mi.load_file(xml)

    def finished(image):
        # The render is lazy until evaluated; wait for the kernels, without numpy.
        dr.eval(image)
        dr.sync_thread()
        return image

    finished(mi.render(scene, seed=0))
    seconds = []
    for seed in range(1, runs + 1):
        start = time.perf_counter()
        image = finished(mi.render(scene, seed=seed))
        seconds.append(time.perf_counter() - start)
    mi.Bitmap(image).write(out)
    print(json.dumps({"scene": xml, "seconds": seconds}), flush=True)


def kind(obj):
    """The plugin's class as Mitsuba prints it, e.g. PerspectiveCamera."""
    return str(obj).split("[", 1)[0].strip()


def load(args):
    mi = mitsuba()
    for xml in args:
        scene = mi.load_file(xml)
        sensor = scene.sensors()[0]
        film = sensor.film()
        print(json.dumps({
            "scene": xml,
            "sensor": kind(sensor),
            "spp": sensor.sampler().sample_count(),
            "sampler": kind(sensor.sampler()),
            "size": [int(film.size()[0]), int(film.size()[1])],
            "integrator": kind(scene.integrator()),
            "shapes": len(scene.shapes()),
            "emitters": len(scene.emitters()),
        }), flush=True)


def main():
    commands = {"render": render, "load": load, "time": time_renders}
    if len(sys.argv) < 3 or sys.argv[1] not in commands:
        sys.exit(__doc__)
    commands[sys.argv[1]](sys.argv[2:])


if __name__ == "__main__":
    main()
