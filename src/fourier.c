/* SPDX-License-Identifier: MIT */
/* fourier.c: builds SCATFUN v1 Fourier-series BSDFs from Eq. 25 (node placement, cosine transforms, convergence, carry-over) and evaluates and measures them as pbrt-v3 reads them. */
#include <errno.h>
#include <float.h>
#include <limits.h>
#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "btdf.h"
#include "btdf_scatfun.h"
#include "model/kernel.h"
#include "scatfun/scatfun.h"
#include "core/core.h"
#include "estimate/estimate.h"
#include "model/facet.h"
#include "scatfun/dct.h"
#include "scatfun/spline.h"

/* ------------------------------------------------------------------------- */
/* Building: per-pair series and adaptive elevation nodes                    */
/* ------------------------------------------------------------------------- */

/* The four blocks of a full dielectric interface, in pbrt-v3's convention (slow index
   mu_s = wo.z, fast index mu_f = -wi.z):
     T_ENTER  mu_s > 0, mu_f > 0: transmission, light entering (index n);
     T_LEAVE  mu_s < 0, mu_f < 0: transmission, light leaving (index 1/n);
     R_TOP    mu_s > 0, mu_f < 0: reflection back into the upper medium (index n);
     R_BOTTOM mu_s < 0, mu_f > 0: reflection inside the dense medium (index 1/n,
              total internal reflection included).
   Every block is built on the half-node grid in (|mu_s|, |mu_f|). */
enum { BLK_T_ENTER = 0, BLK_T_LEAVE = 1, BLK_R_TOP = 2, BLK_R_BOTTOM = 3, NBLK = 4 };
static const int blk_refl[NBLK] = {0, 0, 1, 1};
static const int blk_slow_neg[NBLK] = {0, 1, 0, 1}; /* mu_s < 0 */
static const int blk_fast_neg[NBLK] = {0, 1, 1, 0}; /* mu_f < 0 */
static const int blk_mask[NBLK] = {BTDF_SCATFUN_T_ENTER, BTDF_SCATFUN_T_LEAVE,
                                   BTDF_SCATFUN_R_TOP, BTDF_SCATFUN_R_BOTTOM};

typedef struct pair {
    double *a;     /* nst * m coefficients, channel-major (Y, R, B) */
    uint32_t m;
    uint16_t N;    /* the azimuth grid its samples converged on (<= nmax = 16384) */
    uint16_t done; /* computed in an earlier pass with the same budget: 1, or 2 when
                      dark (no facet connects it at any azimuth: its samples are 0) */
} pair;
/* pair.N holds any grid: a compile-time check that the largest fits */
typedef char pair_grid_fits[BTDF_SCATFUN_MAX_PHI <= 65535 ? 1 : -1];

typedef struct build_ctx {
    const btdf_params *p;
    int nc;        /* model channels */
    int nst;       /* stored channels: 1, or 3 (Y, R, B) */
    double ior[NBLK][3];  /* per block and channel */
    double fold[NBLK][3]; /* per block and model channel: the factor folded into the stored
                             values so pbrt-v3's single-eta radiance path is right for
                             every channel (1 for one channel and for reflection) */
    size_t nmin, nmax; /* phi sample counts (powers of two) */
    double budget; /* current target for e_L1 */
    /* half nodes P[0..K-1] ascending, P[K-1] = 1, and the full node list */
    size_t K;
    double *P;
    double *full; /* 2K + 2 */
    double (*Tn)[NBLK][8]; /* Tn[r][side][0..2]: the DIRECT norm per stored channel at node
                              r, [4..6]: the ADJOINT norm (norms_at) */
    int want[NBLK];
    pair *pairs[NBLK]; /* [block][r * K + c] */
    /* checks */
    size_t nint;    /* intervals = K: [0, P0], [P0, P1], ... */
    double *mid;    /* nint midpoints */
    double (*Tm)[NBLK][8]; /* norms at midpoints */
    double *errc[NBLK];    /* [block][r * nint + j]: column check errors (already normalised) */
    double *errr[NBLK];    /* [block][j]: row check errors (normalised, mu-integrated) */
    double *gapr[NBLK];    /* [block][j * K + col]: row check gap at one column */
    unsigned char *okc[NBLK], *okr[NBLK]; /* errc / gapr entries carried from the last pass */
    pair *pcol[NBLK];      /* [block][r * K + j]: series at (P[r], mid[j]), a future pair */
    pair *prow[NBLK];      /* [block][j * K + col]: series at (mid[j], P[col]) */
    unsigned char *hasTn, *hasTm; /* norms carried from the last pass */
    int oom, capped;    /* flags raised by workers */
    pthread_mutex_t lock;
} build_ctx;

typedef struct build_ws {
    sf_fftbuf fb;
    double *x;       /* samples per stored channel: nst * (nmax + 1) */
    double *a;       /* coefficients per stored channel */
    double *y;       /* inverse values */
    double *ia;      /* interpolated coefficients, nst * (nmax + 1) */
    double *rho;     /* per model channel scratch */
    double *cosg, *sing; /* cos and sin of j pi / nmax, j = 0..nmax */
    double *h2g;         /* sin^2 of j pi / (2 nmax): bt_rho's azimuth term at phi_d */
    int dark;            /* the last converge() found the pair dark (first_grid 0) */
} build_ws;

static void *build_ws_new(void *vctx)
{
    build_ctx *c = vctx;
    build_ws *w = calloc(1, sizeof *w);
    if (!w)
        return NULL;
    size_t len = (size_t)c->nst * (c->nmax + 1);
    w->x = malloc(len * sizeof(double));
    w->a = malloc(len * sizeof(double));
    w->ia = malloc(len * sizeof(double));
    w->y = malloc((c->nmax + 1) * sizeof(double));
    w->rho = malloc(4 * sizeof(double));
    w->cosg = malloc((c->nmax + 1) * sizeof(double));
    w->sing = malloc((c->nmax + 1) * sizeof(double));
    w->h2g = malloc((c->nmax + 1) * sizeof(double));
    if (w->cosg && w->sing && w->h2g) {
        for (size_t j = 0; j <= c->nmax; j++) {
            w->cosg[j] = cos(M_PI * (double)j / (double)c->nmax);
            w->sing[j] = sin(M_PI * (double)j / (double)c->nmax);
            /* 1 + cos phi = 1 - cos phi_d = 2 sin^2(phi_d / 2), without cancellation */
            double sh = sin(0.5 * M_PI * (double)j / (double)c->nmax);
            w->h2g[j] = sh * sh;
        }
        /* exact forward, side and backward planes */
        w->cosg[0] = 1.0, w->sing[0] = 0.0;
        w->cosg[c->nmax] = -1.0, w->sing[c->nmax] = 0.0;
        w->cosg[c->nmax / 2] = 0.0, w->sing[c->nmax / 2] = 1.0;
        w->fb.cosg = w->cosg;
        w->fb.sing = w->sing;
        w->fb.nmax = c->nmax;
    }
    if (!w->cosg || !w->sing || !w->h2g || !w->x || !w->a || !w->ia ||
        !w->y || !w->rho || sf_fft_reserve(&w->fb, c->nmax + 1)) {
        sf_fft_free(&w->fb);
        free(w->x); free(w->a); free(w->ia); free(w->y);
        free(w->rho);
        free(w->cosg);
        free(w->sing);
        free(w->h2g);
        free(w);
        return NULL;
    }
    return w;
}

static void build_ws_free(void *vw)
{
    build_ws *w = vw;
    if (!w)
        return;
    sf_fft_free(&w->fb);
    free(w->x); free(w->a); free(w->ia); free(w->y);
    free(w->rho);
    free(w->cosg);
    free(w->sing);
    free(w->h2g);
    free(w);
}

/* Stored channel values of g = rho * |mu_f| (rho_r * |mu_f| for a reflection block) at
   one azimuth, from the model channels, each times the block's fold factor. */
static void stored_values(const build_ctx *c, int b, const rho_in *ri, const rho_out *ro,
                          const bt_ir *ir, double mu_f, double cph, double sph, double *out)
{
    double v[3];
    for (int k = 0; k < c->nc; k++) {
        double n = c->ior[b][k];
        if (blk_refl[b])
            /* h2 = (1 + cos phi)/2 = sin^2(phi_d/2), MODEL.md 8's azimuth part */
            v[k] = bt_rho_r(n, n - 1.0, c->p->smoothness, ir, 0.5 * (1.0 + cph), sph) * mu_f;
        else
            v[k] = rho_kernel(n, c->p->smoothness, ri, ro, cph, sph) * mu_f;
    }
    if (c->nst == 1) {
        out[0] = v[0];
    } else {
        for (int k = 0; k < 3; k++)
            v[k] *= c->fold[b][k];
        out[0] = LUM_R * v[0] + LUM_G * v[1] + LUM_B * v[2];
        out[1] = v[0];
        out[2] = v[2];
    }
}

/* sample_grid for a one-channel transmission block: Eq. 25 in its branch-free form
   (bt_rho, the public entry points' kernel, which the compiler vectorises) along the
   azimuth row; the same function as rho_kernel's to rounding. */
BT_CLONES static void sample_grid_t1(const build_ctx *c, const build_ws *w, int b,
                                     double mu_s, double mu_f, size_t N, size_t step,
                                     size_t phase, double *x)
{
    /* |mu| <= 1 for every node and midpoint; fmax guards rounding */
    double ss = sqrt(fmax(0.0, 1.0 - mu_s * mu_s)), sf = sqrt(fmax(0.0, 1.0 - mu_f * mu_f));
    /* ti = acos mu_s and b = pi - to = acos mu_f, both in [0, pi/2] */
    double ti = atan2(ss, mu_s), bb = atan2(sf, mu_f);
    double sp = sin(0.5 * (ti + bb)), cp = cos(0.5 * (ti + bb)), sm = sin(0.5 * (ti - bb));
    bt_io io;
    bt_io_set(&io, ss, mu_s, sf, mu_f, sp, cp, sm);
    double n = c->ior[b][0], d = n - 1.0, s = c->p->smoothness;
    bt_io_pref(&io, s, c->p->k0);
    double f = mu_f; /* one channel: no fold (stored_values) */
    size_t g = c->nmax / N; /* N divides nmax: both are powers of two */
    const double *h2 = w->h2g, *sn = w->sing;
    /* a counted loop (the vectoriser needs the trip count): j = phase + t step */
    long cnt = phase <= N ? (long)((N - phase) / step) + 1 : 0, sg = (long)(step * g);
    const double *h2p = h2 + phase * g, *snp = sn + phase * g;
    double *xp = x + phase;
    for (long t = 0; t < cnt; t++)
        xp[t * (long)step] = bt_rho(n, d, s, &io, h2p[t * sg], snp[t * sg]) * f;
}

/* sample_grid for a one-channel reflection block: rho_r (bt_rho_r, branch-free) along
   the azimuth row in a counted loop the compiler vectorises, with the operations of
   stored_values in the same order, so the same samples to the bit. */
