/* SPDX-License-Identifier: MIT */
/* lookup.c: the file read as pbrt-v3 reads it, one point at a time (btdf_scatfun_eval*)
   or one light angle at a time for the reports (sf_fixed_*). */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "btdf.h"
#include "btdf_scatfun.h"
#include "model/kernel.h"
#include "scatfun/scatfun.h"
#include "scatfun/spline.h"

/* ------------------------------------------------------------------------- */
/* Evaluation as pbrt-v3 does it                                             */
/* ------------------------------------------------------------------------- */

/* u_k = rk^k cos(k phi), generated in chunks of COS_CHUNK terms. The first COS_LAG by
   u_{k+1} = 2 rk c u_k - rk^2 u_{k-1} from u_0 = 1 and u_{-1} = cos(-phi) / rk (rk = 1:
   the plain recurrence); then four interleaved chains, u_k = 2 u_4 u_{k-4} - rk^8 u_{k-8}
   (cos(a + b) + cos(a - b) = 2 cos a cos b with b = 4 phi): the one-step chain is bound
   by its latency (two multiplies and a subtraction per term) and took as long as the
   sums. */
enum { COS_CHUNK = 256, COS_LAG = 8 };

typedef struct cos_rec {
    double c_prev, c_cur, rc, r2, A, B;
    double ckb[COS_LAG + COS_CHUNK]; /* the lags, then the chunk */
} cos_rec;

BT_INLINE void cos_rec_init(cos_rec *s, double cphi, double rk)
{
    s->c_prev = cphi;
    s->c_cur = 1.0;
    s->rc = rk * cphi;
    s->r2 = rk * rk;
    s->A = 0.0;
    s->B = s->r2 * s->r2 * s->r2 * s->r2;
}

/* Fills s->ckb + COS_LAG with u_{q0} .. u_{q0 + len - 1}; chunks are asked in order,
   q0 = 0, COS_CHUNK, 2 COS_CHUNK, ... */
BT_INLINE const double *cos_rec_chunk(cos_rec *s, uint32_t q0, uint32_t len)
{
    double *ck = s->ckb + COS_LAG;
    if (q0 > 0) /* the lags of this chunk: the end of the last one */
        memcpy(s->ckb, s->ckb + COS_CHUNK, COS_LAG * sizeof *s->ckb);
    uint32_t t = 0;
    for (; q0 + t < COS_LAG && t < len; t++) {
        ck[t] = s->c_cur;
        double nx = q0 + t == 0 ? s->rc : 2.0 * s->rc * s->c_cur - s->r2 * s->c_prev;
        s->c_prev = s->c_cur;
        s->c_cur = nx;
        if (q0 + t == 4)
            s->A = 2.0 * ck[t];
    }
    for (long u = (long)t; u < (long)len; u++) /* signed: u - 8 reaches the lags */
        ck[u] = s->A * ck[u - 4] - s->B * ck[u - 8];
    return ck;
}

/* sum_t comb[t] ck[t] in four running sums (independent chains) */
BT_INLINE double cos_dot(const double *comb, const double *ck, uint32_t used)
{
    double s4[4] = {0.0, 0.0, 0.0, 0.0};
    uint32_t t = 0;
    for (; t + 4 <= used; t += 4)
        for (int v = 0; v < 4; v++)
            s4[v] += comb[t + v] * ck[t + v];
    for (; t < used; t++)
        s4[0] += comb[t] * ck[t];
    return (s4[0] + s4[1]) + (s4[2] + s4[3]);
}

/* Stored-channel series values (Y, R, B or one channel) at (mu_s, mu_f, cos phi_d).
   The same sum as pbrt-v3's (weights times the cosine series of the 16 stencil
   pairs), arranged for speed: cos(k phi) comes from recurrences once, in chunks; per
   chunk the stencil's weighted series are added into one (as pbrt-v3 interpolates its
   coefficients) and that one is summed against the cosines. Only the order of the
   additions differs. */
