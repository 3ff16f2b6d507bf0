/* SPDX-License-Identifier: MIT */
/* spline.h: pbrt-v3's Catmull-Rom spline over a node list (weights, interval search,
   integral), static inline: the builder's checks, assemble's cdf rows and the reader
   call them per sample. */
#ifndef BTDF_SF_SPLINE_H
#define BTDF_SF_SPLINE_H

#include <stddef.h>

#include "model/kernel.h"
#include "scatfun/scatfun.h"

/* ------------------------------------------------------------------------- */
/* Catmull-Rom weights as pbrt-v3 computes them                              */
/* ------------------------------------------------------------------------- */

/* Weights of nodes off..off+3 for the spline through x[] at v, given i, the largest
   index with x[i] <= v, and v in [x[0], x[n-1]], n >= 2. 0 when the interval found has
   zero width (a malformed node list). */
static inline int cr_weights_at(const double *x, size_t n, double v, size_t lo, long *off,
                         double w[4])
{
    size_t i = lo > n - 2 ? n - 2 : lo;
    double x0 = x[i], x1 = x[i + 1];
    if (!(x1 > x0))
        return 0; /* zero-width interval: t would divide by 0 */
    double t = (v - x0) / (x1 - x0), t2 = t * t, t3 = t2 * t;
    *off = (long)i - 1;
    w[0] = 0.0;
    w[1] = 2.0 * t3 - 3.0 * t2 + 1.0;
    w[2] = -2.0 * t3 + 3.0 * t2;
    w[3] = 0.0;
    /* x1 - x[i-1] >= x1 - x0 > 0 and x[i+2] - x0 >= x1 - x0 > 0 for sorted nodes. */
    if (i > 0) {
        double w0 = (t3 - 2.0 * t2 + t) * (x1 - x0) / (x1 - x[i - 1]);
        w[0] = -w0;
        w[2] += w0;
    } else {
        double w0 = t3 - 2.0 * t2 + t;
        w[1] -= w0;
        w[2] += w0;
    }
    if (i + 2 < n) {
        double w3 = (t3 - t2) * (x1 - x0) / (x[i + 2] - x0);
        w[1] -= w3;
        w[3] = w3;
    } else {
        double w3 = t3 - t2;
        w[1] -= w3;
        w[2] += w3;
    }
    return 1;
}

/* The largest i in [lo, hi] with x[i] <= v, given x[lo] <= v. */
static inline size_t cr_search(const double *x, size_t lo, size_t hi, double v)
{
    while (lo < hi) {
        size_t mid = lo + (hi - lo + 1) / 2;
        if (x[mid] <= v)
            lo = mid;
        else
            hi = mid - 1;
    }
    return lo;
}

/* Weights of nodes off..off+3 for the spline through x[] at v. 0 when v lies outside
   [x[0], x[n-1]] or the interval found has zero width (a malformed node list). */
static inline int cr_weights(const double *x, size_t n, double v, long *off, double w[4])
{
    if (n < 2 || !(v >= x[0] && v <= x[n - 1]))
        return 0;
    return cr_weights_at(x, n, v, cr_search(x, 0, n - 1, v), off, w);
}

/* cr_weights over a file's nodes, the interval found through f->xcell: a walk of a
   node or two from the cell's first instead of a binary search over all of them
   (its ten unpredictable branches per call were 6 % of a .bsdf build's time). The
   same interval, so the same weights, as cr_weights. */
BT_INLINE int cr_weights_f(const btdf_scatfun *f, double v, long *off, double w[4])
{
    const double *x = f->xd;
    size_t n = f->n;
    if (!f->xcell)
        return cr_weights(x, n, v, off, w);
    if (n < 2 || !(v >= x[0] && v <= x[n - 1]))
        return 0;
    /* v - x[0] in [0, span] and scale = cells / span: c in [0, cells], clamped below
       for v = x[n-1] */
    size_t c = (size_t)((v - x[0]) * f->xcell_scale);
    if (c >= f->nxcell)
        c = f->nxcell - 1;
    size_t i = f->xcell[c];
    while (i > 0 && x[i] > v) /* rounding put v one cell too high */
        i--;
    /* the answer lies before the next cell's first node unless rounding put v one
       cell too low: search up to the cell after next */
    size_t hi = c + 2 <= f->nxcell ? f->xcell[c + 2] : n - 1;
    if (hi + 1 < n && x[hi + 1] <= v)
        hi = n - 1; /* never for sorted nodes and c within one cell of v's */
    return cr_weights_at(x, n, v, cr_search(x, i, hi, v), off, w);
}

/* Exact integral of the Catmull-Rom spline through v[] over [x[0], x[n-1]], running
   sums into cdf (cdf[0] = 0), the rule of the format's cdf rows. */
static inline void spline_cdf(const double *x, const double *v, size_t n, double *cdf)
{
    cdf[0] = 0.0;
    for (size_t k = 1; k < n; k++) {
        double w = x[k] - x[k - 1];
        double f0 = v[k - 1], f1 = v[k], d0, d1;
        /* Denominators span at least the interval itself, so they are > 0 when w > 0;
           a zero-width interval adds nothing. */
        if (!(w > 0.0)) {
            cdf[k] = cdf[k - 1];
            continue;
        }
        d0 = k >= 2 ? w * (f1 - v[k - 2]) / (x[k] - x[k - 2]) : f1 - f0;
        d1 = k + 1 < n ? w * (v[k + 1] - f0) / (x[k + 1] - x[k - 1]) : f1 - f0;
        cdf[k] = cdf[k - 1] + w * (0.5 * (f0 + f1) + (d0 - d1) / 12.0);
    }
}


#endif /* BTDF_SF_SPLINE_H */
