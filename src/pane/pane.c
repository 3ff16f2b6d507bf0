/* SPDX-License-Identifier: MIT */
/* pane.c: a pane's system BSDF by adding-doubling in a Fourier basis (docs/pane.md). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "btdf.h"
#include "core/core.h"
#include "model/full.h"
#include "pane/pane_impl.h"

#define PI 3.14159265358979323846

void pane_gauss(int n, double a, double b, double *x, double *w)
{
    /* Newton on P_n from the Chebyshev guesses; 1e-15 is the double's own resolution
       of a node in [-1, 1] */
    for (int i = 0; i < n; i++) {
        double z = cos(PI * (i + 0.75) / (n + 0.5)), dp = 1.0;
        for (int it = 0; it < 100; it++) {
            double p0 = 1.0, p1 = z;
            for (int k = 2; k <= n; k++) {
                double p2 = ((2.0 * k - 1.0) * z * p1 - (k - 1.0) * p0) / k;
                p0 = p1;
                p1 = p2;
            }
            dp = n * (z * p1 - p0) / (z * z - 1.0); /* |z| < 1 strictly for GL nodes */
            double dz = p1 / dp;
            z -= dz;
            if (fabs(dz) < 1e-15)
                break;
        }
        /* node i from the top (z decreasing): store ascending */
        int k = n - 1 - i;
        x[k] = a + (b - a) * 0.5 * (z + 1.0);
        w[k] = (b - a) / ((1.0 - z * z) * dp * dp);
    }
}

BTDF_API void btdf_pane_opts_default(btdf_pane_opts *o)
{
    memset(o, 0, sizeof *o);
    btdf_params_default(&o->front);
    o->back_smooth = 1;
    o->back_smoothness = o->front.smoothness;
}

BTDF_API btdf_status btdf_pane_opts_check(const btdf_pane_opts *o, char *msg, size_t msglen)
{
    if (!o)
        return core_say(BTDF_EINVAL, msg, msglen, "btdf_pane_opts_check: NULL options");
    const btdf_params *p = &o->front;
    if (p->channels != 1 && p->channels != 3)
        return core_say(BTDF_EINVAL, msg, msglen, "pane: channels = %d: use 1 or 3",
                        p->channels);
    for (int c = 0; c < p->channels; c++)
        if (!(p->ior[c] > 1.0 + BTDF_IOR_ONE_EPS) || !(p->ior[c] <= BTDF_IOR_MAX))
            return core_say(BTDF_EINVAL, msg, msglen,
                            "pane: n = %g: a pane in air needs an index above 1 (at most %g)",
                            p->ior[c], BTDF_IOR_MAX);
    if (!o->front_smooth && !(p->smoothness >= BTDF_S_MIN && p->smoothness <= BTDF_S_MAX))
        return core_say(BTDF_EINVAL, msg, msglen, "pane: front s = %g: use [%g, %g]",
                        p->smoothness, BTDF_S_MIN, BTDF_S_MAX);
    if (!o->back_smooth &&
        !(o->back_smoothness >= BTDF_S_MIN && o->back_smoothness <= BTDF_S_MAX))
        return core_say(BTDF_EINVAL, msg, msglen, "pane: back s = %g: use [%g, %g]",
                        o->back_smoothness, BTDF_S_MIN, BTDF_S_MAX);
    if (!(o->thickness_mm >= 0.0 && o->thickness_mm <= BTDF_PANE_THICKNESS_MAX))
        return core_say(BTDF_EINVAL, msg, msglen, "pane: thickness %g mm: use [0, %g]",
                        o->thickness_mm, BTDF_PANE_THICKNESS_MAX);
    if (!(o->absorption_per_mm >= 0.0 && o->absorption_per_mm <= BTDF_PANE_ABSORPTION_MAX))
        return core_say(BTDF_EINVAL, msg, msglen, "pane: absorption %g per mm: use [0, %g]",
                        o->absorption_per_mm, BTDF_PANE_ABSORPTION_MAX);
    if (o->nodes < 0 || o->nodes == 1 || o->nodes == 2 || o->nodes == 3 ||
        o->nodes > BTDF_PANE_NODES_MAX)
        return core_say(BTDF_EINVAL, msg, msglen, "pane: nodes = %d: use 0 (auto) or 4..%d",
                        o->nodes, BTDF_PANE_NODES_MAX);
    if (o->modes < 0 || o->modes > BTDF_PANE_MODES_MAX)
        return core_say(BTDF_EINVAL, msg, msglen, "pane: modes = %d: use 0 (auto) or 1..%d",
                        o->modes, BTDF_PANE_MODES_MAX);
    if (!o->front_smooth && p->model != BTDF_MODEL_FULL) {
        btdf_status st = btdf_params_check(p, msg, msglen);
        if (st != BTDF_OK)
            return st;
    }
    return BTDF_OK;
}

