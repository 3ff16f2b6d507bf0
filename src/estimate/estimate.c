/* SPDX-License-Identifier: MIT */
/* estimate.c: a table's error against its model (MODEL.md section 6) at points it was not built on. */
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include "core/core.h"
#include "estimate/estimate.h"
#include "model/facet.h"
#include "model/full.h"
#include "model/kernel.h"

/* ------------------------------------------------------------------------- */
/* Remembered T and R                                                        */
/* ------------------------------------------------------------------------- */

typedef struct memo_key {
    int refl, channels, model;
    double ior[BTDF_MAX_CHANNELS], s, k0, ti;
} memo_key;

typedef struct memo_ent {
    memo_key key;
    double v[BTDF_MAX_CHANNELS];
    struct memo_ent *next;
} memo_ent;

#define MEMO_BUCKETS 4096

struct albedo_memo {
    pthread_mutex_t lock;
    memo_ent *b[MEMO_BUCKETS];
};

albedo_memo *albedo_memo_new(void)
{
    albedo_memo *m = calloc(1, sizeof *m);
    if (m && pthread_mutex_init(&m->lock, NULL) != 0) {
        free(m);
        return NULL;
    }
    return m;
}

void albedo_memo_free(albedo_memo *m)
{
    if (!m)
        return;
    for (size_t i = 0; i < MEMO_BUCKETS; i++)
        for (memo_ent *e = m->b[i], *nx; e; e = nx) {
            nx = e->next;
            free(e);
        }
    pthread_mutex_destroy(&m->lock);
    free(m);
}

static int key_eq(const memo_key *a, const memo_key *b)
{
    if (a->refl != b->refl || a->channels != b->channels || a->model != b->model ||
        a->s != b->s || a->k0 != b->k0 || a->ti != b->ti)
        return 0;
    for (int c = 0; c < a->channels; c++)
        if (a->ior[c] != b->ior[c])
            return 0;
    return 1;
}

btdf_status albedo_memo_get(albedo_memo *m, const btdf_params *p, int refl, double ti,
                            double *out)
{
    if (!m)
        return refl ? btdf_reflectance(p, ti, out) : btdf_transmittance(p, ti, out);
    memo_key k;
    memset(&k, 0, sizeof k);
    k.refl = refl;
    k.channels = p->channels;
    for (int c = 0; c < p->channels && c < BTDF_MAX_CHANNELS; c++)
        k.ior[c] = p->ior[c];
    k.s = p->smoothness;
    k.k0 = p->k0;
    k.model = (int)p->model;
    k.ti = ti;
    uint64_t bits, nb;
    memcpy(&bits, &ti, sizeof bits);
    memcpy(&nb, &k.ior[0], sizeof nb);
    size_t h = (size_t)((bits ^ (nb * 0x9e3779b97f4a7c15ull) ^ (uint64_t)refl) *
                        0xbf58476d1ce4e5b9ull >> 52) % MEMO_BUCKETS;
    pthread_mutex_lock(&m->lock);
    for (const memo_ent *e = m->b[h]; e; e = e->next)
        if (key_eq(&e->key, &k)) {
            memcpy(out, e->v, (size_t)p->channels * sizeof *out);
            pthread_mutex_unlock(&m->lock);
            return BTDF_OK;
        }
    pthread_mutex_unlock(&m->lock);
    /* computed outside the lock; two threads computing the same key store the same
       value, so either copy may stay */
    btdf_status st = refl ? btdf_reflectance(p, ti, out) : btdf_transmittance(p, ti, out);
    if (st != BTDF_OK)
        return st;
    memo_ent *e = malloc(sizeof *e);
    if (!e)
        return BTDF_OK; /* not remembered: the value is still right */
    e->key = k;
    memset(e->v, 0, sizeof e->v);
    memcpy(e->v, out, (size_t)p->channels * sizeof *out);
    pthread_mutex_lock(&m->lock);
    e->next = m->b[h];
    m->b[h] = e;
    pthread_mutex_unlock(&m->lock);
    return BTDF_OK;
}