BT_CLONES static void sample_grid_r1(const build_ctx *c, const build_ws *w, int b,
                                     double mu_s, double mu_f, size_t N, size_t step,
                                     size_t phase, double *x)
{
    /* |mu| <= 1 for every node and midpoint; fmax guards rounding */
    double ss = sqrt(fmax(0.0, 1.0 - mu_s * mu_s)), sf = sqrt(fmax(0.0, 1.0 - mu_f * mu_f));
    bt_ir ir;
    memset(&ir, 0, sizeof ir);
    /* ti = acos mu_s, tr = acos mu_f, both in [0, pi/2] */
    bt_ir_rad(&ir, atan2(ss, mu_s), atan2(sf, mu_f), c->p->smoothness, c->p->k0);
    double n = c->ior[b][0], d = n - 1.0, s = c->p->smoothness;
    size_t g = c->nmax / N; /* N divides nmax: both are powers of two */
    long cnt = phase <= N ? (long)((N - phase) / step) + 1 : 0, sg = (long)(step * g);
    const double *cg = w->cosg + phase * g, *sn = w->sing + phase * g;
    double *xp = x + phase;
    for (long t = 0; t < cnt; t++) {
        /* phi_d = j pi / N, phi = pi - phi_d: cos phi = -cos phi_d (sample_grid) */
        double cph = -cg[t * sg];
        xp[t * (long)step] = bt_rho_r(n, d, s, &ir, 0.5 * (1.0 + cph), sn[t * sg]) * mu_f;
    }
}

/* The first azimuth grid has at least NMIN_PHI intervals over [0, pi] (8 s for the
   narrowest pairs: first_grid); converge() doubles it until the series settle. */
#define NMIN_PHI 32.0

/* Along the azimuth each of bt_rho's three conditions (BT_RHO_GEOMETRY: e_i.v > 0,
   e_o.v > 0 with the facet's side, and the slope below the exponential's underflow)
   is linear in h2 = sin^2(phi_d/2) in [0, 1]: with w = e_i + e_o, |w|^2 = wx0^2 + wz^2
   + 4 sto (wx0 + sto) h2, so e_i.v and e_o.v are linear in h2; v_z = wz - d cto does
   not depend on phi; and rxy^2 = (A + B h2)^2 + 4 n^2 sto^2 h2 (1 - h2) with A = wx0 -
   d sto, B = 2 n sto, whose h2^2 terms cancel. So is the exponent E = (s^2/4) rxy^2 /
   v_z^2: the Gaussian factor is e^-E0 e^-(G/2) e^((G/2) cos phi_d), G = dE/dh2, a von
   Mises shape whose cosine coefficients fall like exp(-k^2 / |G|).
   For one channel of index n: 0 when the conditions, each relaxed by 1e-9 of its scale
   (far above the kernel's rounding), hold nowhere on [0, 1]; else 1, with *kappa =
   |G|/2 and *width the angle phi_d spanned by the h2 where they all hold; -1 when v_z
   is too close to 0 to tell its sign. */
static int pair_azimuth(double n, double s, const bt_io *io, double *kappa, double *width)
{
    double d = n - 1.0;
    double vz = io->wz - d * io->cto;
    if (!(fabs(vz) > 1e-12))
        return -1;
    double sg = vz < 0.0 ? -1.0 : 1.0, vz2 = vz * vz;
    double w0 = io->wx0 * io->wx0 + io->wz * io->wz, w1 = 4.0 * io->sto * (io->wx0 + io->sto);
    double A = io->wx0 - d * io->sto, B = 2.0 * n * io->sto;
    /* f(h2) = al + be h2 > 0 for sg e_i.v = sg (n |w|^2/2 - d), -sg e_o.v =
       -sg (d + |w|^2/2) and CUT vz^2 - (s^2/4) rxy^2 */
    double al[3] = {sg * (0.5 * n * w0 - d), -sg * (d + 0.5 * w0),
                    BTDF_EXP_CUT * vz2 - 0.25 * s * s * A * A};
    double be[3] = {sg * 0.5 * n * w1, -sg * 0.5 * w1, -0.25 * s * s * (2.0 * A * B + B * B)};
    double lo = 0.0, hi = 1.0;
    for (int i = 0; i < 3; i++) {
        double scale = fabs(al[i]) + fabs(be[i]) + (i == 2 ? BTDF_EXP_CUT * vz2 : 1.0);
        double a = al[i] + 1e-9 * scale; /* relaxed: f > -1e-9 scale */
        if (be[i] > 0.0)
            lo = fmax(lo, -a / be[i]); /* be != 0 */
        else if (be[i] < 0.0)
            hi = fmin(hi, -a / be[i]); /* be != 0 */
        else if (!(a > 0.0))
            lo = 2.0; /* f <= -1e-9 scale at every azimuth */
    }
    if (!(lo < hi))
        return 0;
    /* lo, hi in [0, 1] here, so the sqrt and asin arguments are too */
    *width = 2.0 * (asin(sqrt(fmin(hi, 1.0))) - asin(sqrt(fmax(lo, 0.0))));
    *kappa = 0.5 * fabs(-be[2] / vz2); /* vz2 > 1e-24 */
    return 1;
}

static size_t pow2_at_least(double v);

static void pair_io(double mu_s, double mu_f, bt_io *io)
{
    /* as sample_grid_t1: |mu| <= 1, fmax guards rounding */
    double ss = sqrt(fmax(0.0, 1.0 - mu_s * mu_s)), sf = sqrt(fmax(0.0, 1.0 - mu_f * mu_f));
    double ti = atan2(ss, mu_s), bb = atan2(sf, mu_f);
    double sp = sin(0.5 * (ti + bb)), cp = cos(0.5 * (ti + bb)), sm = sin(0.5 * (ti - bb));
    bt_io_set(io, ss, mu_s, sf, mu_f, sp, cp, sm);
}

/* Declared in scatfun/scatfun.h: pair_azimuth finds no azimuth for any channel. */
int sf_unreachable(const double *ior, int channels, double s, double mu_s,
                        double mu_f)
{
    bt_io io;
    pair_io(mu_s, mu_f, &io);
    for (int k = 0; k < channels; k++) {
        double kappa, width;
        if (pair_azimuth(ior[k], s, &io, &kappa, &width) != 0)
            return 0; /* this channel reaches some azimuth, or may */
    }
    return 1;
}

/* The first azimuth grid of a transmission pair. converge() never accepts a grid
   before comparing it with its double, so the first grid is half of what the accepted
   one must hold: 3 sqrt(kappa) harmonics and 2 points across the azimuths any facet
   reaches, so that the doubled grid has 6 sqrt(kappa) (where the von Mises factor's
   coefficients have fallen to e^-18 of the first) and 4 points across; at least
   FIRST_MIN_PHI (the doubled grid NMIN_PHI) and at most the material's nmin (8 s, for
   the narrowest pairs; also where a channel's v_z is too close to 0 to tell). Until
   this version the first grid held the 6 sqrt(kappa) and 4 points itself: files of
   n = 1.5 (s = 3, 20 at 1e-3; s = 100 at 1e-2), 2.4 (s = 1) and 1.33 (s = 5, four
   blocks) have the same nodes and e_L1 to 3 digits either way, and s = 100 builds in
   13 s instead of 29. 0 when every channel is dark (sf_unreachable's answer). */
#define FIRST_MIN_PHI 16.0
static size_t first_grid(const build_ctx *c, int b, double mu_s, double mu_f)
{
    bt_io io;
    pair_io(mu_s, mu_f, &io);
    double want = 0.0;
    for (int k = 0; k < c->nc; k++) {
        double kappa = 0.0, width = 0.0;
        int r = pair_azimuth(c->ior[b][k], c->p->smoothness, &io, &kappa, &width);
        if (r < 0)
            return c->nmin;
        if (r == 0)
            continue;
        want = fmax(want, fmax(FIRST_MIN_PHI, 3.0 * sqrt(kappa)));
        /* width > 0 when reached; 2 pi / width (2 points across) may be huge: capped
           below */
        want = fmax(want, width > 0.0 ? 2.0 * M_PI / width : HUGE_VAL);
    }
    if (want == 0.0)
        return 0; /* no channel reaches any azimuth */
    return want >= (double)c->nmin ? c->nmin : pow2_at_least(want);
}

/* Fills samples x (stride N2 + 1 per stored channel, N2 = the grid wanted) for the grid
   j pi / N, only at indices j with j % step == phase (step 1: all, 2: odd ones).
   mu_s, mu_f are the block's cosines as magnitudes, in [0, 1]. */
static void sample_grid(const build_ctx *c, const build_ws *w, int b, double mu_s,
                        double mu_f, size_t N, size_t stride, size_t step, size_t phase,
                        double *x)
{
    if (!blk_refl[b] && c->nc == 1) {
        sample_grid_t1(c, w, b, mu_s, mu_f, N, step, phase, x);
        return;
    }
    if (blk_refl[b] && c->nc == 1) {
        sample_grid_r1(c, w, b, mu_s, mu_f, N, step, phase, x);
        return;
    }
    rho_in ri;
    rho_out ro;
    bt_ir ir;
    memset(&ri, 0, sizeof ri); /* only the block's kind of geometry is used */
    memset(&ro, 0, sizeof ro);
    memset(&ir, 0, sizeof ir);
    /* |mu| <= 1 holds for every node and midpoint, so the sqrt arguments are >= 0;
       fmax guards rounding. */
    double ss = sqrt(fmax(0.0, 1.0 - mu_s * mu_s)), sf = sqrt(fmax(0.0, 1.0 - mu_f * mu_f));
    if (blk_refl[b]) {
        /* ti = acos mu_s, tr = acos mu_f, both in [0, pi/2] */
        double ti = atan2(ss, mu_s), tr = atan2(sf, mu_f);
        bt_ir_rad(&ir, ti, tr, c->p->smoothness, c->p->k0);
    } else {
        rho_in_init(&ri, ss, mu_s, c->p->smoothness, c->p->k0);
        rho_out_init(&ro, sf, -mu_f, c->p->smoothness, c->p->k0);
    }
    double v[3];
    size_t g = c->nmax / N; /* N divides nmax: both are powers of two */
    for (size_t j = phase; j <= N; j += step) {
        /* phi_d = j pi / N; phi = pi - phi_d, so cos phi = -cos phi_d. */
        stored_values(c, b, &ri, &ro, &ir, mu_f, -w->cosg[j * g], w->sing[j * g], v);
        for (int k = 0; k < c->nst; k++)
            x[k * stride + j] = v[k];
    }
}

/* Converged coefficients of g at (mu_s, mu_f): doubles the azimuth grid until the
   series of the coarser grid misses the samples of the finer one by less than
   eps_alias (in L1 over the circle, per channel relative to norm[ch]). Leaves w->a
   with stride nmax + 1 holding N + 1 coefficients per stored channel and w->x the
   samples on that grid; returns N (0 on failure). */
