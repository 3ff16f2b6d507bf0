/* SPDX-License-Identifier: MIT */
/* ttree.c: the TensorTree3 of one block, built for Radiance's lookup rule.
 *
 * How Radiance reads a TensorTree3 (its BSDF library, bsdf.c and bsdf_t.c, read for
 * behaviour; checked against the library in tests/radiance.sh):
 *  - SDevalBSDF(out, in) picks the block by the side of `in` and the tree is queried
 *    with `in` as the incident direction: rtrace passes the view (the direction back
 *    to the eye) as `in` and the light as `out`, so the tree's incident coordinate is
 *    the VIEW p, and the light q is its outgoing coordinate;
 *  - coordinate 0 is u0 = (0.5 - FTINY) - 0.5 sin(theta_p), FTINY = 1e-6: uniform in
 *    sin(theta_p); only u0 < 0.5 is used (isotropic: rank 3, no azimuth of p);
 *  - the light q is turned about z by -atan2(-p_y, -p_x) (p's horizontal direction of
 *    travel to +x) and its (x, y) goes through the concentric square map (Shirley and
 *    Chiu): coordinates 1 and 2, in which area times pi is projected solid angle;
 *  - the tree is descended by halving every coordinate at each node (child bit d =
 *    upper half of coordinate d) down to a leaf, whose value is returned as it is:
 *    nearest cell, no interpolation (then perturbed by at most 1.5e-4 relative).
 *
 * What the error measures (MODEL.md 6) in these coordinates: e_L1 is taken per LIGHT
 * direction, over the views. A light at polar angle ti sits at Chebyshev radius
 * r = sin(ti) of the square, max(|2a - 1|, |2b - 1|) = r (the concentric map takes
 * circles to squares), and the views sweep u0 (the view's polar angle) and the
 * position along that square ring (the view's azimuth). With d(mu) = sin tp d(sin tp)
 * d(phi_p), the view's projected solid angle, and dr dphi = pi da db / r:
 *   e_L1(r) = integral over u0 and the ring of |rho - value| d(mu) / max(T(ti), 0.01).
 * So a cell of the tree adds to the e_L1 of every light whose ring crosses it, by
 *   its share(r) = integral over the cell at ring r of |rho - value| d(mu) / floor(r).
 *
 * The builder: every cell is sampled at 4 x 4 x 4 midpoints; the leaf holds their mean
 * weighted by sin(tp) (the projected-solid-angle average, so each light's transmittance
 * is kept). Its samples are sorted into 4 bins of r, each bin's share estimated as
 * above (averaged over the bin's rings), and the largest share is the cell's `contrib`.
 * A cell is split while contrib > eps. Since that rule looks at a cell alone, the tree
 * for a larger eps is the tree for a smaller one cut where contrib <= eps: one build,
 * grown in steps (rad_tb_grow), can be cut (rad_tb_extract) at any eps above, so the
 * caller searches eps against an error estimate without evaluating cells again.
 */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "radiance/radiance_impl.h"

#define RAD_FTINY 1e-6 /* Radiance's FTINY in double builds, in u0 */
#define NS 4           /* samples per cell and dimension */
#define NR_GRID 129    /* nodes of the floor max(T, 0.01) over the ring radius r in [0, 1] */

void rad_square_to_disk(double a, double b, double *x, double *y)
{
    /* Shirley and Chiu's concentric map: four wedges, r = the larger |coordinate|. */
    double p = 2.0 * a - 1.0, q = 2.0 * b - 1.0, r, phi;
    if (p == 0.0 && q == 0.0) {
        *x = *y = 0.0;
        return;
    }
    if (p > -q) {
        if (p > q) {
            r = p;
            phi = (M_PI / 4.0) * (q / p); /* p > |q| >= 0: no 1/0 */
        } else {
            r = q;
            phi = (M_PI / 4.0) * (2.0 - p / q); /* q >= |p|, q > 0 */
        }
    } else if (p < q) {
        r = -p;
        phi = (M_PI / 4.0) * (4.0 + q / p); /* -p > |q|, p < 0 */
    } else {
        r = -q;
        phi = q != 0.0 ? (M_PI / 4.0) * (6.0 - p / q) : 0.0; /* q = 0 only at the centre */
    }
    *x = r * cos(phi);
    *y = r * sin(phi);
}