/* ---- the operators of one face for one channel ---- */

/* An operator per mode: rows outgoing nodes, cols incoming, op[(m * rows + r) * cols + c];
   radiance in, radiance out (the solid angle and cosine of the incoming node inside). */
typedef struct face_ops {
    double *r_out, *t_in, *r_in, *t_out; /* air->air, air->glass, glass->glass, glass->air */
} face_ops;

typedef struct sample_job {
    const btdf_model_ctx *cn, *ci; /* index n (light from the air), 1/n (from the glass) */
    int ch, m, np;
    const double *cosm;             /* cos(m phi_p), [p * m + m]: a sample's modes in a row */
    const double *mi, *wi, *mo;     /* incoming nodes and weights, outgoing nodes */
    int ni, no;
    int reflect, from_glass;
    double *op;
} sample_job;

/* One outgoing row of an operator: for every incoming node, rho sampled in phi and
   projected on the modes: entry = c_m w_j mu_j (-1)^m b_m, with b_m the cosine
   coefficients of rho(phi) (trapezoid over [0, pi], exact for the modes kept) and
   (-1)^m turning btdf.h's phi (pi: forward) into the propagation azimuth difference,
   which flat faces keep. c_m (2 pi, then pi) times b_m's 1/pi (2/pi) is 2. */
static void sample_row(void *arg, size_t orow)
{
    const sample_job *J = arg;
    const btdf_model_ctx *c = J->from_glass ? J->ci : J->cn;
    double tod = acos(J->mo[orow]) * 180.0 / PI;
    double *rho = malloc(sizeof(double) * ((size_t)J->np + (size_t)J->m));
    if (!rho)
        return; /* the caller checks a canary */
    double *acc = rho + J->np;
    const btdf_full *fu = btdf_model_ctx_params(c)->model == BTDF_MODEL_FULL
                              ? btdf_model_ctx_full(c, J->ch) : NULL;
    const int M = J->m;
    for (int j = 0; j < J->ni; j++) {
        double tid = acos(J->mi[j]) * 180.0 / PI;
        if (fu) /* full: its multiply scattered modes once per pair */
            full_rho_row_deg(fu, J->reflect, tid, J->reflect ? tod : 180.0 - tod, J->np, rho);
        else
            for (int p = 0; p < J->np; p++) {
                double phd = 180.0 * p / (J->np - 1);
                rho[p] = J->reflect ? btdf_model_ctx_rho_r_deg(c, J->ch, tid, tod, phd)
                                    : btdf_model_ctx_rho_deg(c, J->ch, tid, 180.0 - tod, phd);
            }
        double dphi = PI / (J->np - 1);
        /* the lit span [lo, hi] of the samples: the terms outside it are zeros, whose
           sums change no bit of the ones inside (at s = 10 a lobe spans some 6 % of the
           azimuths, and the projection was half the build) */
        int lo = 0, hi = J->np - 1;
        while (lo <= hi && rho[lo] == 0.0)
            lo++;
        while (hi >= lo && rho[hi] == 0.0)
            hi--;
        if (lo > hi) { /* no facet connects the pair: every mode is the zero the sums give */
            for (int m = 0; m < J->m; m++)
                J->op[((size_t)m * J->no + orow) * J->ni + j] = (m & 1) ? -0.0 : 0.0;
            continue;
        }
        int p0 = lo > 1 ? lo : 1, p1 = hi < J->np - 2 ? hi : J->np - 2;
        /* every mode's sum in the order of p, the modes side by side (the same
           operations per mode as one sum at a time, so the same bits) */
        const double *c0 = J->cosm, *cl = J->cosm + (size_t)(J->np - 1) * M;
        for (int m = 0; m < M; m++)
            acc[m] = 0.5 * (rho[0] * c0[m] + rho[J->np - 1] * cl[m]);
        for (int p = p0; p <= p1; p++) {
            const double *cp = J->cosm + (size_t)p * M;
            double r = rho[p];
            for (int m = 0; m < M; m++)
                acc[m] += r * cp[m];
        }
        for (int m = 0; m < M; m++) {
            double v = 2.0 * J->wi[j] * J->mi[j] * acc[m] * dphi;
            J->op[((size_t)m * J->no + orow) * J->ni + j] = (m & 1) ? -v : v;
        }
    }
    free(rho);
}

