/* SPDX-License-Identifier: MIT */
/* source.c: a SCATFUN file of a caller's BSDF given by its azimuthal modes (a pane's
   system, docs/pane.md): the nodes, the cut series, the cdf rows, and the file's error
   against the source (btdf_scatfun_build_source). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "btdf_scatfun.h"
#include "core/core.h"
#include "scatfun/scatfun.h"
#include "scatfun/spline.h"

#define SRC_PI 3.14159265358979323846
#define SRC_ANGLES 24 /* stratified light angles per block (and as many at midpoints) */
#define SRC_CELLS 128 /* midpoint cells in mu_v and in phi on [0, pi] */

static const int src_blocks[4] = {BTDF_SCATFUN_T_ENTER, BTDF_SCATFUN_T_LEAVE,
                                  BTDF_SCATFUN_R_TOP, BTDF_SCATFUN_R_BOTTOM};

/* The block of a pair from the signs of its slow and fast nodes. */
static int pair_block(int slow_neg, int fast_neg)
{
    if (!slow_neg)
        return fast_neg ? BTDF_SCATFUN_R_TOP : BTDF_SCATFUN_T_ENTER;
    return fast_neg ? BTDF_SCATFUN_T_LEAVE : BTDF_SCATFUN_R_BOTTOM;
}

/* The work of one pass: the full node list (2K + 2, as the builder's: -P reversed, two
   zeros, P) and, per slow node, its row of cut series. */
typedef struct src_pass {
    const btdf_scatfun_source *s;
    double tol;
    size_t K, n;
    const double *P;  /* K half nodes, ascending in (0, 1) */
    double *full;     /* n */
    float **row;      /* n rows: the kept coefficients of the row, in fast order */
    uint32_t **len;   /* n rows: each pair's kept length */
    int failed;       /* a row could not get its memory */
} src_pass;

/* Trapezoid weights of the half nodes on [0, 1] (0 and the pole node's gap to 1 count
   as flat ends): w[r] for the value at P[r]. */
static void half_weights(const double *P, size_t K, double *w)
{
    for (size_t r = 0; r < K; r++) {
        double lo = r ? P[r - 1] : 0.0, hi = r + 1 < K ? P[r + 1] : 1.0;
        w[r] = 0.5 * (hi - lo);
    }
}

/* The row of slow node i: every pair's series from the source, (-1)^m c_m |mu_f|, cut
   where its tail is within the row's threshold (per block: the light row's T). */