static size_t converge(build_ctx *c, build_ws *w, int side, double mu_s, double mu_f,
                       const double *norm, double eps_alias)
{
    size_t S = c->nmax + 1;
    size_t N = blk_refl[side] ? c->nmin : first_grid(c, side, mu_s, mu_f);
    w->dark = N == 0;
    if (N == 0) {
        /* No facet connects the pair at any azimuth (n = 1.5, s = 20 at 1e-3: 880,000
           of 1.86 million series): what the samples below would find on the material's
           grids, 0 (2 nmin <= nmax: build_impl), without sampling. */
        N = 2 * c->nmin;
        for (int k = 0; k < c->nst; k++) {
            memset(w->x + (size_t)k * S, 0, (N + 1) * sizeof *w->x);
            memset(w->a + (size_t)k * S, 0, (N + 1) * sizeof *w->a);
        }
        return N;
    }
    sample_grid(c, w, side, mu_s, mu_f, N, S, 1, 0, w->x);
    for (int k = 0; k < c->nst; k++)
        if (sf_dct_forward(&w->fb, w->x + k * S, N, w->a + k * S))
            return 0;
    int zero = 1;
    for (int k = 0; k < c->nst && zero; k++)
        for (size_t j = 0; j <= N && zero; j++)
            zero = w->x[k * S + j] == 0.0;
    for (;;) {
        if (2 * N > c->nmax) {
            pthread_mutex_lock(&c->lock);
            c->capped = 1;
            pthread_mutex_unlock(&c->lock);
            return N;
        }
        size_t N2 = 2 * N;
        /* spread the old samples onto the finer grid from the top down */
        for (int k = 0; k < c->nst; k++)
            for (size_t j = N + 1; j-- > 0;)
                w->x[k * S + 2 * j] = w->x[k * S + j];
        sample_grid(c, w, side, mu_s, mu_f, N2, S, 2, 1, w->x);
        if (zero) {
            /* no transmission on either grid (an unreachable pair): all zero */
            for (int k = 0; k < c->nst && zero; k++)
                for (size_t j = 1; j <= N2 && zero; j += 2)
                    zero = w->x[k * S + j] == 0.0;
            if (zero) {
                /* the N2 + 1 coefficients the caller reads, not the whole stride (nmax
                   + 1: zeroing 128 KiB per unreachable pair was 4% of a build) */
                for (int k = 0; k < c->nst; k++)
                    memset(w->a + (size_t)k * S, 0, (N2 + 1) * sizeof *w->a);
                return N2;
            }
        }
        double worst = 0.0;
        for (int k = 0; k < c->nst; k++) {
            /* The measured L1 over the circle of the coarse series against the new
               samples (the points it did not see) is its error, not a bound on it.
               Until this version transmission used the bound 2 pi sum |a'_q - a_q|
               (a' the finer grid's): where g has a kink or an edge in phi (reflection
               below the dense side, where facets start to reflect totally, Fresnel ~
               1 - sqrt; transmission, where the facets needed turn away or pass the
               critical angle) the coefficients decay like q^-1.5 or slower and the
               bound kept doubling the grid: n = 1.5, s = 3 at 1e-3 converged 50,534
               series at N = 1024 to 4096; measured, none needs more than 512, with
               the same nodes and the same measured e_L1 of the file. */
            double l1 = sf_series_l1(&w->fb, w->a + k * S, N + 1, N2, w->x + k * S, w->y);
            if (l1 < 0.0)
                return 0;
            double d = l1 / norm[k]; /* norm >= T_FLOOR */
            if (d > worst)
                worst = d;
            if (sf_dct_forward(&w->fb, w->x + k * S, N2, w->a + k * S))
                return 0;
        }
        N = N2;
        if (worst <= eps_alias)
            return N;
    }
}

/* Shortest length m whose dropped tail costs at most eps_trunc (L1 over the circle,
   relative to norm[ch]) in every stored channel. */
enum { TRUNC_BLOCK = 64 };

BT_CLONES static size_t truncate_len(const build_ctx *c, const double *a, size_t S, size_t N,
                           const double *norm, double eps_trunc)
{
    size_t m = 0;
    for (int k = 0; k < c->nst; k++) {
        const double *ak = a + k * S;
        /* integral over the circle of |sum_{q>=m} a_q cos q phi| <= 4 sum |a_q| for
           q >= 1, and 2 pi |a_0| */
        double tail = 0.0;
        size_t q = N + 1;
        int stop = 0;
        /* In blocks of TRUNC_BLOCK from the top (the one-at-a-time loop waited on a
           division per coefficient, over thousands of coefficients per series: 8 % of
           an s = 20 build). A block whose terms, summed in four lanes, keep the tail
           below eps_trunc by more than their rounding (64 terms >= 0: at most 64 ulps
           of the sum) cannot stop the walk anywhere inside, so it is taken whole; the
           block where the tail would reach eps_trunc is walked term by term. Terms
           are multiplied by 1/norm rather than divided. The same m as the
           one-at-a-time walk with divisions except where the tail ties eps_trunc to
           about 1e-12 (the files compared were byte for byte the same). */
        double inv = 1.0 / norm[k]; /* norm >= T_FLOOR > 0 */
        while (q > 0 && !stop) {
            size_t nb = q < TRUNC_BLOCK ? q : TRUNC_BLOCK, lo = q - nb;
            double add[TRUNC_BLOCK];
            for (size_t i = 0; i < nb; i++)
                add[i] = 4.0 * fabs(ak[lo + i]) * inv;
            if (lo == 0)
                add[0] = 2.0 * M_PI * fabs(ak[0]) * inv;
            if (nb == TRUNC_BLOCK) {
                double b4[4] = {0.0, 0.0, 0.0, 0.0};
                for (size_t i4 = 0; i4 < TRUNC_BLOCK; i4 += 4)
                    for (int v = 0; v < 4; v++)
                        b4[v] += add[i4 + v];
                double bs = (b4[0] + b4[1]) + (b4[2] + b4[3]);
                if (tail + bs <= eps_trunc * (1.0 - 1e-12)) {
                    tail += bs;
                    q = lo;
                    continue;
                }
            }
            for (size_t i = nb; i-- > 0;) {
                if (tail + add[i] > eps_trunc) {
                    stop = 1;
                    break;
                }
                tail += add[i];
                q--;
            }
        }
        if (q > m)
            m = q;
    }
    return m;
}

/* Shares of the current budget for the node checks. Each check bounds one
   interpolation direction at interval midpoints by the triangle inequality, and files
   that passed checks at 0.35 each measured 2 to 8 times below the tolerance (the
   nodes were set by the worst midpoint of every row), so the checks take 0.7 each;
   what decides is the file's own measurement below, not the checks.
   That measurement accepts a file at ACCEPT_SHARE of the tolerance (the final report
   uses other test angles and finds other maxima, so a margin); test angles above
   MARK_SHARE of it get their elevation interval split, for at most LOCAL_ROUNDS
   rounds, before the shares are halved and everything recomputed. */
#define SHARE_CHECK 0.7
#define ACCEPT_SHARE 0.75
#define MARK_SHARE 0.5
#define LOCAL_ROUNDS 24
/* Each measurement after a local round uses the next seed: a file is accepted on test
   angles its splits were not chosen from (one fixed seed let the splits fit its
   angles: s = 20 at 1e-3 passed 0.75e-3 on them and measured 1.45e-3 on others). */
#define QUICK_SEED 0x5ca7f00dULL
/* Facet-slope points per test angle of those measurements (the report's default is
   8192; the 64 x 64 direction points come on top). A quarter of the default spreads no
   more: per-angle e_L1 at 2048 against 8192 points differed by 1.0 % and 4.3 % rms
   (n = 1.5, s = 3 at 1e-3, entering and leaving side), 1.6 % and 0.4 % (s = 100 at
   1e-2), where two seeds at 8192 differ by 0.9 %, 4.0 %, 1.2 % and 0.35 % (angles
   within 0.3 of the worst); the worst angle's e_L1 moved by at most 2.6 %, inside
   ACCEPT_SHARE's margin. The measurement then costs 1.6 (s = 3) to 3.3 (s = 100)
   times less. */
#define QUICK_PPA 2048
/* The measurements screen their first angles (est_opts): each is read with 512 lobe
   points and a 32 x 32 direction grid (a quarter of the points), and again with the
   full sets where that reads at least SCREEN_SHARE of the acceptance level, or 0 (a
   screen that saw no error knows nothing); the refinement rounds read in full. Three
   angles in four stay screened. A screened reading can be several times off: over the
   builds of ten materials (about 12,500 angles, docs/benchmarks.md) the full reading
   was 0.34 to 2.4 times the screened one where that was read again, and up to 3.7
   times where it was not (full readings above 0.05 of the acceptance level); the
   screened angles read in full at most 0.36 of the acceptance level. A failing angle
   would have to read 6.7 times too low to stay screened. Ten files built with and
   without screening were byte for byte the same. An angle read again equals its
   unscreened reading to the bit (its points depend on ti and the seed only). */
#define QUICK_SCREEN_PPA 512
#define QUICK_SCREEN_NUNI 32
#define SCREEN_SHARE 0.15

static double share_alias(const build_ctx *c) { return 0.05 * c->budget; }
static double share_trunc(const build_ctx *c) { return 0.10 * c->budget; }
static double share_col(const build_ctx *c) { return SHARE_CHECK * c->budget; }
static double share_row(const build_ctx *c) { return SHARE_CHECK * c->budget; }

/* Keeps the truncated series of the converged coefficients in w->a as pair pr. */
/* For a reflection block: the shortest length m <= m0 whose dropped tail, measured as
   the L1 over the circle of the tail series on the grid of N (not bounded by 4 sum
   |a_q|, far too pessimistic for the k^-1.5 decay of a cusp), costs at most eps_trunc
   in every stored channel. Bisection: the measured tail shrinks with m. */
static size_t truncate_len_measured(const build_ctx *c, build_ws *w, size_t N, size_t m0,
                                    const double *norm, double eps_trunc)
{
    size_t S = c->nmax + 1, lo = 0, hi = m0; /* hi passes (the bound holds there) */
    /* A bracket from the coefficients alone, without transforms. With the trapezoid
       sum Tr over the grid of N (weights summing to pi) and the discrete orthogonality
       of cos(q phi) on it, Tr(t^2) = sum c_q a_q^2 (c_q = pi for q = 0 and N, pi/2
       otherwise), so by Cauchy-Schwarz the measured tail 2 Tr(|t|) is at most
       2 sqrt(pi Tr(t^2)): where that is within eps_trunc, m passes. And 2 Tr(|t|) >=
       2 |Tr(t cos r phi)| = 2 c_r |a_r| for every r >= m: where that exceeds it, m
       fails. The bisection then runs inside the bracket only (fewer inverse transforms,
       same rule). */
    {
        size_t up = 0, low = 0; /* up passes in every channel; below low some fails */
        for (int k = 0; k < c->nst; k++) {
            const double *ak = w->a + k * S;
            double lim = eps_trunc * norm[k]; /* norm >= T_FLOOR > 0 */
            double t2 = 0.0;
            size_t q = m0, upk = m0, lowk = 0;
            /* tail sums from the top: every q > m0 - 1 was dropped by the bound */
            for (size_t r = m0; r <= N; r++) {
                double cr = (r == 0 || r == N) ? M_PI : 0.5 * M_PI;
                t2 += cr * ak[r] * ak[r];
            }
            while (q > 0) {
                double cr = (q - 1 == 0 || q - 1 == N) ? M_PI : 0.5 * M_PI;
                double a = ak[q - 1];
                if (2.0 * cr * fabs(a) > lim) {
                    lowk = q; /* m = q - 1 and below keep a_{q-1} in the tail: fail */
                    break;
                }
                t2 += cr * a * a;
                if (2.0 * sqrt(M_PI * t2) <= lim)
                    upk = q - 1;
                q--;
            }
            if (upk > up)
                up = upk;
            if (lowk > low)
                low = lowk;
        }
        if (up < hi)
            hi = up;
        lo = low < hi ? low : hi;
    }
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        int pass = 1;
        for (int k = 0; k < c->nst && pass; k++) {
            /* tail coefficients a_q for q >= mid, in w->ia (mid <= m0 <= N + 1) */
            memset(w->ia, 0, mid * sizeof *w->ia);
            memcpy(w->ia + mid, w->a + k * S + mid, (N + 1 - mid) * sizeof *w->ia);
            double l1 = sf_series_l1(&w->fb, w->ia, N + 1, N, NULL, w->y);
            if (l1 < 0.0)
                return m0;
            pass = l1 / norm[k] <= eps_trunc; /* norm >= T_FLOOR */
        }
        if (pass)
            hi = mid;
        else
            lo = mid + 1;
    }
    return hi;
}