/* The quadrature of one channel: air nodes mu (no), glass nodes mg (ng = no + nt): the
   first no are the air nodes refracted (Snell: a flat face maps node k to node k), the
   rest Gauss-Legendre over the cone of total internal reflection [0, mu_c]. */
typedef struct quad {
    int no, ng;
    const double *mu, *w;
    double *mg, *wg;
    double n;
} quad;

static int quad_make(quad *q, const double *mu, const double *w, int no, int nt, double n)
{
    q->no = no;
    q->ng = no + nt;
    q->mu = mu;
    q->w = w;
    q->n = n;
    q->mg = malloc(sizeof(double) * (size_t)q->ng);
    q->wg = malloc(sizeof(double) * (size_t)q->ng);
    if (!q->mg || !q->wg)
        return 0;
    for (int k = 0; k < no; k++) {
        double s2 = (1.0 - mu[k] * mu[k]) / (n * n);
        q->mg[k] = sqrt(1.0 - s2); /* s2 < 1 / n^2 < 1 */
        /* mu_g dmu_g = mu dmu / n^2 */
        q->wg[k] = w[k] * mu[k] / (n * n * q->mg[k]);
    }
    if (nt > 0)
        pane_gauss(nt, 0.0, sqrt(1.0 - 1.0 / (n * n)), q->mg + no, q->wg + no);
    return 1;
}

static void quad_free(quad *q)
{
    free(q->mg);
    free(q->wg);
}

/* A flat face: every operator diagonal and the same for every mode. */
static void face_flat(const quad *q, int modes, face_ops *f)
{
    size_t no = (size_t)q->no, ng = (size_t)q->ng;
    double n = q->n;
    for (int m = 0; m < modes; m++) {
        double *ro = f->r_out + (size_t)m * no * no, *ti = f->t_in + (size_t)m * ng * no;
        double *ri = f->r_in + (size_t)m * ng * ng, *to = f->t_out + (size_t)m * no * ng;
        for (size_t k = 0; k < no; k++) {
            double th = acos(q->mu[k]);
            ro[k * no + k] = btdf_fresnel_r(n, th);
            /* radiance over n^2 is kept across a flat face */
            ti[k * no + k] = n * n * btdf_fresnel_t(n, th);
            to[k * ng + k] = btdf_fresnel_t(n, th) / (n * n);
        }
        for (size_t k = 0; k < ng; k++)
            ri[k * ng + k] = btdf_fresnel_r(1.0 / n, acos(q->mg[k]));
    }
}

