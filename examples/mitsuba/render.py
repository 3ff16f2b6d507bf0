# SPDX-License-Identifier: MIT
"""Renders one of the example scenes with the btdftab plugin (docs/mitsuba3.md).

    python examples/mitsuba/render.py face|glass TABLE OUT.png [--mode table|analytic]
        [--part both|transmission|reflection] [--variant llvm_ad_rgb] [--spp 64]
        [--res N] [--bsdf btdftab|roughdielectric]
    python examples/mitsuba/render.py pane BACK OUT.png [--smoothness S]
        [--model xu-sun|smith|full] [--variant ...] [--spp 64] [--res N]

face: examples/mitsuba/face.xml, the rough face of a block lit from inside (the paper's
Fig. 11), 256 x 256 by default; glass: examples/mitsuba/glass.xml, a rough glass sphere
holding both lobes, 160 x 160 by default (--part applies to it only; --bsdf
roughdielectric renders it with Mitsuba's own rough dielectric instead, Beckmann with
alpha = 2/s and the table's n, for a picture beside the plugin's); pane:
examples/mitsuba/pane.xml, a frosted pane drawn as one thin surface (btdftab_pane)
before a checkered wall and two balls, 256 x 256 by default, its back face BACK
(smooth, or the back face's smoothness) in place of a table.
Writes OUT.png (sRGB) and OUT-linear.exr (linear), and prints the render time. An
output that would replace an input (the table, the scene) or the other output is
refused before any work (exit status 2).
"""
import argparse
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "python"))  # the checkout's plugin

import mitsuba as mi  # noqa: E402

RES = {"face": 256, "glass": 160, "pane": 256}
ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
ap.add_argument("scene", choices=sorted(RES))
ap.add_argument("table", help="the table (pane: the back face, smooth or S)")
ap.add_argument("out")
ap.add_argument("--mode", default="table", choices=["table", "analytic"])
ap.add_argument("--part", default="both", choices=["both", "transmission", "reflection"])
ap.add_argument("--variant", default="llvm_ad_rgb")
ap.add_argument("--spp", type=int, default=64)
ap.add_argument("--res", type=int, default=0, help="image side in pixels (0: the scene's)")
ap.add_argument("--bsdf", default="btdftab", choices=["btdftab", "roughdielectric"],
                help="glass: the sphere's BSDF (roughdielectric: Mitsuba's, same n and s)")
ap.add_argument("--smoothness", type=float, default=3.0, help="pane: the front's s")
ap.add_argument("--model", default="xu-sun", choices=["xu-sun", "smith", "full"],
                help="pane: the faces' model")
a = ap.parse_args()
res = a.res or RES[a.scene]
scene_xml = os.path.join(HERE, a.scene + ".xml")
out_exr = os.path.splitext(a.out)[0] + "-linear.exr"


def same_file(p, q):
    """True when paths p and q name one file (existing or not)."""
    if os.path.exists(p) and os.path.exists(q):
        return os.path.samefile(p, q)
    return os.path.realpath(p) == os.path.realpath(q)


for o in (a.out, out_exr):
    for name, i in ((("the table", a.table),) if a.scene != "pane" else ()) + (
            ("the scene", scene_xml),):
        if same_file(o, i):
            ap.error("output %s would replace %s %s: choose another OUT" % (o, name, i))
if same_file(a.out, out_exr):
    ap.error("OUT %s is also the linear picture's name: give OUT a .png name" % a.out)
try:
    mi.set_variant(a.variant)
except (ImportError, AttributeError) as e:
    sys.exit("variant %s: %s\n(llvm variants need libLLVM 16 or newer: on Debian 12 "
             "apt-get install libllvm19 and set DRJIT_LIBLLVM_PATH="
             "/usr/lib/x86_64-linux-gnu/libLLVM-19.so; or --variant scalar_rgb, slower)"
             % (a.variant, e))
import btdftab_mitsuba  # noqa: E402,F401  (registers `btdftab`, `btdftab_pane`)

params = dict(filename=os.path.abspath(a.table), mode=a.mode, spp=str(a.spp), res=str(res))
if a.scene == "pane":
    params = dict(back=a.table, smoothness=repr(a.smoothness), model=a.model,
                  spp=str(a.spp), res=str(res))
if a.scene == "glass":
    params["part"] = a.part  # face.xml holds one part and has no $part
if a.bsdf == "roughdielectric":
    if a.scene != "glass":
        ap.error("--bsdf roughdielectric: for the scene glass")
    import re

    import btdftab
    t = btdftab.open(a.table)  # the material: n and s of the table
    text = open(scene_xml).read()
    mine = re.compile(r'<bsdf type="btdftab">.*?</bsdf>', re.S)
    theirs = ('<bsdf type="roughdielectric"><string name="distribution" value="beckmann"/>'
              '<float name="alpha" value="%.17g"/><float name="int_ior" value="%.17g"/>'
              '<float name="ext_ior" value="1"/><boolean name="sample_visible" '
              'value="true"/></bsdf>' % (2.0 / t.smoothness, t.ior[0]))
    text, count = mine.subn(theirs, text)
    assert count == 1, "glass.xml holds one btdftab BSDF"
    for k in ("filename", "mode", "part"):  # the plugin's own: Mitsuba refuses unused ones
        params.pop(k, None)
    scene = mi.load_string(text, **params)
else:
    scene = mi.load_file(scene_xml, **params)
t = time.perf_counter()
img = mi.render(scene)
mi.util.write_bitmap(out_exr, img, write_async=False)
mi.util.write_bitmap(a.out, img, write_async=False)
what = a.mode if a.bsdf == "btdftab" else a.bsdf
if a.scene == "pane":
    what = "s %g, back %s, %s" % (a.smoothness, a.table, a.model)
print("%s: %s, %dx%d, %d spp, %s%s, %s: %.2f s (including JIT compilation)"
      % (a.out, a.scene, res, res, a.spp, what,
         ", part " + a.part if a.scene == "glass" else "", a.variant, time.perf_counter() - t))
