/* SPDX-License-Identifier: MIT */
/* sim.c: btdf_sim_run: options, the batches and their threads, and the reduction of
   the tallies into means with batch-means standard errors.

   Work: for every (channel, angle) job the rays are cut into the same batches; batch b
   runs on surface realisation b (white-noise stream (seed, SURFACE, b)) with rays from
   stream (seed, RAYS + angle, b). A worker takes the next (batch, job) item, and since
   items of one batch are adjacent, usually keeps its surface for the next item. Each
   batch's counts are stored in its own slot and summed in batch order at the end;
   histogram counts are summed per thread as integers, which add exactly in any order.
   So no result depends on which thread ran what. */
#include "btdf_sim.h"

#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "sim/pane.h"
#include "sim/rng.h"
#include "sim/surface.h"
#include "sim/trace.h"

enum { PURPOSE_SURFACE = 1, PURPOSE_BACK = 2, PURPOSE_RAYS = 0x1000 };

/* Counts of one batch of one job. */
enum { Q_R1, Q_R2, Q_R3, Q_T1, Q_T2, Q_T3, Q_LOST, Q_HITS, Q_COUNT };

#define BATCH_MAX ((uint64_t)1 << 22) /* rays per batch: keeps sums of squares < 2^63 */
#define BINS_MAX 3600
/* Realisations whose statistics are measured (the first ones): the autocorrelation
   costs about as much as making the surface, and 32 give the means to under 1 %. */
#define STATS_REALISATIONS 32

static btdf_status say(btdf_status st, char *msg, size_t msglen, const char *fmt, ...)
{
    if (msg && msglen) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(msg, msglen, fmt, ap);
        va_end(ap);
    }
    return st;
}

BTDF_API void btdf_sim_opts_default(btdf_sim_opts *o)
{
    memset(o, 0, sizeof *o);
    o->channels = 1;
    o->ior[0] = o->ior[1] = o->ior[2] = 1.5;
    o->smoothness = 3.0;
    o->rays = 1000000;
    o->seed = 1;
    o->cells_per_tau = 16;
    o->tile_tau = 16;
    o->accel = 0; /* the plain DDA: faster than the hierarchy at ti = 30 (btdf-bench sim) */
    o->phi_bins = 1;
}

/* Rays per batch. A batch is one surface realisation, the unit of the error: every
   ray of realisation b (of every angle and channel) sees the same surface, so the
   error of a mean is the spread between realisations over sqrt(batches), which holds
   the surface-to-surface spread whole. Making a 256 x 256 surface costs about as much
   as 5,000 paths at s = 3, so a realisation carries at least RAYS_PER_REAL rays once
   there are 32 of them (surface under 5 % of the time): 32 realisations up to 3.2e6
   rays (the error of a standard error is then 1/sqrt(62) = 13 %), then more up to 128
   (6 %), then larger ones, never more than BATCH_MAX rays in one. */
#define RAYS_PER_REAL 100000
static uint64_t batch_size(const btdf_sim_opts *o)
{
    if (o->batch_rays)
        return o->batch_rays;
    uint64_t nb = o->rays / RAYS_PER_REAL;
    nb = nb < 32 ? 32 : nb > 128 ? 128 : nb;
    nb = nb > o->rays ? o->rays : nb; /* rays >= 2: at least two batches */
    uint64_t b = (o->rays + nb - 1) / nb;
    return b > BATCH_MAX ? BATCH_MAX : b;
}

static int grid_n(const btdf_sim_opts *o)
{
    return o->cells_per_tau * o->tile_tau;
}

static int threads_of(const btdf_sim_opts *o)
{
    if (o->threads > 0)
        return o->threads;
    long t = sysconf(_SC_NPROCESSORS_ONLN);
    return t < 1 ? 1 : t > 256 ? 256 : (int)t;
}

static size_t hist_bins(const btdf_sim_opts *o)
{
    return o->theta_bins > 0 ? (size_t)o->theta_bins * (size_t)o->phi_bins : 0;
}

/* Bytes a run takes: per thread a tile, its scratch and the histogram sums; per job
   and batch one slot of counts; the result's histograms. */