static btdf_status face_rough(const quad *q, int modes, const btdf_model_ctx *cn,
                              const btdf_model_ctx *ci, int ch, int threads, face_ops *f)
{
    int np = 2 * modes + 1;
    double *cosm = malloc(sizeof(double) * (size_t)modes * (size_t)np);
    if (!cosm)
        return BTDF_ENOMEM;
    for (int m = 0; m < modes; m++)
        for (int p = 0; p < np; p++)
            cosm[(size_t)p * modes + m] = cos(m * PI * p / (np - 1));
    struct {
        double *op;
        const double *mi, *wi, *mo;
        int ni, no, reflect, glass;
    } jobs[4] = {
        {f->r_out, q->mu, q->w, q->mu, q->no, q->no, 1, 0},
        {f->t_in, q->mu, q->w, q->mg, q->no, q->ng, 0, 0},
        {f->r_in, q->mg, q->wg, q->mg, q->ng, q->ng, 1, 1},
        {f->t_out, q->mg, q->wg, q->mu, q->ng, q->no, 0, 1},
    };
    for (int k = 0; k < 4; k++) {
        sample_job J = {cn, ci, ch, modes, np, cosm, jobs[k].mi, jobs[k].wi, jobs[k].mo,
                        jobs[k].ni, jobs[k].no, jobs[k].reflect, jobs[k].glass, jobs[k].op};
        /* a canary: a row whose buffer could not be had stays NaN */
        jobs[k].op[0] = NAN;
        core_parallel_for(threads, (size_t)jobs[k].no, sample_row, &J);
        if (isnan(jobs[k].op[0])) {
            free(cosm);
            return BTDF_ENOMEM;
        }
    }
    free(cosm);
    /* Energy: each incidence node's reflected and transmitted columns are scaled so
       their discrete hemispherical sums equal the model's own T and R at that node
       (btdf_model_ctx_albedo): point samples of a sharp lobe miss its integral by up
       to 1 % (s = 1, docs/pane.md), and the light trapped by total internal reflection
       would multiply a per-bounce excess. */
    for (int g = 0; g < 2; g++) {
        int ni = g ? q->ng : q->no, nR = g ? q->ng : q->no, nT = g ? q->no : q->ng;
        const double *mi = g ? q->mg : q->mu, *wi = g ? q->wg : q->w;
        const double *mR = g ? q->mg : q->mu, *wR = g ? q->wg : q->w;
        const double *mT = g ? q->mu : q->mg, *wT = g ? q->w : q->wg;
        double *R = g ? f->r_in : f->r_out, *T = g ? f->t_out : f->t_in;
        for (int j = 0; j < ni; j++) {
            double r = 0.0, t = 0.0, Tt[BTDF_MAX_CHANNELS], Rt[BTDF_MAX_CHANNELS];
            for (int o = 0; o < nR; o++)
                r += wR[o] * mR[o] * R[(size_t)o * ni + j];
            for (int o = 0; o < nT; o++)
                t += wT[o] * mT[o] * T[(size_t)o * ni + j];
            r /= wi[j] * mi[j];
            t /= wi[j] * mi[j];
            if (btdf_model_ctx_albedo(g ? ci : cn, acos(mi[j]), Tt, Rt) != BTDF_OK)
                continue;
            /* below 1e-9 the lobe is all but gone: nothing to rescale */
            double sr = r > 1e-9 ? Rt[ch] / r : 1.0, st = t > 1e-9 ? Tt[ch] / t : 1.0;
            for (int m = 0; m < modes; m++) {
                for (int o = 0; o < nR; o++)
                    R[((size_t)m * nR + o) * ni + j] *= sr;
                for (int o = 0; o < nT; o++)
                    T[((size_t)m * nT + o) * ni + j] *= st;
            }
        }
    }
    return BTDF_OK;
}

/* ---- dense linear algebra on small matrices ---- */

/* c = a b, a r x k, b k x n */
static void mm(const double *a, const double *b, int r, int k, int n, double *c)
{
    for (int i = 0; i < r; i++) {
        double *ci = c + (size_t)i * n;
        for (int j = 0; j < n; j++)
            ci[j] = 0.0;
        for (int l = 0; l < k; l++) {
            double v = a[(size_t)i * k + l];
            if (v == 0.0)
                continue;
            const double *bl = b + (size_t)l * n;
            for (int j = 0; j < n; j++)
                ci[j] += v * bl[j];
        }
    }
}

/* Solves a x = b in place (a n x n, destroyed; b n x c becomes x) by Gaussian elimination
   with partial pivoting. a = I - (a product of reflections), whose spectral radius is
   below 1 whenever light can leave: the pivots stay away from 0. */