void rad_disk_to_square(double x, double y, double *a, double *b)
{
    double r = sqrt(x * x + y * y), phi = atan2(y, x), p, q;
    if (phi < -M_PI / 4.0)
        phi += 2.0 * M_PI; /* [-pi/4, 7pi/4) */
    if (phi < M_PI / 4.0) {
        p = r;
        q = phi * r / (M_PI / 4.0);
    } else if (phi < 3.0 * M_PI / 4.0) {
        q = r;
        p = -(phi - M_PI / 2.0) * r / (M_PI / 4.0);
    } else if (phi < 5.0 * M_PI / 4.0) {
        p = -r;
        q = -(phi - M_PI) * r / (M_PI / 4.0);
    } else {
        q = -r;
        p = (phi - 3.0 * M_PI / 2.0) * r / (M_PI / 4.0);
    }
    *a = 0.5 * (p + 1.0);
    *b = 0.5 * (q + 1.0);
}

double rad_u0_of_sin(double sin_ti) { return (0.5 - RAD_FTINY) - 0.5 * sin_ti; }

size_t rad_tree_leaf(const rad_node *nodes, double u0, double a, double b)
{
    double pos[3] = {u0, a, b};
    size_t k = 0;
    while (nodes[k].child >= 0) {
        int n = 0;
        for (int d = 2; d >= 0; d--) {
            double sp = 2.0 * pos[d];
            int t = sp >= 1.0;
            n |= t << d;
            pos[d] = sp - (double)t;
        }
        k = (size_t)nodes[k].child + (size_t)n;
    }
    return k;
}

double rad_tree_lookup(const rad_node *nodes, double u0, double a, double b)
{
    return nodes[rad_tree_leaf(nodes, u0, a, b)].v;
}

/* ---------------------------------------------------------------- builder */

typedef struct tb_node {
    int32_t child; /* first of 8 children, or -1 */
    float v;       /* the leaf value exactly as written to the file (CIE Y in colour) */
    float contrib; /* the cell's largest share of one light's e_L1 (see the top) */
} tb_node;

typedef struct tt_ctx {
    int nch;                /* 1, or 3: R, G, B, each at its own index (colour) */
    int same[3];            /* the first channel of channel c's index (computed once) */
    double n[3], scale[3];  /* per channel: the block's index and scale */
    double s, k0;
    btdf_model model;       /* the shadowing-masking (kernel.h): full's is smith's */
    const btdf_full *ms[3]; /* model full: each channel's tally at n[ch], else NULL */
    int reflect;            /* 1: rho_r(n) (reciprocal, no scale); 0: scale rho(n; p -> q) */
    double rfloor[3][NR_GRID]; /* max(T or R of the light, 0.01) at r = k / (NR_GRID - 1) */
    double m[3][3];         /* colour: R, G, B -> X, Y, Z */
    int min_level, max_level;
} tt_ctx;

/* A colour builder's floats per node: RAD_CV (R, G, B, u', v': radiance.h), then each
   channel's share (the contrib of that channel alone). */
#define TB_CV (RAD_CV + 3)

typedef struct tt_buf {
    tb_node *v;
    float *cv;              /* colour: TB_CV floats per node, else NULL */
    size_t n, cap, max;
    int depth;
    int budget_hit, nomem;
} tt_buf;

static int32_t buf_alloc(tt_buf *b, size_t count, int colour)
{
    if (b->n + count > b->max || b->n + count > (size_t)INT32_MAX) {
        b->budget_hit = 1;
        return -1;
    }
    if (b->n + count > b->cap) {
        size_t cap = b->cap ? 2 * b->cap : 64;
        while (cap < b->n + count)
            cap *= 2;
        tb_node *v = realloc(b->v, cap * sizeof *v);
        if (!v) {
            b->nomem = 1;
            return -1;
        }
        b->v = v;
        if (colour) {
            float *cv = realloc(b->cv, cap * TB_CV * sizeof *cv);
            if (!cv) {
                b->nomem = 1;
                return -1;
            }
            b->cv = cv;
        }
        b->cap = cap;
    }
    int32_t first = (int32_t)b->n;
    for (size_t i = 0; i < count; i++) {
        b->v[b->n + i].child = -1;
        b->v[b->n + i].v = 0.0f;
        b->v[b->n + i].contrib = 0.0f;
    }
    b->n += count;
    return first;
}

/* Channel ch's floor at ring radius x, linear between the grid's nodes. */
static double floor_at(const tt_ctx *c, int ch, double x)
{
    double t = fmin(fmax(x, 0.0), 1.0) * (NR_GRID - 1);
    long i = (long)t;
    if (i >= NR_GRID - 1)
        return c->rfloor[ch][NR_GRID - 1];
    double w = t - (double)i;
    return (1.0 - w) * c->rfloor[ch][i] + w * c->rfloor[ch][i + 1];
}