static double memory_needed(const btdf_sim_opts *o, uint64_t nb)
{
    double n = (double)grid_n(o), jobs = (double)o->channels * (double)o->n_theta;
    int rows = o->profile ? 1 : (int)n; /* a profile is a strip */
    double tile =
        (double)sim_surface_bytes((int)n, rows) + (double)sim_scratch_bytes((int)n, rows);
    if (o->pane && o->back_smoothness > 0.0)
        tile += (double)sim_surface_bytes((int)n, rows); /* the back face's tile */
    double hist = (double)hist_bins(o) * 4.0;
    return (double)threads_of(o) * (tile + hist * jobs * 3.0 * 8.0) +
           jobs * (double)nb * Q_COUNT * 8.0 + jobs * hist * sizeof(btdf_sim_est);
}

BTDF_API btdf_status btdf_sim_opts_check(const btdf_sim_opts *o, char *msg, size_t msglen)
{
    if (!o)
        return say(BTDF_EINVAL, msg, msglen, "options missing");
    btdf_params p;
    btdf_params_default(&p);
    p.channels = o->channels;
    for (int c = 0; c < BTDF_MAX_CHANNELS; c++)
        p.ior[c] = o->ior[c];
    p.smoothness = o->smoothness;
    btdf_status st = btdf_params_check(&p, msg, msglen);
    if (st != BTDF_OK)
        return st;
    if (o->n_theta == 0 || !o->theta_i)
        return say(BTDF_EINVAL, msg, msglen, "no incident angle given");
    if (o->n_theta > 100000)
        return say(BTDF_EINVAL, msg, msglen, "%zu incident angles: at most 100000", o->n_theta);
    for (size_t k = 0; k < o->n_theta; k++) {
        double t = o->theta_i[k];
        if (!isfinite(t) || t < 0.0 || t >= 1.5707963267948966)
            return say(BTDF_EINVAL, msg, msglen,
                       "incident angle %g deg: must lie in [0, 90) deg", t * 57.29577951308232);
    }
    if (o->rays < 2 || o->rays > BTDF_SIM_RAYS_MAX)
        return say(BTDF_EINVAL, msg, msglen,
                   "rays %llu: must lie in [2, %llu] per angle and channel",
                   (unsigned long long)o->rays, (unsigned long long)BTDF_SIM_RAYS_MAX);
    if (o->batch_rays && (o->batch_rays > BATCH_MAX || o->rays / o->batch_rays < 2))
        return say(BTDF_EINVAL, msg, msglen,
                   "batch of %llu rays: must be at most %llu and leave at least two batches",
                   (unsigned long long)o->batch_rays, (unsigned long long)BATCH_MAX);
    if (o->cells_per_tau < BTDF_SIM_CELLS_PER_TAU_MIN ||
        o->cells_per_tau > BTDF_SIM_CELLS_PER_TAU_MAX)
        return say(BTDF_EINVAL, msg, msglen, "cells per correlation length %d: must lie in [%d, %d]",
                   o->cells_per_tau, BTDF_SIM_CELLS_PER_TAU_MIN, BTDF_SIM_CELLS_PER_TAU_MAX);
    if (o->tile_tau < BTDF_SIM_TILE_TAU_MIN || o->tile_tau > BTDF_SIM_TILE_TAU_MAX)
        return say(BTDF_EINVAL, msg, msglen, "tile of %d correlation lengths: must lie in [%d, %d]",
                   o->tile_tau, BTDF_SIM_TILE_TAU_MIN, BTDF_SIM_TILE_TAU_MAX);
    int n = grid_n(o);
    if (n > BTDF_SIM_N_MAX || (n & (n - 1)) != 0)
        return say(BTDF_EINVAL, msg, msglen,
                   "grid of %d points per side (cells per tau %d x tile %d): must be a power "
                   "of two, at most %d",
                   n, o->cells_per_tau, o->tile_tau, BTDF_SIM_N_MAX);
    if (o->threads < 0 || o->threads > 1024)
        return say(BTDF_EINVAL, msg, msglen, "threads %d: must lie in [0, 1024]", o->threads);
    if (o->theta_bins < 0 || o->theta_bins > BINS_MAX ||
        (o->theta_bins > 0 && (o->phi_bins < 1 || o->phi_bins > BINS_MAX)))
        return say(BTDF_EINVAL, msg, msglen, "histogram of %d x %d bins: each must lie in [1, %d]",
                   o->theta_bins, o->phi_bins, BINS_MAX);
    if (o->accel != 0 && o->accel != 1)
        return say(BTDF_EINVAL, msg, msglen, "accel %d: must be 0 or 1", o->accel);
    if (o->profile != 0 && o->profile != 1)
        return say(BTDF_EINVAL, msg, msglen, "profile %d: must be 0 (2D surface) or 1 (1D "
                   "profile)", o->profile);
    st = sim_pane_check(o, msg, msglen);
    if (st != BTDF_OK)
        return st;
    uint64_t bs = batch_size(o), nb = (o->rays + bs - 1) / bs;
    double need = memory_needed(o, nb);
    if (o->max_memory && need > (double)o->max_memory)
        return say(BTDF_EBUDGET, msg, msglen,
                   "the surfaces and tallies need %.0f MB, above the memory limit of %.0f MB",
                   need / 1048576.0, (double)o->max_memory / 1048576.0);
    return BTDF_OK;
}