static void solve(double *a, double *b, int n, int c)
{
    for (int k = 0; k < n; k++) {
        int piv = k;
        for (int i = k + 1; i < n; i++)
            if (fabs(a[(size_t)i * n + k]) > fabs(a[(size_t)piv * n + k]))
                piv = i;
        if (piv != k) {
            for (int j = 0; j < n; j++) {
                double t = a[(size_t)k * n + j];
                a[(size_t)k * n + j] = a[(size_t)piv * n + j];
                a[(size_t)piv * n + j] = t;
            }
            for (int j = 0; j < c; j++) {
                double t = b[(size_t)k * c + j];
                b[(size_t)k * c + j] = b[(size_t)piv * c + j];
                b[(size_t)piv * c + j] = t;
            }
        }
        double d = a[(size_t)k * n + k];
        if (fabs(d) < 1e-300)
            d = 1e-300; /* light that never leaves: no pivot is this small (above) */
        for (int i = k + 1; i < n; i++) {
            double f = a[(size_t)i * n + k] / d;
            if (f == 0.0)
                continue;
            for (int j = k; j < n; j++)
                a[(size_t)i * n + j] -= f * a[(size_t)k * n + j];
            for (int j = 0; j < c; j++)
                b[(size_t)i * c + j] -= f * b[(size_t)k * c + j];
        }
    }
    for (int k = n - 1; k >= 0; k--) {
        double d = a[(size_t)k * n + k];
        if (fabs(d) < 1e-300)
            d = 1e-300;
        for (int j = 0; j < c; j++) {
            double s = b[(size_t)k * c + j];
            for (int l = k + 1; l < n; l++)
                s -= a[(size_t)k * n + l] * b[(size_t)l * c + j];
            b[(size_t)k * c + j] = s / d;
        }
    }
}

static int face_alloc(face_ops *f, const quad *q, int modes)
{
    size_t no = (size_t)q->no, ng = (size_t)q->ng, m = (size_t)modes;
    f->r_out = calloc(m * no * no, sizeof(double));
    f->t_in = calloc(m * ng * no, sizeof(double));
    f->r_in = calloc(m * ng * ng, sizeof(double));
    f->t_out = calloc(m * no * ng, sizeof(double));
    return f->r_out && f->t_in && f->r_in && f->t_out;
}

static void face_free(face_ops *f)
{
    free(f->r_out);
    free(f->t_in);
    free(f->r_in);
    free(f->t_out);
}

/* Scratch of the adding equations of one mode. */
typedef struct adder {
    int no, ng;
    double *att;                 /* exp(-a d / mu_g) per glass node */
    double *rbe, *x, *d, *t1, *t2; /* ng x ng, ng x ng, ng x no, ng x no, ng x no */
} adder;

/* One mode. Fields inside: D going down just below the front, U going up just below the
   front; the back face sees A D and sends back A^-1 U. With Rbe = A Rb A:
     light on the front: D = (I - Rf' Rbe)^-1 Tf L, R = Rf + Tf' Rbe D, T = Tb A D;
     light on the back:  U = (I - Rbe Rf')^-1 A Tb' L, T = Tf' U, R = Rb' + Tb A Rf' U.
   The direct reflection of a flat outer face is left out (it is the delta part). */
