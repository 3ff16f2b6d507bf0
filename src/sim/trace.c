/* SPDX-License-Identifier: MIT */
/* trace.c: rays through a height-field tile of triangles.

   Cell (i, j) spans [i, i+1] x [j, j+1] in grid units and holds two planar triangles
   split by the diagonal u = v (local coordinates u = x/dx - i, v = y/dx - j):
     A (u >= v): corners (0,0), (1,0), (1,1): z = h00 + (h10 - h00) u + (h11 - h10) v
     B (u <= v): corners (0,0), (1,1), (0,1): z = h00 + (h11 - h01) u + (h01 - h00) v
   The surface is continuous, so along the part of a ray over one triangle the height
   of the ray above the plane, f(t), is linear: a hit is a sign change of f between
   the ends of that part, located exactly by linear interpolation. Parts are the
   segments of the ray between cell edges and the diagonal.

   The walk is a grid DDA (Amanatides & Woo 1987) on every level of a min/max
   hierarchy (surface.h): a unit whose height range the ray's height range over the
   unit misses is skipped whole; otherwise its 4 x 4 children are walked over the
   same parameter interval. Every crossing parameter is computed the same way at
   every level, ((boundary) - o) / d, so neighbouring levels agree on where a unit
   begins and ends. */
#include "sim/trace.h"

#include <math.h>
#include <stdlib.h>

#include "sim/rng.h"

/* The cell walk is written once and compiled per case (see walk_cells). */
#if defined(__GNUC__)
#define SIM_INLINE static inline __attribute__((always_inline))
#else
#define SIM_INLINE static inline
#endif

typedef struct walk_ctx {
    const sim_surface *s;
    const double *o, *d;
    double inv[2]; /* 1 / d[0], 1 / d[1] (inf for 0, never used then) */
    double sgn;    /* +1: ray above the surface, -1: below */
    double t;   /* the hit */
    double b, c; /* its plane's slopes per grid unit */
} walk_ctx;

static inline double hgt(const sim_surface *s, int64_t i, int64_t j)
{
    uint64_t m = (uint64_t)s->n - 1u;
    return s->h[(((uint64_t)j & s->ymask) << s->log2n) + ((uint64_t)i & m)];
}

/* The part [a, b] of the ray over the plane z = z0 + pb u + pc v (local origin lu, lv). */
static inline int test_part(walk_ctx *w, double lu, double lv, double a, double b, double z0,
                            double pb, double pc)
{
    const double *o = w->o, *d = w->d;
    double fa = w->sgn * (o[2] + a * d[2] - (z0 + pb * (lu + a * d[0]) + pc * (lv + a * d[1])));
    double fb = w->sgn * (o[2] + b * d[2] - (z0 + pb * (lu + b * d[0]) + pc * (lv + b * d[1])));
    if (!(fb < 0.0))
        return 0;
    /* The ray is on its side at the start of every part (f >= 0); a value below 0
       there is rounding of a touch, and counts as 0. */
    fa = fa > 0.0 ? fa : 0.0;
    /* fa - fb > 0 since fb < 0 <= fa */
    w->t = a + (b - a) * (fa / (fa - fb));
    w->b = pb;
    w->c = pc;
    return 1;
}

static int test_cell(walk_ctx *w, int64_t i, int64_t j, double ta, double tb)
{
    const sim_surface *s = w->s;
    double h00 = hgt(s, i, j), h10 = hgt(s, i + 1, j);
    double h01 = hgt(s, i, j + 1), h11 = hgt(s, i + 1, j + 1);
    double lu = w->o[0] - (double)i, lv = w->o[1] - (double)j;
    double g0 = lu - lv, gd = w->d[0] - w->d[1];
    double cut[3] = {ta, tb, tb};
    int parts = 1;
    if (gd != 0.0) {
        double td = -g0 / gd; /* where the ray crosses the diagonal; gd != 0 */
        if (td > ta && td < tb) {
            cut[1] = td;
            parts = 2;
        }
    }
    for (int p = 0; p < parts; p++) {
        double a = cut[p], b = cut[p + 1];
        double gm = g0 + 0.5 * (a + b) * gd;
        int hit = gm >= 0.0 ? test_part(w, lu, lv, a, b, h00, h10 - h00, h11 - h10)
                            : test_part(w, lu, lv, a, b, h00, h11 - h01, h01 - h00);
        if (hit)
            return 1;
    }
    return 0;
}