BT_CLONES static int eval_stored(const btdf_scatfun *f, double mu_s, double mu_f, double cphi,
                                 double rk, double *val)
{
    long os, of;
    double ws[4], wf[4];
    for (uint32_t k = 0; k < f->channels; k++)
        val[k] = 0.0;
    if (!cr_weights_f(f, mu_s, &os, ws) || !cr_weights_f(f, mu_f, &of, wf))
        return 0;
    double pw[16];
    uint32_t poff[16], pm[16], mtop = 0;
    int np = 0;
    for (int a = 0; a < 4; a++) {
        long i = os + a;
        if (ws[a] == 0.0 || i < 0 || i >= (long)f->n)
            continue;
        for (int b = 0; b < 4; b++) {
            long o = of + b;
            if (wf[b] == 0.0 || o < 0 || o >= (long)f->n)
                continue;
            size_t e = 2 * ((size_t)i * f->n + (size_t)o);
            if (f->offsets[e + 1] == 0)
                continue;
            pw[np] = ws[a] * wf[b];
            poff[np] = f->offsets[e];
            pm[np] = f->offsets[e + 1];
            if (pm[np] > mtop)
                mtop = pm[np];
            np++;
        }
    }
    cos_rec cr;
    cos_rec_init(&cr, cphi, rk);
    for (uint32_t q0 = 0; q0 < mtop; q0 += COS_CHUNK) {
        uint32_t len = mtop - q0 < COS_CHUNK ? mtop - q0 : COS_CHUNK;
        const double *ck = cos_rec_chunk(&cr, q0, len);
        /* As pbrt-v3 does: the stencil's weighted series summed into one (an
           element-wise loop the compiler vectorises), then one cosine sum. */
        for (uint32_t k = 0; k < f->channels; k++) {
            double comb[COS_CHUNK];
            uint32_t used = 0;
            for (int e = 0; e < np; e++) {
                if (pm[e] <= q0)
                    continue;
                uint32_t l = pm[e] - q0 < len ? pm[e] - q0 : len;
                const float *a = f->coeffs + poff[e] + (size_t)k * pm[e] + q0;
                double w = pw[e];
                for (uint32_t t = used; t < l; t++)
                    comb[t] = 0.0;
                if (l > used)
                    used = l;
                for (uint32_t t = 0; t < l; t++)
                    comb[t] += w * (double)a[t];
            }
            val[k] += cos_dot(comb, ck, used);
        }
    }
    return 1;
}

/* Stored channels -> output channels with pbrt-v3's clamps and G rebuilt from Y. */
static void stored_to_out(uint32_t channels, const double *val, double *out)
{
    if (channels == 1) {
        out[0] = fmax(0.0, val[0]);
        return;
    }
    double Y = fmax(0.0, val[0]), R = fmax(0.0, val[1]), B = fmax(0.0, val[2]);
    out[0] = R;
    out[1] = fmax(0.0, INV_GY * Y - INV_GB * B - INV_GR * R);
    out[2] = B;
}

static btdf_status eval_mu_rk(const btdf_scatfun *f, double mu_s, double mu_f,
                              double cos_phi_d, int radiance, double rk, double *out);

BTDF_API btdf_status btdf_scatfun_eval_mu(const btdf_scatfun *f, double mu_s, double mu_f,
                                          double cos_phi_d, int radiance, double *out)
{
    return eval_mu_rk(f, mu_s, mu_f, cos_phi_d, radiance, 1.0, out);
}

/* btdf_scatfun_eval_mu with harmonic k scaled by rk^k (rk = 1: as pbrt-v3 reads). */
static btdf_status eval_mu_rk(const btdf_scatfun *f, double mu_s, double mu_f,
                              double cos_phi_d, int radiance, double rk, double *out)
{
    if (!f || !out || !isfinite(mu_s) || !isfinite(mu_f) || !isfinite(cos_phi_d))
        return BTDF_EINVAL;
    for (uint32_t k = 0; k < f->channels; k++)
        out[k] = 0.0;
    double val[3];
    double cphi = fmin(1.0, fmax(-1.0, cos_phi_d));
    int ok = eval_stored(f, mu_s, mu_f, cphi, rk, val);
    /* f = value / |mu_f|: at mu_f = 0 (grazing) the stored value is 0 too; return 0. */
    if (!ok || !(fabs(mu_f) > 0.0))
        return BTDF_OK;
    stored_to_out(f->channels, val, out);
    double scale = 1.0 / fabs(mu_f);
    if (radiance && mu_s * mu_f > 0.0) {
        /* pbrt-v3's radiance factor e^2, e = 1/eta for light from below; the reader
           guarantees eta is finite and > 0 */
        double e = mu_f > 0.0 ? 1.0 / (double)f->eta : (double)f->eta;
        scale *= e * e;
    }
    for (uint32_t k = 0; k < f->channels; k++) {
        double v = out[k] * scale;
        out[k] = isfinite(v) ? v : 0.0;
    }
    return BTDF_OK;
}