/* The smallest floor over ring radii [lo, hi]: the ends and the nodes between. */
static double floor_min(const tt_ctx *c, int ch, double lo, double hi)
{
    double m = fmin(floor_at(c, ch, lo), floor_at(c, ch, hi));
    long i0 = (long)ceil(fmax(lo, 0.0) * (NR_GRID - 1)), i1 = (long)floor(fmin(hi, 1.0) * (NR_GRID - 1));
    for (long i = i0; i <= i1; i++)
        m = fmin(m, c->rfloor[ch][i]);
    return m;
}

/* Leaf values carry 4 significant digits (relative rounding <= 5e-4, which moves an
   e_L1 by at most 5e-4 of the energy the file holds: a twentieth of the smallest
   tolerance, 1e-2), and are stored as the file writes them, so the object and the
   file agree: the text reads back to this very float in Radiance. */
static float file_value(double v)
{
    char t[32];
    snprintf(t, sizeof t, "%.4g", v);
    return (float)strtod(t, NULL);
}

/* u', v' of the equal-energy white (x = y = 1/3): (4, 9) / 19. */
#define WHITE_U (4.0 / 19.0)
#define WHITE_V (9.0 / 19.0)

void rad_colour_leaf(const double m[3][3], const float rgb[3], float *y, float uv[2])
{
    double xyz[3];
    for (int i = 0; i < 3; i++)
        xyz[i] = m[i][0] * rgb[0] + m[i][1] * rgb[1] + m[i][2] * rgb[2];
    double s = xyz[0] + 15.0 * xyz[1] + 3.0 * xyz[2];
    *y = file_value(xyz[1]);
    /* u', v' of X, Y, Z; where there is no light (s = 0: the channels are >= 0 and m's
       entries > 0, so X = Y = Z = 0) the white point's, a valid chromaticity that
       Radiance turns into x, y with y > 0 (its u', v' -> x, y -> X, Z divides by y) */
    uv[0] = (float)(s > 0.0 ? 4.0 * xyz[0] / s : WHITE_U);
    uv[1] = (float)(s > 0.0 ? 9.0 * xyz[1] / s : WHITE_V);
}

void rad_colour_xyz(double y, double u, double v, double xyz[3])
{
    if (!(v > 0.0)) { /* never written (v' = 9Y / s > 0 or the white's): no 1/0 */
        xyz[0] = xyz[1] = xyz[2] = 0.0;
        return;
    }
    xyz[0] = y * 9.0 * u / (4.0 * v);
    xyz[1] = y;
    xyz[2] = y * (12.0 - 3.0 * u - 20.0 * v) / (4.0 * v);
}

/* Distance from 0 to [lo, hi] and the largest |x| on it. */
static double dist0(double lo, double hi) { return lo > 0.0 ? lo : (hi < 0.0 ? -hi : 0.0); }
static double absmax(double lo, double hi) { return fmax(fabs(lo), fabs(hi)); }

/* rho_r (MODEL.md section 8) at index n for the view e_i = (st, 0, ct) and the light at
   disk point r (cos phi, sin phi) of the tree (phi = pi: specular), with the shadowing
   factors vi = V(ti), vr = V(tr) given: Fr D V V / (4 cos ti cos tr) with the
   half vector h = e_i + e_r, cos a = |h| / 2, tan^2 tn = (h_x^2 + h_y^2) / h_z^2. */
static double rho_r_cell(const tt_ctx *c, double n, double st, double ct, double vi, double r,
                         double cph, double sph, double vr)
{
    double cr = sqrt(fmax(0.0, 1.0 - r * r));
    double hx = st + r * cph, hy = r * sph, hz = ct + cr; /* hz > 0: both cosines >= 0 */
    double rxy2 = hx * hx + hy * hy, hz2 = hz * hz, u2 = rxy2 + hz2;
    if (!(ct > 0.0 && cr > 0.0 && hz2 > 0.0))
        return 0.0; /* grazing: rho_r -> 0 (shadowing), and no 1/0 */
    double sec2 = u2 / hz2;
    double fr = bt_fresnel_r(n, n - 1.0, 0.5 * sqrt(u2));
    double v = c->s * c->s / (16.0 * M_PI) * fr * exp(-0.25 * c->s * c->s * rxy2 / hz2) *
               sec2 * sec2 * vi * vr / (ct * cr);
    return v >= DBL_MIN ? v : 0.0;
}