static void add_mode(adder *s, const face_ops *f, const face_ops *b, int m, int flat_f,
                     int flat_b, double *out[PANE_BLOCKS])
{
    int no = s->no, ng = s->ng;
    size_t oo = (size_t)no * no, go = (size_t)ng * no, gg = (size_t)ng * ng;
    const double *rf = f->r_out + m * oo, *tf = f->t_in + m * go, *rfi = f->r_in + m * gg,
                 *tfi = f->t_out + m * go;
    const double *rbo = b->r_out + m * oo, *tbo = b->t_in + m * go, *rb = b->r_in + m * gg,
                 *tb = b->t_out + m * go;
    double *rF = out[pane_block(BTDF_PANE_FRONT, BTDF_PART_REFLECTION)] + m * oo;
    double *tF = out[pane_block(BTDF_PANE_FRONT, BTDF_PART_TRANSMISSION)] + m * oo;
    double *rB = out[pane_block(BTDF_PANE_BACK, BTDF_PART_REFLECTION)] + m * oo;
    double *tB = out[pane_block(BTDF_PANE_BACK, BTDF_PART_TRANSMISSION)] + m * oo;
    for (int i = 0; i < ng; i++)
        for (int j = 0; j < ng; j++)
            s->rbe[(size_t)i * ng + j] = s->att[i] * rb[(size_t)i * ng + j] * s->att[j];
    /* light on the front */
    mm(rfi, s->rbe, ng, ng, ng, s->x);
    for (size_t k = 0; k < gg; k++)
        s->x[k] = (k % (size_t)(ng + 1) == 0 ? 1.0 : 0.0) - s->x[k];
    memcpy(s->d, tf, go * sizeof(double));
    solve(s->x, s->d, ng, no);
    mm(s->rbe, s->d, ng, ng, no, s->t1);
    mm(tfi, s->t1, no, ng, no, rF);
    if (!flat_f)
        for (size_t k = 0; k < oo; k++)
            rF[k] += rf[k];
    for (int i = 0; i < ng; i++)
        for (int j = 0; j < no; j++)
            s->t1[(size_t)i * no + j] = s->att[i] * s->d[(size_t)i * no + j];
    mm(tb, s->t1, no, ng, no, tF);
    /* light on the back */
    mm(s->rbe, rfi, ng, ng, ng, s->x);
    for (size_t k = 0; k < gg; k++)
        s->x[k] = (k % (size_t)(ng + 1) == 0 ? 1.0 : 0.0) - s->x[k];
    for (int i = 0; i < ng; i++)
        for (int j = 0; j < no; j++)
            s->d[(size_t)i * no + j] = s->att[i] * tbo[(size_t)i * no + j];
    solve(s->x, s->d, ng, no);
    mm(tfi, s->d, no, ng, no, tB);
    mm(rfi, s->d, ng, ng, no, s->t1);
    for (int i = 0; i < ng; i++)
        for (int j = 0; j < no; j++)
            s->t2[(size_t)i * no + j] = s->att[i] * s->t1[(size_t)i * no + j];
    mm(tb, s->t2, no, ng, no, rB);
    if (!flat_b)
        for (size_t k = 0; k < oo; k++)
            rB[k] += rbo[k];
}

/* The model objects of one face: index n (light from the air) and 1/n (from the glass). */
static btdf_status face_ctx(const btdf_pane *P, double s, btdf_model_ctx **cn,
                            btdf_model_ctx **ci, char *msg, size_t msglen)
{
    btdf_params p = P->o.front;
    p.smoothness = s;
    btdf_status st = btdf_model_ctx_new(&p, P->o.full, cn, msg, msglen);
    if (st != BTDF_OK)
        return st;
    for (int c = 0; c < p.channels; c++)
        p.ior[c] = 1.0 / p.ior[c];
    return btdf_model_ctx_new(&p, P->o.full, ci, msg, msglen);
}