static void pass_row(void *arg, size_t i)
{
    src_pass *ps = arg;
    const btdf_scatfun_source *s = ps->s;
    size_t K = ps->K, n = ps->n, M = (size_t)s->modes;
    ps->row[i] = NULL;
    ps->len[i] = calloc(n, sizeof(uint32_t));
    double *a = malloc(n * M * sizeof(double)), *w = malloc(K * sizeof(double));
    if (!ps->len[i] || !a || !w) {
        free(a);
        free(w);
        ps->failed = 1;
        return;
    }
    half_weights(ps->P, K, w);
    /* node K is the zero of the side below (the spline reaches it from -P[0]), K + 1 the
       zero above. At a zero slow node the light grazes: rho |mu_f| is not 0 there (a
       reflection lobe at grazing), so those rows hold the source's values at the floor
       cosine SF_MU_FLOOR, its limit; a row of zeros would bend the spline through the
       first interval for every light within it (e_L1 0.11 at 89.9 deg for a source
       constant in mu, at every refinement). */
    int slow_neg = i <= K;
    double ms = i == K || i == K + 1 ? SF_MU_FLOOR : fabs(ps->full[i]);
    /* the threshold of each half of the row (fast < 0, fast > 0), from its T */
    double thr[2] = {0.0, 0.0};
    for (size_t o = 0; o < n; o++) {
        double *ao = a + o * M;
        memset(ao, 0, M * sizeof(double));
        int fast_neg = o < K;
        if (o == K || o == K + 1)
            continue; /* a view at mu_f = 0: rho |mu_f| = 0 */
        int b = pair_block(slow_neg, fast_neg);
        if (!(s->blocks & b))
            continue;
        double mf = fabs(ps->full[o]);
        s->modes_at(s->user, b, ms, mf, ao);
        for (size_t m = 0; m < M; m++) /* phi_d = pi - phi: cos(m phi) = (-1)^m cos(m phi_d) */
            ao[m] *= (m & 1 ? -mf : mf);
        size_t r = fast_neg ? K - 1 - o : o - (K + 2);
        thr[!fast_neg] += 2.0 * SRC_PI * w[r] * fabs(ao[0]);
    }
    for (int h = 0; h < 2; h++) /* e_L1 of the cut <= 2 pi thr / max(T, 0.01) = tol / 4 */
        thr[h] = 0.25 * ps->tol * fmax(thr[h], T_FLOOR) / (2.0 * SRC_PI);
    size_t total = 0;
    for (size_t o = 0; o < n; o++) {
        const double *ao = a + o * M;
        double tail = 0.0, t = thr[!(o < K)];
        size_t m = M;
        while (m > 0 && tail + fabs(ao[m - 1]) <= t)
            tail += fabs(ao[--m]);
        ps->len[i][o] = (uint32_t)m;
        total += m;
    }
    ps->row[i] = malloc((total ? total : 1) * sizeof(float));
    if (!ps->row[i]) {
        ps->failed = 1;
    } else {
        size_t pos = 0;
        for (size_t o = 0; o < n; o++)
            for (uint32_t m = 0; m < ps->len[i][o]; m++)
                ps->row[i][pos++] = (float)a[o * M + m];
    }
    free(a);
    free(w);
}

static void pass_free(src_pass *ps)
{
    for (size_t i = 0; ps->row && i < ps->n; i++) {
        free(ps->row[i]);
        free(ps->len[i]);
    }
    free(ps->row);
    free(ps->len);
    free(ps->full);
}

/* The file of half nodes P[0..K). */
static btdf_status make_file(const btdf_scatfun_source *s, double tol, const double *P,
                             size_t K, int threads, btdf_scatfun **out, char *msg,
                             size_t msglen)
{
    src_pass ps = {s, tol, K, 2 * K + 2, P, NULL, NULL, NULL, 0};
    size_t n = ps.n;
    ps.full = malloc(n * sizeof(double));
    ps.row = calloc(n, sizeof(float *));
    ps.len = calloc(n, sizeof(uint32_t *));
    if (!ps.full || !ps.row || !ps.len) {
        pass_free(&ps);
        return BTDF_ENOMEM;
    }
    for (size_t r = 0; r < K; r++) {
        ps.full[K + 2 + r] = P[r];
        ps.full[K - 1 - r] = -P[r];
    }
    ps.full[K] = ps.full[K + 1] = 0.0;
    core_parallel_for(threads, n, pass_row, &ps);
    if (ps.failed) {
        pass_free(&ps);
        return BTDF_ENOMEM;
    }
    size_t total = 0, mmax = 0;
    for (size_t i = 0; i < n; i++)
        for (size_t o = 0; o < n; o++) {
            total += ps.len[i][o];
            mmax = ps.len[i][o] > mmax ? ps.len[i][o] : mmax;
        }
    if (total > MAX_COEFFS_BUILD) {
        pass_free(&ps);
        return core_say(BTDF_EOVERFLOW, msg, msglen,
                        "%zu coefficients exceed the build's budget of %zu", total,
                        (size_t)MAX_COEFFS_BUILD);
    }
    btdf_scatfun *f = sf_alloc((uint32_t)n, (uint32_t)total, (uint32_t)mmax, 1, 0, 0);
    double *v = malloc(n * sizeof(double)), *cdf = malloc(n * sizeof(double));
    if (!f || !v || !cdf) {
        free(v);
        free(cdf);
        btdf_scatfun_free(f);
        pass_free(&ps);
        return BTDF_ENOMEM;
    }
    f->eta = (float)s->eta;
    f->alpha[0] = f->alpha[1] = (float)s->alpha;
    for (size_t i = 0; i < n; i++)
        f->nodes[i] = (float)ps.full[i];
    size_t pos = 0;
    for (size_t i = 0; i < n; i++) {
        size_t rp = 0;
        for (size_t o = 0; o < n; o++) {
            uint32_t m = ps.len[i][o];
            f->offsets[2 * (i * n + o)] = (uint32_t)pos;
            f->offsets[2 * (i * n + o) + 1] = m;
            memcpy(f->coeffs + pos, ps.row[i] + rp, m * sizeof(float));
            pos += m;
            rp += m;
        }
    }
    pass_free(&ps);
    if (sf_index(f)) {
        free(v);
        free(cdf);
        btdf_scatfun_free(f);
        return BTDF_ENOMEM;
    }
    /* cdf rows from the stored (float) a_0, as a reader recomputes them */
    for (size_t i = 0; i < n; i++) {
        for (size_t o = 0; o < n; o++) {
            uint32_t m = f->offsets[2 * (i * n + o) + 1];
            v[o] = m ? (double)f->coeffs[f->offsets[2 * (i * n + o)]] : 0.0;
        }
        spline_cdf(f->xd, v, n, cdf);
        for (size_t o = 0; o < n; o++)
            f->cdf[i * n + o] = (float)cdf[o];
    }
    free(v);
    free(cdf);
    f->sides = s->blocks;
    *out = f;
    return BTDF_OK;
}

