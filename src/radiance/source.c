/* SPDX-License-Identifier: MIT */
/* source.c: Klems matrices and tensor trees of a caller's BSDF (btdf_rad_source), such as
   the system of a pane (docs/pane.md): the same blocks, frames and files as the
   interface's, values from the caller. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "radiance/radiance_impl.h"

/* Gauss-Legendre on [-1, 1], 3 points: exact for quintics along each axis of a patch. */
static const double g3x[3] = {-0.7745966692414834, 0.0, 0.7745966692414834};
static const double g3w[3] = {0.5555555555555556, 0.8888888888888888, 0.5555555555555556};
#define SRC_Q 3

/* The value block k returns for the view p and the light q (Radiance's frame, pointing
   away), from the source in the light's own frame. */
static double src_value(const btdf_rad_source *s, int k, const double p[3], const double q[3])
{
    double ti = acos(fmin(1.0, fabs(q[2]))), to = acos(fmin(1.0, fabs(p[2])));
    /* btdf.h's phi: the view's azimuth less the light's (a light from -Z sees both turned
       by pi about x, which changes the sign of phi only, and the BSDF is even in it) */
    double phi = atan2(p[1], p[0]) - atan2(q[1], q[0]);
    double v = s->eval(s->user, k, ti, to, phi);
    return isfinite(v) && v > 0.0 ? v : 0.0;
}

typedef struct src_job {
    const btdf_rad_source *s;
    const rad_klems_basis *kb;
    int k;
    double *acc; /* [o * np + i] */
    double *rect; /* per patch: w0, w1, p0, p1 */
    size_t cur;   /* the incident patch (src_klems_bands) */
} src_job;

static void patch_rect4(const rad_klems_basis *kb, int p, double r[4])
{
    int band = 0;
    while (p >= kb->nphi[band])
        p -= kb->nphi[band++];
    double t0 = kb->theta[band] * M_PI / 180.0, t1 = kb->theta[band + 1] * M_PI / 180.0;
    double dp = 2.0 * M_PI / kb->nphi[band];
    r[0] = sin(t0) * sin(t0);
    r[1] = sin(t1) * sin(t1);
    r[2] = (p - 0.5) * dp;
    r[3] = (p + 0.5) * dp;
}

/* A direction on side sg (+1 / -1) at (w = sin^2 theta, azimuth). */
static void dir_of(double w, double az, double sg, double d[3])
{
    double st = sqrt(w), ct = sqrt(1.0 - w); /* w in [0, 1] */
    d[0] = st * cos(az);
    d[1] = st * sin(az);
    d[2] = sg * ct;
}

/* The outgoing patches of incident node p by bands: in a band every patch has the same 3
   polar nodes, so the source is asked once per polar node for all the band's azimuths. */
static void src_klems_bands(const src_job *J, int k, const double p[3], double sq, double wgi)
{
    const rad_klems_basis *kb = J->kb;
    int np = kb->npatch, first = 0;
    size_t i = (size_t)(J->cur);
    double to = acos(fmin(1.0, fabs(p[2]))), azp = atan2(p[1], p[0]);
    double phi[3 * 64], val[3 * 64];
    for (int band = 0; band < kb->nbands; band++) {
        int nb = kb->nphi[band];
        const double *r0 = J->rect + 4 * first;
        for (int c = 0; c < SRC_Q; c++) {
            double w = r0[0] + (r0[1] - r0[0]) * 0.5 * (g3x[c] + 1.0);
            double ti = asin(sqrt(w));
            for (int j = 0; j < nb; j++) {
                const double *ro = J->rect + 4 * (first + j);
                for (int d = 0; d < SRC_Q; d++)
                    phi[j * SRC_Q + d] = azp - (ro[2] + (ro[3] - ro[2]) * 0.5 * (g3x[d] + 1.0));
            }
            J->s->eval_phis(J->s->user, k, ti, to, (size_t)(nb * SRC_Q), phi, val);
            for (int j = 0; j < nb; j++) {
                double s = 0.0;
                for (int d = 0; d < SRC_Q; d++) {
                    double v = val[j * SRC_Q + d];
                    s += g3w[c] * g3w[d] * 0.25 * (isfinite(v) && v > 0.0 ? v : 0.0);
                }
                J->acc[(size_t)(first + j) * np + i] += wgi * s;
            }
        }
        first += nb;
    }
    (void)sq;
}

/* One incident patch i of block k: M[o][i] = 1/(L_i L_o) int_i int_o f cos cos, by 3 x 3
   Gauss points in (w, phi) over each patch (projected solid angle dw/2 dphi); p is the
   reverse of the incident patch's direction of travel (klems.c), q the outgoing patch's
   direction. The delta the source names lands on the diagonal: its mirror (or straight
   through) direction has the incident patch's index. */