BTDF_API double btdf_sim_bin_solid_angle(int theta_bins, int phi_bins, int theta_bin,
                                         int phi_bin)
{
    (void)phi_bin; /* every |phi| bin has the same width */
    if (theta_bins < 1 || phi_bins < 1 || theta_bin < 0 || theta_bin >= theta_bins)
        return 0.0;
    double w = 1.5707963267948966 / theta_bins;
    double ca = cos(w * theta_bin), cb = cos(w * (theta_bin + 1));
    return (ca - cb) * 2.0 * (3.141592653589793 / phi_bins);
}

/* ------------------------------------------------------------------------- */

typedef struct run_ctx {
    const btdf_sim_opts *o;
    const sim_gen *gen;
    const sim_gen *gen_back; /* a pane's rough back face, else NULL */
    uint64_t bs, nb;  /* batch size, batches per job */
    uint64_t b0, b1;  /* the batches this run traces or reduces: [b0, b1) */
    size_t jobs, bins;
    uint64_t items, next;
    uint64_t *counts;            /* [(job * nb + b) * Q_COUNT + q] */
    sim_surface_stats *stats;    /* [b] */
    unsigned char *stats_done;   /* [b] */
    uint64_t done_rays, total_rays;
    double run_c, run_c2, run_n; /* running T of the first job, for progress only */
    uint64_t run_b;
    int failed;
    pthread_mutex_t mu;
} run_ctx;

/* Per-thread histogram sums: [((job * 4 + h) * bins + bin) * 3 + {c, c^2, c n}]. */
typedef struct worker {
    run_ctx *rc;
    uint64_t *hsum;
    uint32_t *hcount; /* one batch's counts, [h * bins + bin] */
} worker;

static void bin_of(const run_ctx *rc, const double dir[3], size_t *bin)
{
    int nt = rc->o->theta_bins, np = rc->o->phi_bins;
    double z = fabs(dir[2]);
    z = z < 1.0 ? z : 1.0;
    int it = (int)(acos(z) * (nt / 1.5707963267948966));
    it = it < nt ? it : nt - 1;
    int ip = (int)(fabs(atan2(dir[1], dir[0])) * (np / 3.141592653589793));
    ip = ip < np ? ip : np - 1;
    *bin = (size_t)it * (size_t)np + (size_t)ip;
}

static void run_batch(worker *wk, const sim_surface *surf, const sim_surface *back, size_t job,
                      uint64_t b)
{
    run_ctx *rc = wk->rc;
    const btdf_sim_opts *o = rc->o;
    size_t k = job % o->n_theta;
    int ch = (int)(job / o->n_theta);
    uint64_t n = rc->bs, first = b * rc->bs;
    n = first + n > o->rays ? o->rays - first : n;
    /* the same rays for every channel: differences between channels are sharper */
    uint64_t rng = sim_stream(o->seed, PURPOSE_RAYS + k, b);
    uint64_t q[Q_COUNT] = {0};
    if (rc->bins)
        memset(wk->hcount, 0, 4 * rc->bins * sizeof *wk->hcount);
    const sim_surface *front = o->front_flat ? NULL : surf;
    sim_pane pane = {{o->from_back ? back : front, o->from_back ? front : back}, o->ior[ch],
                     o->thickness_mm, o->absorption_per_mm};
    double st = sin(o->theta_i[k]), ct = cos(o->theta_i[k]); /* the same for every ray */
    for (uint64_t r = 0; r < n; r++) {
        sim_path p;
        if (o->pane)
            sim_pane_path(&pane, o->theta_i[k], o->accel, &rng, &p);
        else
            sim_path_run(surf, o->ior[ch], st, ct, o->accel, o->profile, &rng, &p);
        q[Q_HITS] += (uint64_t)p.hits;
        if (p.end == SIM_END_LOST) {
            q[Q_LOST]++;
            continue;
        }
        if (p.end == SIM_END_ABSORBED) /* counted as rays - R - T - lost */
            continue;
        int ord = p.hits < 3 ? p.hits - 1 : 2;
        ord = ord < 0 ? 0 : ord; /* every path hits at least once; kept in range */
        q[(p.end == SIM_END_R ? Q_R1 : Q_T1) + ord]++;
        if (rc->bins) {
            size_t bin;
            bin_of(rc, p.dir, &bin);
            size_t h = p.end == SIM_END_R ? 2 : 0;
            wk->hcount[h * rc->bins + bin]++;
            if (p.hits == 1)
                wk->hcount[(h + 1) * rc->bins + bin]++;
        }
    }
    memcpy(rc->counts + (job * rc->nb + b) * Q_COUNT, q, sizeof q);
    if (rc->bins) {
        uint64_t *hs = wk->hsum + job * 4 * rc->bins * 3;
        for (size_t i = 0; i < 4 * rc->bins; i++) {
            uint64_t c = wk->hcount[i];
            if (c) {
                hs[i * 3] += c;
                hs[i * 3 + 1] += c * c;
                hs[i * 3 + 2] += c * n;
            }
        }
    }
}