typedef struct est_job {
    const btdf_params *p; /* the truth: the model of these parameters */
    est_eval_fn fn;       /* the evaluation under test */
    const void *obj;
    const double *ti;     /* the test angles */
    size_t ppa;           /* points per angle of this pass */
    size_t nu, npsi, nmu, nphi; /* this pass's sets */
    uint64_t seed;
    btdf_ti_error *res;
    size_t *points;
    int refl;             /* 1: the truth is rho_r over the upper hemisphere, R for T */
    albedo_memo *memo;    /* T and R remembered across calls, or NULL */
    est_prep_fn prep;     /* per-angle context for fn, or NULL (then fn reads all of q) */
    est_done_fn done;     /* frees what prep returned */
    int l1_only;          /* refinement follows e_L1 only */
    int nread;            /* readings fn returns per point (1 or 2; est_opts) */
    double stop_above;    /* est_opts */
    btdf_full *const *ms; /* model full: each channel's tally (est_opts.full), or NULL */
} est_job;

/*
 * Two sample sets per incident angle, combined by the balance heuristic (multiple
 * importance sampling) on the measure |cos to| d(omega_o):
 *  A: facet slopes stratified in w = 1 - exp(-u^2) and psi, which follows the lobe
 *     however narrow it is; a sample stands for V_A = |cos to|/chi d(omega_h) of it;
 *  B: outgoing directions stratified in (cos to, phi), V_B = |cos to| d(cos to) d(phi).
 * Each sample counts with V_A V_B / (V_A + V_B) (V_A = infinity where A cannot reach).
 * A alone has unbounded weights for n < 1, where chi -> 0 at the critical angle;
 * B alone misses narrow lobes; together they are bounded and follow the lobe.
 * Reflection (MODEL.md section 8) is measured the same way on cos tr d(omega_r): A's
 * facets mirror e_i (V_A = cos tr 4 (e_i.h) d(omega_h)), B's directions cover the upper
 * hemisphere, and R(ti) takes the place of T(ti).
 */
#define U_EST 7.0 /* A's neglected tail holds exp(-49) of the facet distribution */

/* Model full: the tally's multiply scattered part at the outgoing direction (|cos| mu,
   cos phi), the same expression as the table's (table/full.c), so that where the two
   agree it cancels to the bit; 0 for the other models and at grazing in or out (as
   btdf_full_rho_deg). */
static double est_ms(const est_job *j, int c, double ti, double cti, double mu, double cph)
{
    if (!j->ms || !(cti > 0.0) || !(fabs(mu) > 0.0))
        return 0.0;
    return full_ms(j->ms[c], j->refl, ti * (180.0 / M_PI), fabs(mu), cph);
}

void est_fold(btdf_ti_error *r, const est_acc *a, double T, int c)
{
    double fl = fmax(T, 0.01); /* MODEL.md section 6 floor */
    if (c == 0) {
        r->T = T;
        r->T_table = T + a->sgn;
    }
    r->e_l1 = fmax(r->e_l1, a->l1 / fl);
    r->e_t = fmax(r->e_t, fabs(a->sgn) / fl);
    r->e_max = fmax(r->e_max, (T >= 0.01 && a->vmax > 0.0) ? a->dmax / a->vmax : 0.0);
}

void est_worse(const btdf_ti_error *rr, int nr, btdf_ti_error *out)
{
    int wr = nr == 2 && rr[1].e_l1 > rr[0].e_l1;
    out->T = rr[0].T;
    out->T_table = rr[wr].T_table;
    out->e_l1 = rr[wr].e_l1;
    out->e_t = nr == 2 ? fmax(rr[0].e_t, rr[1].e_t) : rr[0].e_t;
    out->e_max = nr == 2 ? fmax(rr[0].e_max, rr[1].e_max) : rr[0].e_max;
}

/* Measure one A sample of slope u (tan tn = 2u/s) stands for, per unit outgoing
   weight |cos to|/chi: d(omega_h)/(dw dpsi) (2/s^2) e^{u^2} / q^{3/2}, q = 1 + tan^2 tn,
   times the stratum size, doubled for psi < 0. */