/* The largest over the r bins of sum |f - v| ws: a cell's share of one light's e_L1. */
static double tt_binmax(double f[NS][NS * NS], double ws[NS][NS * NS], const int *bin, double v)
{
    double e[NS] = {0.0}, m = 0.0;
    for (int i = 0; i < NS; i++)
        for (int k = 0; k < NS * NS; k++)
            e[bin[k]] += fabs(f[i][k] - v) * ws[i][k];
    for (int q = 0; q < NS; q++)
        m = fmax(m, e[q]);
    return m;
}

/* Samples cell (level, i0, i1, i2): its value (per channel in colour, into cv) and its
   contrib (the worst channel's). */
static void tt_eval(const tt_ctx *c, tb_node *nd, float *cv, int level, uint32_t i0,
                    uint32_t i1, uint32_t i2)
{
    double h = ldexp(1.0, -level), f[NS][NS * NS], rr[NS * NS];
    /* smith: G2 does not factor into the two directions' parts, so it is formed per
       pair of samples (rho_out_init_m), from Lambda of each side */
    int smith = c->model == BTDF_MODEL_SMITH;
    rho_out ro[NS * NS];
    double cph[NS * NS], sph[NS * NS], vr[NS * NS];
    for (int j = 0; j < NS; j++) {
        for (int k = 0; k < NS; k++) {
            double a = ((double)i1 + (j + 0.5) / NS) * h, bb = ((double)i2 + (k + 0.5) / NS) * h;
            double x, y;
            rad_square_to_disk(a, bb, &x, &y);
            double r2 = fmin(1.0, x * x + y * y), r = sqrt(r2);
            int m = j * NS + k;
            rr[m] = r;
            if (!c->reflect)
                rho_out_init(&ro[m], r, -sqrt(1.0 - r2), c->s, c->k0);
            else if (smith) /* Lambda(tr) here; the pair's G2 below */
                vr[m] = bt_lambda(r, sqrt(1.0 - r2), c->s);
            else /* a midpoint has r < 1: cos > 0 */
                vr[m] = shadow_v(r / sqrt(1.0 - r2), c->s, c->k0);
            /* phi = psi + pi, psi the azimuth of (x, y); any phi at the centre r = 0 */
            cph[m] = r > 0.0 ? -x / r : 1.0;
            sph[m] = r > 0.0 ? -y / r : 0.0;
        }
    }
    double sp[NS], cp[NS], vi[NS];
    rho_in ri[NS];
    for (int i = 0; i < NS; i++) {
        double u0 = ((double)i0 + (i + 0.5) / NS) * h;
        double st = fmin(1.0, fmax(0.0, 1.0 - 2.0 * (u0 + RAD_FTINY)));
        sp[i] = st;
        cp[i] = sqrt(1.0 - st * st);
        if (c->reflect)
            vi[i] = smith ? bt_lambda(st, cp[i], c->s) /* Lambda(ti): the pair's G2 below */
                          : shadow_v(st / cp[i], c->s, c->k0); /* cp > 0 below u0 = 0.5 - FTINY */
        else
            rho_in_init_m(&ri[i], st, cp[i], c->s, c->k0, c->model);
    }
    /* The cell's ring radii: the Chebyshev norm of (2a - 1, 2b - 1) over the cell. */
    double alo = 2.0 * i1 * h - 1.0, blo = 2.0 * i2 * h - 1.0;
    double rmin = fmax(dist0(alo, alo + 2.0 * h), dist0(blo, blo + 2.0 * h));
    double rmax = fmax(absmax(alo, alo + 2.0 * h), absmax(blo, blo + 2.0 * h));
    double dr = (rmax - rmin) / NS; /* > 0: a cell of side 2h spans 2h in one coordinate */
    /* one sample: d(u0) d(a) d(b) = (h / NS)^3; d(mu) dr = 2 sin tp d(u0) pi da db / r,
       so its weight in the mean e_L1 of the rings of its bin is ws / (dr floor) */
    double w = 2.0 * M_PI * pow(h / NS, 3.0) / dr, ws[NS][NS * NS], fl[NS];
    int bin[NS * NS];
    for (int m = 0; m < NS * NS; m++) {
        int q = (int)((rr[m] - rmin) / dr);
        bin[m] = q < 0 ? 0 : (q >= NS ? NS - 1 : q);
    }
    float val[3] = {0.0f, 0.0f, 0.0f};
    double cmax = 0.0, share[3] = {0.0, 0.0, 0.0};
    for (int ch = 0; ch < c->nch; ch++) {
        if (c->same[ch] != ch) { /* an index met before: the same samples, value, share */
            val[ch] = val[c->same[ch]];
            share[ch] = share[c->same[ch]];
            continue;
        }
        double sum = 0.0, wsum = 0.0;
        for (int i = 0; i < NS; i++) {
            if (c->reflect) {
                for (int m = 0; m < NS * NS; m++)
                    f[i][m] = smith ? rho_r_cell(c, c->n[ch], sp[i], cp[i], 1.0, rr[m], cph[m],
                                                 sph[m], bt_smith_r_factor(vi[i], vr[m]))
                                    : rho_r_cell(c, c->n[ch], sp[i], cp[i], vi[i], rr[m], cph[m],
                                                 sph[m], vr[m]);
            } else {
                for (int m = 0; m < NS * NS; m++) {
                    rho_out om = ro[m];
                    if (smith)
                        rho_out_init_m(&om, ro[m].sin_to, ro[m].cos_to, c->s, c->k0, &ri[i]);
                    f[i][m] = c->scale[ch] *
                              rho_kernel(c->n[ch], c->s, &ri[i], &om, cph[m], sph[m]);
                }
            }
            if (c->ms[ch]) /* full: the tally's part at the same samples (mu = cos tq) */
                for (int m = 0; m < NS * NS; m++)
                    f[i][m] += c->scale[ch] *
                               full_ms(c->ms[ch], c->reflect, asin(sp[i]) * (180.0 / M_PI),
                                       sqrt(fmax(0.0, 1.0 - rr[m] * rr[m])), cph[m]);
            double row = 0.0;
            for (int m = 0; m < NS * NS; m++)
                row += f[i][m];
            sum += sp[i] * row;
            wsum += sp[i] * NS * NS;
        }
        /* wsum = 0 only if every sample has sin tp = 0, which midpoints below u0 = 0.5
           never do; the plain mean then */
        double mean = wsum > 0.0 ? sum / wsum : 0.0;
        double lo = 1e300, hi = 0.0;
        for (int q = 0; q < NS; q++) {
            double r0 = rmin + q * dr;
            fl[q] = floor_min(c, ch, r0, r0 + dr);
        }
        for (int i = 0; i < NS; i++) {
            for (int m = 0; m < NS * NS; m++) {
                /* r >= h / NS at a midpoint (the centre is a cell corner): no 1/0 */
                ws[i][m] = w * sp[i] / fmax(rr[m], 1e-300) / fl[bin[m]];
                lo = fmin(lo, f[i][m]);
                hi = fmax(hi, f[i][m]);
            }
        }
        /* The leaf value: the one whose largest bin share is smallest (convex in v, so a
           golden-section search over [min f, max f]); it equals the mean for a lobe that
           is linear over the cell, and near grazing light, where the floor max(T, 0.01)
           of the outer rings is far below the inner ones', it leans towards the outer. */
        double x0 = lo, x1 = hi, g = 0.5 * (sqrt(5.0) - 1.0);
        double ya = x1 - g * (x1 - x0), yb = x0 + g * (x1 - x0);
        double ea = tt_binmax(f, ws, bin, ya), eb = tt_binmax(f, ws, bin, yb);
        for (int it = 0; it < 40 && x1 - x0 > 1e-6 * (hi > 0.0 ? hi : 1.0); it++) {
            if (ea <= eb) {
                x1 = yb;
                yb = ya;
                eb = ea;
                ya = x1 - g * (x1 - x0);
                ea = tt_binmax(f, ws, bin, ya);
            } else {
                x0 = ya;
                ya = yb;
                ea = eb;
                yb = x0 + g * (x1 - x0);
                eb = tt_binmax(f, ws, bin, yb);
            }
        }
        double v = hi > lo ? 0.5 * (x0 + x1) : mean;
        val[ch] = file_value(v);
        share[ch] = tt_binmax(f, ws, bin, val[ch]);
        cmax = fmax(cmax, share[ch]);
    }
    nd->contrib = (float)fmin(cmax, 3e38);
    if (c->nch == 3) {
        for (int ch = 0; ch < 3; ch++) {
            cv[ch] = val[ch];
            cv[RAD_CV + ch] = (float)fmin(share[ch], 3e38);
        }
        rad_colour_leaf(c->m, val, &nd->v, cv + 3);
    } else {
        nd->v = val[0];
    }
}