static int keep_series(build_ctx *c, build_ws *w, int side, size_t N, const double *norm,
                       pair *pr)
{
    (void)side; /* every block: the bound first, then the measured tail */
    size_t S = c->nmax + 1;
    size_t m = truncate_len(c, w->a, S, N, norm, share_trunc(c));
    if (m > 0)
        m = truncate_len_measured(c, w, N, m, norm, share_trunc(c));
    free(pr->a);
    pr->a = NULL;
    pr->m = (uint32_t)m;
    pr->N = (uint16_t)N; /* N <= nmax = 16384 */
    pr->done = 0;
    if (m) {
        pr->a = malloc((size_t)c->nst * m * sizeof(double));
        if (!pr->a) {
            pr->m = 0;
            return -1;
        }
        for (int k = 0; k < c->nst; k++)
            memcpy(pr->a + (size_t)k * m, w->a + k * S, m * sizeof(double));
    }
    pr->done = w->dark ? 2 : 1; /* w->dark: set by the converge() of these coefficients */
    return 0;
}

static void pair_norm(const build_ctx *c, int side, const double *ns, const double *nf,
                      double *out);

/* One slow row of one side: the series of every pair (r, c). */
static void job_row(void *vctx, void *vws, size_t idx)
{
    build_ctx *c = vctx;
    build_ws *w = vws;
    int side = (int)(idx / c->K);
    size_t r = idx % c->K;
    if (!c->want[side])
        return;
    double norm[3];
    for (size_t col = 0; col < c->K; col++) {
        pair *pr = &c->pairs[side][r * c->K + col];
        if (pr->done)
            continue;
        pair_norm(c, side, c->Tn[r][side], c->Tn[col][side], norm);
        size_t N = converge(c, w, side, c->P[r], c->P[col], norm, share_alias(c));
        if (N == 0 || keep_series(c, w, side, N, norm, pr))
            goto oom;
    }
    return;
oom:
    pthread_mutex_lock(&c->lock);
    c->oom = 1;
    pthread_mutex_unlock(&c->lock);
}

/* Full node index -> half index r on the positive half (nodes > 0), or -1 for the two
   zero nodes and the negative half. */
static long half_pos(const build_ctx *c, long idx)
{
    long K = (long)c->K;
    return idx >= K + 2 ? idx - (K + 2) : -1;
}

/* Full node index -> half index r of its magnitude and its sign (1: negative), or -1
   for the two zero nodes. */
static long half_any(const build_ctx *c, long idx, int *neg)
{
    long K = (long)c->K;
    *neg = idx <= K - 1;
    if (idx >= K + 2)
        return idx - (K + 2);
    return idx >= 0 && idx <= K - 1 ? K - 1 - idx : -1;
}

/* Adds weight * series of pair (r, col) into ia (stride S per channel). */
static void add_pair(const build_ctx *c, int side, size_t r, size_t col, double wgt,
                     double *ia, size_t S, size_t *mlen)
{
    const pair *pr = &c->pairs[side][r * c->K + col];
    for (int k = 0; k < c->nst; k++)
        for (size_t q = 0; q < pr->m; q++)
            ia[k * S + q] += wgt * pr->a[(size_t)k * pr->m + q];
    if (pr->m > *mlen)
        *mlen = pr->m;
}

/* Zeroes ia (stride S per channel) over the longest series of the stencil at off with
   weights wt: the fixed index is the row `fixed` (along = 1, stencil over columns) or
   the column (along = 0, stencil over rows). l1_gap reads no further than that. */
static void zero_stencil(const build_ctx *c, double *ia, size_t S, int side, size_t fixed,
                         long off, const double *wt, int along)
{
    size_t top = 0;
    for (int b = 0; b < 4; b++) {
        long h = half_pos(c, off + b);
        if (h < 0 || wt[b] == 0.0)
            continue;
        size_t idx = along ? fixed * c->K + (size_t)h : (size_t)h * c->K + fixed;
        if (c->pairs[side][idx].m > top)
            top = c->pairs[side][idx].m;
    }
    for (int k = 0; k < c->nst; k++)
        memset(ia + (size_t)k * S, 0, top * sizeof *ia);
}

/* A check whose series was kept from an earlier pass (its midpoint and the budget are
   the same; only a neighbour's split changed its stencil) needs the truth samples
   again, not the series: the samples on the grid they converged on, in w->x, the same
   values converge() left there. Returns that grid, or 0 when the series must be
   computed. */
static size_t truth_again(const build_ctx *c, build_ws *w, int side, double mu_s,
                          double mu_f, const pair *pr)
{
    if (!pr->done || pr->N == 0)
        return 0;
    if (pr->done == 2) { /* dark: the samples converge() wrote, all 0 */
        for (int k = 0; k < c->nst; k++)
            memset(w->x + (size_t)k * (c->nmax + 1), 0, ((size_t)pr->N + 1) * sizeof *w->x);
        return pr->N;
    }
    sample_grid(c, w, side, mu_s, mu_f, pr->N, c->nmax + 1, 1, 0, w->x);
    return pr->N;
}

/* The truth at (mu_s, mu_f) in w->x on a grid of N fits series of up to N + 1 terms;
   when the interpolated stencil is longer (its nodes' series converged on finer grids
   than this pair's), the samples are taken again on the grid that fits it, so that
   l1_gap sees all of it. Returns the grid. */
static size_t truth_for(const build_ctx *c, build_ws *w, int side, double mu_s, double mu_f,
                        size_t N, size_t mlen)
{
    if (mlen <= N + 1 || N >= c->nmax)
        return N;
    size_t N2 = N;
    while (N2 + 1 < mlen && N2 < c->nmax)
        N2 *= 2;
    sample_grid(c, w, side, mu_s, mu_f, N2, c->nmax + 1, 1, 0, w->x);
    return N2;
}

/* L1 over the circle, per stored channel relative to norm, of (interpolated series
   in w->ia, length mlen) minus the truth sampled in w->x on the grid of N. */
static double l1_gap(build_ctx *c, build_ws *w, size_t N, size_t mlen, const double *norm)
{
    size_t S = c->nmax + 1;
    double worst = 0.0;
    if (mlen > N + 1)
        mlen = N + 1; /* higher harmonics alias on this grid; the truth converged on it */
    for (int k = 0; k < c->nst; k++) {
        double l1 = sf_series_l1(&w->fb, w->ia + k * S, mlen, N, w->x + k * S, w->y);
        if (l1 < 0.0)
            return HUGE_VAL;
        l1 /= norm[k]; /* norm >= T_FLOOR */
        if (l1 > worst)
            worst = l1;
    }
    return worst;
}

/* Column check for one (side, slow row r): truth at every interval midpoint of the
   fast axis against the spline across the columns. */
static void job_colcheck(void *vctx, void *vws, size_t idx)
{
    build_ctx *c = vctx;
    build_ws *w = vws;
    int side = (int)(idx / c->K);
    size_t r = idx % c->K;
    if (!c->want[side])
        return;
    size_t S = c->nmax + 1;
    size_t nfull = 2 * c->K + 2;
    double norm[3];
    for (size_t j = 0; j < c->nint; j++) {
        if (c->okc[side][r * c->nint + j])
            continue; /* same row, same stencil, same budget as last pass */
        double x = c->mid[j];
        size_t N = truth_again(c, w, side, c->P[r], x, &c->pcol[side][r * c->K + j]);
        if (N == 0) {
            pair_norm(c, side, c->Tn[r][side], c->Tm[j][side], norm);
            N = converge(c, w, side, c->P[r], x, norm, share_alias(c));
            if (N == 0 || keep_series(c, w, side, N, norm, &c->pcol[side][r * c->K + j]))
                goto oom;
        }
        long off;
        double wt[4];
        size_t mlen = 0;
        /* the positive-half stencil; the negative half is its mirror image */
        if (cr_weights(c->full, nfull, x, &off, wt)) {
            zero_stencil(c, w->ia, S, side, r, off, wt, 1);
            for (int b = 0; b < 4; b++) {
                long h = half_pos(c, off + b);
                if (h >= 0 && wt[b] != 0.0)
                    add_pair(c, side, r, (size_t)h, wt[b], w->ia, S, &mlen);
            }
        }
        N = truth_for(c, w, side, c->P[r], x, N, mlen);
        /* relative to the DIRECT norm; the ADJOINT reading rescales (adj_ratio) */
        c->errc[side][r * c->nint + j] = l1_gap(c, w, N, mlen, c->Tn[r][side]);
    }
    return;
oom:
    pthread_mutex_lock(&c->lock);
    c->oom = 1;
    pthread_mutex_unlock(&c->lock);
}

/* Row check for one (side, interval j): truth at the slow midpoint against the
   spline across the rows, integrated over the fast nodes (trapezoid weights). */
static void job_rowcheck(void *vctx, void *vws, size_t idx)
{
    build_ctx *c = vctx;
    build_ws *w = vws;
    int side = (int)(idx / c->nint);
    size_t j = idx % c->nint;
    if (!c->want[side])
        return;
    size_t S = c->nmax + 1;
    size_t nfull = 2 * c->K + 2;
    double x = c->mid[j];
    double norm[3];
    long off = 0; /* read only when ok; the 0 quiets a maybe-uninitialized warning */
    double wt[4];
    int ok = cr_weights(c->full, nfull, x, &off, wt);
    double total = 0.0;
    for (size_t col = 0; col < c->K; col++) {
        double lo = col == 0 ? 0.0 : c->P[col - 1];
        double hi = col + 1 < c->K ? c->P[col + 1] : c->P[col];
        double *gap = &c->gapr[side][j * c->K + col];
        if (c->okr[side][j * c->K + col]) {
            total += 0.5 * (hi - lo) * *gap;
            continue;
        }
        size_t N = truth_again(c, w, side, x, c->P[col], &c->prow[side][j * c->K + col]);
        if (N == 0) {
            pair_norm(c, side, c->Tm[j][side], c->Tn[col][side], norm);
            N = converge(c, w, side, x, c->P[col], norm, share_alias(c));
            if (N == 0 || keep_series(c, w, side, N, norm, &c->prow[side][j * c->K + col]))
                goto oom;
        }
        size_t mlen = 0;
        if (ok) {
            zero_stencil(c, w->ia, S, side, col, off, wt, 0);
            for (int a = 0; a < 4; a++) {
                long h = half_pos(c, off + a);
                if (h >= 0 && wt[a] != 0.0)
                    add_pair(c, side, (size_t)h, col, wt[a], w->ia, S, &mlen);
            }
        }
        N = truth_for(c, w, side, x, c->P[col], N, mlen);
        *gap = l1_gap(c, w, N, mlen, c->Tm[j][side]); /* DIRECT norm, as errc */
        total += 0.5 * (hi - lo) * *gap;
    }
    c->errr[side][j] = total;
    return;
oom:
    pthread_mutex_lock(&c->lock);
    c->oom = 1;
    pthread_mutex_unlock(&c->lock);
}