/* (mu_s, mu_f, radiance) of a block and mode for directions in MODEL.md's frame, given
   by ci = cos ti and co = |cos to| (to the transmitted angle in [pi/2, pi] or, for
   reflection, tr in [0, pi/2]), both in [0, 1]. */
static void side_mus(btdf_side side, btdf_scatfun_mode mode, double ci, double co,
                     double *mu_s, double *mu_f, int *radiance)
{
    int adj = mode == BTDF_SCATFUN_ADJOINT;
    *radiance = adj;
    switch ((int)side) {
    case BTDF_SCATFUN_T_ENTER:
        *mu_s = adj ? -co : ci, *mu_f = adj ? -ci : co;
        break;
    case BTDF_SCATFUN_T_LEAVE:
        *mu_s = adj ? co : -ci, *mu_f = adj ? ci : -co;
        break;
    case BTDF_SCATFUN_R_TOP: /* the camera's direction in the slow index for ADJOINT */
        *mu_s = adj ? co : ci, *mu_f = adj ? -ci : -co;
        break;
    default: /* BTDF_SCATFUN_R_BOTTOM */
        *mu_s = adj ? -co : -ci, *mu_f = adj ? ci : co;
        break;
    }
}

BTDF_API btdf_status btdf_scatfun_eval_side(const btdf_scatfun *f, btdf_side side,
                                            btdf_scatfun_mode mode, double ti, double to,
                                            double phi, double *out)
{
    if (!f || !out)
        return BTDF_EINVAL;
    int b = (int)side;
    if (b != BTDF_SCATFUN_T_ENTER && b != BTDF_SCATFUN_T_LEAVE && b != BTDF_SCATFUN_R_TOP &&
        b != BTDF_SCATFUN_R_BOTTOM)
        return BTDF_EINVAL;
    if (mode != BTDF_SCATFUN_DIRECT && mode != BTDF_SCATFUN_ADJOINT)
        return BTDF_EINVAL;
    int refl = b == BTDF_SCATFUN_R_TOP || b == BTDF_SCATFUN_R_BOTTOM;
    int to_ok = refl ? (to >= 0.0 && to <= M_PI / 2) : (to >= M_PI / 2 && to <= M_PI);
    if (!(ti >= 0.0 && ti <= M_PI / 2) || !to_ok || !isfinite(phi))
        return BTDF_EDOMAIN;
    /* phi = pi is forward (specular), phi_d = 0: cos phi_d = -cos phi */
    return sf_eval_side_cos(f, side, mode, cos(ti), fabs(cos(to)), -cos(phi), out);
}

/* btdf_scatfun_eval_side from cosines: ci = cos ti and co = |cos to| in [0, 1], cpd =
   cos phi_d = -cos phi in [-1, 1]; side and mode checked by the caller. */