static double a_measure(double u, double s, double dw, double dpsi)
{
    double rr = 2.0 * u / s, q = 1.0 + rr * rr;
    return (2.0 / (s * s)) * exp(u * u) / (q * sqrt(q)) * dw * dpsi * 2.0;
}

static void est_angle(void *arg, size_t k)
{
    est_job *j = arg;
    const btdf_params *p = j->p;
    double ti = j->ti[k];
    /* The stream depends on the angle, not on k: an angle gets the same points whatever
       the order in which the rounds below add angles. */
    uint64_t bits;
    memcpy(&bits, &ti, sizeof bits);
    uint64_t rng = j->seed ^ (0xa0761d6478bd642full * (bits | 1u));
    double sti = sin(ti), cti = cos(ti), s = p->smoothness;
    rho_in a;
    rho_in_init_m(&a, sti, cti, s, p->k0, p->model); /* the truth is the table's model */
    /* with a context (prep), fn reads the cosines of q only: the angles are left 0 */
    void *ctx = j->prep ? j->prep(j->obj, ti) : NULL;
    const void *obj = ctx ? ctx : j->obj;
    btdf_ti_error *r = &j->res[k];
    memset(r, 0, sizeof *r);
    r->ti = ti;
    double Tall[BTDF_MAX_CHANNELS];
    int refl = j->refl;
    if (albedo_memo_get(j->memo, p, refl, ti, Tall) != BTDF_OK)
        for (int c = 0; c < p->channels; c++)
            Tall[c] = 0.0; /* ti in range and p checked: not reached */
    double wmax = -expm1(-U_EST * U_EST);
    double dw = wmax / (double)j->nu, dpsi = M_PI / (double)j->npsi;
    double dmu = 1.0 / (double)j->nmu, dphi = M_PI / (double)j->nphi;
    size_t pts = 0;
    int nr = j->nread == 2 ? 2 : 1;
    double tab[2 * BTDF_MAX_CHANNELS];
    btdf_ti_error rr[2]; /* per reading; the angle's result is the worse */
    memset(rr, 0, sizeof rr);
    for (int c = 0; c < p->channels; c++) {
        double n = p->ior[c], T = Tall[c];
        if (j->ms) /* full's norm: smith's quadrature plus the tallied orders 2+ */
            T += full_ms_energy(j->ms[c], refl, ti, NULL);
        est_acc acc[2] = {{0.0, 0.0, 0.0, 0.0}, {0.0, 0.0, 0.0, 0.0}};
        for (size_t iu = 0; iu < j->nu; iu++) {
            for (size_t ip = 0; ip < j->npsi; ip++) {
                double w = wmax * ((double)iu + core_unif(&rng)) / (double)j->nu;
                double psi = M_PI * ((double)ip + core_unif(&rng)) / (double)j->npsi;
                double u = sqrt(-log1p(-w)); /* w < 1: finite */
                double rr = 2.0 * u / s;
                double ctn = 1.0 / sqrt(1.0 + rr * rr), stn = rr * ctn;
                facet_geo g;
                pts++;
                if (!(refl ? facet_eval_r(n, s, p->k0, &a, stn, ctn, cos(psi), sin(psi), &g)
                           : facet_eval(n, s, p->k0, &a, stn, ctn, cos(psi), sin(psi), &g)))
                    continue; /* no outgoing direction: both the table and the model are 0 */
                double va = g.weight * a_measure(u, s, dw, dpsi);
                double vb = fabs(g.cos_to) * dmu * dphi * 2.0;
                double to = 0.0, pf = 0.0;
                if (!j->prep) {
                    to = atan2(g.sin_to, g.cos_to);
                    pf = fabs(atan2(g.sin_phi, g.cos_phi));
                }
                const double q[8] = {sti, cti, g.sin_to, g.cos_to, g.cos_phi, g.sin_phi, pf, to};
                j->fn(obj, ti, q, tab);
                /* g.rho is the model through the kernel, independent of the table */
                double truth = g.rho + est_ms(j, c, ti, cti, g.cos_to, g.cos_phi);
                for (int e = 0; e < nr; e++)
                    est_add(&acc[e], tab[e * p->channels + c], truth,
                            va > 0.0 ? va * vb / (va + vb) : 0.0);
            }
        }
        for (size_t im = 0; im < j->nmu; im++) {
            for (size_t ip = 0; ip < j->nphi; ip++) {
                double mu = ((double)im + core_unif(&rng)) / (double)j->nmu; /* |cos to| */
                mu = refl ? mu : -mu;
                double ph = M_PI * ((double)ip + core_unif(&rng)) / (double)j->nphi;
                double sto = sqrt(fmax(0.0, 1.0 - mu * mu)), cph = cos(ph), sph = sin(ph);
                double vb = fabs(mu) * dmu * dphi * 2.0, share = vb, tn, ps, ca_r;
                pts++;
                if (refl && facet_of_r(sti, cti, sto, mu, cph, sph, &tn, &ps, &ca_r)) {
                    /* V_A of the mirroring facet from its own e_i.h (ca_r > 0 where
                       e_i + e_r points up, mu > 0 here): cos tr 4 (e_i.h) d(omega_h) */
                    double u = 0.5 * s * tan(tn); /* tn < pi/2: facet_of_r needs h_z > 0 */
                    double va = u < U_EST ? mu * 4.0 * ca_r * a_measure(u, s, dw, dpsi) : 0.0;
                    if (va > 0.0)
                        share = va * vb / (va + vb);
                } else if (!refl && facet_of(n, sti, cti, sto, mu, cph, sph, &tn, &ps)) {
                    double u = 0.5 * s * tan(tn);
                    facet_geo g;
                    if (u < U_EST &&
                        facet_eval(n, s, p->k0, &a, sin(tn), cos(tn), cos(ps), sin(ps), &g)) {
                        double va = g.weight * a_measure(u, s, dw, dpsi);
                        share = va * vb / (va + vb);
                    }
                }
                double rho;
                if (refl) {
                    rho = btdf_rho_r_model(p->model, n, s, p->k0, ti, atan2(sto, mu), ph);
                } else {
                    rho_out b;
                    rho_out_init_m(&b, sto, mu, s, p->k0, &a);
                    rho = rho_kernel(n, s, &a, &b, cph, sph);
                }
                const double q[8] = {sti, cti, sto, mu, cph, sph, ph,
                                     j->prep ? 0.0 : atan2(sto, mu)};
                j->fn(obj, ti, q, tab);
                rho += est_ms(j, c, ti, cti, mu, cph);
                for (int e = 0; e < nr; e++)
                    est_add(&acc[e], tab[e * p->channels + c], rho, share);
            }
        }
        for (int e = 0; e < nr; e++)
            est_fold(&rr[e], &acc[e], T, c);
    }
    est_worse(rr, nr, r); /* the worse reading at this angle */
    if (ctx)
        j->done(ctx);
    j->points[k] = pts;
}