/* ------------------------------------------------------------------------- */
/* The file's error against the source                                       */
/* ------------------------------------------------------------------------- */

typedef struct src_check {
    const btdf_scatfun_source *s;
    const btdf_scatfun *f;
    const double *ci;   /* the light cosines tested, nang of them */
    size_t nang;
    const double *cosm; /* cos(m phi_k), SRC_CELLS x modes */
    double *e_l1, *e_t; /* per (block, angle) */
    int failed;
} src_check;

static void check_one(void *arg, size_t idx)
{
    src_check *c = arg;
    const btdf_scatfun_source *s = c->s;
    size_t M = (size_t)s->modes, bk = idx / c->nang, k = idx % c->nang;
    int b = src_blocks[bk];
    c->e_l1[idx] = c->e_t[idx] = 0.0;
    if (!(s->blocks & b))
        return;
    double ci = c->ci[k], *cm = malloc(M * sizeof(double));
    sf_fixed_read *r = sf_fixed_new(c->f, (btdf_side)b, BTDF_SCATFUN_DIRECT, ci);
    if (!cm || !r) {
        free(cm);
        sf_fixed_free(r);
        c->failed = 1;
        return;
    }
    /* midpoint cells of width 1 / SRC_CELLS in mu_v and pi / SRC_CELLS in phi on [0, pi],
       twice (the BSDF is even in phi) */
    double cell = (1.0 / SRC_CELLS) * (SRC_PI / SRC_CELLS) * 2.0;
    double l1 = 0.0, Ts = 0.0, Tf = 0.0;
    const sf_fixed_read *rr = r;
    for (size_t j = 0; j < SRC_CELLS; j++) {
        double co = (j + 0.5) / SRC_CELLS;
        s->modes_at(s->user, b, ci, co, cm);
        for (size_t q = 0; q < SRC_CELLS; q++) {
            const double *cq = c->cosm + q * M;
            double vs = 0.0, vf;
            for (size_t m = 0; m < M; m++)
                vs += cm[m] * cq[m];
            vs = vs > 0.0 ? vs : 0.0; /* the source's rho is max(0, series) */
            /* cq[1] = cos phi; cos phi_d = -cos phi */
            double cphi = M > 1 ? cq[1] : cos((q + 0.5) * SRC_PI / SRC_CELLS);
            sf_fixed_eval_n(&rr, 1, co, -cphi, &vf);
            l1 += fabs(vf - vs) * co;
            Ts += vs * co;
            Tf += vf * co;
        }
    }
    l1 *= cell;
    Ts *= cell;
    Tf *= cell;
    double den = fmax(Ts, T_FLOOR); /* MODEL.md 6: relative to max(T, 0.01), never 0 */
    c->e_l1[idx] = l1 / den;
    c->e_t[idx] = fabs(Tf - Ts) / den;
    free(cm);
    sf_fixed_free(r);
}