btdf_status sf_eval_side_cos(const btdf_scatfun *f, btdf_side side,
                                 btdf_scatfun_mode mode, double ci, double co, double cpd,
                                 double *out)
{
    double ms, mf;
    int rad;
    side_mus(side, mode, ci, co, &ms, &mf, &rad);
    /* Within 0.02 deg of the normal (|mu| above the outermost node, 1 - 2^-24 in files
       this library writes) read the outermost node: a renderer gives 0 there, the model
       has no such gap (docs/scatfun.md, "Views on the normal"). */
    /* Inside that cap harmonic k is scaled by (sin theta / sin theta_node)^k for each
       direction in it: near the normal the k-th Fourier term of a BSDF goes like
       sin^k of each angle (it is smooth in the direction vectors), so the outermost
       node's series, stored at 0.0198 deg, is carried to the view's angle instead of
       read unchanged (which would turn the lobe about the normal by that angle: an
       e_L1 of 1.4e-3 at normal incidence for s = 3). */
    double rk = 1.0, top = f->xd[f->n - 1], bot = f->xd[0];
    double sn_top = sqrt(fmax(0.0, 1.0 - top * top)), sn_bot = sqrt(fmax(0.0, 1.0 - bot * bot));
    if (ms > top && sn_top > 0.0)
        rk *= sqrt(fmax(0.0, 1.0 - ms * ms)) / sn_top; /* sn_top > 0: nodes inside (-1, 1) */
    if (ms < bot && sn_bot > 0.0)
        rk *= sqrt(fmax(0.0, 1.0 - ms * ms)) / sn_bot;
    if (mf > top && sn_top > 0.0)
        rk *= sqrt(fmax(0.0, 1.0 - mf * mf)) / sn_top;
    if (mf < bot && sn_bot > 0.0)
        rk *= sqrt(fmax(0.0, 1.0 - mf * mf)) / sn_bot;
    ms = fmin(top, fmax(bot, ms));
    mf = fmin(top, fmax(bot, mf));
    return eval_mu_rk(f, ms, mf, cpd, rad, rk, out);
}

BTDF_API btdf_status btdf_scatfun_eval(const btdf_scatfun *f, double ti, double to,
                                       double phi, double *out)
{
    return btdf_scatfun_eval_side(f, BTDF_SIDE_ENTER, BTDF_SCATFUN_DIRECT, ti, to, phi, out);
}



/* A reading of one block at one light angle, for the reports: the light's cosine is
   one index of the file (the slow one for DIRECT, the fast one for ADJOINT: side_mus)
   and the same for every view of that angle, so the spline across it is applied once
   per angle, to every node of the other index, instead of once per view (16 stencil
   series per view become 4). Values are btdf_scatfun_eval_side's up to the order of
   the additions. */
struct sf_fixed_read {
    const btdf_scatfun *f;
    btdf_side side;
    btdf_scatfun_mode mode;
    double ci;       /* the light's cosine */
    int ok;          /* 0: the light's cosine lies outside the nodes: everything reads 0 */
    int slow_fixed;  /* 1: the slow index is the light's (DIRECT) */
    double rk_fixed; /* the light's share of the near-normal scaling (sf_eval_side_cos) */
    size_t *off;     /* per node of the other index: where its series start in buf */
    uint32_t *len;   /* per node of the other index: the combined length (0: none) */
    double *buf;     /* per node, channels x len: the light's stencil combined */
};

/* Clamps mu into the nodes' range as sf_eval_side_cos does; returns the factor of the
   near-normal scaling (1 inside). */
BT_INLINE double cap_mu(const btdf_scatfun *f, double *mu)
{
    double top = f->xd[f->n - 1], bot = f->xd[0], rk = 1.0;
    double sn_top = sqrt(fmax(0.0, 1.0 - top * top)), sn_bot = sqrt(fmax(0.0, 1.0 - bot * bot));
    if (*mu > top && sn_top > 0.0)
        rk = sqrt(fmax(0.0, 1.0 - *mu * *mu)) / sn_top; /* sn_top > 0: nodes inside (-1, 1) */
    if (*mu < bot && sn_bot > 0.0)
        rk = sqrt(fmax(0.0, 1.0 - *mu * *mu)) / sn_bot;
    *mu = fmin(top, fmax(bot, *mu));
    return rk;
}

void sf_fixed_free(sf_fixed_read *r)
{
    if (!r)
        return;
    free(r->off);
    free(r->len);
    free(r->buf);
    free(r);
}