typedef struct tt_job {
    const tt_ctx *c;
    int level;           /* level of the task cells */
    uint32_t n0, n1, n2; /* task cells per dimension (u0 < 0.5, b < 0.5 only) */
    tt_buf *bufs;
    double eps[3];       /* rad_tb_grow's thresholds, per channel */
} tt_job;

/* Whether cell k is split at thresholds eps: its contrib above eps (one channel), some
   channel's share above that channel's eps (colour). */
static int tt_split(const tb_node *v, const float *cv, size_t k, const double eps[3])
{
    if (!cv)
        return v[k].contrib > eps[0];
    const float *sh = cv + k * TB_CV + RAD_CV;
    return sh[0] > eps[0] || sh[1] > eps[1] || sh[2] > eps[2];
}

/* Splits, below node k, every leaf whose contrib is above eps, again and again. */
static void tt_grow(const tt_job *j, tt_buf *b, int32_t k, int level, uint32_t i0,
                    uint32_t i1, uint32_t i2)
{
    if (level > b->depth)
        b->depth = level;
    if (b->v[k].child < 0) {
        if (!tt_split(b->v, b->cv, (size_t)k, j->eps) || level >= j->c->max_level ||
            b->budget_hit)
            return;
        int32_t ch = buf_alloc(b, 8, j->c->nch == 3);
        if (ch < 0)
            return;
        b->v[k].child = ch;
        for (int n = 0; n < 8; n++)
            tt_eval(j->c, &b->v[ch + n], b->cv ? b->cv + (size_t)(ch + n) * TB_CV : NULL,
                    level + 1, 2 * i0 + (n & 1), 2 * i1 + ((n >> 1) & 1),
                    2 * i2 + ((n >> 2) & 1));
    }
    int32_t ch = b->v[k].child;
    for (int n = 0; n < 8; n++)
        tt_grow(j, b, ch + n, level + 1, 2 * i0 + (n & 1), 2 * i1 + ((n >> 1) & 1),
                2 * i2 + ((n >> 2) & 1));
}

