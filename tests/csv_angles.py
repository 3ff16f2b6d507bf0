#!/usr/bin/env python3
"""The degree columns of a btdftab CSV table: each the shortest decimal that converts
(d * pi / 180, as the command line converts degrees) to the radian column beside it,
wherever some double near it does. Exits 1 on the first angle that breaks it.
usage: csv_angles.py TABLE.csv [DEGREES_THAT_MUST_APPEAR_AS_WRITTEN ...]"""
import math
import sys


def converts(d, r):
    return d * math.pi / 180.0 == r


def reachable(r):
    """Whether some double within 8 ulps of r * 180 / pi converts back to r."""
    x = r * 180.0 / math.pi
    lo = hi = x
    for _ in range(9):
        if converts(lo, r) or converts(hi, r):
            return True
        lo, hi = math.nextafter(lo, -math.inf), math.nextafter(hi, math.inf)
    return False


def shortest(text, r):
    """No shorter %g form without an exponent converts to r."""
    for p in range(1, 18):
        t = '%.*g' % (p, float(text))
        if 'e' not in t and len(t) < len(text) and converts(float(t), r):
            return False
    return True


seen = set()
rows = 0
for line in open(sys.argv[1]):
    if line.startswith('#') or line.startswith('theta_i_deg'):
        continue
    c = line.rstrip('\n').split(',')
    rows += 1
    for d, r in ((c[0], c[4]), (c[1], c[5]), (c[2], c[6])):
        rv = float(r)
        seen.add(d)
        if 'e' in d:
            sys.exit('%s: an exponent in a degree column (row %d)' % (d, rows))
        if converts(float(d), rv):
            if not shortest(d, rv):
                sys.exit('%s: a shorter decimal converts to %s (row %d)' % (d, r, rows))
        elif reachable(rv):
            sys.exit('%s does not convert to %s, though a double near it does (row %d)'
                     % (d, r, rows))
missing = [d for d in sys.argv[2:] if d not in seen]
if missing or rows == 0:
    sys.exit('rows %d; not printed as written: %s' % (rows, ' '.join(missing)))
print('%d rows: every degree column converts to its radians where any double does' % rows)