static void *worker_main(void *arg)
{
    worker *wk = arg;
    run_ctx *rc = wk->rc;
    sim_scratch *scr = sim_scratch_new(rc->gen);
    sim_surface surf, back;
    memset(&surf, 0, sizeof surf);
    memset(&back, 0, sizeof back);
    uint64_t have = UINT64_MAX;
    if (!scr) {
        pthread_mutex_lock(&rc->mu);
        rc->failed = 1;
        pthread_mutex_unlock(&rc->mu);
        return NULL;
    }
    for (;;) {
        pthread_mutex_lock(&rc->mu);
        uint64_t it = rc->failed ? rc->items : rc->next;
        if (it < rc->items)
            rc->next++;
        pthread_mutex_unlock(&rc->mu);
        if (it >= rc->items)
            break;
        uint64_t b = rc->b0 + it / rc->jobs;
        size_t job = (size_t)(it % rc->jobs);
        if (b != have) {
            sim_surface_free(&surf);
            sim_surface_stats st;
            int measured = b < STATS_REALISATIONS;
            int (*gen)(const sim_gen *, sim_scratch *, uint64_t, sim_surface *,
                       sim_surface_stats *) = rc->o->profile ? sim_gen_profile : sim_gen_surface;
            if (gen(rc->gen, scr, sim_stream(rc->o->seed, PURPOSE_SURFACE, b), &surf,
                    measured ? &st : NULL) != 0) {
                pthread_mutex_lock(&rc->mu);
                rc->failed = 1;
                pthread_mutex_unlock(&rc->mu);
                break;
            }
            if (rc->gen_back) {
                sim_surface_free(&back);
                if (sim_gen_surface(rc->gen_back, scr, sim_stream(rc->o->seed, PURPOSE_BACK, b),
                                    &back, NULL) != 0) {
                    pthread_mutex_lock(&rc->mu);
                    rc->failed = 1;
                    pthread_mutex_unlock(&rc->mu);
                    break;
                }
            }
            have = b;
            /* every thread that makes realisation b measures the same numbers */
            if (measured) {
                rc->stats[b] = st;
                rc->stats_done[b] = 1;
            }
        }
        run_batch(wk, &surf, rc->gen_back ? &back : NULL, job, b);
        pthread_mutex_lock(&rc->mu);
        const uint64_t *q = rc->counts + (job * rc->nb + b) * Q_COUNT;
        uint64_t n = b * rc->bs + rc->bs > rc->o->rays ? rc->o->rays - b * rc->bs : rc->bs;
        rc->done_rays += n;
        if (job == 0) {
            double c = (double)(q[Q_T1] + q[Q_T2] + q[Q_T3]) / (double)n;
            rc->run_c += c;
            rc->run_c2 += c * c;
            rc->run_b++;
        }
        if (rc->o->progress) {
            double se = NAN;
            if (rc->run_b > 1) {
                double m = rc->run_c / (double)rc->run_b;
                double v = (rc->run_c2 / (double)rc->run_b - m * m) / (double)(rc->run_b - 1);
                se = sqrt(v > 0.0 ? v : 0.0); /* rounding can make v slightly negative */
            }
            rc->o->progress(rc->o->progress_ctx, rc->done_rays, rc->total_rays, se);
        }
        pthread_mutex_unlock(&rc->mu);
    }
    sim_surface_free(&surf);
    sim_surface_free(&back);
    sim_scratch_free(scr);
    return NULL;
}