/* The norms of one block at cosine mu (a node or a midpoint), in the stored values'
   units, per stored channel:
   out[0..2], DIRECT (the slow index is the light's): max(T, floor) for the light at
     mu (max(R, floor) for a reflection block), times the block's fold factor, so
     that an error relative to it is the unfolded error;
   out[4..6], ADJOINT (the fast index is the light's, pbrt-v3's radiance mode, what a
     path tracer's camera rays read): the error of light at mu, integrated over the
     camera's slow index, is (e^2/mu) times the integral of |error of the stored value|
     cos(camera), with e^2 the radiance factor (1/eta^2 for T_ENTER, whose light comes
     from below, eta^2 for T_LEAVE, 1 for reflection) and normalised by max(T', floor)
     of that light (T' of the other side's index; R of the same block for
     reflection). So one pair's series may err by max(T', floor) mu / e^2 in the
     stored units; cos(camera) <= 1 leaves a factor 2 of margin. */
/* The norms only set the shares the node checks allow (what decides is the file's own
   measurement, with T and R converged to about 3e-7), so T and R come from a coarser
   rule: 8 x 3 panels differ from the converged ones by at most 6.9e-4 of max(T, 0.01)
   (n = 1/2.4, s = 20, past the critical angle) and 1.9e-5 of max(R, 0.01), over n in
   {1.5, 1.33, 2.4, 1.1, 1.0001} and their inverses, s in {0.5, 1, 3, 10, 20, 100,
   1000}, ti in 0.5-degree steps, for a quarter of T's cost and an eighth of R's. */
#define NORM_U_PANELS 8
#define NORM_PSI_PANELS 3

static void norms_at(const build_ctx *c, int side, double mu, double *out)
{
    btdf_params q = *c->p;
    for (int k = 0; k < c->nc; k++)
        q.ior[k] = c->ior[side][k];
    double T[3] = {0, 0, 0};
    /* acos of a value in [0, 1] is in [0, pi/2], the accepted range */
    double ti = acos(fmin(1.0, fmax(0.0, mu)));
    bt_albedo_panels(&q, blk_refl[side], ti, NORM_U_PANELS, NORM_PSI_PANELS, T);
    if (c->nst == 1) {
        out[0] = fmax(T[0], T_FLOOR);
    } else {
        const double *fo = c->fold[side];
        out[0] = fmax(LUM_R * T[0] * fo[0] + LUM_G * T[1] * fo[1] + LUM_B * T[2] * fo[2],
                      T_FLOOR);
        out[1] = fmax(T[0], T_FLOOR) * fo[0];
        out[2] = fmax(T[2], T_FLOOR) * fo[2];
    }
    /* the adjoint light's index: the other transmission block's, or this block's */
    double e2 = 1.0, eta = c->p->ior[c->nc == 3 ? 1 : 0]; /* the header's eta */
    if (!blk_refl[side]) {
        int other = side == BLK_T_ENTER ? BLK_T_LEAVE : BLK_T_ENTER;
        for (int k = 0; k < c->nc; k++)
            q.ior[k] = c->ior[other][k];
        bt_albedo_panels(&q, 0, ti, NORM_U_PANELS, NORM_PSI_PANELS, T);
        e2 = side == BLK_T_ENTER ? 1.0 / (eta * eta) : eta * eta; /* eta > 0 (checked) */
    }
    /* mu >= the first node or midpoint > 0; the floor keeps the norm positive should
       a node ever sit on the grazing cosine 0 */
    double w = fmax(mu, 1e-9) / e2;
    if (c->nst == 1) {
        out[4] = fmax(T[0], T_FLOOR) * w;
    } else {
        out[4] = fmax(LUM_R * T[0] + LUM_G * T[1] + LUM_B * T[2], T_FLOOR) * w;
        out[5] = fmax(T[0], T_FLOOR) * w;
        out[6] = fmax(T[2], T_FLOOR) * w;
    }
}

/* Job k of K * NBLK * 2: the norms of node or midpoint k / (2 NBLK) for one block,
   unless carried from the last pass. */
static void job_norms(void *vctx, size_t k)
{
    build_ctx *c = vctx;
    size_t j = k / (2 * NBLK);
    int s = (int)(k / 2 % NBLK), at_mid = (int)(k % 2);
    if (!c->want[s])
        return;
    if (at_mid && !c->hasTm[j])
        norms_at(c, s, c->mid[j], c->Tm[j][s]);
    else if (!at_mid && !c->hasTn[j])
        norms_at(c, s, c->P[j], c->Tn[j][s]);
}

/* The norm of the series at (slow node with norms ns, fast node with norms nf): it
   must serve both readings, DIRECT (relative to the slow node's light) and ADJOINT
   (relative to the fast node's light), so the smaller of the two. A three-channel
   transmission block is read ADJOINT only: its fold makes the DIRECT reading off by
   (n_c/n_G)^2 by design (build_impl). */
static void pair_norm(const build_ctx *c, int side, const double *ns, const double *nf,
                      double *out)
{
    for (int k = 0; k < c->nst; k++)
        out[k] = c->nst == 3 && !blk_refl[side] ? nf[4 + k] : fmin(ns[k], nf[4 + k]);
}

/* A gap measured relative to the slow node's DIRECT norms ns, times this, bounds it
   relative to the fast node's ADJOINT norms nf (the worst channel of each). */
static double adj_ratio(const build_ctx *c, const double *ns, const double *nf)
{
    double r = 0.0;
    for (int k = 0; k < c->nst; k++)
        r = fmax(r, ns[k] / nf[4 + k]); /* norms > 0 (norms_at) */
    return r;
}

static void free_pair_array(pair **pp, size_t count)
{
    if (!*pp)
        return;
    for (size_t i = 0; i < count; i++)
        free((*pp)[i].a);
    free(*pp);
    *pp = NULL;
}

/* Frees everything that belongs to one node set (sizes follow c->K). */
static void free_state(build_ctx *c)
{
    size_t KK = c->K * c->K;
    for (int s = 0; s < NBLK; s++) {
        free_pair_array(&c->pairs[s], KK);
        free_pair_array(&c->pcol[s], KK);
        free_pair_array(&c->prow[s], KK);
        free(c->errc[s]);
        free(c->errr[s]);
        free(c->gapr[s]);
        free(c->okc[s]);
        free(c->okr[s]);
        c->errc[s] = c->errr[s] = c->gapr[s] = NULL;
        c->okc[s] = c->okr[s] = NULL;
    }
    free(c->Tn);
    free(c->Tm);
    free(c->hasTn);
    free(c->hasTm);
    free(c->mid);
    c->Tn = c->Tm = NULL;
    c->hasTn = c->hasTm = NULL;
    c->mid = NULL;
}

/* Allocates what is missing for the current node set; 0 on success. */
static int ensure_state(build_ctx *c)
{
    size_t K = c->K, KK = K * K;
    for (int s = 0; s < NBLK; s++) {
        if (!c->pairs[s])
            c->pairs[s] = calloc(KK, sizeof(pair));
        if (!c->pcol[s])
            c->pcol[s] = calloc(KK, sizeof(pair));
        if (!c->prow[s])
            c->prow[s] = calloc(KK, sizeof(pair));
        if (!c->errc[s])
            c->errc[s] = calloc(KK, sizeof(double));
        if (!c->gapr[s])
            c->gapr[s] = calloc(KK, sizeof(double));
        if (!c->okc[s])
            c->okc[s] = calloc(KK, 1);
        if (!c->okr[s])
            c->okr[s] = calloc(KK, 1);
        free(c->errr[s]);
        c->errr[s] = calloc(K, sizeof(double));
        if (!c->pairs[s] || !c->pcol[s] || !c->prow[s] || !c->errc[s] || !c->gapr[s] ||
            !c->okc[s] || !c->okr[s] || !c->errr[s])
            return -1;
    }
    if (!c->Tn)
        c->Tn = calloc(K, sizeof *c->Tn);
    if (!c->Tm)
        c->Tm = calloc(K, sizeof *c->Tm);
    if (!c->hasTn)
        c->hasTn = calloc(K, 1);
    if (!c->hasTm)
        c->hasTm = calloc(K, 1);
    free(c->mid);
    c->mid = malloc(K * sizeof *c->mid);
    return c->Tn && c->Tm && c->hasTn && c->hasTm && c->mid ? 0 : -1;
}

static int set_nodes(build_ctx *c, const double *P, size_t K);

/* carry_over's work for one block: the block's pairs, check series and carried check
   results moved to their places in the new grid. Every loop walks its source row by
   row (the arrays are row-major: a column walk strides K records, and this runs on
   every pass). */
typedef struct carry_job {
    build_ctx *c;
    size_t KQ;
    const unsigned char *ins, *same, *sten;
    const size_t *map, *qn;
    pair *(*np)[3];
    double **ne, **ng;
    unsigned char **noc, **nor;
} carry_job;

static void carry_block(void *arg, size_t s)
{
    const carry_job *J = arg;
    build_ctx *c = J->c;
    size_t K = c->K, KQ = J->KQ;
    const size_t *map = J->map, *qn = J->qn;
    const unsigned char *ins = J->ins, *same = J->same, *sten = J->sten;
    pair *pp = c->pairs[s], *pc = c->pcol[s], *pr = c->prow[s];
    pair *n0 = J->np[s][0], *n1 = J->np[s][1], *n2 = J->np[s][2];
    for (size_t r = 0; r < K; r++) {
        pair *dst = n0 + map[r] * KQ;
        for (size_t col = 0; col < K; col++) {
            dst[map[col]] = pp[r * K + col];
            pp[r * K + col].a = NULL;
        }
    }
    /* column checks: pcol[r * K + j] is the series at (P[r], mid[j]) */
    for (size_t r = 0; r < K; r++) {
        for (size_t j = 0; j < K; j++) {
            pair *src = &pc[r * K + j];
            if (ins[j] == 1)
                n0[map[r] * KQ + qn[j]] = *src; /* (P[r], new node) */
            else if (same[j])
                n1[map[r] * KQ + map[j]] = *src;
            else
                free(src->a);
            src->a = NULL;
            if (sten[j]) {
                J->ne[s][map[r] * KQ + map[j]] = c->errc[s][r * K + j];
                J->noc[s][map[r] * KQ + map[j]] = 1;
            }
        }
    }
    /* row checks: prow[j * K + col] is the series at (mid[j], P[col]) */
    for (size_t j = 0; j < K; j++) {
        for (size_t col = 0; col < K; col++) {
            pair *src = &pr[j * K + col];
            if (ins[j] == 1)
                n0[qn[j] * KQ + map[col]] = *src; /* (new node, P[col]) */
            else if (same[j])
                n2[map[j] * KQ + map[col]] = *src;
            else
                free(src->a);
            src->a = NULL;
            if (sten[j]) {
                J->ng[s][map[j] * KQ + map[col]] = c->gapr[s][j * K + col];
                J->nor[s][map[j] * KQ + map[col]] = 1;
            }
        }
    }
}