/* The reader of (f, side, mode) at light cosine ci in [0, 1]; NULL when out of memory. */
sf_fixed_read *sf_fixed_new(const btdf_scatfun *f, btdf_side side, btdf_scatfun_mode mode,
                             double ci)
{
    sf_fixed_read *r = calloc(1, sizeof *r);
    if (!r)
        return NULL;
    r->f = f;
    r->side = side;
    r->mode = mode;
    r->ci = ci;
    r->slow_fixed = mode == BTDF_SCATFUN_DIRECT;
    double ms, mf;
    int rad;
    side_mus(side, mode, ci, 0.5, &ms, &mf, &rad);
    double mu = r->slow_fixed ? ms : mf;
    r->rk_fixed = cap_mu(f, &mu);
    long os;
    double w[4];
    uint32_t n = f->n;
    r->off = malloc((n + 1) * sizeof *r->off);
    r->len = calloc(n, sizeof *r->len);
    if (!r->off || !r->len) {
        sf_fixed_free(r);
        return NULL;
    }
    r->ok = cr_weights_f(f, mu, &os, w);
    if (!r->ok) {
        memset(r->off, 0, (n + 1) * sizeof *r->off);
        return r;
    }
    /* The views' cosine keeps one sign at this angle, and in files with two zero
       nodes in the middle (this library's) every stencil of that sign stays on its
       own side: only those nodes are combined (the others keep length 0). */
    uint32_t o_lo = 0, o_hi = n;
    if (n >= 4 && n % 2 == 0 && f->xd[n / 2 - 1] == 0.0 && f->xd[n / 2] == 0.0) {
        double vs, vf;
        side_mus(side, mode, ci, 1.0, &vs, &vf, &rad);
        int pos = (r->slow_fixed ? vf : vs) > 0.0;
        o_lo = pos ? n / 2 - 1 : 0;
        o_hi = pos ? n : n / 2 + 1;
    }
    size_t total = 0;
    for (uint32_t o = 0; o < n; o++) {
        uint32_t m = 0;
        if (o < o_lo || o >= o_hi) {
            r->off[o] = total;
            r->len[o] = 0;
            continue;
        }
        for (int a = 0; a < 4; a++) {
            long i = os + a;
            if (w[a] == 0.0 || i < 0 || i >= (long)n)
                continue;
            size_t e = r->slow_fixed ? 2 * ((size_t)i * n + o) : 2 * ((size_t)o * n + (size_t)i);
            if (f->offsets[e + 1] > m)
                m = f->offsets[e + 1];
        }
        r->off[o] = total;
        r->len[o] = m;
        total += (size_t)m * f->channels;
    }
    r->off[n] = total;
    r->buf = calloc(total ? total : 1, sizeof *r->buf);
    if (!r->buf) {
        sf_fixed_free(r);
        return NULL;
    }
    for (uint32_t o = o_lo; o < o_hi; o++) {
        for (int a = 0; a < 4; a++) {
            long i = os + a;
            if (w[a] == 0.0 || i < 0 || i >= (long)n)
                continue;
            size_t e = r->slow_fixed ? 2 * ((size_t)i * n + o) : 2 * ((size_t)o * n + (size_t)i);
            uint32_t m = f->offsets[e + 1];
            for (uint32_t k = 0; k < f->channels; k++) {
                const float *src = f->coeffs + f->offsets[e] + (size_t)k * m;
                double *dst = r->buf + r->off[o] + (size_t)k * r->len[o];
                for (uint32_t t = 0; t < m; t++)
                    dst[t] += w[a] * (double)src[t];
            }
        }
    }
    return r;
}

/* One view of a sf_fixed_read: the spline stencil of the view's cosine over the
   combined series, and what the value's scaling needs. */
typedef struct fixed_view {
    const double *ser[4];
    double wt[4];
    uint32_t ln[4], mtop;
    int np, ok, rad;
    double ms, mf, rk;
} fixed_view;

static void fixed_view_at(const sf_fixed_read *r, double co, fixed_view *v)
{
    const btdf_scatfun *f = r->f;
    v->ok = 0;
    v->np = 0;
    v->mtop = 0;
    if (!r->ok)
        return;
    side_mus(r->side, r->mode, r->ci, co, &v->ms, &v->mf, &v->rad);
    double mu = r->slow_fixed ? v->mf : v->ms;
    v->rk = r->rk_fixed * cap_mu(f, &mu);
    if (r->slow_fixed)
        v->mf = mu;
    else
        v->ms = mu;
    long ov;
    double w[4];
    if (!cr_weights_f(f, mu, &ov, w))
        return;
    v->ok = 1;
    for (int b = 0; b < 4; b++) {
        long o = ov + b;
        if (w[b] == 0.0 || o < 0 || o >= (long)f->n || r->len[o] == 0)
            continue;
        v->ser[v->np] = r->buf + r->off[o];
        v->ln[v->np] = r->len[o];
        v->wt[v->np] = w[b];
        if (v->ln[v->np] > v->mtop)
            v->mtop = v->ln[v->np];
        v->np++;
    }
}