static void tt_task(void *arg, size_t t)
{
    tt_job *j = arg;
    uint32_t i2 = (uint32_t)(t % j->n2), i1 = (uint32_t)((t / j->n2) % j->n1);
    uint32_t i0 = (uint32_t)(t / ((size_t)j->n2 * j->n1));
    tt_buf *b = &j->bufs[t];
    if (b->n == 0) {
        if (buf_alloc(b, 1, j->c->nch == 3) < 0)
            return;
        tt_eval(j->c, &b->v[0], b->cv, j->level, i0, i1, i2);
    }
    tt_grow(j, b, 0, j->level, i0, i1, i2);
}

struct rad_tb {
    tt_ctx c;
    tt_job j;
    size_t ntask;
    int threads;
};

rad_tb *rad_tb_new(const btdf_params *p, const rad_block *blk, btdf_full *const *ms,
                   btdf_full *const *ms_light, int threads)
{
    rad_tb *t = calloc(1, sizeof *t);
    if (!t)
        return NULL;
    tt_ctx *c = &t->c;
    c->nch = p->channels == 3 ? 3 : 1;
    /* blk is block k = 2 reflect + (p on +Z) for some index; its geometry per channel */
    int k = 2 * blk->reflect + (blk->side == BTDF_SIDE_LEAVE);
    rad_block bc[3];
    for (int ch = 0; ch < c->nch; ch++) {
        if (c->nch == 3)
            rad_block_of(k, p->ior[ch], &bc[ch]);
        else
            bc[ch] = *blk;
        c->n[ch] = bc[ch].n;
        c->scale[ch] = bc[ch].scale;
        c->same[ch] = ch;
        for (int d = ch - 1; d >= 0; d--)
            if (p->ior[d] == p->ior[ch])
                c->same[ch] = d;
    }
    rad_rgb_to_xyz(c->m);
    c->s = p->smoothness;
    c->k0 = p->k0;
    c->model = p->model == BTDF_MODEL_FULL ? BTDF_MODEL_SMITH : p->model;
    for (int ch = 0; ch < c->nch; ch++)
        c->ms[ch] = ms ? ms[ch] : NULL;
    c->reflect = blk->reflect;
    /* Start where a cell is no wider than the lobe (about 2/s rad in facet slope). */
    int lv = 3 + (int)ceil(log2(fmax(1.0, p->smoothness / 2.0)));
    c->min_level = lv < 3 ? 3 : (lv > 6 ? 6 : lv);
    c->max_level = 18;
    for (int ch = 0; ch < c->nch; ch++) {
        btdf_params q = *p;
        q.model = c->model;
        q.channels = 1;
        q.ior[0] = bc[ch].n_light;
        for (int i = 0; i < NR_GRID; i++) {
            double r = (double)i / (NR_GRID - 1), v = 0.0;
            if (c->same[ch] != ch) {
                c->rfloor[ch][i] = c->rfloor[c->same[ch]][i];
                continue;
            }
            if (blk->reflect)
                btdf_reflectance(&q, asin(r), &v);
            else
                btdf_transmittance(&q, asin(r), &v);
            if (ms_light && ms_light[ch]) /* full's norm: plus the tallied orders 2+ */
                v += full_ms_energy(ms_light[ch], blk->reflect, asin(r), NULL);
            c->rfloor[ch][i] = fmax(v, 0.01); /* MODEL.md section 6 floor */
        }
    }
    t->threads = threads;
    t->j.c = c;
    t->j.level = c->min_level;
    t->j.n0 = 1u << (t->j.level - 1);
    t->j.n1 = 1u << t->j.level;
    t->j.n2 = 1u << (t->j.level - 1);
    t->ntask = (size_t)t->j.n0 * t->j.n1 * t->j.n2;
    t->j.bufs = calloc(t->ntask, sizeof *t->j.bufs);
    if (!t->j.bufs) {
        free(t);
        return NULL;
    }
    return t;
}