/* Moves everything still valid to the refined node set Q (KQ nodes, a superset of
   c->P). ins[j] = 1 when old interval j got the node mid[j], whose check series
   become pairs; 2 when it got another node. Series at unchanged nodes, checks
   whose stencil is unchanged and norms are kept, so a pass only computes what the
   new nodes touch. Returns 0 on success; on failure the old state is intact. */
static int carry_over(build_ctx *c, const double *Q, size_t KQ, const unsigned char *ins,
                      int threads)
{
    size_t K = c->K, KK2 = KQ * KQ;
    size_t *map = malloc(K * sizeof *map), *qn = malloc(K * sizeof *qn);
    unsigned char *same = malloc(K), *sten = malloc(K);
    pair *np[NBLK][3] = {{NULL}};
    double *ne[NBLK] = {NULL}, *ng[NBLK] = {NULL};
    unsigned char *noc[NBLK] = {NULL}, *nor[NBLK] = {NULL};
    double(*tn)[NBLK][8] = calloc(KQ, sizeof *tn), (*tm)[NBLK][8] = calloc(KQ, sizeof *tm);
    unsigned char *htn = calloc(KQ, 1), *htm = calloc(KQ, 1);
    int ok = map && qn && same && sten && tn && tm && htn && htm;
    for (int s = 0; s < NBLK && ok; s++) {
        for (int k = 0; k < 3; k++)
            ok &= (np[s][k] = calloc(KK2, sizeof(pair))) != NULL;
        ok &= (ne[s] = calloc(KK2, sizeof(double))) != NULL;
        ok &= (ng[s] = calloc(KK2, sizeof(double))) != NULL;
        ok &= (noc[s] = calloc(KK2, 1)) != NULL;
        ok &= (nor[s] = calloc(KK2, 1)) != NULL;
    }
    if (!ok) {
        for (int s = 0; s < NBLK; s++) {
            for (int k = 0; k < 3; k++)
                free(np[s][k]);
            free(ne[s]);
            free(ng[s]);
            free(noc[s]);
            free(nor[s]);
        }
        free(map); free(qn); free(same); free(sten); free(tn); free(tm); free(htn); free(htm);
        return -1;
    }
    for (size_t r = 0, q = 0; r < K; r++) {
        while (Q[q] != c->P[r])
            q++; /* every old node is in the new list, in order */
        map[r] = q;
    }
    for (size_t j = 0; j < K; j++) {
        same[j] = !ins[j];
        qn[j] = ins[j] ? map[j] - 1 : (size_t)-1; /* the new node sits just before P[j] */
    }
    for (size_t j = 0; j < K; j++)
        sten[j] = same[j] && (j == 0 || same[j - 1]) && (j + 1 >= K || same[j + 1]);
    carry_job cj = {c, KQ, ins, same, sten, map, qn, np, ne, ng, noc, nor};
    core_parallel_for(threads, NBLK, carry_block, &cj); /* the blocks share nothing */
    for (size_t r = 0; r < K; r++) {
        memcpy(tn[map[r]], c->Tn[r], sizeof tn[0]);
        htn[map[r]] = c->hasTn[r];
    }
    for (size_t j = 0; j < K; j++) {
        if (ins[j] == 1) {
            memcpy(tn[qn[j]], c->Tm[j], sizeof tn[0]);
            htn[qn[j]] = c->hasTm[j];
        }
        if (same[j]) {
            memcpy(tm[map[j]], c->Tm[j], sizeof tm[0]);
            htm[map[j]] = c->hasTm[j];
        }
    }
    free_state(c); /* the moved series were detached above */
    for (int s = 0; s < NBLK; s++) {
        c->pairs[s] = np[s][0];
        c->pcol[s] = np[s][1];
        c->prow[s] = np[s][2];
        c->errc[s] = ne[s];
        c->gapr[s] = ng[s];
        c->okc[s] = noc[s];
        c->okr[s] = nor[s];
    }
    c->Tn = tn;
    c->Tm = tm;
    c->hasTn = htn;
    c->hasTm = htm;
    free(map); free(qn); free(same); free(sten);
    return set_nodes(c, Q, KQ); /* sets K first, so sizes stay consistent on failure */
}

static double to_float_node(double v) { return (double)(float)v; }

static int set_nodes(build_ctx *c, const double *P, size_t K)
{
    c->K = K; /* first: the per-node-set arrays already have this size */
    double *np = realloc(c->P, K * sizeof *np);
    if (!np)
        return -1;
    c->P = np;
    memcpy(c->P, P, K * sizeof *P);
    double *full = realloc(c->full, (2 * K + 2) * sizeof *full);
    if (!full)
        return -1;
    c->full = full;
    for (size_t r = 0; r < K; r++) {
        full[K + 2 + r] = P[r];
        full[K - 1 - r] = -P[r];
    }
    full[K] = full[K + 1] = 0.0;
    return 0;
}


/* Fills a btdf_scatfun from the pairs of the current pass. */
static btdf_status assemble(build_ctx *c, btdf_scatfun **out, char *msg, size_t msglen)
{
    size_t K = c->K, n = 2 * K + 2;
    size_t total = 0, mmax = 0;
    for (int s = 0; s < NBLK; s++) {
        if (!c->want[s])
            continue;
        for (size_t i = 0; i < K * K; i++) {
            total += (size_t)c->pairs[s][i].m * (size_t)c->nst;
            if (c->pairs[s][i].m > mmax)
                mmax = c->pairs[s][i].m;
        }
    }
    if (total > UINT32_MAX)
        return core_say(BTDF_EOVERFLOW, msg, msglen, "%zu coefficients exceed the format's 32-bit count",
                   total);
    btdf_scatfun *f = sf_alloc((uint32_t)n, (uint32_t)total, (uint32_t)mmax, (uint32_t)c->nst,
                               0, 0);
    if (!f)
        return BTDF_ENOMEM;
    f->eta = (float)(c->nc == 3 ? c->p->ior[1] : c->p->ior[0]);
    /* Beckmann alpha of Eq. 25's facet distribution: RMS slope 2/s (MODEL.md 2);
       s >= BTDF_S_MIN > 0 was checked */
    f->alpha[0] = f->alpha[1] = (float)(2.0 / c->p->smoothness);
    double *v = malloc(n * sizeof(double)), *cd = malloc(n * sizeof(double));
    if (!v || !cd) {
        free(v);
        free(cd);
        btdf_scatfun_free(f);
        return BTDF_ENOMEM;
    }
    for (size_t i = 0; i < n; i++)
        f->nodes[i] = (float)c->full[i];
    if (sf_index(f)) {
        free(v);
        free(cd);
        btdf_scatfun_free(f);
        return BTDF_ENOMEM;
    }
    size_t pos = 0;
    for (size_t i = 0; i < n; i++) {
        for (size_t o = 0; o < n; o++) {
            const pair *pr = NULL;
            int ni, no;
            long hi = half_any(c, (long)i, &ni), ho = half_any(c, (long)o, &no);
            for (int s = 0; s < NBLK && !pr && hi >= 0 && ho >= 0; s++)
                if (c->want[s] && blk_slow_neg[s] == ni && blk_fast_neg[s] == no)
                    pr = &c->pairs[s][(size_t)hi * K + (size_t)ho];
            size_t m = pr ? pr->m : 0;
            f->offsets[2 * (i * n + o)] = (uint32_t)pos;
            f->offsets[2 * (i * n + o) + 1] = (uint32_t)m;
            for (size_t q = 0; q < m * (size_t)c->nst; q++)
                f->coeffs[pos + q] = (float)pr->a[q];
            pos += m * (size_t)c->nst;
        }
    }
    /* cdf rows from the stored (float) a_0 of Y, as a reader recomputes them */
    for (size_t i = 0; i < n; i++) {
        for (size_t o = 0; o < n; o++) {
            uint32_t m = f->offsets[2 * (i * n + o) + 1];
            v[o] = m ? (double)f->coeffs[f->offsets[2 * (i * n + o)]] : 0.0;
            cd[o] = (double)f->nodes[o];
        }
        double *row = malloc(n * sizeof(double));
        if (!row) {
            free(v);
            free(cd);
            btdf_scatfun_free(f);
            return BTDF_ENOMEM;
        }
        spline_cdf(cd, v, n, row);
        for (size_t o = 0; o < n; o++)
            f->cdf[i * n + o] = (float)row[o];
        free(row);
    }
    free(v);
    free(cd);
    f->built = 1;
    f->params = *c->p;
    f->sides = 0;
    for (int s = 0; s < NBLK; s++)
        f->sides |= c->want[s] ? blk_mask[s] : 0;
    *out = f;
    return BTDF_OK;
}

/* Where interval j of the half nodes is checked and split: the midpoint in angle.
   The last interval [P[K-2], 1] is cut at a fraction endr of its angle instead: rho
   moves with sin ti, which is sqrt(1 - mu) near mu = 1, so the spline error there
   only falls like the interval's angle and bisection would need many passes. */
static double split_point(const double *P, size_t K, size_t j, double endr)
{
    double lo = j == 0 ? 0.0 : P[j - 1];
    /* acos of values in [0, 1] */
    double alo = acos(fmin(1.0, lo)), ahi = acos(fmin(1.0, P[j]));
    if (j == K - 1 && K > 1)
        return cos(ahi + (alo - ahi) * endr);
    return cos(0.5 * (alo + ahi));
}

static size_t pow2_at_least(double v)
{
    size_t p = 1;
    while ((double)p < v && p < ((size_t)1 << 30))
        p <<= 1;
    return p;
}

/* Error estimate of one side with a fixed sample (for the build's own loop): the
   file's own evaluation, QUICK_PPA facet points per angle, a seed of the builder's. Test
   angles whose e_L1 exceeds mark_at get their elevation interval marked in split
   (half nodes P[0..K-1]; both sides share them); *nmark counts new marks. */