/* Everything of one channel. Long: the faces, the scratch, the modes, the readout. */
static btdf_status build_channel(btdf_pane *P, int ch, const btdf_model_ctx *const ctx[4],
                                 char *msg, size_t msglen)
{
    const btdf_pane_opts *o = &P->o;
    int no = P->n, modes = P->m, threads = o->threads;
    int flat_f = o->front_smooth, flat_b = o->back_smooth;
    /* two flat faces trap the light of the cone of total internal reflection, which
       none enters: it is left out (its equations are 0 = 0) */
    int nt = (flat_f && flat_b) ? 0 : (no + 1) / 2;
    double n = o->front.ior[ch];
    quad q;
    face_ops F = {0}, B = {0};
    adder s = {0};
    btdf_status st = BTDF_ENOMEM;
    if (!quad_make(&q, P->mu, P->w, no, nt, n))
        goto done;
    int ng = q.ng;
    if (!face_alloc(&F, &q, modes) || !face_alloc(&B, &q, modes))
        goto done;
    s.no = no;
    s.ng = ng;
    s.att = malloc(sizeof(double) * (size_t)ng);
    s.rbe = malloc(sizeof(double) * (size_t)ng * ng);
    s.x = malloc(sizeof(double) * (size_t)ng * ng);
    s.d = malloc(sizeof(double) * (size_t)ng * no);
    s.t1 = malloc(sizeof(double) * (size_t)ng * no);
    s.t2 = malloc(sizeof(double) * (size_t)ng * no);
    if (!s.att || !s.rbe || !s.x || !s.d || !s.t1 || !s.t2)
        goto done;
    double ad = o->absorption_per_mm * o->thickness_mm;
    for (int k = 0; k < ng; k++)
        s.att[k] = exp(-ad / q.mg[k]); /* mu_g > 0 at every Gauss node */
    if (flat_f)
        face_flat(&q, modes, &F);
    else if ((st = face_rough(&q, modes, ctx[0], ctx[1], ch, threads, &F)) != BTDF_OK)
        goto done;
    if (flat_b)
        face_flat(&q, modes, &B);
    else if ((st = face_rough(&q, modes, ctx[2], ctx[3], ch, threads, &B)) != BTDF_OK)
        goto done;
    st = BTDF_ENOMEM;
    pane_ch *pc = &P->ch[ch];
    size_t oo = (size_t)no * no;
    for (int k = 0; k < PANE_BLOCKS; k++) {
        pc->coef[k] = calloc((size_t)modes * oo, sizeof(double));
        pc->spec[k] = calloc((size_t)no, sizeof(double));
        pc->alb[k] = calloc((size_t)no, sizeof(double));
        if (!pc->coef[k] || !pc->spec[k] || !pc->alb[k])
            goto done;
    }
    for (int m = 0; m < modes; m++)
        add_mode(&s, &F, &B, m, flat_f, flat_b, pc->coef);
    /* the delta parts: the direct mirror of a flat outer face; two flat faces make every
       block diagonal (mode 0's diagonal is its weight) */
    for (int j = 0; j < no; j++) {
        if (flat_f)
            pc->spec[pane_block(BTDF_PANE_FRONT, BTDF_PART_REFLECTION)][j] =
                F.r_out[(size_t)j * no + j];
        if (flat_b)
            pc->spec[pane_block(BTDF_PANE_BACK, BTDF_PART_REFLECTION)][j] =
                B.r_out[(size_t)j * no + j];
    }
    for (int k = 0; k < PANE_BLOCKS; k++) {
        double *c = pc->coef[k];
        if (flat_f && flat_b) {
            for (int j = 0; j < no; j++) {
                pc->spec[k][j] += c[(size_t)j * no + j];
                for (int m = 0; m < modes; m++)
                    c[(size_t)m * oo + (size_t)j * no + j] = 0.0;
            }
        }
        /* albedo from mode 0: sum_o w_o mu_o S[o][j] / (w_j mu_j), then the coefficients
           b_m(j, o) = (-1)^m S_m[o][j] / (c_m w_j mu_j), stored [m][j][o] */
        double *tmp = malloc(sizeof(double) * oo);
        if (!tmp)
            goto done;
        for (int j = 0; j < no; j++) {
            double a = 0.0;
            for (int oi = 0; oi < no; oi++)
                a += P->w[oi] * P->mu[oi] * c[(size_t)oi * no + j];
            pc->alb[k][j] = a / (P->w[j] * P->mu[j]) + pc->spec[k][j];
        }
        for (int m = 0; m < modes; m++) {
            double *cm = c + (size_t)m * oo;
            memcpy(tmp, cm, sizeof(double) * oo);
            double cmf = (m == 0 ? 2.0 * PI : PI) * ((m & 1) ? -1.0 : 1.0);
            for (int j = 0; j < no; j++)
                for (int oi = 0; oi < no; oi++)
                    cm[(size_t)j * no + oi] =
                        tmp[(size_t)oi * no + j] / (cmf * P->w[j] * P->mu[j]);
        }
        free(tmp);
    }
    st = BTDF_OK;
done:
    if (st == BTDF_ENOMEM)
        core_say(st, msg, msglen, "pane: out of memory (%d nodes, %d modes)", no, modes);
    quad_free(&q);
    face_free(&F);
    face_free(&B);
    free(s.att);
    free(s.rbe);
    free(s.x);
    free(s.d);
    free(s.t1);
    free(s.t2);
    return st;
}

/* The quadrature chosen from the roughest lobe (docs/pane.md): the lobes are about 2/s
   wide, so the nodes and modes grow with s. */