void rad_tb_free(rad_tb *t)
{
    if (!t)
        return;
    for (size_t k = 0; k < t->ntask; k++) {
        free(t->j.bufs[k].v);
        free(t->j.bufs[k].cv);
    }
    free(t->j.bufs);
    free(t);
}

size_t rad_tb_nodes(const rad_tb *t)
{
    size_t n = 0;
    for (size_t k = 0; k < t->ntask; k++)
        n += t->j.bufs[k].n;
    return n;
}

btdf_status rad_tb_grow(rad_tb *t, double eps, size_t max_nodes)
{
    const double e3[3] = {eps, eps, eps};
    return rad_tb_grow3(t, e3, max_nodes);
}

btdf_status rad_tb_grow3(rad_tb *t, const double eps[3], size_t max_nodes)
{
    /* Each task may use what the others leave: checked in total below. */
    size_t used = rad_tb_nodes(t);
    for (size_t k = 0; k < t->ntask; k++)
        t->j.bufs[k].max = t->j.bufs[k].n + (max_nodes > used ? max_nodes - used : 0);
    for (int c = 0; c < 3; c++)
        t->j.eps[c] = eps[c];
    core_parallel_for(t->threads, t->ntask, tt_task, &t->j);
    int nomem = 0, hit = 0;
    for (size_t k = 0; k < t->ntask; k++) {
        nomem |= t->j.bufs[k].nomem || !t->j.bufs[k].v;
        hit |= t->j.bufs[k].budget_hit;
    }
    if (nomem)
        return BTDF_ENOMEM;
    return hit || rad_tb_nodes(t) > max_nodes ? BTDF_EBUDGET : BTDF_OK;
}

typedef struct tt_out {
    rad_node *v;
    float *cv; /* colour: RAD_CV per node, else NULL */
    int colour;
    size_t n, cap;
    int depth, nomem;
    double eps[3];
    const tt_job *j;
} tt_out;

