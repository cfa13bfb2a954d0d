"""Mitsuba 3 on `chambre export --mitsuba` scenes, for tests/export.rs (no numpy needed).

  python3 tools/mitsuba_render.py render SCENE.xml SEED OUT.pfm [SCENE.xml SEED OUT.pfm ...]
      renders each scene with the sampler's own sample count and seed SEED, and writes the
      linear RGB image as PFM.
  python3 tools/mitsuba_render.py load SCENE.xml [SCENE.xml ...]
      loads each scene and prints one JSON line about it: what it holds, as Mitsuba read it.

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
    if len(sys.argv) < 3 or sys.argv[1] not in ("render", "load"):
        sys.exit(__doc__)
    {"render": render, "load": load}[sys.argv[1]](sys.argv[2:])


if __name__ == "__main__":
    main()