static void src_klems_in(void *arg, size_t i)
{
    src_job JJ = *(const src_job *)arg;
    JJ.cur = i;
    const src_job *J = &JJ;
    const rad_klems_basis *kb = J->kb;
    int np = kb->npatch, k = J->k, refl = k >= 2;
    double sp = k % 2 == 0 ? -1.0 : 1.0, sq = refl ? sp : -sp;
    const double *ri = J->rect + 4 * i;
    double Li = 0.5 * (ri[1] - ri[0]) * (ri[3] - ri[2]);
    for (int o = 0; o < np; o++)
        J->acc[(size_t)o * np + i] = 0.0;
    for (int a = 0; a < SRC_Q; a++)
        for (int b = 0; b < SRC_Q; b++) {
            double wi = ri[0] + (ri[1] - ri[0]) * 0.5 * (g3x[a] + 1.0);
            double ai = ri[2] + (ri[3] - ri[2]) * 0.5 * (g3x[b] + 1.0);
            double wgi = g3w[a] * g3w[b] * 0.25; /* the patch's share, sums to 1 */
            double t[3], p[3];
            dir_of(wi, ai, -sp, t); /* the light's travel, reversed: p */
            p[0] = -t[0];
            p[1] = -t[1];
            p[2] = -t[2];
            if (J->s->eval_phis) {
                src_klems_bands(J, k, p, sq, wgi);
            } else
            for (int o = 0; o < np; o++) {
                const double *ro = J->rect + 4 * o;
                double s = 0.0;
                for (int c = 0; c < SRC_Q; c++)
                    for (int d = 0; d < SRC_Q; d++) {
                        double q[3];
                        dir_of(ro[0] + (ro[1] - ro[0]) * 0.5 * (g3x[c] + 1.0),
                               ro[2] + (ro[3] - ro[2]) * 0.5 * (g3x[d] + 1.0), sq, q);
                        s += g3w[c] * g3w[d] * 0.25 * src_value(J->s, k, p, q);
                    }
                J->acc[(size_t)o * np + i] += wgi * s;
            }
            if (J->s->specular) {
                double th = asin(sqrt(wi));
                /* the delta's power over the outgoing patch's projected solid angle, L_i */
                J->acc[(size_t)i * np + i] += wgi * J->s->specular(J->s->user, k, th) / Li;
            }
        }
}

/* The Klems matrices of the four blocks. Three channels: each channel's exact patch
   averages (the source called with user_ch[c]), combined into CIE X, Y, Z by Radiance's
   RGB primaries and each then rounded, as rad_klems_colour combines an interface's. */
static btdf_status src_klems(const btdf_rad_source *s, btdf_rad *r, int threads, char *msg,
                             size_t msglen)
{
    const rad_klems_basis *kb = r->kb;
    size_t np = (size_t)kb->npatch, nn = np * np;
    int nc = r->channels == 3 ? 3 : 1;
    double *rect = malloc(sizeof(double) * 4 * np), *acc[3] = {NULL, NULL, NULL}, m[3][3];
    int bad = !rect;
    for (int c = 0; c < nc; c++)
        bad |= !(acc[c] = malloc(sizeof(double) * nn));
    for (size_t p = 0; p < np && !bad; p++)
        patch_rect4(kb, (int)p, rect + 4 * p);
    rad_rgb_to_xyz(m);
    for (int k = 0; k < 4 && !bad; k++) {
        for (int c = 0; c < nc; c++) {
            btdf_rad_source sc = *s;
            if (nc == 3)
                sc.user = s->user_ch[c];
            src_job J = {&sc, kb, k, acc[c], rect, 0};
            core_parallel_for(threads, np, src_klems_in, &J);
        }
        rad_block *b = &r->b[k];
        float **dst[3] = {&b->klems_x, &b->klems, &b->klems_z};
        for (int i = 0; i < nc && !bad; i++) {
            float *out = *dst[nc == 3 ? i : 1] = malloc(sizeof(float) * nn);
            bad |= !out;
            for (size_t e = 0; out && e < nn; e++)
                out[e] = rad_klems_value(nc == 3 ? m[i][0] * acc[0][e] + m[i][1] * acc[1][e] +
                                                       m[i][2] * acc[2][e]
                                                 : acc[0][e]);
        }
    }
    free(rect);
    for (int c = 0; c < 3; c++)
        free(acc[c]);
    return bad ? core_say(BTDF_ENOMEM, msg, msglen, "out of memory") : BTDF_OK;
}

/* A full tree of `depth` levels: leaf (u0, a, b) holds the source at its centre, and the
   delta's power over the leaf's projected solid angle (pi 4^-depth: the concentric map
   keeps areas) where the delta's direction falls. Nodes in Radiance's order: the 8
   children of a node at child .. child + 7, bit d of the index the upper half of
   dimension d (u0, a, b as dimensions 0, 1, 2). */