/* The worst error of f against s over the blocks s has. */
static btdf_status check_file(const btdf_scatfun_source *s, const btdf_scatfun *f,
                              const double *P, size_t K, int threads,
                              btdf_scatfun_source_error *err)
{
    size_t M = (size_t)s->modes, nang = 2 * SRC_ANGLES;
    double ci[2 * SRC_ANGLES];
    for (size_t k = 0; k < SRC_ANGLES; k++) /* stratified in angle on [0, pi/2) */
        ci[k] = cos((k + 0.5) * (SRC_PI / 2) / SRC_ANGLES);
    for (size_t k = 0; k < SRC_ANGLES; k++) { /* midpoints of intervals spread over P */
        size_t r = K > 1 ? (k * (K - 1)) / SRC_ANGLES : 0;
        double lo = r + 1 < K ? P[r] : 0.0, hi = r + 1 < K ? P[r + 1] : P[0];
        ci[SRC_ANGLES + k] = cos(0.5 * (acos(lo) + acos(hi)));
    }
    double *cosm = malloc(SRC_CELLS * M * sizeof(double));
    double *e = malloc(2 * 4 * nang * sizeof(double));
    if (!cosm || !e) {
        free(cosm);
        free(e);
        return BTDF_ENOMEM;
    }
    for (size_t q = 0; q < SRC_CELLS; q++)
        for (size_t m = 0; m < M; m++)
            cosm[q * M + m] = cos((double)m * (q + 0.5) * SRC_PI / SRC_CELLS);
    src_check c = {s, f, ci, nang, cosm, e, e + 4 * nang, 0};
    core_parallel_for(threads, 4 * nang, check_one, &c);
    memset(err, 0, sizeof *err);
    err->angles = nang;
    for (size_t idx = 0; idx < 4 * nang; idx++) { /* in order: the same for any threads */
        if (c.e_l1[idx] > err->e_l1) {
            err->e_l1 = c.e_l1[idx];
            err->e_l1_ti = acos(ci[idx % nang]);
            err->block = src_blocks[idx / nang];
        }
        err->e_t = fmax(err->e_t, c.e_t[idx]);
    }
    int failed = c.failed;
    free(cosm);
    free(e);
    return failed ? BTDF_ENOMEM : BTDF_OK;
}

/* The half nodes of the next pass: every interval of P (and [0, P[0]]) split at its
   middle angle; NULL when out of memory. */
static double *split_nodes(const double *P, size_t K, size_t *K2)
{
    double *Q = malloc(2 * K * sizeof(double));
    if (!Q)
        return NULL;
    size_t q = 0;
    for (size_t r = 0; r < K; r++) {
        double lo = r ? P[r - 1] : 0.0;
        double mid = (double)(float)cos(0.5 * (acos(lo) + acos(P[r])));
        if (mid > lo && mid < P[r]) /* float rounding may land on an end: skip it */
            Q[q++] = mid;
        Q[q++] = P[r];
    }
    *K2 = q;
    return Q;
}