/* Ratio estimate sum c / sum n and its batch-means error, from the exact integer sums
   of c, c^2, c n over B batches (sum n and sum n^2 given). */
static btdf_sim_est ratio_est(double sc, double sc2, double scn, double sn, double sn2,
                              double B)
{
    btdf_sim_est e = {0.0, 0.0};
    if (sn <= 0.0)
        return e;
    e.mean = sc / sn;
    if (B < 2.0)
        return e;
    double p = e.mean;
    double ss = sc2 - 2.0 * p * scn + p * p * sn2; /* sum (c_b - p n_b)^2 */
    ss = ss > 0.0 ? ss : 0.0;                      /* cancellation can leave -0 */
    double nbar = sn / B;
    e.se = sqrt(ss / (B - 1.0) / B) / nbar;
    return e;
}

static void reduce_job(const run_ctx *rc, size_t job, btdf_sim_tally *t)
{
    double s[Q_COUNT] = {0}, s2[Q_COUNT] = {0}, sn_[Q_COUNT] = {0}, sn = 0.0, sn2 = 0.0;
    double sR = 0, sR2 = 0, sRn = 0, sT = 0, sT2 = 0, sTn = 0, sA = 0, sA2 = 0, sAn = 0;
    for (uint64_t b = rc->b0; b < rc->b1; b++) {
        const uint64_t *q = rc->counts + (job * rc->nb + b) * Q_COUNT;
        double n = (double)(b * rc->bs + rc->bs > rc->o->rays ? rc->o->rays - b * rc->bs
                                                               : rc->bs);
        sn += n;
        sn2 += n * n;
        for (int i = 0; i < Q_COUNT; i++) {
            double c = (double)q[i];
            s[i] += c;
            s2[i] += c * c;
            sn_[i] += c * n;
        }
        double R = (double)(q[Q_R1] + q[Q_R2] + q[Q_R3]), T = (double)(q[Q_T1] + q[Q_T2] + q[Q_T3]);
        sR += R;
        sR2 += R * R;
        sRn += R * n;
        sT += T;
        sT2 += T * T;
        sTn += T * n;
        double A = n - R - T - (double)q[Q_LOST]; /* absorbed: exact in doubles below 2^53 */
        sA += A;
        sA2 += A * A;
        sAn += A * n;
    }
    double B = (double)(rc->b1 - rc->b0);
    t->R = ratio_est(sR, sR2, sRn, sn, sn2, B);
    t->T = ratio_est(sT, sT2, sTn, sn, sn2, B);
    t->A = ratio_est(sA, sA2, sAn, sn, sn2, B);
    for (int i = 0; i < BTDF_SIM_ORDERS; i++) {
        t->R_order[i] = ratio_est(s[Q_R1 + i], s2[Q_R1 + i], sn_[Q_R1 + i], sn, sn2, B);
        t->T_order[i] = ratio_est(s[Q_T1 + i], s2[Q_T1 + i], sn_[Q_T1 + i], sn, sn2, B);
    }
    t->mean_hits = ratio_est(s[Q_HITS], s2[Q_HITS], sn_[Q_HITS], sn, sn2, B);
    t->rays = (uint64_t)sn;
    t->lost = (uint64_t)s[Q_LOST];
    t->batches = rc->b1 - rc->b0;
}

