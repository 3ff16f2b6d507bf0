# SPDX-License-Identifier: MIT
"""pane_polar.py BTDFTAB DIR: `btdftab polar --back` draws the pane's own values.

The picture is read back (a PNG decoder of the standard library: 8-bit RGB or RGBA, not
interlaced, as the preview writes) and its lobe measured along rays from the plot's
centre, as tests/test_png.c measures the interface's: the curve's radius at one angle
(near the peak) scaled by the ratio of `btdftab eval --back`'s rho |cos to| at a second
angle to the first puts a point that the curve passes. The
angles are picked where the pane and the interface (or the two faces of the pane)
differ by a factor of 3 or more, so that a picture of the wrong values fails. Prints
TAP lines; exit 1 on a failure.
"""
import math
import os
import struct
import subprocess
import sys
import zlib

BT, DIR = sys.argv[1], sys.argv[2]
CURVE0 = (20, 90, 200)  # the first curve's colour (src/preview/polar.c, palette)
failed = 0
count = 0


def check(ok, what):
    global failed, count
    count += 1
    print(("ok %d - " % count if ok else "not ok - ") + what)
    failed += 0 if ok else 1


def read_png(path):
    """(width, height, rows of bytes RGB)."""
    with open(path, "rb") as f:
        data = f.read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", path
    pos, idat, hdr = 8, b"", None
    while pos < len(data):
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        if kind == b"IHDR":
            hdr = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        pos += 12 + n
    w, h, depth, ctype, _, _, interlace = hdr
    assert depth == 8 and ctype in (2, 6) and interlace == 0, hdr
    bpp = 3 if ctype == 2 else 4
    raw = zlib.decompress(idat)
    stride = w * bpp
    rows, prev = [], bytearray(stride)
    for y in range(h):
        ft = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b = prev[i]
            c = prev[i - bpp] if i >= bpp else 0
            if ft == 1:
                line[i] = (line[i] + a) & 255
            elif ft == 2:
                line[i] = (line[i] + b) & 255
            elif ft == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif ft == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(bytes(line) if bpp == 3 else
                    bytes(v for k, v in enumerate(line) if k % 4 != 3))
        prev = line
    return w, h, rows


def px(img, x, y):
    r = img[2][y]
    return r[3 * x], r[3 * x + 1], r[3 * x + 2]


def surface_y(img):
    """The centre row of the dark surface line across the whole width."""
    w, h, _ = img
    ys = [y for y in range(h) if px(img, 2, y)[0] < 100 and px(img, w - 3, y)[0] < 100]
    assert 1 <= len(ys) <= 4, ys
    return sum(ys) / len(ys) + 0.5


def ray_extent(img, cx, cy, to_deg):
    """The farthest pixel of the curve's colour (within 40 a component) from the centre
    within 1.2 pixels of the ray at to (degrees from the upward normal, forward side),
    below the surface."""
    w, h, _ = img
    to = math.radians(to_deg)
    ux, uy = math.sin(to), -math.cos(to)  # image y grows downwards
    best = 0.0
    for y in range(int(cy) + 3, h):
        for x in range(int(cx), w):
            dx, dy = x + 0.5 - cx, y + 0.5 - cy
            along, across = dx * ux + dy * uy, abs(dx * uy - dy * ux)
            if along > 0 and across <= 1.2 and \
                    all(abs(p - q) <= 40 for p, q in zip(px(img, x, y), CURVE0)):
                best = max(best, along)
    return best


def colour_near(img, x, y, r):
    """Whether a pixel of the curve's colour lies within r pixels of (x, y)."""
    w, h, _ = img
    for yy in range(int(y) - r, int(y) + r + 1):
        for xx in range(int(x) - r, int(x) + r + 1):
            if 0 <= xx < w and 0 <= yy < h and \
                    all(abs(p - q) <= 40 for p, q in zip(px(img, xx, yy), CURVE0)):
                return True
    return False


def tool(*args, stdin=None):
    r = subprocess.run([BT] + [str(a) for a in args], input=stdin, capture_output=True,
                       text=True)
    if r.returncode != 0:
        raise RuntimeError("btdftab %s: exit %d: %s" % (" ".join(map(str, args)),
                                                       r.returncode, r.stderr))
    return r.stdout


# light on the rough front (s = 1, flat back, 4 mm) at 30 degrees: its lobe peaks near
# to = 120 and is 0.36 of that at 160; the interface's is 0 at 120. Light on the flat
# back: 0.53 at 155 of its value at 170, the front's 1.6 there.
PANE = ["--back", "smooth", "-s", 1]
for light, big, small in (("front", 120.0, 160.0), ("back", 170.0, 155.0)):
    png = os.path.join(DIR, "polar-%s.png" % light)
    tool("polar", *PANE, "--light", light, "-o", png)
    vals = [float(v) for v in tool("eval", *PANE, "--light", light,
                                   stdin="30 %r 180\n30 %r 180\n" % (big, small)).split()]
    v_big = vals[0] * abs(math.cos(math.radians(big)))
    v_small = vals[1] * abs(math.cos(math.radians(small)))
    img = read_png(png)
    cx, cy = img[0] / 2.0, surface_y(img)
    # the farthest pixel of the 2.2-pixel line is 1.1 beyond the curve
    r_big = ray_extent(img, cx, cy, big) - 1.1
    want = r_big * v_small / v_big
    t = math.radians(small)
    x, y = cx + want * math.sin(t), cy - want * math.cos(t)
    # the curve passes within 2 pixels of the point eval --back's ratio puts it at: the
    # 2.2-pixel line's half width and the pixel grid, as test_png's lobes; r_big's own
    # pixel is carried through a ratio below 1
    check(r_big > 100 and colour_near(img, x, y, 2),
          "polar --back --light %s: lobe radius %.1f px at %g deg; at %g deg the curve "
          "passes the radius eval --back's ratio gives, %.1f px" % (light, r_big, big,
                                                                   small, want))
print("%d passed, %d failed" % (count - failed, failed))
sys.exit(1 if failed else 0)