static double quick_l1(const btdf_scatfun *f, const btdf_params *p, btdf_side side, int threads,
                       uint64_t seed, albedo_memo *memo, const double *P, size_t K,
                       double mark_at, double accept_at, unsigned char *split,
                       size_t *nmark)
{
    btdf_report r;
    memset(&r, 0, sizeof r);
    /* btdf_scatfun_report's work, with T and R remembered from the last measurement;
       e_L1 is all the build reads, and once the first angles fail the acceptance
       (stop_above) their marks are what the build needs: the refinement rounds, which
       look for a larger worst, are left to the next measurement. stop_above is 0 for
       the last measurement (split NULL), which must be whole. */
    est_opts opt = {1, 1, split ? accept_at : 0.0, split ? QUICK_SCREEN_PPA : 0,
                    split ? QUICK_SCREEN_NUNI : 0, SCREEN_SHARE * accept_at};
    if (sf_report_mis(f, p, side, 24, QUICK_PPA, seed, threads, &opt, memo, &r) !=
        BTDF_OK) {
        free(r.per_ti);
        return HUGE_VAL;
    }
    for (size_t k = 0; split && k < r.test_angles; k++) {
        double mu = cos(r.per_ti[k].ti);
        size_t j = 0; /* interval j is (P[j-1], P[j]], P[-1] = 0 */
        while (j + 1 < K && P[j] < mu)
            j++;
        if (!(r.per_ti[k].e_l1 > mark_at))
            continue;
        if (!split[j]) {
            split[j] = 1;
            ++*nmark;
        }
    }
    free(r.per_ti);
    return r.e_l1_max;
}

/* Bytes the builder holds in series (pairs and check series, double precision) and
   pair records, for the memory cap. */
static size_t state_bytes(const build_ctx *c)
{
    size_t KK = c->K * c->K, b = 0;
    for (int s = 0; s < NBLK; s++) {
        if (!c->want[s])
            continue;
        const pair *arr[3] = {c->pairs[s], c->pcol[s], c->prow[s]};
        for (int a = 0; a < 3; a++) {
            if (!arr[a])
                continue;
            b += KK * sizeof(pair);
            for (size_t i = 0; i < KK; i++)
                b += (size_t)arr[a][i].m * (size_t)c->nst * sizeof(double);
        }
    }
    return b;
}

BTDF_API btdf_status btdf_scatfun_build(const btdf_params *p, double tolerance,
                                        btdf_side side, int threads, btdf_scatfun **out,
                                        char *msg, size_t msglen)
{
    return btdf_scatfun_build_limits(p, tolerance, side, threads, 0, 0, out, msg, msglen);
}

BTDF_API btdf_status btdf_scatfun_check(const btdf_params *p, double tolerance,
                                        btdf_side side, char *msg, size_t msglen)
{
    btdf_status st = btdf_params_check(p, msg, msglen);
    if (st != BTDF_OK)
        return st;
    if (!(tolerance >= 1e-6 && tolerance <= 0.5))
        return core_say(BTDF_EINVAL, msg, msglen, "tolerance %g: must lie in [1e-6, 0.5]", tolerance);
    if ((int)side < 1 || (int)side > BTDF_SCATFUN_ALL)
        return core_say(BTDF_EINVAL, msg, msglen,
                           "blocks %d: must be a mask of 1 (transmission entering), 2 "
                           "(transmission leaving), 4 (reflection on top), 8 (reflection "
                           "below), from 1 to 15", (int)side);
    return BTDF_OK;
}

static btdf_status build_impl(const btdf_params *p, double tolerance, btdf_side side,
                              int threads, size_t max_coeffs, size_t max_bytes,
                              btdf_progress_fn progress, void *user, btdf_scatfun **out,
                              char *msg, size_t msglen);

BTDF_API btdf_status btdf_scatfun_build_limits(const btdf_params *p, double tolerance,
                                               btdf_side side, int threads, size_t max_coeffs,
                                               size_t max_bytes, btdf_scatfun **out,
                                               char *msg, size_t msglen)
{
    return build_impl(p, tolerance, side, threads, max_coeffs, max_bytes, NULL, NULL, out, msg,
                      msglen);
}

BTDF_API btdf_status btdf_scatfun_build_progress(const btdf_params *p, double tolerance,
                                                 btdf_side side, int threads, size_t max_coeffs,
                                                 size_t max_bytes, btdf_progress_fn progress,
                                                 void *user, btdf_scatfun **out, char *msg,
                                                 size_t msglen)
{
    return build_impl(p, tolerance, side, threads, max_coeffs, max_bytes, progress, user, out,
                      msg, msglen);
}