#if defined(__GNUC__)
/* Four doubles as one vector (GCC's vector extension, also Clang's): element-wise
   operations, each lane rounded as the scalar operation is. Macros, not functions: a
   function passing such a vector changes the ABI where AVX is not enabled. Other
   compilers take the scalar loop below, with the same sums in the same order. */
typedef double v4d __attribute__((vector_size(4 * sizeof(double))));
#define V4D_ALL(x) ((v4d){(x), (x), (x), (x)})
#endif

/* val[k] += the view's series over harmonics q0 .. q0 + len - 1 against ck: the
   stencil's weighted sum at each harmonic times its cosine, in four running sums, as
   eval_stored's combine-then-cos_dot does (the same additions in the same order:
   each harmonic's combination starts from 0 and adds the series that reach it in
   stencil order; harmonics in whole groups of four go to sums t mod 4, the rest to
   the first), without storing the combination (zeroing that buffer alone was a
   tenth of the reading's profile). */
BT_INLINE void fixed_view_chunk(const fixed_view *v, uint32_t channels, uint32_t q0,
                                uint32_t len, const double *ck, double *val)
{
    for (uint32_t k = 0; k < channels; k++) {
        const double *a[4];
        double w[4];
        uint32_t l[4], used = 0, lmin = len;
        int na = 0;
        for (int e = 0; e < v->np; e++) {
            if (v->ln[e] <= q0)
                continue;
            l[na] = v->ln[e] - q0 < len ? v->ln[e] - q0 : len;
            a[na] = v->ser[e] + (size_t)k * v->ln[e] + q0;
            w[na] = v->wt[e];
            if (l[na] > used)
                used = l[na];
            if (l[na] < lmin)
                lmin = l[na];
            na++;
        }
        if (na == 0)
            continue;
        uint32_t full = used & ~3u; /* cos_dot's groups of four */
        uint32_t fast = (lmin < full ? lmin : full) & ~3u;
        double s4[4] = {0.0, 0.0, 0.0, 0.0};
        uint32_t t = 0;
        /* Four series (the common stencil): the four running sums are one vector
           (the compiler vectorised none of these loops as scalar code). Three or two:
           the same sums in scalars. */
        if (na == 4) {
            const double *a0 = a[0], *a1 = a[1], *a2 = a[2], *a3 = a[3];
#if defined(__GNUC__)
            v4d w0 = V4D_ALL(w[0]), w1 = V4D_ALL(w[1]), w2 = V4D_ALL(w[2]),
                w3 = V4D_ALL(w[3]), acc = V4D_ALL(0.0);
            for (; t < fast; t += 4) {
                v4d x0, x1, x2, x3, k4, c = V4D_ALL(0.0);
                memcpy(&x0, a0 + t, sizeof x0); /* unaligned loads */
                memcpy(&x1, a1 + t, sizeof x1);
                memcpy(&x2, a2 + t, sizeof x2);
                memcpy(&x3, a3 + t, sizeof x3);
                memcpy(&k4, ck + t, sizeof k4);
                c += w0 * x0;
                c += w1 * x1;
                c += w2 * x2;
                c += w3 * x3;
                acc += c * k4;
            }
            for (int u = 0; u < 4; u++)
                s4[u] = acc[u];
#else
            double w0 = w[0], w1 = w[1], w2 = w[2], w3 = w[3];
            for (; t < fast; t += 4)
                for (int u = 0; u < 4; u++) { /* lane u of the vector loop */
                    double c = 0.0;
                    c += w0 * a0[t + u];
                    c += w1 * a1[t + u];
                    c += w2 * a2[t + u];
                    c += w3 * a3[t + u];
                    s4[u] += c * ck[t + u];
                }
#endif
        } else if (na == 3) {
            const double *a0 = a[0], *a1 = a[1], *a2 = a[2];
            double w0 = w[0], w1 = w[1], w2 = w[2];
            for (; t < fast; t += 4)
                for (int u = 0; u < 4; u++) {
                    double c = 0.0;
                    c += w0 * a0[t + u];
                    c += w1 * a1[t + u];
                    c += w2 * a2[t + u];
                    s4[u] += c * ck[t + u];
                }
        } else if (na == 2) {
            const double *a0 = a[0], *a1 = a[1];
            double w0 = w[0], w1 = w[1];
            for (; t < fast; t += 4)
                for (int u = 0; u < 4; u++) {
                    double c = 0.0;
                    c += w0 * a0[t + u];
                    c += w1 * a1[t + u];
                    s4[u] += c * ck[t + u];
                }
        }
        for (; t < used; t++) {
            double c = 0.0;
            for (int e = 0; e < na; e++)
                if (l[e] > t)
                    c += w[e] * a[e][t];
            s4[t < full ? t % 4 : 0] += c * ck[t];
        }
        val[k] += (s4[0] + s4[1]) + (s4[2] + s4[3]);
    }
}