/* ------------------------------------------------------------------------- */
/* Which incident angles: stratified, every knot interval, and refinement      */
/* ------------------------------------------------------------------------- */

/*
 * A table's error as a function of ti is a row of bumps, one per interval between
 * slices (zero at the slices, largest near the middle), and it can change fast where
 * T does (near grazing incidence, near the critical angle). Stratified angles alone
 * step over narrow bumps, so the test angles are:
 *  1. test_angles stratified angles (one random angle per equal stratum); the means
 *     of the report are over these only, so they stay unbiased;
 *  2. the ends of the range and the midpoint of every interval between adjacent
 *     knots (the table's slice angles) inside the range;
 *  3. rounds of refinement: between neighbours (in ti) whose errors differ by more
 *     than a factor 1.5 (for either metric), where the larger is within a factor 3 of
 *     the worst so far, the midpoint is added; so are the two midpoints on either
 *     side of the worst angle, and the midpoint between neighbours whose T differ by
 *     more than a factor 1.5 (T floored at 1e-3). Rounds stop when nothing is added, after REFINE_ROUNDS,
 *     or when the gap falls below REFINE_MIN_GAP. A caller that reads e_L1 only (the
 *     .bsdf builder's own measurements) leaves e_max out of these rules: in the
 *     builder's n = 1.5, s = 3 build at 1e-3 they added about a fifth of the angles.
 */