static btdf_status build_impl(const btdf_params *p, double tolerance, btdf_side side,
                              int threads, size_t max_coeffs, size_t max_bytes,
                              btdf_progress_fn progress, void *user, btdf_scatfun **out,
                              char *msg, size_t msglen)
{
    if (!out)
        return core_say(BTDF_EINVAL, msg, msglen, "output pointer missing");
    btdf_status st = btdf_scatfun_check(p, tolerance, side, msg, msglen);
    if (st != BTDF_OK)
        return st;
    if (max_coeffs == 0 || max_coeffs > MAX_COEFFS_BUILD)
        max_coeffs = MAX_COEFFS_BUILD;
    /* A lobe narrower than one elevation interval, even with the whole node budget
       spread evenly over 90 degrees, cannot be followed by nodes shared by every
       incident angle: stop before any work. The transmitted lobe is about
       (n' - 1) 2/s rad wide in outgoing angle, n' = max(n, 1/n) (facet slopes of RMS
       2/s, MODEL.md 2). */
    {
        double nw = HUGE_VAL;
        for (int k = 0; k < p->channels; k++) {
            double n1 = p->ior[k] >= 1.0 ? p->ior[k] : 1.0 / p->ior[k]; /* ior > 0 (checked) */
            nw = fmin(nw, (n1 - 1.0) * 2.0 / p->smoothness);           /* s > 0 (checked) */
        }
        double least = (M_PI / 2) / (double)BTDF_SCATFUN_MAX_HALF_NODES;
        if (nw < least)
            return core_say(BTDF_EBUDGET, msg, msglen,
                               "the transmitted lobe is about %.3g deg wide (n = %.9g, s = %g), "
                               "narrower than one elevation interval (%.3g deg) even with all "
                               "%d half nodes of the format's budget; nothing built: use a "
                               "facet-space table (.exr/.csv) for this material",
                               nw * 180.0 / M_PI, p->ior[p->channels == 3 ? 1 : 0],
                               p->smoothness, least * 180.0 / M_PI,
                               BTDF_SCATFUN_MAX_HALF_NODES);
    }
    double t0 = core_now();
    build_ctx c;
    memset(&c, 0, sizeof c);
    if (pthread_mutex_init(&c.lock, NULL) != 0)
        return core_say(BTDF_ENOMEM, msg, msglen, "cannot create a mutex");
    c.p = p;
    c.nc = p->channels;
    c.nst = p->channels == 3 ? 3 : 1;
    for (int k = 0; k < c.nc; k++) {
        c.ior[BLK_T_ENTER][k] = c.ior[BLK_R_TOP][k] = p->ior[k];
        /* ior >= BTDF_IOR_MIN > 0 (checked) */
        c.ior[BLK_T_LEAVE][k] = c.ior[BLK_R_BOTTOM][k] = 1.0 / p->ior[k];
    }
    for (int b = 0; b < NBLK; b++) {
        c.want[b] = ((int)side & blk_mask[b]) != 0;
        for (int k = 0; k < 3; k++)
            c.fold[b][k] = 1.0;
    }
    if (c.nc == 3) {
        /* pbrt-v3 scales transmission by e^2 with the header's one eta = n_G: reading
           T_LEAVE for light from above gives n_G^2 rho_c(1/n_c; o->i), and the truth is
           n_c^2 rho_c(1/n_c; o->i) (reciprocity), so that block carries (n_c/n_G)^2;
           T_ENTER read for light from below gives rho_c(n_c; o->i)/n_G^2 against
           rho_c(n_c; o->i)/n_c^2, so it carries (n_G/n_c)^2. Reflection has no factor. */
        for (int k = 0; k < 3; k++) {
            double q = p->ior[k] / p->ior[1]; /* ior > 0 (checked) */
            c.fold[BLK_T_LEAVE][k] = q * q;
            c.fold[BLK_T_ENTER][k] = 1.0 / (q * q);
        }
    }
    /* The lobe spans about 2/s rad of facet tilt; a first azimuth grid of about 8 s
       points puts several samples across it, so no lobe falls between samples. The
       narrowest pairs need that; a transmission pair starts on the grid its own lobe
       and edges need (first_grid), at most this. */
    c.nmin = pow2_at_least(fmax(NMIN_PHI, 8.0 * p->smoothness));
    if (c.nmin > BTDF_SCATFUN_MAX_PHI / 2)
        c.nmin = BTDF_SCATFUN_MAX_PHI / 2;
    c.nmax = BTDF_SCATFUN_MAX_PHI;
    c.budget = tolerance;

    btdf_scatfun *best = NULL;
    double best_err = HUGE_VAL;
    /* T and R of the test angles, kept across the measurements (NULL: computed each time) */
    albedo_memo *memo = albedo_memo_new();
    /* initial half nodes: mu = sin of equal angle steps, denser towards grazing */
    size_t K0 = 8;
    double *P = malloc(BTDF_SCATFUN_MAX_HALF_NODES * 2 * sizeof *P);
    /* fresh[j]: interval j was made by the last pass's split; ahead: fronts (below) */
    unsigned char *fresh = calloc(BTDF_SCATFUN_MAX_HALF_NODES * 2, 1);
    unsigned char *ahead = calloc(BTDF_SCATFUN_MAX_HALF_NODES, 1);
    if (!P || !fresh || !ahead) {
        st = BTDF_ENOMEM;
        goto done;
    }
    for (size_t j = 0; j < K0; j++)
        P[j] = to_float_node(sin((double)(j + 1) * M_PI / (2.0 * (double)K0)));
    P[K0 - 1] = POLE_NODE;
    size_t K = K0;
    int tighten = 0, local = 0, stall = 0;
    double last_err = HUGE_VAL; /* the previous measurement, for stall */
    const char *limit = "node"; /* which budget stopped refinement */
    st = BTDF_OK;
    for (int pass = 0;; pass++) {
        if (set_nodes(&c, P, K)) {
            st = BTDF_ENOMEM;
            goto done;
        }
        c.nint = K;
        if (ensure_state(&c)) {
            st = BTDF_ENOMEM;
            goto done;
        }
        for (size_t j = 0; j < K; j++)
            /* checked where a split would put the node, so check series become pairs */
            c.mid[j] = to_float_node(split_point(P, K, j, 0.5));
        /* the norms of new nodes and midpoints (each its own job: same values on any
           number of threads) */
        core_parallel_for(threads, K * NBLK * 2, job_norms, &c);
        for (size_t j = 0; j < K; j++)
            c.hasTn[j] = c.hasTm[j] = 1;
        if (core_parallel_for_ws(threads, NBLK * K, job_row, &c, build_ws_new, build_ws_free) || c.oom) {
            st = BTDF_ENOMEM;
            goto done;
        }
        size_t total = 0;
        for (int s = 0; s < NBLK; s++)
            for (size_t i = 0; c.want[s] && i < K * K; i++)
                total += c.pairs[s][i].m * (size_t)c.nst;
        if (total > max_coeffs) {
            limit = "coefficient";
            st = BTDF_EBUDGET;
            break;
        }
        if (max_bytes && state_bytes(&c) > max_bytes) {
            limit = "memory";
            st = BTDF_EBUDGET;
            break;
        }
        if (core_parallel_for_ws(threads, NBLK * K, job_colcheck, &c, build_ws_new, build_ws_free) ||
            core_parallel_for_ws(threads, NBLK * K, job_rowcheck, &c, build_ws_new, build_ws_free) ||
            c.oom) {
            st = BTDF_ENOMEM;
            goto done;
        }
        if (max_bytes && state_bytes(&c) > max_bytes) {
            limit = "memory";
            st = BTDF_EBUDGET;
            break;
        }
        /* mark intervals to split */
        unsigned char *split = calloc(K, 1);
        if (!split) {
            st = BTDF_ENOMEM;
            goto done;
        }
        size_t nsplit = 0;
        double endr = 1.0;
        /* The checks bound both readings of every block (norms_at): DIRECT, the light
           in the slow index, integrates the error over the fast one; ADJOINT, the light
           in the fast index, over the slow one. One interval check serves both with the
           axes swapped: the fast-midpoint gaps (errc) summed along a row are the DIRECT
           error there, summed down a column of rows the ADJOINT error of the light at
           that midpoint; the slow-midpoint gaps (gapr) the other way round. A
           three-channel transmission block is read ADJOINT only (pair_norm). */
        double *ea = calloc(K, sizeof *ea);
        if (!ea) {
            free(split);
            st = BTDF_ENOMEM;
            goto done;
        }
        int rowbad = 0; /* once a row fails, also split the ones close to failing */
        for (int s = 0; s < NBLK; s++) {
            if (!c.want[s])
                continue;
            int direct = !(c.nst == 3 && !blk_refl[s]);
            for (size_t j = 0; direct && j < K; j++)
                rowbad |= c.errr[s][j] > share_row(&c);
        }
        for (int s = 0; s < NBLK; s++) {
            if (!c.want[s])
                continue;
            int direct = !(c.nst == 3 && !blk_refl[s]);
            for (size_t r = 0; direct && r < K; r++) {
                double sum = 0.0;
                for (size_t j = 0; j < K; j++) {
                    double wid = P[j] - (j == 0 ? 0.0 : P[j - 1]);
                    sum += wid * c.errc[s][r * K + j];
                }
                if (sum <= share_col(&c))
                    continue;
                for (size_t j = 0; j < K; j++) {
                    double wid = P[j] - (j == 0 ? 0.0 : P[j - 1]);
                    if (wid * c.errc[s][r * K + j] > share_col(&c) / (double)K)
                        split[j] = 1;
                }
            }
            for (size_t j = 0; direct && j < K; j++)
                if (c.errr[s][j] > share_row(&c) && j == K - 1)
                    /* error ~ the last interval's angle: aim at half the share */
                    endr = fmin(endr, fmax(1.0 / 64.0, 0.5 * share_row(&c) / c.errr[s][j]));
            for (size_t j = 0; direct && j < K; j++)
                if (c.errr[s][j] > (rowbad ? 0.7 : 1.0) * share_row(&c))
                    split[j] = 1;
            /* ADJOINT, light at fast node col: the slow-midpoint gaps down the column */
            for (size_t col = 0; col < K; col++) {
                double sum = 0.0;
                for (size_t j = 0; j < K; j++) {
                    double wid = P[j] - (j == 0 ? 0.0 : P[j - 1]);
                    /* the camera's cosine, the slow midpoint's: the ADJOINT integral's
                       weight (norms_at) */
                    ea[j] = wid * c.mid[j] * c.gapr[s][j * K + col] *
                            adj_ratio(&c, c.Tm[j][s], c.Tn[col][s]);
                    sum += ea[j];
                }
                if (sum <= share_col(&c))
                    continue;
                for (size_t j = 0; j < K; j++)
                    if (ea[j] > share_col(&c) / (double)K)
                        split[j] = 1;
            }
            /* ADJOINT, light at fast midpoint j: the fast-midpoint gaps over the rows */
            for (size_t j = 0; j < K; j++) {
                double tot = 0.0;
                for (size_t r = 0; r < K; r++) {
                    double lo = r == 0 ? 0.0 : P[r - 1], hi = r + 1 < K ? P[r + 1] : P[r];
                    tot += 0.5 * (hi - lo) * P[r] * c.errc[s][r * K + j] *
                           adj_ratio(&c, c.Tn[r][s], c.Tm[j][s]);
                }
                if (tot > share_row(&c)) {
                    split[j] = 1;
                    if (j == K - 1)
                        endr = fmin(endr, fmax(1.0 / 64.0, 0.5 * share_row(&c) / tot));
                }
            }
        }
        free(ea);
        /* Fronts. A new node is also a new row and column of pairs, and the checks sum
           over rows and columns: an interval next to a freshly split one can fail only
           because the new rows now see it (measured for n = 1.5, s = 3 at 1e-3: the
           failing interval moved one step outwards per pass, its check at 3.1, 2.6,
           2.2, 1.7, 1.3 times the share, six passes). When an interval that was not
           just split fails beside one that was, split the next one outwards too: the
           front moves two intervals per pass. */
        for (size_t j = 0; j < K; j++)
            ahead[j] = 0;
        for (size_t j = 0; j < K; j++) {
            if (!split[j] || fresh[j])
                continue;
            if (j > 0 && fresh[j - 1] && j + 1 < K && !fresh[j + 1])
                ahead[j + 1] = 1;
            if (j + 1 < K && fresh[j + 1] && j > 0 && !fresh[j - 1])
                ahead[j - 1] = 1;
        }
        for (size_t j = 0; j < K; j++)
            split[j] |= ahead[j];
        for (size_t j = 0; j < K; j++)
            nsplit += split[j];
        if (progress) /* K nodes checked, nsplit intervals to split */
            progress(user, tighten ? "series (tighter)" : "elevation nodes", K, nsplit);
        if (nsplit == 0) {
            /* The node checks pass: measure the file itself. Where it misses, split the
               elevation intervals of the test angles that miss (the checks run at
               interval midpoints only; the report hunts for the worst angles), keeping
               every series; only when that finds nothing to split, halve the shares
               and recompute everything. */
            btdf_scatfun *f = NULL;
            st = assemble(&c, &f, msg, msglen);
            if (st != BTDF_OK) {
                free(split);
                goto done;
            }
            double e = 0.0;
            size_t nmark = 0;
            for (int s = 0; s < NBLK; s++)
                if (c.want[s])
                    e = fmax(e, quick_l1(f, p, (btdf_side)blk_mask[s], threads,
                                         QUICK_SEED + (uint64_t)local, memo, P, K,
                                         MARK_SHARE * tolerance, ACCEPT_SHARE * tolerance,
                                         split, &nmark));
            /* A failing measurement may have skipped its refinement (stop_above): its
               e is a lower bound, so such a file is not kept as the best; should the
               budget run out, the last file is measured whole below. */
            if (e < best_err && e <= ACCEPT_SHARE * tolerance) {
                btdf_scatfun_free(best);
                best = f;
                best_err = e;
            } else {
                btdf_scatfun_free(f);
            }
            if (e <= ACCEPT_SHARE * tolerance && !c.capped) {
                free(split);
                st = BTDF_OK;
                break;
            }
            /* Splits that do not lower the error (two measurements in a row above 0.9 of
               the one before) point at the series, not at the nodes: tighten. */
            stall = e > 0.9 * last_err ? stall + 1 : 0;
            last_err = e;
            if (nmark > 0 && local < LOCAL_ROUNDS && stall < 2 && !c.capped) {
                local++;
                nsplit = nmark; /* on to the insertion below */
            } else {
                if (++tighten > 6 || c.capped) {
                    free(split);
                    st = BTDF_EBUDGET;
                    break;
                }
                c.budget *= 0.5;
                memset(fresh, 0, K);
                stall = 0;
                last_err = HUGE_VAL;
                free(split);
                free_state(&c); /* every series and check depends on the budget */
                continue;       /* same nodes, tighter series and checks */
            }
        }
        if (K + nsplit > BTDF_SCATFUN_MAX_HALF_NODES) {
            limit = "node";
            free(split);
            st = BTDF_EBUDGET;
            break;
        }
        /* insert split points (rounded to float, strictly inside their interval) */
        double *Q = P + BTDF_SCATFUN_MAX_HALF_NODES;
        unsigned char *ins = calloc(K, 1);
        if (!ins) {
            free(split);
            st = BTDF_ENOMEM;
            goto done;
        }
        size_t KQ = 0;
        if (endr > 0.5)
            endr = 0.5;
        for (size_t j = 0; j < K; j++) {
            double lo = j == 0 ? 0.0 : P[j - 1];
            double m = to_float_node(split_point(P, K, j, endr));
            if (split[j] && m > lo && m < P[j]) {
                fresh[KQ] = 1;
                Q[KQ++] = m;
                ins[j] = m == c.mid[j] ? 1 : 2;
                fresh[KQ] = 1;
            } else {
                fresh[KQ] = 0;
            }
            Q[KQ++] = P[j];
        }
        free(split);
        if (KQ == K) {
            free(ins);
            st = BTDF_EBUDGET; /* float spacing reached: nothing left to split */
            break;
        }
        if (carry_over(&c, Q, KQ, ins, threads)) {
            free(ins);
            st = BTDF_ENOMEM;
            goto done;
        }
        free(ins);
        memcpy(P, Q, KQ * sizeof *P);
        K = KQ;
        (void)pass;
    }
    if (st == BTDF_EBUDGET || !best) {
        /* keep the finest file reached as the answer, measured honestly */
        btdf_scatfun *f = NULL;
        if (c.pairs[0] || c.pairs[1]) {
            btdf_status a = assemble(&c, &f, msg, msglen);
            if (a == BTDF_OK) {
                double e = 0.0;
                for (int s = 0; s < NBLK; s++)
                    if (c.want[s])
                        e = fmax(e, quick_l1(f, p, (btdf_side)blk_mask[s], threads,
                                             QUICK_SEED + (uint64_t)local, memo, NULL, 0,
                                             0.0, 0.0, NULL, NULL));
                if (e < best_err || !best) {
                    btdf_scatfun_free(best);
                    best = f;
                    best_err = e;
                } else {
                    btdf_scatfun_free(f);
                }
            }
        }
        if (!best) {
            st = BTDF_ENOMEM;
            goto done;
        }
        if (best_err <= tolerance)
            st = BTDF_OK;
    }
done:
    free_state(&c);
    free(c.P);
    free(c.full);
    free(P);
    free(fresh);
    free(ahead);
    pthread_mutex_destroy(&c.lock);
    if (st != BTDF_OK && st != BTDF_EBUDGET) {
        albedo_memo_free(memo);
        btdf_scatfun_free(best);
        return st;
    }
    best->tolerance = tolerance;
    best->seconds_build = core_now() - t0;
    if (memo) { /* the file's reports test the same knot midpoints: hand over T and R */
        albedo_memo_free(best->memo);
        best->memo = memo;
    }
    *out = best;
    if (st == BTDF_EBUDGET)
        return core_say(BTDF_EBUDGET, msg, msglen,
                   "%s budget reached (%u nodes, %u coefficients, mMax %u) with estimated "
                   "e_L1 %.3g > tolerance %g",
                   limit, best->n, best->ncoeffs, best->mmax, best_err, tolerance);
    return BTDF_OK;
}