typedef struct tree_job {
    const btdf_rad_source *s;
    int k, depth;
    size_t side; /* 2^depth */
    float *leaf; /* [(iu * side + ia) * side + ib] */
} tree_job;

static void tree_row(void *arg, size_t iu)
{
    const tree_job *J = arg;
    size_t n = J->side;
    int k = J->k, refl = k >= 2;
    double sp = k % 2 == 0 ? -1.0 : 1.0, sq = refl ? sp : -sp;
    double u0 = (iu + 0.5) / (double)n;
    /* rad_u0_of_sin inverted (its 1e-6 offset is far below a leaf) */
    double st = 1.0 - 2.0 * u0, ct = sqrt(1.0 - st * st);
    double p[3] = {-st, 0.0, sp * ct}; /* travelling towards +x, as rad_tree_coords turns */
    double cell = M_PI / (double)(n * n);
    double spec = J->s->specular ? J->s->specular(J->s->user, k, asin(st)) : 0.0;
    /* the delta's direction: the mirror (reflection) or straight through */
    double dq[3] = {st, 0.0, sq * ct};
    double da, db;
    rad_disk_to_square(dq[0], dq[1], &da, &db);
    size_t sa = (size_t)(da * n), sb = (size_t)(db * n);
    if (sa >= n)
        sa = n - 1;
    if (sb >= n)
        sb = n - 1;
    for (size_t ia = 0; ia < n; ia++)
        for (size_t ib = 0; ib < n; ib++) {
            double x, y, q[3];
            rad_square_to_disk((ia + 0.5) / (double)n, (ib + 0.5) / (double)n, &x, &y);
            double r2 = x * x + y * y;
            q[0] = x;
            q[1] = y;
            q[2] = sq * sqrt(r2 < 1.0 ? 1.0 - r2 : 0.0);
            double v = src_value(J->s, k, p, q);
            if (spec > 0.0 && ia == sa && ib == sb)
                v += spec / cell;
            J->leaf[(iu * n + ia) * n + ib] = (float)v;
        }
}

/* Node k of the full tree over [lo, lo + size)^3 (in leaves), its children after it. */
static size_t tree_fill(rad_node *nodes, size_t *next, const float *leaf, size_t n, size_t k,
                        size_t u, size_t a, size_t b, size_t size)
{
    if (size == 1) {
        nodes[k].child = -1;
        nodes[k].v = leaf[(u * n + a) * n + b];
        return k;
    }
    size_t c = *next;
    *next += 8;
    nodes[k].child = (int32_t)c;
    nodes[k].v = 0.0f;
    size_t h = size / 2;
    for (int i = 0; i < 8; i++)
        tree_fill(nodes, next, leaf, n, c + (size_t)i, u + ((i & 1) ? h : 0),
                  a + ((i & 2) ? h : 0), b + ((i & 4) ? h : 0), h);
    return k;
}

/* btdf_rad_source.merge: 1 when node k is a leaf once its subtree is merged; *lo and *hi
   the range of the full tree's leaves under it (a merged leaf stands for all of them, so
   a merge two levels up is checked against those, not against the means below it). */
static int tree_merge(rad_node *nodes, size_t k, double eps, double *lo, double *hi)
{
    if (nodes[k].child < 0) {
        *lo = *hi = (double)nodes[k].v;
        return 1;
    }
    size_t c = (size_t)nodes[k].child;
    int leaves = 1;
    *lo = HUGE_VAL;
    *hi = -HUGE_VAL;
    for (size_t i = 0; i < 8; i++) {
        double l, h;
        leaves &= tree_merge(nodes, c + i, eps, &l, &h);
        *lo = fmin(*lo, l);
        *hi = fmax(*hi, h);
    }
    if (!leaves)
        return 0;
    double mean = 0.0; /* children of one node have equal size: the mean keeps the integral */
    for (size_t i = 0; i < 8; i++)
        mean += (double)nodes[c + i].v;
    mean /= 8.0;
    double lim = eps * fmax(fabs(mean), 0.01 / M_PI);
    if (*hi - mean > lim || mean - *lo > lim)
        return 0;
    nodes[k].child = -1;
    nodes[k].v = (float)mean;
    return 1;
}

/* The nodes reachable from src[k] into dst[d], children contiguous after their parent
   as tree_fill lays them; counts the leaves. */
static void tree_copy(const rad_node *src, size_t k, rad_node *dst, size_t d, size_t *next,
                      size_t *leaves)
{
    dst[d] = src[k];
    if (src[k].child < 0) {
        (*leaves)++;
        return;
    }
    size_t c = *next;
    *next += 8;
    dst[d].child = (int32_t)c;
    for (size_t i = 0; i < 8; i++)
        tree_copy(src, (size_t)src[k].child + i, dst, c + i, next, leaves);
}