static void pane_auto(const btdf_pane_opts *o, int *nodes, int *modes)
{
    double s = 0.0;
    if (!o->front_smooth)
        s = o->front.smoothness;
    if (!o->back_smooth && o->back_smoothness > s)
        s = o->back_smoothness;
    /* measured at n = 1.5, s = 3 (docs/pane.md): 72 nodes and 96 modes put e_L1 against
       96 and 128 at 6.5e-4; 36 nodes left 3e-2 near normal incidence */
    double nn = 24.0 + 16.0 * s, mm_ = 24.0 + 24.0 * s;
    *nodes = o->nodes ? o->nodes : (int)(nn < 192.0 ? nn : 192.0);
    *modes = o->modes ? o->modes : (int)(mm_ < 256.0 ? mm_ : 256.0);
    if (o->front_smooth && o->back_smooth) {
        /* every part a delta: nothing spreads in azimuth; the weights are interpolated
           in cos theta, to 1.4e-4 with 24 nodes at 86 deg and below 1e-5 with 64 */
        if (!o->modes)
            *modes = 1;
        if (!o->nodes)
            *nodes = 64;
    }
}

BTDF_API btdf_status btdf_pane_new(const btdf_pane_opts *o, btdf_pane **out, char *msg,
                                   size_t msglen)
{
    if (!out)
        return core_say(BTDF_EINVAL, msg, msglen, "btdf_pane_new: NULL argument");
    btdf_status st = btdf_pane_opts_check(o, msg, msglen);
    if (st != BTDF_OK)
        return st;
    double t0 = core_now();
    btdf_pane *P = calloc(1, sizeof *P);
    if (!P)
        return core_say(BTDF_ENOMEM, msg, msglen, "pane: out of memory");
    P->o = *o;
    if (o->full) {
        P->full = *o->full;
        P->o.full = &P->full;
    }
    pane_auto(o, &P->n, &P->m);
    P->mu = malloc(sizeof(double) * (size_t)P->n);
    P->w = malloc(sizeof(double) * (size_t)P->n);
    btdf_model_ctx *ctx[4] = {0};
    if (!P->mu || !P->w) {
        st = core_say(BTDF_ENOMEM, msg, msglen, "pane: out of memory");
        goto fail;
    }
    pane_gauss(P->n, 0.0, 1.0, P->mu, P->w);
    if (!o->front_smooth &&
        (st = face_ctx(P, o->front.smoothness, &ctx[0], &ctx[1], msg, msglen)) != BTDF_OK)
        goto fail;
    if (!o->back_smooth &&
        (st = face_ctx(P, o->back_smoothness, &ctx[2], &ctx[3], msg, msglen)) != BTDF_OK)
        goto fail;
    for (int c = 0; c < o->front.channels; c++)
        if ((st = build_channel(P, c, (const btdf_model_ctx *const *)ctx, msg, msglen)) !=
            BTDF_OK)
            goto fail;
    for (int k = 0; k < 4; k++)
        btdf_model_ctx_free(ctx[k]);
    P->seconds = core_now() - t0;
    *out = P;
    return BTDF_OK;
fail:
    for (int k = 0; k < 4; k++)
        btdf_model_ctx_free(ctx[k]);
    btdf_pane_free(P);
    return st;
}

BTDF_API void btdf_pane_free(btdf_pane *P)
{
    if (!P)
        return;
    for (int c = 0; c < BTDF_MAX_CHANNELS; c++)
        for (int k = 0; k < PANE_BLOCKS; k++) {
            free(P->ch[c].coef[k]);
            free(P->ch[c].spec[k]);
            free(P->ch[c].alb[k]);
        }
    free(P->mu);
    free(P->w);
    free(P);
}

BTDF_API const btdf_pane_opts *btdf_pane_get_opts(const btdf_pane *P) { return &P->o; }

BTDF_API void btdf_pane_size(const btdf_pane *P, int *nodes, int *modes)
{
    if (nodes)
        *nodes = P->n;
    if (modes)
        *modes = P->m;
}

BTDF_API double btdf_pane_seconds_build(const btdf_pane *P) { return P->seconds; }