/* The cells met by the ray over [ta, tb]: the DDA of walk() below at its level 0
   (unit side S = 1), in a loop of its own. It computes every crossing as walk() does,
   ((boundary) - o) / d with the boundary an integer held exactly in a double, so both
   find the same cells over the same intervals and the same hits. The bound test takes
   the ray's height at one end of the cell's interval only, the end where the ray is
   nearest the side it comes from: z(t) = o + t d is monotone in t after rounding too,
   so that end's height is exactly the minimum (above) or maximum (below) of the two.
   With clamp, the cells' indices are kept within [ilo, ihi] x [jlo, jhi] (a parent
   unit's children, where rounding of the parent's interval could step out); without,
   the interval alone ends the walk. 1 at the first hit. */
SIM_INLINE int walk_cells_in(walk_ctx *w, const int clamp, const int above, int64_t ilo,
                             int64_t ihi, int64_t jlo, int64_t jhi, double ta, double tb)
{
    const sim_surface *s = w->s;
    const double o0 = w->o[0], o1 = w->o[1], o2 = w->o[2];
    const double d0 = w->d[0], d1 = w->d[1], d2 = w->d[2];
    const double inv0 = w->inv[0], inv1 = w->inv[1];
    int64_t i = (int64_t)floor(o0 + ta * d0);
    int64_t j = (int64_t)floor(o1 + ta * d1);
    if (clamp) {
        i = i < ilo ? ilo : i > ihi ? ihi : i;
        j = j < jlo ? jlo : j > jhi ? jhi : j;
    }
    int64_t si = d0 > 0.0 ? 1 : -1, sj = d1 > 0.0 ? 1 : -1;
    /* the far boundaries of the cell along x and y, as doubles (integers below 2^53:
       adding 1 is exact, so bx = (double)(i + (si > 0)) at every step) */
    double bx = (double)(i + (si > 0)), by = (double)(j + (sj > 0));
    double sx = (double)si, sy = (double)sj;
    /* d = 0 along an axis: that axis is never crossed */
    double tx = d0 != 0.0 ? (bx - o0) * inv0 : INFINITY;
    double ty = d1 != 0.0 ? (by - o1) * inv1 : INFINITY;
    /* the end of [t0, t1] nearest the side: its exit when the ray heads towards it */
    const int at_exit = above ? d2 < 0.0 : d2 > 0.0;
    const double *bound = above ? s->hi[0] : s->lo[0];
    /* the bound's index, wrapped into the tile and stepped with the cell */
    const uint64_t mx = (uint64_t)s->n - 1u, my = s->ymask << s->log2n;
    const uint64_t stepy = (uint64_t)sj << s->log2n;
    uint64_t qx = (uint64_t)i & mx, qy = ((uint64_t)j << s->log2n) & my;
    double t0 = ta;
    for (;;) {
        double t1 = tx < ty ? tx : ty;
        t1 = t1 < tb ? t1 : tb;
        t1 = t1 > t0 ? t1 : t0;
        double z = o2 + (at_exit ? t1 : t0) * d2;
        double b = bound[qy + qx];
        /* Above, a hit needs the ray below the cell's highest point somewhere over it;
           below, above its lowest. */
        if ((above ? z <= b : z >= b) && test_cell(w, i, j, t0, t1))
            return 1;
        if (t1 >= tb)
            return 0;
        /* the step, without a branch on the axis (which one comes next is as good as
           random, a branch would miss often) */
        int alx = tx <= ty;
        i += alx ? si : 0;
        j += alx ? 0 : sj;
        qx = alx ? (qx + (uint64_t)si) & mx : qx;
        qy = alx ? qy : (qy + stepy) & my;
        bx += alx ? sx : 0.0;
        by += alx ? 0.0 : sy;
        if (clamp && (i < ilo || i > ihi || j < jlo || j > jhi))
            return 0;
        double nx = (bx - o0) * inv0, ny = (by - o1) * inv1;
        tx = alx ? nx : tx;
        ty = alx ? ty : ny;
        t0 = t1;
    }
}

/* The walk compiled for each case, so that none tests a constant inside its loop. */
static int walk_cells(walk_ctx *w, double ta, double tb)
{
    return w->sgn > 0.0 ? walk_cells_in(w, 0, 1, 0, 0, 0, 0, ta, tb)
                        : walk_cells_in(w, 0, 0, 0, 0, 0, 0, ta, tb);
}

static int walk_cells_clamped(walk_ctx *w, int64_t ilo, int64_t ihi, int64_t jlo, int64_t jhi,
                              double ta, double tb)
{
    return w->sgn > 0.0 ? walk_cells_in(w, 1, 1, ilo, ihi, jlo, jhi, ta, tb)
                        : walk_cells_in(w, 1, 0, ilo, ihi, jlo, jhi, ta, tb);
}