static btdf_status check_source(const btdf_scatfun_source *s, double tol, char *msg,
                                size_t msglen)
{
    if (!s || !s->modes_at || !s->nodes)
        return core_say(BTDF_EINVAL, msg, msglen, "source: a NULL callback or node list");
    if (s->blocks < 1 || s->blocks > 15)
        return core_say(BTDF_EINVAL, msg, msglen, "source: blocks = %d: must be a mask 1..15",
                        s->blocks);
    if (s->modes < 1 || s->modes > BTDF_SCATFUN_MAX_PHI)
        return core_say(BTDF_EINVAL, msg, msglen, "source: modes = %d: must lie in 1..%d",
                        s->modes, BTDF_SCATFUN_MAX_PHI);
    if (s->nnodes < 2 || s->nnodes > BTDF_SCATFUN_MAX_HALF_NODES)
        return core_say(BTDF_EINVAL, msg, msglen, "source: %zu nodes: must be 2..%d",
                        s->nnodes, BTDF_SCATFUN_MAX_HALF_NODES);
    for (size_t r = 0; r < s->nnodes; r++)
        if (!(s->nodes[r] > (r ? s->nodes[r - 1] : 0.0) && s->nodes[r] < 1.0))
            return core_say(BTDF_EINVAL, msg, msglen,
                            "source: node %zu = %.17g: nodes must ascend inside (0, 1)", r,
                            s->nodes[r]);
    if (!(s->eta > 0.0 && isfinite(s->eta)) || !(s->alpha >= 0.0 && isfinite(s->alpha)))
        return core_say(BTDF_EINVAL, msg, msglen,
                        "source: eta %.9g, alpha %.9g: eta must be > 0, alpha >= 0", s->eta,
                        s->alpha);
    if (!(tol >= 1e-6 && tol <= 0.5))
        return core_say(BTDF_EINVAL, msg, msglen, "tolerance %.9g: must lie in [1e-6, 0.5]",
                        tol);
    return BTDF_OK;
}

/* The first half nodes: the source's as floats (repeats after rounding dropped), then
   the pole node. */
static double *first_half_nodes(const btdf_scatfun_source *s, size_t *K)
{
    double *P = malloc((s->nnodes + 1) * sizeof(double));
    if (!P)
        return NULL;
    size_t k = 0;
    for (size_t r = 0; r < s->nnodes; r++) {
        double v = (double)(float)s->nodes[r];
        if (v > 0.0 && v < POLE_NODE && (k == 0 || v > P[k - 1]))
            P[k++] = v;
    }
    P[k++] = POLE_NODE;
    *K = k;
    return P;
}

BTDF_API btdf_status btdf_scatfun_build_source(const btdf_scatfun_source *s, double tolerance,
                                               int threads, btdf_scatfun **out,
                                               btdf_scatfun_source_error *err, char *msg,
                                               size_t msglen)
{
    if (!out || !err)
        return core_say(BTDF_EINVAL, msg, msglen, "source: NULL out or err");
    btdf_status st = check_source(s, tolerance, msg, msglen);
    if (st != BTDF_OK)
        return st;
    double t0 = core_now();
    size_t K;
    double *P = first_half_nodes(s, &K);
    if (!P)
        return BTDF_ENOMEM;
    btdf_scatfun *best = NULL;
    btdf_scatfun_source_error be;
    memset(&be, 0, sizeof be);
    for (;;) {
        btdf_scatfun *f = NULL;
        btdf_scatfun_source_error e;
        st = make_file(s, tolerance, P, K, threads, &f, msg, msglen);
        if (st == BTDF_OK)
            st = check_file(s, f, P, K, threads, &e);
        if (st != BTDF_OK) {
            btdf_scatfun_free(f);
            break;
        }
        btdf_scatfun_free(best);
        best = f;
        be = e;
        be.half_nodes = K;
        if (e.e_l1 <= tolerance && e.e_t <= tolerance)
            break;
        size_t K2;
        double *Q = split_nodes(P, K, &K2);
        if (!Q) {
            st = BTDF_ENOMEM;
            break;
        }
        if (K2 > BTDF_SCATFUN_MAX_HALF_NODES || K2 == K) {
            free(Q);
            st = core_say(BTDF_EBUDGET, msg, msglen,
                          "tolerance %.3g not met within %d half nodes: e_L1 %.3g, e_T %.3g "
                          "with %zu",
                          tolerance, BTDF_SCATFUN_MAX_HALF_NODES, e.e_l1, e.e_t, K);
            break;
        }
        free(P);
        P = Q;
        K = K2;
    }
    free(P);
    if (st != BTDF_OK && st != BTDF_EBUDGET) {
        btdf_scatfun_free(best);
        return st;
    }
    best->seconds_build = core_now() - t0;
    be.seconds = best->seconds_build;
    *out = best;
    *err = be;
    return st;
}