/* The view's value from its series sums val, as eval_mu_rk scales it. */
static void fixed_view_out(const btdf_scatfun *f, const fixed_view *v, const double *val,
                           double *out)
{
    for (uint32_t k = 0; k < f->channels; k++)
        out[k] = 0.0;
    /* f = value / |mu_f|: at mu_f = 0 (grazing) the stored value is 0 too; read 0 */
    if (!v->ok || !(fabs(v->mf) > 0.0))
        return;
    stored_to_out(f->channels, val, out);
    double scale = 1.0 / fabs(v->mf);
    if (v->rad && v->ms * v->mf > 0.0) {
        /* pbrt-v3's radiance factor, as eval_mu_rk; eta finite and > 0 */
        double e = v->mf > 0.0 ? 1.0 / (double)f->eta : (double)f->eta;
        scale *= e * e;
    }
    for (uint32_t k = 0; k < f->channels; k++) {
        double x = out[k] * scale;
        out[k] = isfinite(x) ? x : 0.0;
    }
}

/* sf_eval_side_cos(f, side, mode, r[i]->ci, co, cpd, out + i channels) through the
   combined series, for nr = 1 or 2 readings of one file at the same point (a block's
   DIRECT and ADJOINT readings). Both readings' views have the same |mu| and so, for
   this library's mirror-symmetric nodes, the same near-normal factor rk: then the
   cosines cos(k phi) rk^k are made once for the two. The values are those of one
   reading at a time, bit for bit: the same cosines, the same sums in the same
   order. */
/* static: GCC exports the resolver of a cloned function whatever -fvisibility says,
   so the clones stay in this file and sf_fixed_eval_n below is a plain call. */
static BT_CLONES void fixed_eval_n(const sf_fixed_read *const *r, int nr, double co,
                                   double cpd, double *out)
{
    const btdf_scatfun *f = r[0]->f;
    uint32_t ch = f->channels;
    fixed_view v[2];
    double val[2][3] = {{0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}};
    for (int i = 0; i < nr; i++)
        fixed_view_at(r[i], co, &v[i]);
    double cphi = fmin(1.0, fmax(-1.0, cpd));
    int shared = nr == 2 && v[0].ok && v[1].ok && v[0].rk == v[1].rk;
    for (int i = 0; i < nr; i++) {
        if (!v[i].ok || (shared && i == 1))
            continue;
        uint32_t mtop = v[i].mtop;
        if (shared && v[1].mtop > mtop)
            mtop = v[1].mtop;
        cos_rec cr;
        cos_rec_init(&cr, cphi, v[i].rk);
        for (uint32_t q0 = 0; q0 < mtop; q0 += COS_CHUNK) {
            uint32_t len = mtop - q0 < COS_CHUNK ? mtop - q0 : COS_CHUNK;
            const double *ck = cos_rec_chunk(&cr, q0, len);
            if (q0 < v[i].mtop)
                fixed_view_chunk(&v[i], ch, q0, len, ck, val[i]);
            if (shared && q0 < v[1].mtop)
                fixed_view_chunk(&v[1], ch, q0, len, ck, val[1]);
        }
    }
    for (int i = 0; i < nr; i++)
        fixed_view_out(f, &v[i], val[i], out + (size_t)i * ch);
}

void sf_fixed_eval_n(const sf_fixed_read *const *r, int nr, double co, double cpd,
                     double *out)
{
    fixed_eval_n(r, nr, co, cpd, out);
}