#define REFINE_ROUNDS 6
#define REFINE_MIN_GAP 2e-4 /* rad, 0.01 deg; 2e-2/s where the shadowing edge is narrower */
#define REFINE_MAX_ADD 96   /* angles per round */

static int cmp_err_ti(const void *a, const void *b)
{
    double x = ((const btdf_ti_error *)a)->ti, y = ((const btdf_ti_error *)b)->ti;
    return (x > y) - (x < y);
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Runs the estimate at n angles ti[], appending results to res (which has room). */
static void run_angles(est_job *j, int threads, const double *ti, size_t n, btdf_ti_error *res,
                       size_t *points)
{
    j->ti = ti;
    j->res = res;
    j->points = points;
    core_parallel_for(threads, n, est_angle, j);
}

/* Largest ratio of two errors, with a floor so that noise near 0 does not count. */
static double ratio(double a, double b, double fl)
{
    a = fmax(a, fl);
    b = fmax(b, fl);
    return a > b ? a / b : b / a;
}

/* The first angles: test_angles stratified over [ti_min, ti_max] (their count is
   *nstrat), then the two ends and the midpoints of the knot intervals wider than
   min_gap (a zero-width range has one angle only). Returns the count. */
static size_t est_first_angles(double ti_min, double ti_max, size_t test_angles,
                               uint64_t seed, const double *knots, size_t nknots,
                               double min_gap, double *ti, size_t *nstrat)
{
    double span = ti_max - ti_min;
    uint64_t rng = seed ^ 0x243f6a8885a308d3ull;
    size_t n = 0;
    for (size_t k = 0; k < test_angles; k++) {
        double x = ti_min + span * ((double)k + core_unif(&rng)) / (double)test_angles;
        ti[n++] = fmin(x, ti_max);
    }
    *nstrat = n;
    if (span > 0.0) {
        ti[n++] = ti_min;
        ti[n++] = ti_max;
        for (size_t k = 0; k + 1 < nknots; k++) {
            double a = fmax(knots[k], ti_min), b = fmin(knots[k + 1], ti_max);
            if (b > a && b - a > min_gap)
                ti[n++] = 0.5 * (a + b);
        }
    }
    return n;
}

/* Screening (est_opts): the n first angles were read with the small sets; read again
   with the full ones those whose small reading reaches screen_at or is 0 (a screen that
   saw no error knows nothing). Leaves j reading in full. */
static void est_screen(est_job *j, const est_opts *opt, int threads, size_t full_ppa,
                       size_t full_nu, size_t full_nuni, const double *ti, size_t n,
                       btdf_ti_error *res, size_t *points)
{
    j->ppa = full_ppa;
    j->nu = full_nu;
    j->nmu = j->nphi = full_nuni;
    double *again = malloc(n * sizeof *again);
    size_t *where = malloc(n * sizeof *where);
    btdf_ti_error *res2 = calloc(n, sizeof *res2);
    size_t *pts2 = calloc(n, sizeof *pts2);
    size_t na = 0;
    if (again && where && res2 && pts2) {
        for (size_t k = 0; k < n; k++) {
            int small = res[k].e_l1 < opt->screen_at && res[k].e_l1 > 0.0; /* NaN: no */
            if (!small) {
                where[na] = k;
                again[na++] = ti[k];
            }
        }
        run_angles(j, threads, again, na, res2, pts2);
        for (size_t q = 0; q < na; q++) {
            res[where[q]] = res2[q];
            points[where[q]] += pts2[q];
        }
    } else {
        run_angles(j, threads, ti, n, res, points); /* out of memory: all in full */
    }
    free(again);
    free(where);
    free(res2);
    free(pts2);
}

/* The midpoints one refinement round adds to the n angles read so far (into add, at
   most REFINE_MAX_ADD): intervals where the error or T changes fast, and those beside
   the worst angle. Returns the count; 0 when out of memory (the estimate so far
   stands: refinement is an improvement). */
static size_t est_refine_points(const est_job *j, const btdf_ti_error *res, size_t n,
                                double min_gap, double *add)
{
    btdf_ti_error *srt = malloc(n * sizeof *srt);
    if (!srt)
        return 0;
    memcpy(srt, res, n * sizeof *srt);
    qsort(srt, n, sizeof *srt, cmp_err_ti);
    double wl1 = 0.0, wmx = 0.0;
    size_t worst = 0;
    for (size_t k = 0; k < n; k++) {
        if (srt[k].e_l1 > wl1) {
            wl1 = srt[k].e_l1;
            worst = k;
        }
        wmx = fmax(wmx, srt[k].e_max);
    }
    size_t na = 0;
    for (size_t k = 0; k + 1 < n; k++) {
        const btdf_ti_error *a = &srt[k], *b = &srt[k + 1];
        if (!(b->ti - a->ti > min_gap))
            continue;
        int l1 = fmax(a->e_l1, b->e_l1) >= wl1 / 3.0 && wl1 > 0.0 &&
                 ratio(a->e_l1, b->e_l1, 0.01 * wl1) > 1.5;
        int mx = fmax(a->e_max, b->e_max) >= wmx / 3.0 && wmx > 0.0 &&
                 ratio(a->e_max, b->e_max, 0.01 * wmx) > 1.5;
        /* T changing fast: the error's floor max(T, 0.01) and the lobe with it */
        int tf = ratio(a->T, b->T, 1e-3) > 1.5;
        int near_worst = (wl1 > 0.0 && (k + 1 == worst || k == worst)) ||
                         (wmx > 0.0 && (a->e_max == wmx || b->e_max == wmx));
        if (j->l1_only) /* e_max is not read: its rules add nothing the caller uses */
            mx = 0, near_worst = wl1 > 0.0 && (k + 1 == worst || k == worst);
        if (l1 || mx || tf || near_worst)
            add[na++] = 0.5 * (a->ti + b->ti);
    }
    free(srt);
    if (na > REFINE_MAX_ADD) {
        /* keep the ones nearest the worst angles: sort by nothing fancier than taking
           every other one, evenly over ti */
        qsort(add, na, sizeof *add, cmp_double);
        double step = (double)na / REFINE_MAX_ADD;
        for (size_t k = 0; k < REFINE_MAX_ADD; k++)
            add[k] = add[(size_t)((double)k * step)];
        na = REFINE_MAX_ADD;
    }
    return na;
}

/* The report of the n angles read (res, sorted here; r takes it): means over the
   stratified angles only, the first nstrat (the others crowd where errors are large);
   then every angle, sorted by ti, for the maxima and the list. */
static void est_summarise(btdf_ti_error *res, const size_t *points, size_t n, size_t nstrat,
                          btdf_report *r)
{
    memset(r, 0, sizeof *r);
    size_t nmean_max = 0;
    for (size_t k = 0; k < nstrat; k++) {
        r->e_l1_mean += res[k].e_l1 / (double)nstrat;
        r->e_t_mean += res[k].e_t / (double)nstrat;
        if (res[k].T >= 0.01) {
            nmean_max++;
            r->e_max_mean += res[k].e_max;
        }
    }
    if (nmean_max)
        r->e_max_mean /= (double)nmean_max;
    qsort(res, n, sizeof *res, cmp_err_ti);
    r->test_angles = n;
    r->per_ti = res;
    for (size_t k = 0; k < n; k++) {
        const btdf_ti_error *e = &res[k];
        r->test_points += points[k];
        r->e_l1_max = fmax(r->e_l1_max, e->e_l1);
        r->e_t_max = fmax(r->e_t_max, e->e_t);
        r->e_max_max = fmax(r->e_max_max, e->e_max);
        if (e->T >= 0.01)
            r->e_max_angles++;
    }
}

/* The estimate: the first angles (stratified, the ends, the knots' midpoints), read
   with the screen's small sets when asked, then refinement rounds where the error or T
   changes fast, then the summary. */
static btdf_status estimate_impl(const btdf_params *p, int refl, double ti_min,
                                 double ti_max, size_t test_angles, size_t points_per_angle,
                                 uint64_t seed, int threads, const double *knots,
                                 size_t nknots, est_eval_fn fn, est_prep_fn prep, est_done_fn done, const void *obj,
                                 const est_opts *opt, albedo_memo *memo, btdf_report *r)
{
    if (!p || !fn || !r || !(ti_min >= 0.0 && ti_max <= M_PI / 2 && ti_min <= ti_max))
        return BTDF_EINVAL;
    if (test_angles == 0)
        test_angles = 48;
    if (points_per_angle == 0)
        points_per_angle = 8192;
    if (test_angles > 100000 || points_per_angle > 100000000 || nknots > 1000000)
        return BTDF_EINVAL;
    double t0 = core_now();
    est_job j;
    memset(&j, 0, sizeof j);
    j.p = p;
    j.refl = refl;
    j.fn = fn;
    j.prep = prep && done ? prep : NULL;
    j.done = done;
    j.l1_only = opt ? opt->l1_only : 0;
    j.nread = opt && opt->nread == 2 ? 2 : 1;
    j.stop_above = opt ? opt->stop_above : 0.0;
    j.ms = opt ? opt->full : NULL;
    btdf_params single;
    if (j.ms) { /* the kernel and the quadrature take full's single scattering, smith */
        single = *p;
        single.model = BTDF_MODEL_SMITH;
        j.p = &single;
    }
    j.ppa = points_per_angle;
    j.obj = obj;
    j.npsi = 32;
    j.nu = (points_per_angle + 31) / 32;
    j.nmu = 64;
    j.nphi = 64;
    j.seed = seed;
    j.memo = memo;
    double span = ti_max - ti_min;
    /* V(ti) falls to 0 before grazing over about 1/s rad (smoothness >= 1e-3 checked) */
    double min_gap = fmin(REFINE_MIN_GAP, 2e-2 / p->smoothness);
    /* capacity: stratified + 2 ends + knot midpoints + refinement rounds */
    size_t cap = test_angles + 2 + (nknots + 1) + REFINE_ROUNDS * REFINE_MAX_ADD;
    double *ti = malloc(cap * sizeof *ti);
    btdf_ti_error *res = calloc(cap, sizeof *res);
    size_t *points = calloc(cap, sizeof *points);
    if (!ti || !res || !points) {
        free(ti);
        free(res);
        free(points);
        return BTDF_ENOMEM;
    }
    size_t nstrat;
    size_t n = est_first_angles(ti_min, ti_max, test_angles, seed, knots, nknots, min_gap, ti,
                                &nstrat);
    int screen = opt && opt->l1_only && opt->screen_ppa > 0 && opt->screen_nuni > 0 &&
                 opt->screen_ppa < points_per_angle && opt->screen_nuni < j.nmu;
    size_t full_nu = j.nu, full_nuni = j.nmu;
    if (screen) {
        j.ppa = opt->screen_ppa;
        j.nu = (opt->screen_ppa + 31) / 32;
        j.nmu = j.nphi = opt->screen_nuni;
    }
    run_angles(&j, threads, ti, nstrat, res, points);
    if (n > nstrat)
        run_angles(&j, threads, ti + nstrat, n - nstrat, res + nstrat, points + nstrat);
    if (screen)
        est_screen(&j, opt, threads, points_per_angle, full_nu, full_nuni, ti, n, res, points);
    int refine = 1;
    if (j.stop_above > 0.0) /* the answer is known: the worst is above stop_above */
        for (size_t k = 0; k < n && refine; k++)
            refine = !(res[k].e_l1 > j.stop_above);
    for (int round = 0; refine && round < REFINE_ROUNDS && span > 0.0; round++) {
        double *add = malloc((2 * n + 2) * sizeof *add);
        size_t na = add ? est_refine_points(&j, res, n, min_gap, add) : 0;
        if (na == 0 || n + na > cap) {
            free(add);
            break;
        }
        memcpy(ti + n, add, na * sizeof *add);
        free(add);
        run_angles(&j, threads, ti + n, na, res + n, points + n);
        n += na;
    }
    free(ti);
    est_summarise(res, points, n, nstrat, r);
    free(points);
    r->seconds_estimate = core_now() - t0;
    return BTDF_OK;
}

btdf_status est_knots(const btdf_params *p, double ti_min, double ti_max,
                                size_t test_angles, size_t points_per_angle, uint64_t seed,
                                int threads, const double *knots, size_t nknots,
                                est_eval_fn fn, const void *obj, albedo_memo *memo,
                                btdf_report *r)
{
    return estimate_impl(p, 0, ti_min, ti_max, test_angles, points_per_angle, seed, threads,
                         knots, nknots, fn, NULL, NULL, obj, NULL, memo, r);
}

btdf_status est_knots_prep(const btdf_params *p, double ti_min, double ti_max,
                                     size_t test_angles, size_t points_per_angle,
                                     uint64_t seed, int threads, const double *knots,
                                     size_t nknots, est_eval_fn fn, est_prep_fn prep,
                                     est_done_fn done, const void *obj, const est_opts *opt,
                                     albedo_memo *memo, btdf_report *r)
{
    return estimate_impl(p, 0, ti_min, ti_max, test_angles, points_per_angle, seed, threads,
                         knots, nknots, fn, prep, done, obj, opt, memo, r);
}

btdf_status est_knots_prep_part(const btdf_params *p, int refl, double ti_min, double ti_max,
                                size_t test_angles, size_t points_per_angle, uint64_t seed,
                                int threads, const double *knots, size_t nknots,
                                est_eval_fn fn, est_prep_fn prep, est_done_fn done,
                                const void *obj, const est_opts *opt, albedo_memo *memo,
                                btdf_report *r)
{
    return estimate_impl(p, refl, ti_min, ti_max, test_angles, points_per_angle, seed, threads,
                         knots, nknots, fn, prep, done, obj, opt, memo, r);
}

btdf_status est_fn(const btdf_params *p, double ti_min, double ti_max,
                             size_t test_angles, size_t points_per_angle, uint64_t seed,
                             int threads, est_eval_fn fn, const void *obj, btdf_report *r)
{
    return estimate_impl(p, 0, ti_min, ti_max, test_angles, points_per_angle, seed, threads,
                         NULL, 0, fn, NULL, NULL, obj, NULL, NULL, r);
}

btdf_status est_knots_part(const btdf_params *p, int refl, double ti_min,
                                     double ti_max, size_t test_angles,
                                     size_t points_per_angle, uint64_t seed, int threads,
                                     const double *knots, size_t nknots, est_eval_fn fn,
                                     const void *obj, btdf_report *r)
{
    return estimate_impl(p, refl, ti_min, ti_max, test_angles, points_per_angle, seed, threads,
                         knots, nknots, fn, NULL, NULL, obj, NULL, NULL, r);
}

btdf_status est_knots_part_opt(const btdf_params *p, int refl, double ti_min,
                                         double ti_max, size_t test_angles,
                                         size_t points_per_angle, uint64_t seed, int threads,
                                         const double *knots, size_t nknots, est_eval_fn fn,
                                         const void *obj, const est_opts *opt, btdf_report *r)
{
    return estimate_impl(p, refl, ti_min, ti_max, test_angles, points_per_angle, seed, threads,
                         knots, nknots, fn, NULL, NULL, obj, opt, NULL, r);
}

btdf_status est_fn_r(const btdf_params *p, double ti_min, double ti_max,
                               size_t test_angles, size_t points_per_angle, uint64_t seed,
                               int threads, est_eval_fn fn, const void *obj, btdf_report *r)
{
    return estimate_impl(p, 1, ti_min, ti_max, test_angles, points_per_angle, seed, threads,
                         NULL, 0, fn, NULL, NULL, obj, NULL, NULL, r);
}

BTDF_API void btdf_report_clear(btdf_report *r)
{
    if (!r)
        return;
    free(r->per_ti);
    r->per_ti = NULL;
}