/* The units of level k >= 1 met by the ray over [ta, tb], their indices kept within
   [ilo, ihi] x [jlo, jhi] (the parent's children). 1 at the first hit. */
static int walk(walk_ctx *w, int k, int64_t ilo, int64_t ihi, int64_t jlo, int64_t jhi,
                double ta, double tb)
{
    const sim_surface *s = w->s;
    const double *o = w->o, *d = w->d;
    int sh = s->shift[k];
    double S = (double)((int64_t)1 << sh), invS = 1.0 / S; /* powers of two: exact */
    uint64_t side_m = ((uint64_t)s->n >> sh) - 1u;
    uint64_t side_my = s->ymask >> sh; /* rows per unit - 1: side_m, or 0 on a strip */
    int sideshift = s->log2n - sh;
    int64_t i = (int64_t)floor((o[0] + ta * d[0]) * invS);
    int64_t j = (int64_t)floor((o[1] + ta * d[1]) * invS);
    i = i < ilo ? ilo : i > ihi ? ihi : i;
    j = j < jlo ? jlo : j > jhi ? jhi : j;
    int64_t si = d[0] > 0.0 ? 1 : -1, sj = d[1] > 0.0 ? 1 : -1;
    /* d = 0 along an axis: that axis is never crossed */
    double tx = d[0] != 0.0 ? ((double)(i + (si > 0)) * S - o[0]) * w->inv[0] : INFINITY;
    double ty = d[1] != 0.0 ? ((double)(j + (sj > 0)) * S - o[1]) * w->inv[1] : INFINITY;
    const double *lo = s->lo[k], *hi = s->hi[k];
    double t0 = ta;
    for (;;) {
        double t1 = tx < ty ? tx : ty;
        t1 = t1 < tb ? t1 : tb;
        t1 = t1 > t0 ? t1 : t0;
        double za = o[2] + t0 * d[2], zb = o[2] + t1 * d[2];
        size_t q = (size_t)((((uint64_t)j & side_my) << sideshift) + ((uint64_t)i & side_m));
        /* as in walk_cells, for the unit's bounds */
        int near = w->sgn > 0.0 ? (za < zb ? za : zb) <= hi[q] : (za > zb ? za : zb) >= lo[q];
        if (near) {
            int hit = k == 1 ? walk_cells_clamped(w, i * 4, i * 4 + 3, j * 4, j * 4 + 3, t0, t1)
                             : walk(w, k - 1, i * 4, i * 4 + 3, j * 4, j * 4 + 3, t0, t1);
            if (hit)
                return 1;
        }
        if (t1 >= tb)
            return 0;
        if (tx <= ty) {
            i += si;
            if (i < ilo || i > ihi)
                return 0;
            tx = ((double)(i + (si > 0)) * S - o[0]) * w->inv[0];
        } else {
            j += sj;
            if (j < jlo || j > jhi)
                return 0;
            ty = ((double)(j + (sj > 0)) * S - o[1]) * w->inv[1];
        }
        t0 = t1;
    }
}

int sim_first_hit(const sim_surface *s, const double o[3], const double d[3], int above,
                  double tmax, int accel, double *t, double nrm[3])
{
    /* a zero component gives inf, which walk never multiplies (it tests d first) */
    walk_ctx w = {s, o, d, {1.0 / d[0], 1.0 / d[1]}, above ? 1.0 : -1.0, 0.0, 0.0, 0.0};
    int top = accel ? s->levels - 1 : 0;
    int hit = top > 0 ? walk(&w, top, INT64_MIN / 8, INT64_MAX / 8, INT64_MIN / 8,
                             INT64_MAX / 8, 0.0, tmax)
                      : walk_cells(&w, 0.0, tmax);
    if (!hit)
        return 0;
    *t = w.t;
    /* Physical normal of z = b x/dx + c y/dx: (-b/dx, -c/dx, 1); its length >= 1. */
    double nx = -w.b / s->dx, ny = -w.c / s->dx;
    double inv = 1.0 / sqrt(nx * nx + ny * ny + 1.0);
    nrm[0] = nx * inv;
    nrm[1] = ny * inv;
    nrm[2] = inv;
    return 1;
}

/* Horizontal travel (in cells) after which a ray still inside the slab is stopped. */
#define SIM_MAX_TRAVEL_TILES 64.0