static btdf_status src_tree(const btdf_rad_source *s, int depth, btdf_rad *r, int threads,
                            char *msg, size_t msglen)
{
    size_t n = (size_t)1 << depth, leaves = n * n * n, total = 0;
    for (size_t l = 1, d = 0; d <= (size_t)depth; d++, l *= 8)
        total += l;
    float *leaf = malloc(sizeof(float) * leaves);
    if (!leaf)
        return core_say(BTDF_ENOMEM, msg, msglen, "out of memory (tree depth %d)", depth);
    for (int k = 0; k < 4; k++) {
        tree_job J = {s, k, depth, n, leaf};
        core_parallel_for(threads, n, tree_row, &J);
        rad_block *b = &r->b[k];
        b->nodes = malloc(sizeof(rad_node) * total);
        if (!b->nodes) {
            free(leaf);
            return core_say(BTDF_ENOMEM, msg, msglen, "out of memory (tree depth %d)", depth);
        }
        size_t next = 1;
        tree_fill(b->nodes, &next, leaf, n, 0, 0, 0, 0, n);
        b->nnodes = total;
        b->leaves = leaves;
        b->depth = depth;
        double lo, hi;
        if (s->merge > 0.0 && tree_merge(b->nodes, 0, s->merge, &lo, &hi) == 0) {
            rad_node *c = malloc(sizeof(rad_node) * total);
            if (!c) {
                free(leaf);
                return core_say(BTDF_ENOMEM, msg, msglen, "out of memory (tree depth %d)",
                                depth);
            }
            size_t nx = 1, nl = 0;
            tree_copy(b->nodes, 0, c, 0, &nx, &nl);
            free(b->nodes);
            b->nodes = c;
            b->nnodes = nx;
            b->leaves = nl;
        } else if (s->merge > 0.0) { /* every leaf merged into the root */
            b->nodes[0].child = -1;
            b->nnodes = 1;
            b->leaves = 1;
        }
    }
    free(leaf);
    return BTDF_OK;
}

BTDF_API btdf_status btdf_rad_build_source(const btdf_rad_source *s, const btdf_params *p,
                                           btdf_rad_basis basis, int depth, int threads,
                                           btdf_rad **out, char *msg, size_t msglen)
{
    if (!s || !s->eval || !p || !out)
        return core_say(BTDF_EINVAL, msg, msglen, "btdf_rad_build_source: NULL argument");
    if (p->channels == 3 && basis == BTDF_RAD_TREE3)
        return core_say(BTDF_ENOTSUP, msg, msglen,
                        "btdf_rad_build_source: three channels: the Klems bases only (a "
                        "colour tree3 of a caller's BSDF is not available)");
    if (p->channels == 3 && !(s->user_ch[0] && s->user_ch[1] && s->user_ch[2]))
        return core_say(BTDF_EINVAL, msg, msglen,
                        "btdf_rad_build_source: three channels need user_ch[0..2]");
    if (p->channels != 1 && p->channels != 3)
        return core_say(BTDF_EINVAL, msg, msglen,
                        "btdf_rad_build_source: %d channels: one or three", p->channels);
    if (!(s->merge >= 0.0 && s->merge <= 0.5))
        return core_say(BTDF_EINVAL, msg, msglen, "merge %g: use 0 (the full tree) to 0.5",
                        s->merge);
    if (basis == BTDF_RAD_TREE3 && !(depth >= 1 && depth <= BTDF_RAD_SOURCE_DEPTH_MAX))
        return core_say(BTDF_EINVAL, msg, msglen, "tree depth %d: use 1..%d", depth,
                        BTDF_RAD_SOURCE_DEPTH_MAX);
    double t0 = core_now();
    btdf_rad *r = calloc(1, sizeof *r);
    if (!r)
        return core_say(BTDF_ENOMEM, msg, msglen, "out of memory");
    r->basis = basis;
    r->p = *p;
    r->channels = p->channels;
    r->nblocks = 4;
    r->kb = basis == BTDF_RAD_TREE3 ? NULL : rad_klems(basis);
    for (int k = 0; k < 4; k++)
        rad_block_of(k, p->ior[0], &r->b[k]);
    if (s->description)
        snprintf(r->system, sizeof r->system, "%s", s->description);
    btdf_status st = basis == BTDF_RAD_TREE3 ? src_tree(s, depth, r, threads, msg, msglen)
                                             : src_klems(s, r, threads, msg, msglen);
    if (st != BTDF_OK) {
        btdf_rad_free(r);
        return st;
    }
    r->seconds_build = core_now() - t0;
    *out = r;
    return BTDF_OK;
}
