# SPDX-License-Identifier: MIT
"""Renders examples/mitsuba/glass.xml, a rough glass sphere, with the btdftab plugin
(docs/mitsuba3.md).

    python examples/mitsuba/render_glass.py TABLE OUT.png [--part both] [--mode table]
        [--variant llvm_ad_rgb] [--spp 64] [--res 160]

Writes OUT.png (sRGB) and OUT.exr (linear), and prints the render time.
"""
import argparse
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "python"))  # the checkout's plugin

import mitsuba as mi  # noqa: E402

ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
ap.add_argument("table")
ap.add_argument("out")
ap.add_argument("--part", default="both", choices=["both", "transmission", "reflection"])
ap.add_argument("--mode", default="table", choices=["table", "analytic"])
ap.add_argument("--variant", default="llvm_ad_rgb")
ap.add_argument("--spp", type=int, default=64)
ap.add_argument("--res", type=int, default=160)
a = ap.parse_args()
try:
    mi.set_variant(a.variant)
except (ImportError, AttributeError) as e:
    sys.exit("variant %s: %s\n(llvm variants need libLLVM 16 or newer: on Debian 12 "
             "apt-get install libllvm19 and set DRJIT_LIBLLVM_PATH="
             "/usr/lib/x86_64-linux-gnu/libLLVM-19.so; or --variant scalar_rgb, slower)"
             % (a.variant, e))
import btdftab_mitsuba  # noqa: E402,F401  (registers `btdftab`)

scene = mi.load_file(os.path.join(HERE, "glass.xml"), filename=os.path.abspath(a.table),
                     mode=a.mode, part=a.part, spp=str(a.spp), res=str(a.res))
t = time.perf_counter()
img = mi.render(scene)
mi.util.write_bitmap(os.path.splitext(a.out)[0] + ".exr", img, write_async=False)
mi.util.write_bitmap(a.out, img, write_async=False)
print("%s: %dx%d, %d spp, part %s, %s, %s: %.2f s (including JIT compilation)"
      % (a.out, a.res, a.res, a.spp, a.part, a.mode, a.variant, time.perf_counter() - t))