int sim_turn(double dp[3], const double nf[3], double eta, uint64_t *rng)
{
    double ci = -(dp[0] * nf[0] + dp[1] * nf[1] + dp[2] * nf[2]);
    /* A crossing implies ci > 0; rounding of a grazing touch can give <= 0, which
       is the grazing limit, total reflection. */
    ci = ci > 0.0 ? (ci < 1.0 ? ci : 1.0) : 0.0;
    double s2t = (1.0 - ci * ci) / (eta * eta); /* eta >= BTDF_IOR_MIN > 0 */
    double R = 1.0, ctt = 0.0;
    if (s2t < 1.0) {
        ctt = sqrt(1.0 - s2t);
        /* both denominators > 0: ci, ctt >= 0 and not both 0 (ci = 0 gives ctt > 0
           only when eta > 1, and then eta ctt > 0) */
        double rs = (ci - eta * ctt) / (ci + eta * ctt);
        double rp = (eta * ci - ctt) / (eta * ci + ctt);
        R = 0.5 * (rs * rs + rp * rp);
    }
    int crossed = 0;
    if (sim_uniform(rng) < R) {
        for (int a = 0; a < 3; a++)
            dp[a] += 2.0 * ci * nf[a];
    } else {
        for (int a = 0; a < 3; a++)
            dp[a] = dp[a] / eta + (ci / eta - ctt) * nf[a];
        crossed = 1;
    }
    /* unit length again (it is 1 to rounding; the norm is near 1, never 0) */
    double len = 1.0 / sqrt(dp[0] * dp[0] + dp[1] * dp[1] + dp[2] * dp[2]);
    for (int a = 0; a < 3; a++)
        dp[a] *= len;
    return crossed;
}

int sim_walk(const sim_surface *s, double n, int above, int accel, uint64_t *rng, double dp[3],
             int *hits_out)
{
    double o[3] = {sim_uniform(rng) * s->n, sim_uniform(rng) * s->n, above ? s->hmax : s->hmin};
    double N = (double)s->n, cap = SIM_MAX_TRAVEL_TILES * N;
    int hits = 0, end = SIM_END_LOST;
    for (;;) {
        double dg[3] = {dp[0] / s->dx, dp[1] / s->dx, dp[2]};
        double hl = sqrt(dg[0] * dg[0] + dg[1] * dg[1]);
        /* Leave the slab [hmin, hmax], or stop after cap cells sideways; dg[2] = 0 or
           hl = 0 leave only the other limit. */
        double tz = dg[2] > 0.0 ? (s->hmax - o[2]) / dg[2]
                  : dg[2] < 0.0 ? (s->hmin - o[2]) / dg[2] : INFINITY;
        double th = hl > 0.0 ? cap / hl : INFINITY;
        double tmax = tz < th ? tz : th;
        tmax = tmax > 0.0 ? tmax : 0.0;
        double t, nrm[3];
        if (!sim_first_hit(s, o, dg, above, tmax, accel, &t, nrm)) {
            if (tz <= th)
                end = above ? (dp[2] > 0.0 ? SIM_END_R : SIM_END_LOST)
                            : (dp[2] < 0.0 ? SIM_END_T : SIM_END_LOST);
            break;
        }
        if (++hits > SIM_MAX_HITS)
            break;
        for (int a = 0; a < 2; a++) {
            o[a] += t * dg[a];
            o[a] -= floor(o[a] / N) * N; /* back into the tile, which is periodic */
        }
        o[2] += t * dg[2];
        /* The normal on the side the light comes from, and the index ratio it meets. */
        double sg = above ? 1.0 : -1.0;
        double nf[3] = {sg * nrm[0], sg * nrm[1], sg * nrm[2]};
        if (sim_turn(dp, nf, above ? n : 1.0 / n, rng))
            above = !above;
    }
    *hits_out = hits;
    return end;
}

void sim_path_run(const sim_surface *s, double n, double st, double ct, int accel, int in_plane,
                  uint64_t *rng, sim_path *out)
{
    double pin = 6.283185307179586 * sim_uniform(rng);
    /* in the plane: azimuth 0 or pi exactly (sin pi is 1e-16, not 0) */
    double cp = in_plane ? (pin < 3.141592653589793 ? 1.0 : -1.0) : cos(pin);
    double sp = in_plane ? 0.0 : sin(pin);
    double dp[3] = {-st * cp, -st * sp, -ct};
    out->end = sim_walk(s, n, 1, accel, rng, dp, &out->hits);
    /* Back to the frame whose incident azimuth is 0. */
    out->dir[0] = dp[0] * cp + dp[1] * sp;
    out->dir[1] = -dp[0] * sp + dp[1] * cp;
    out->dir[2] = dp[2];
}