static int32_t out_alloc(tt_out *o, size_t count)
{
    if (o->n + count > o->cap) {
        size_t cap = o->cap ? 2 * o->cap : 1024;
        while (cap < o->n + count)
            cap *= 2;
        rad_node *v = realloc(o->v, cap * sizeof *v);
        if (!v || cap > (size_t)INT32_MAX) {
            if (v)
                o->v = v;
            o->nomem = 1;
            return -1;
        }
        o->v = v;
        if (o->colour) {
            float *cv = realloc(o->cv, cap * RAD_CV * sizeof *cv);
            if (!cv) {
                o->nomem = 1;
                return -1;
            }
            o->cv = cv;
        }
        o->cap = cap;
    }
    int32_t first = (int32_t)o->n;
    for (size_t i = 0; i < count; i++) {
        o->v[o->n + i].child = -1;
        o->v[o->n + i].v = 0.0f;
        if (o->colour) { /* no light, in the white point's chromaticity (rad_colour_leaf) */
            static const float none[3] = {0.0f, 0.0f, 0.0f};
            static const double unit[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
            float y, *cv = o->cv + (o->n + i) * RAD_CV;
            cv[0] = cv[1] = cv[2] = 0.0f;
            rad_colour_leaf(unit, none, &y, cv + 3);
        }
    }
    o->n += count;
    return first;
}

/* Children of node di that are 8 leaves of one value (all zero where no light goes,
   say) read the same as one leaf: fold them (they are the last 8 nodes written). */
static void fold(tt_out *o, int32_t di)
{
    int32_t ch = o->v[di].child;
    if (ch < 0 || (size_t)ch + 8 != o->n)
        return;
    for (int n = 0; n < 8; n++)
        if (o->v[ch + n].child >= 0 || o->v[ch + n].v != o->v[ch].v)
            return;
    if (o->colour) { /* and of one colour: every channel, u' and v' */
        const float *c0 = o->cv + (size_t)ch * RAD_CV;
        for (int n = 1; n < 8; n++)
            for (int e = 0; e < RAD_CV; e++)
                if (c0[(size_t)n * RAD_CV + e] != c0[e])
                    return;
        memcpy(o->cv + (size_t)di * RAD_CV, c0, RAD_CV * sizeof *c0);
    }
    o->v[di].v = o->v[ch].v;
    o->v[di].child = -1;
    o->n -= 8;
}

static void copy_sub(tt_out *o, const tt_buf *src, int32_t si, int mirror, int32_t di,
                     int level)
{
    o->v[di].v = src->v[si].v;
    if (o->colour)
        memcpy(o->cv + (size_t)di * RAD_CV, src->cv + (size_t)si * TB_CV,
               RAD_CV * sizeof *o->cv);
    o->depth = level > o->depth ? level : o->depth;
    if (src->v[si].child < 0 || !tt_split(src->v, src->cv, (size_t)si, o->eps))
        return;
    int32_t ch = out_alloc(o, 8);
    if (ch < 0)
        return;
    o->v[di].child = ch;
    for (int n = 0; n < 8; n++)
        copy_sub(o, src, src->v[si].child + (mirror ? (n ^ 4) : n), mirror, ch + n,
                 level + 1);
    fold(o, di);
}

/* Lays the tree out from the root: full levels above the task cells, placeholders for
   u0 >= 0.5, the task subtrees below, mirrored (b -> 1 - b) for b >= 0.5. */
static void assemble(tt_out *o, int32_t di, int level, uint32_t i0, uint32_t i1, uint32_t i2)
{
    const tt_job *j = o->j;
    if (level == j->level) {
        int mirror = i2 >= j->n2;
        uint32_t m2 = mirror ? 2 * j->n2 - 1 - i2 : i2;
        size_t t = ((size_t)i0 * j->n1 + i1) * j->n2 + m2;
        copy_sub(o, &j->bufs[t], 0, mirror, di, level);
        return;
    }
    int32_t ch = out_alloc(o, 8);
    if (ch < 0)
        return;
    o->v[di].child = ch;
    for (int n = 0; n < 8; n++) {
        uint32_t c0 = 2 * i0 + (n & 1), c1 = 2 * i1 + ((n >> 1) & 1), c2 = 2 * i2 + ((n >> 2) & 1);
        if (level == 0 && (n & 1))
            continue; /* u0 >= 0.5 is never looked up: a { 0 } placeholder */
        assemble(o, ch + n, level + 1, c0, c1, c2);
    }
    fold(o, di);
}

btdf_status rad_tb_extract(const rad_tb *t, double eps, rad_block *blk)
{
    const double e3[3] = {eps, eps, eps};
    return rad_tb_extract3(t, e3, blk);
}

btdf_status rad_tb_extract3(const rad_tb *t, const double eps[3], rad_block *blk)
{
    tt_out o;
    memset(&o, 0, sizeof o);
    o.j = &t->j;
    for (int c = 0; c < 3; c++)
        o.eps[c] = eps[c];
    o.colour = t->c.nch == 3;
    if (out_alloc(&o, 1) >= 0)
        assemble(&o, 0, 0, 0, 0, 0);
    if (o.nomem) {
        free(o.v);
        free(o.cv);
        return BTDF_ENOMEM;
    }
    free(blk->nodes);
    free(blk->cv);
    blk->nodes = o.v;
    blk->cv = o.cv;
    blk->nnodes = o.n;
    blk->leaves = 0;
    for (size_t i = 0; i < o.n; i++)
        blk->leaves += o.v[i].child < 0;
    blk->depth = o.depth;
    return BTDF_OK;
}

btdf_status rad_tree_build(const btdf_params *p, double eps, int threads, size_t max_nodes,
                           rad_block *blk, char *msg, size_t msglen)
{
    rad_tb *t = rad_tb_new(p, blk, NULL, NULL, threads);
    if (!t)
        return core_say(BTDF_ENOMEM, msg, msglen, "out of memory building the tensor tree");
    btdf_status st = rad_tb_grow(t, eps, max_nodes);
    if (st == BTDF_OK || st == BTDF_EBUDGET) {
        btdf_status se = rad_tb_extract(t, eps, blk);
        st = se != BTDF_OK ? se : st;
    }
    rad_tb_free(t);
    if (st == BTDF_ENOMEM)
        return core_say(st, msg, msglen, "out of memory building the tensor tree");
    if (st == BTDF_EBUDGET)
        return core_say(st, msg, msglen, "tensor tree node budget (%zu) reached", max_nodes);
    return st;
}