BTDF_API void btdf_sim_result_free(btdf_sim_result *r)
{
    if (!r)
        return;
    if (r->tally)
        for (size_t k = 0; k < r->count; k++) {
            free(r->tally[k].hist_T);
            free(r->tally[k].hist_T1);
            free(r->tally[k].hist_R);
            free(r->tally[k].hist_R1);
        }
    free(r->tally);
    free(r->raw_counts);
    free(r->raw_hist);
    free(r->raw_stats);
    free(r);
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* The histograms of every job from the threads' integer sums. */
static int reduce_hist(const run_ctx *rc, const uint64_t *hraw, btdf_sim_result *res)
{
    size_t bins = rc->bins, per = 4 * bins * 3;
    double sn = 0.0, sn2 = 0.0;
    for (uint64_t b = rc->b0; b < rc->b1; b++) {
        double n = (double)(b * rc->bs + rc->bs > rc->o->rays ? rc->o->rays - b * rc->bs
                                                               : rc->bs);
        sn += n;
        sn2 += n * n;
    }
    for (size_t job = 0; job < rc->jobs; job++) {
        btdf_sim_tally *t = &res->tally[job];
        btdf_sim_est **h[4] = {&t->hist_T, &t->hist_T1, &t->hist_R, &t->hist_R1};
        for (int k = 0; k < 4; k++) {
            *h[k] = calloc(bins, sizeof(btdf_sim_est));
            if (!*h[k])
                return -1;
            for (size_t i = 0; i < bins; i++) {
                const uint64_t *hs = hraw + job * per + ((size_t)k * bins + i) * 3;
                (*h[k])[i] = ratio_est((double)hs[0], (double)hs[1], (double)hs[2], sn, sn2,
                                       (double)(rc->b1 - rc->b0));
            }
        }
    }
    return 0;
}

/* The result from the counts of batches [b0, b1), the histograms' integer sums hraw
   and the measured realisations: the tallies, the histograms, the surface, and a copy
   of the raw integers (so shards can be merged). */
static btdf_status finish(const run_ctx *rc, const uint64_t *hraw, btdf_sim_result *res)
{
    const btdf_sim_opts *o = rc->o;
    int n = grid_n(o);
    double tau = o->smoothness;
    for (size_t job = 0; job < rc->jobs; job++) {
        btdf_sim_tally *t = &res->tally[job];
        t->theta_i = o->theta_i[job % o->n_theta];
        t->channel = (int)(job / o->n_theta);
        t->ior = o->ior[t->channel];
        reduce_job(rc, job, t);
        res->rays_traced += t->rays;
        res->hits_traced += (uint64_t)llround(t->mean_hits.mean * (double)t->rays);
    }
    if (rc->bins && reduce_hist(rc, hraw, res) != 0)
        return BTDF_ENOMEM;
    res->smoothness = o->smoothness;
    res->profile = o->profile;
    res->pane = o->pane;
    res->theta_bins = rc->bins ? o->theta_bins : 0;
    res->phi_bins = rc->bins ? o->phi_bins : 0;
    btdf_sim_surface *sf = &res->surface;
    sf->n = n;
    sf->dx = tau / o->cells_per_tau;
    sf->tile = sf->dx * n;
    sf->tile_bytes = sim_surface_bytes(n, o->profile ? 1 : n);
    double a = 0, b = 0, c = 0;
    int made = 0;
    for (uint64_t i = rc->b0; i < rc->b1; i++)
        if (rc->stats_done[i]) {
            a += rc->stats[i].rms_height * rc->stats[i].rms_height;
            b += rc->stats[i].rms_slope * rc->stats[i].rms_slope;
            c += rc->stats[i].corr_length;
            made++;
        }
    sf->realisations = made;
    /* made is 0 only for a shard past the first 32 realisations */
    sf->rms_height = made ? sqrt(a / made) : 0.0;
    sf->rms_slope = made ? sqrt(b / made) : 0.0;
    sf->corr_length = made ? c / made : 0.0;
    uint64_t nb = rc->b1 - rc->b0;
    res->batches_total = rc->nb;
    res->batch_first = rc->b0;
    res->batch_end = rc->b1;
    res->raw_counts = calloc(rc->jobs * nb * Q_COUNT, sizeof *res->raw_counts);
    res->raw_stats = calloc(nb * 3, sizeof *res->raw_stats);
    if (!res->raw_counts || !res->raw_stats)
        return BTDF_ENOMEM;
    for (size_t job = 0; job < rc->jobs; job++)
        memcpy(res->raw_counts + job * nb * Q_COUNT, rc->counts + (job * rc->nb + rc->b0) * Q_COUNT,
               nb * Q_COUNT * sizeof *res->raw_counts);
    for (uint64_t i = 0; i < nb; i++)
        if (rc->stats_done[rc->b0 + i]) {
            res->raw_stats[i * 3] = rc->stats[rc->b0 + i].rms_height;
            res->raw_stats[i * 3 + 1] = rc->stats[rc->b0 + i].rms_slope;
            res->raw_stats[i * 3 + 2] = rc->stats[rc->b0 + i].corr_length;
        }
    if (rc->bins) {
        size_t len = rc->jobs * 4 * rc->bins * 3;
        res->raw_hist = malloc(len * sizeof *res->raw_hist);
        if (!res->raw_hist)
            return BTDF_ENOMEM;
        memcpy(res->raw_hist, hraw, len * sizeof *res->raw_hist);
    }
    return BTDF_OK;
}

BTDF_API uint64_t btdf_sim_batch_count(const btdf_sim_opts *o)
{
    uint64_t bs = batch_size(o);
    return (o->rays + bs - 1) / bs;
}

BTDF_API btdf_status btdf_sim_run(const btdf_sim_opts *o, btdf_sim_result **out, char *msg,
                                  size_t msglen)
{
    btdf_status st = btdf_sim_opts_check(o, msg, msglen);
    if (st != BTDF_OK)
        return st;
    if (!out)
        return say(BTDF_EINVAL, msg, msglen, "no result pointer");
    int n = grid_n(o), nthreads = threads_of(o);
    double tau = o->smoothness; /* sigma = 1 */
    run_ctx rc;
    memset(&rc, 0, sizeof rc);
    rc.o = o;
    rc.bs = batch_size(o);
    rc.nb = (o->rays + rc.bs - 1) / rc.bs;
    rc.b0 = 0;
    rc.b1 = rc.nb;
    if (o->batch_end) {
        if (o->batch_first >= o->batch_end || o->batch_end > rc.nb)
            return say(BTDF_EINVAL, msg, msglen,
                       "batches [%llu, %llu): must be a non-empty range within [0, %llu)",
                       (unsigned long long)o->batch_first, (unsigned long long)o->batch_end,
                       (unsigned long long)rc.nb);
        rc.b0 = o->batch_first;
        rc.b1 = o->batch_end;
    }
    rc.jobs = (size_t)o->channels * o->n_theta;
    rc.bins = hist_bins(o);
    rc.items = (rc.b1 - rc.b0) * rc.jobs;
    rc.total_rays = 0;
    for (uint64_t b = rc.b0; b < rc.b1; b++)
        rc.total_rays += (b * rc.bs + rc.bs > o->rays ? o->rays - b * rc.bs : rc.bs) * rc.jobs;
    btdf_sim_result *res = calloc(1, sizeof *res);
    worker *wk = calloc((size_t)nthreads, sizeof *wk);
    pthread_t *th = calloc((size_t)nthreads, sizeof *th);
    sim_gen *gen = o->profile ? sim_gen_new_profile(n, tau / o->cells_per_tau, tau)
                              : sim_gen_new(n, tau / o->cells_per_tau, tau);
    double tb = o->back_smoothness; /* the back face's tau */
    sim_gen *gen_back = o->pane && tb > 0.0 ? sim_gen_new(n, tb / o->cells_per_tau, tb) : NULL;
    rc.gen = gen;
    rc.gen_back = gen_back;
    rc.counts = calloc(rc.jobs * rc.nb * Q_COUNT, sizeof *rc.counts);
    rc.stats = calloc(rc.nb, sizeof *rc.stats);
    rc.stats_done = calloc(rc.nb, 1);
    int started = 0;
    uint64_t *hraw = NULL;
    st = BTDF_ENOMEM;
    if (!res || !wk || !th || !gen || !rc.counts || !rc.stats || !rc.stats_done ||
        (o->pane && tb > 0.0 && !gen_back))
        goto done;
    res->tally = calloc(rc.jobs, sizeof *res->tally);
    if (!res->tally)
        goto done;
    res->count = rc.jobs;
    for (int w = 0; w < nthreads; w++) {
        wk[w].rc = &rc;
        if (rc.bins) {
            wk[w].hsum = calloc(rc.jobs * 4 * rc.bins * 3, sizeof *wk[w].hsum);
            wk[w].hcount = calloc(4 * rc.bins, sizeof *wk[w].hcount);
            if (!wk[w].hsum || !wk[w].hcount)
                goto done;
        }
    }
    pthread_mutex_init(&rc.mu, NULL);
    double t0 = now_s();
    for (; started < nthreads; started++)
        if (pthread_create(&th[started], NULL, worker_main, &wk[started]) != 0)
            break;
    if (started == 0)
        worker_main(&wk[0]); /* no thread could start: this one does the work */
    for (int w = 0; w < started; w++)
        pthread_join(th[w], NULL);
    res->seconds = now_s() - t0;
    pthread_mutex_destroy(&rc.mu);
    if (rc.failed)
        goto done;
    /* the threads' integer histogram sums (threads that never started hold zeros) */
    if (rc.bins) {
        size_t len = rc.jobs * 4 * rc.bins * 3;
        hraw = calloc(len, sizeof *hraw);
        if (!hraw)
            goto done;
        for (int w = 0; w < nthreads; w++)
            for (size_t i = 0; i < len; i++)
                hraw[i] += wk[w].hsum[i];
    }
    if (finish(&rc, hraw, res) != BTDF_OK)
        goto done;
    *out = res;
    res = NULL;
    st = BTDF_OK;
done:
    if (st == BTDF_ENOMEM)
        say(st, msg, msglen, "out of memory for the surfaces and tallies");
    if (wk)
        for (int w = 0; w < nthreads; w++) {
            free(wk[w].hsum);
            free(wk[w].hcount);
        }
    free(wk);
    free(th);
    free(rc.counts);
    free(rc.stats);
    free(rc.stats_done);
    free(hraw);
    sim_gen_free(gen);
    sim_gen_free(gen_back);
    btdf_sim_result_free(res);
    return st;
}

BTDF_API btdf_status btdf_sim_merge(const btdf_sim_opts *o, const btdf_sim_result *const *parts,
                                    size_t nparts, btdf_sim_result **out, char *msg,
                                    size_t msglen)
{
    btdf_status st = btdf_sim_opts_check(o, msg, msglen);
    if (st != BTDF_OK)
        return st;
    if (!out || !parts || nparts == 0)
        return say(BTDF_EINVAL, msg, msglen, "no parts to merge");
    run_ctx rc;
    memset(&rc, 0, sizeof rc);
    rc.o = o;
    rc.bs = batch_size(o);
    rc.nb = (o->rays + rc.bs - 1) / rc.bs;
    rc.b0 = 0;
    rc.b1 = rc.nb;
    rc.jobs = (size_t)o->channels * o->n_theta;
    rc.bins = hist_bins(o);
    size_t hlen = rc.jobs * 4 * rc.bins * 3;
    rc.counts = calloc(rc.jobs * rc.nb * Q_COUNT, sizeof *rc.counts);
    rc.stats = calloc(rc.nb, sizeof *rc.stats);
    rc.stats_done = calloc(rc.nb, 1);
    unsigned char *have = calloc(rc.nb, 1);
    uint64_t *hraw = calloc(hlen ? hlen : 1, sizeof *hraw);
    btdf_sim_result *res = calloc(1, sizeof *res);
    st = BTDF_ENOMEM;
    if (!rc.counts || !rc.stats || !rc.stats_done || !have || !hraw || !res)
        goto done;
    res->tally = calloc(rc.jobs, sizeof *res->tally);
    if (!res->tally)
        goto done;
    res->count = rc.jobs;
    for (size_t p = 0; p < nparts; p++) {
        const btdf_sim_result *r = parts[p];
        uint64_t nb = r ? r->batch_end - r->batch_first : 0;
        if (!r || r->batches_total != rc.nb || r->count != rc.jobs || !r->raw_counts ||
            r->batch_end > rc.nb || nb == 0 || (rc.bins && !r->raw_hist) ||
            (!rc.bins && r->raw_hist)) {
            st = say(BTDF_EINVAL, msg, msglen,
                     "part %zu: not a run of these options (batches, cases or bins differ)", p + 1);
            goto done;
        }
        for (uint64_t i = 0; i < nb; i++) {
            uint64_t b = r->batch_first + i;
            if (have[b]) {
                st = say(BTDF_EINVAL, msg, msglen, "batch %llu is in two parts",
                         (unsigned long long)b);
                goto done;
            }
            have[b] = 1;
            for (size_t job = 0; job < rc.jobs; job++)
                memcpy(rc.counts + (job * rc.nb + b) * Q_COUNT,
                       r->raw_counts + (job * nb + i) * Q_COUNT, Q_COUNT * sizeof *rc.counts);
            if (b < STATS_REALISATIONS) {
                rc.stats[b].rms_height = r->raw_stats[i * 3];
                rc.stats[b].rms_slope = r->raw_stats[i * 3 + 1];
                rc.stats[b].corr_length = r->raw_stats[i * 3 + 2];
                rc.stats_done[b] = 1;
            }
        }
        for (size_t i = 0; i < hlen; i++)
            hraw[i] += r->raw_hist[i]; /* integers: exact in any order */
        res->seconds += r->seconds;
    }
    for (uint64_t b = 0; b < rc.nb; b++)
        if (!have[b]) {
            st = say(BTDF_EINVAL, msg, msglen, "batch %llu of %llu is in no part",
                     (unsigned long long)b, (unsigned long long)rc.nb);
            goto done;
        }
    st = finish(&rc, hraw, res);
    if (st != BTDF_OK)
        goto done;
    *out = res;
    res = NULL;
done:
    if (st == BTDF_ENOMEM)
        say(st, msg, msglen, "out of memory for the tallies");
    free(rc.counts);
    free(rc.stats);
    free(rc.stats_done);
    free(have);
    free(hraw);
    btdf_sim_result_free(res);
    return st;
}
