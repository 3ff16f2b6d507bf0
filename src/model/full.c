/* SPDX-License-Identifier: MIT */
/* full.c: the model `full` (docs/model.md section 12): the single scattering of
   `smith` plus the light the surface scatters two or more times, tallied once per
   material by a random walk on the Smith microsurface (Heitz et al. 2016, "Multiple-
   scattering microfacet BSDFs with the Smith model", the dielectric walk) and kept as a
   smooth series in the outgoing direction at a ladder of incidence angles. */
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "btdf.h"
#include "core/core.h"
#include "model/full.h"
#include "model/kernel.h"

/* The ladder of incidence angles (degrees) the walk is tallied at; between two the
   coefficients are interpolated linearly. Denser towards grazing, where the multiple
   scattering grows fastest; the last node stands in for 90 (a ray at exactly 90 degrees
   never meets the mean plane). */
static const double full_base_deg[] = {0,  5,  10, 15, 20, 25, 30, 35, 40, 45, 50,
                                       55, 60, 65, 70, 74, 78, 81, 84, 86, 87, 88,
                                       89, 89.5, 89.9};
#define FULL_BASE ((int)(sizeof full_base_deg / sizeof full_base_deg[0]))
/* For n < 1 the single scattering bends at the critical angle asin(n): the ladder gets
   these offsets (degrees) about it, so the linear interpolation follows the bend. */
static const double full_crit_off[] = {-6, -3, -1.5, -0.5, 0.5, 1.5, 3, 6};
#define FULL_CRIT ((int)(sizeof full_crit_off / sizeof full_crit_off[0]))
/* full.h sizes the object for this ladder */
typedef char full_ladder_fits[FULL_BASE + FULL_CRIT == FULL_NODES_MAX ? 1 : -1];
/* the public view of the series (btdf_full_get_series) has these sizes */
typedef char full_series_k_check[FULL_K == BTDF_FULL_SERIES_K ? 1 : -1];
typedef char full_series_m_check[FULL_M == BTDF_FULL_SERIES_M ? 1 : -1];
typedef char full_series_n_check[FULL_NODES_MAX == BTDF_FULL_SERIES_NODES ? 1 : -1];
typedef char full_series_sub_check[FULL_SUB == BTDF_FULL_SERIES_SUB ? 1 : -1];
/* ------------------------------------------------------------------------- */
/* The Smith microsurface (uniform heights in [-1, 1]; the walk's result does not
   depend on the height distribution, Heitz et al. 2016 sec. 3)                */
/* ------------------------------------------------------------------------- */

/* Lambda of the ray direction w (unit), signed as in Heitz et al. 2016: Lambda(w) >= 0
   for w going up, -1 - Lambda(-w) for w going down. */
static double walk_lambda(const double w[3], double s)
{
    double c = fabs(w[2]);
    double sn = sqrt(fmax(0.0, 1.0 - c * c)); /* rounding can push c above 1 */
    double l = bt_lambda(sn, c, s);
    return w[2] >= 0.0 ? l : -1.0 - l;
}

/* C1(h), the height distribution's CDF, floored so its logarithm stays finite. */
static double walk_c1(double h)
{
    double c = 0.5 * (h + 1.0);
    return c < 1e-300 ? 1e-300 : c > 1.0 ? 1.0 : c;
}

/* The next height along the ray (direction wr, from height hr), or INFINITY when the
   ray leaves the microsurface (Heitz et al. 2016, algorithm 2). */
static double walk_height(const double wr[3], double hr, double s, double u)
{
    double c1 = walk_c1(hr);
    double l1u = log(1.0 - u); /* u < 1, so 1 - u >= 2^-53: finite */
    if (wr[2] > 0.0) {
        double lam = walk_lambda(wr, s);
        if (!(lam > 0.0))
            return INFINITY; /* straight up: nothing shadows it */
        double lc = log(c1);
        if (l1u < lam * lc)
            return INFINITY; /* 1 - u < G1 = C1(hr)^Lambda: it escapes */
        double x = lc - l1u / lam; /* <= 0 by the test above */
        double c = exp(x < 0.0 ? x : 0.0);
        return 2.0 * c - 1.0;
    }
    if (wr[2] == 0.0)
        return hr; /* exactly horizontal: meets the surface where it is */
    /* going down: C1(h) = C1(hr) (1 - u)^(1 / (1 + Lambda(-wr))), always a hit */
    double lm = -1.0 - walk_lambda(wr, s); /* Lambda(-wr) >= 0 */
    double c = c1 * exp(l1u / (1.0 + lm));
    return 2.0 * c - 1.0;
}

/* The visible-slope x of the unit-roughness Beckmann surface seen from polar angle
   theta (sin st > 0, cos ct any sign), by inverting its CDF
     F(x) = (ct (1 + erf x)/2 + st exp(-x^2)/(2 sqrt(pi))) / A,  x <= cot theta
   (A the projected area; Heitz & d'Eon 2014) with a bracketed Newton iteration. */
static double walk_slope_x(double st, double ct, double u)
{
    const double isp = 0.28209479177387814; /* 1/(2 sqrt(pi)) */
    double cot = ct / st;                   /* st > 1e-12 by the caller */
    double hi = cot < 30.0 ? cot : 30.0;    /* erf is 1 in double past 6 */
    double lo = (hi < -8.0 ? hi : -8.0) - 8.0;
    double A = ct * 0.5 * (1.0 + erf(hi)) + st * isp * exp(-hi * hi);
    if (!(A > 1e-300))
        return hi; /* the surface is seen edge-on from below: the last visible slope */
    double x = hi < 0.0 ? hi - 0.5 : 0.0;
    for (int it = 0; it < 100 && hi - lo > 1e-13; it++) {
        double e = exp(-x * x);
        double f = (ct * 0.5 * (1.0 + erf(x)) + st * isp * e) / A - u;
        if (f > 0.0)
            hi = x;
        else
            lo = x;
        double d = e * (ct - x * st) * (2.0 * isp) / A; /* F'(x) >= 0 for x <= cot */
        double xn = d > 0.0 ? x - f / d : 0.5 * (lo + hi);
        if (!(xn > lo && xn < hi))
            xn = 0.5 * (lo + hi); /* Newton left the bracket: bisect */
        if (fabs(f) < 1e-14)
            break;
        x = xn;
    }
    return x;
}

/* A normal m of the Beckmann surface (alpha) visible from wi (unit, any hemisphere),
   by the stretching of Heitz & d'Eon 2014. */
static void walk_vndf(const double wi[3], double alpha, uint64_t *rng, double m[3])
{
    double vx = alpha * wi[0], vy = alpha * wi[1], vz = wi[2];
    double vl = sqrt(vx * vx + vy * vy + vz * vz); /* >= min(alpha, 1) > 0 */
    vx /= vl;
    vy /= vl;
    vz /= vl;
    double rxy = sqrt(vx * vx + vy * vy);
    double u1 = core_unif(rng), u2 = core_unif(rng), u3 = core_unif(rng);
    double gy = sqrt(-log(1.0 - u2)) * cos(2.0 * M_PI * u3); /* N(0, 1/2): Box-Muller */
    double sx, sy;
    if (rxy < 1e-12) { /* seen from straight above or below: the slopes themselves */
        double r = sqrt(-log(1.0 - u1)); /* the slope pair: N(0, 1/2) each */
        sx = r * cos(2.0 * M_PI * u2);
        sy = r * sin(2.0 * M_PI * u2);
        if (vz < 0.0) { /* from straight below nothing is visible but an edge */
            sx = 30.0;
        }
    } else {
        double x = walk_slope_x(rxy, vz, u1);
        double cp = vx / rxy, sp = vy / rxy;
        sx = cp * x - sp * gy;
        sy = sp * x + cp * gy;
    }
    sx *= alpha;
    sy *= alpha;
    double ml = sqrt(sx * sx + sy * sy + 1.0);
    m[0] = -sx / ml;
    m[1] = -sy / ml;
    m[2] = 1.0 / ml;
}

/* The walk of one path from wi (upper hemisphere). Returns 0 transmitted, 1 reflected,
   -1 lost; the outgoing direction in wo, the number of scattering events in *order. */
static int walk_path(const btdf_full *f, const double wi[3], uint64_t *rng, double wo[3],
                     int *order)
{
    double wr[3] = {-wi[0], -wi[1], -wi[2]};
    double hr = 2.0; /* above every height */
    int outside = 1;
    for (int k = 0; k < FULL_MAX_EVENTS; k++) {
        double u = core_unif(rng);
        if (outside)
            hr = walk_height(wr, hr, f->s, u);
        else {
            double nw[3] = {-wr[0], -wr[1], -wr[2]};
            hr = -walk_height(nw, -hr, f->s, u);
        }
        if (isinf(hr)) {
            memcpy(wo, wr, sizeof wr);
            *order = k;
            return outside ? 1 : 0;
        }
        /* scatter at the facet: wv = -wr points back along the ray */
        double wv[3] = {-wr[0], -wr[1], -wr[2]}, m[3];
        double eta = outside ? f->n : 1.0 / f->n;
        if (outside)
            walk_vndf(wv, f->alpha, rng, m);
        else {
            double nv[3] = {-wv[0], -wv[1], -wv[2]};
            walk_vndf(nv, f->alpha, rng, m);
            m[0] = -m[0];
            m[1] = -m[1];
            m[2] = -m[2];
        }
        double ci = wv[0] * m[0] + wv[1] * m[1] + wv[2] * m[2];
        if (!(ci > 0.0))
            ci = 0.0; /* an edge-on facet (rounding): it reflects, below */
        double st2 = (1.0 - ci * ci) / (eta * eta);
        double F = 1.0, ct = 0.0;
        if (st2 < 1.0 && ci > 0.0) {
            ct = sqrt(1.0 - st2);
            double rs = (ci - eta * ct) / (ci + eta * ct); /* ci + eta ct > 0 */
            double rp = (eta * ci - ct) / (eta * ci + ct);
            F = 0.5 * (rs * rs + rp * rp);
        }
        if (core_unif(rng) < F) {
            for (int j = 0; j < 3; j++)
                wr[j] = -wv[j] + 2.0 * ci * m[j];
        } else {
            double g = ci / eta - ct;
            for (int j = 0; j < 3; j++)
                wr[j] = -wv[j] / eta + g * m[j];
            outside = !outside;
        }
        double l = sqrt(wr[0] * wr[0] + wr[1] * wr[1] + wr[2] * wr[2]);
        if (!(l > 0.5))
            return -1; /* cannot happen for unit vectors; guards the division */
        for (int j = 0; j < 3; j++)
            wr[j] /= l;
    }
    return -1;
}

/* ------------------------------------------------------------------------- */
/* Tallies                                                                   */
/* ------------------------------------------------------------------------- */

typedef struct full_item {
    double c[2][FULL_NB];   /* sums of p_k(mu) cos(m phi) over order >= 2, T and R */
    double e1[2], ems[2];   /* counts */
    double lost;
} full_item;

typedef struct full_job {
    btdf_full *f;
    uint64_t chunks;
    full_item *items; /* [node * chunks + chunk] */
} full_job;

/* b[k * FULL_M + m] = sin^m t q_km(mu) cos(m phi), from mu = |cos t| and cos phi. */
static void full_basis(const btdf_full *f, double mu, double cphi, double *b)
{
    double cm[FULL_M], sm[FULL_M];
    double st = sqrt(fmax(0.0, 1.0 - mu * mu)); /* rounding can push mu above 1 */
    cm[0] = 1.0;
    cm[1] = cphi;
    for (int m = 2; m < FULL_M; m++)
        cm[m] = 2.0 * cphi * cm[m - 1] - cm[m - 2]; /* Chebyshev: cos(m phi) */
    sm[0] = 1.0;
    for (int m = 1; m < FULL_M; m++)
        sm[m] = sm[m - 1] * st;
    for (int m = 0; m < FULL_M; m++)
        for (int k = 0; k < FULL_K; k++) {
            double v = 0.0;
            for (int j = FULL_K - 1; j >= 0; j--)
                v = v * mu + f->poly[m][k][j];
            b[k * FULL_M + m] = v * sm[m] * cm[m];
        }
}

static void full_run_item(void *arg, size_t idx)
{
    full_job *jb = arg;
    btdf_full *f = jb->f;
    size_t node = idx / jb->chunks, chunk = idx % jb->chunks;
    full_item *it = &jb->items[idx];
    memset(it, 0, sizeof *it);
    uint64_t first = chunk * FULL_CHUNK;
    uint64_t count = f->paths - first < FULL_CHUNK ? f->paths - first : FULL_CHUNK;
    /* one stream per (seed, node, chunk): the result does not depend on the threads */
    uint64_t rng = f->seed ^ (0x9e3779b97f4a7c15ull * (node + 1)) ^
                   (0xc2b2ae3d27d4eb4full * (chunk + 1));
    (void)core_mix(&rng);
    double sti, cti;
    model_sincos_deg(f->node_deg[node], &sti, &cti);
    double wi[3] = {sti, 0.0, cti};
    for (uint64_t p = 0; p < count; p++) {
        double wo[3];
        int order = 0;
        int side = walk_path(f, wi, &rng, wo, &order);
        if (side < 0) {
            it->lost += 1.0;
            continue;
        }
        if (order <= 1) {
            it->e1[side] += 1.0;
            continue;
        }
        it->ems[side] += 1.0;
        double mu = fabs(wo[2]);
        double rxy = sqrt(wo[0] * wo[0] + wo[1] * wo[1]);
        double cphi = rxy > 0.0 ? wo[0] / rxy : 1.0; /* straight out: any phi */
        double b[FULL_NB];
        full_basis(f, mu, cphi, b);
        for (int j = 0; j < FULL_NB; j++)
            it->c[side][j] += b[j];
    }
}

/* <mu^i sin^m t, mu^j sin^m t> = int_0^1 mu^(i+j+1) (1 - mu^2)^m dmu, by the binomial
   expansion of (1 - mu^2)^m (m < 5: exact to rounding). */
static double full_moment(int e, int m)
{
    double sum = 0.0, c = 1.0; /* c = (-1)^r binom(m, r) */
    for (int r = 0; r <= m; r++) {
        sum += c / (e + 2 * r + 2);
        c = -c * (m - r) / (r + 1);
    }
    return sum;
}

/* For each m, the polynomials q_km with sin^m t q_km orthonormal for mu dmu: Gram-
   Schmidt on the monomials with the exact inner products of full_moment. */
void full_make_poly(double poly[FULL_M][FULL_K][FULL_K])
{
    for (int m = 0; m < FULL_M; m++)
        for (int k = 0; k < FULL_K; k++) {
            double v[FULL_K] = {0};
            v[k] = 1.0;
            for (int pass = 0; pass < 2; pass++) /* twice: re-orthogonalised, as the
                                                    moment matrix is Hilbert-like */
                for (int q = 0; q < k; q++) {
                    double d = 0.0;
                    for (int i = 0; i < FULL_K; i++)
                        for (int j = 0; j < FULL_K; j++)
                            d += v[i] * poly[m][q][j] * full_moment(i + j, m);
                    for (int j = 0; j < FULL_K; j++)
                        v[j] -= d * poly[m][q][j];
                }
            double nn = 0.0;
            for (int i = 0; i < FULL_K; i++)
                for (int j = 0; j < FULL_K; j++)
                    nn += v[i] * v[j] * full_moment(i + j, m);
            double inv = 1.0 / sqrt(nn); /* nn > 0: the functions are independent */
            for (int j = 0; j < FULL_K; j++)
                poly[m][k][j] = v[j] * inv;
        }
}

BTDF_API void btdf_full_opts_default(btdf_full_opts *o)
{
    memset(o, 0, sizeof *o);
    o->paths = BTDF_FULL_PATHS_DEFAULT;
    o->seed = 1;
}

BTDF_API btdf_status btdf_full_new(double n, double s, const btdf_full_opts *opts,
                                   btdf_full **out, char *msg, size_t msglen)
{
    if (!out)
        return core_say(BTDF_EINVAL, msg, msglen, "btdf_full_new: out is NULL");
    btdf_full_opts o;
    if (opts)
        o = *opts;
    else
        btdf_full_opts_default(&o);
    btdf_params p;
    btdf_params_default(&p);
    p.ior[0] = n;
    p.smoothness = s;
    p.model = BTDF_MODEL_SMITH;
    btdf_status st = btdf_params_check(&p, msg, msglen);
    if (st != BTDF_OK)
        return st;
    if (o.paths < 1000 || o.paths > BTDF_FULL_PATHS_MAX)
        return core_say(BTDF_EINVAL, msg, msglen,
                        "paths %llu: must lie in [1000, %llu] per incidence angle",
                        (unsigned long long)o.paths, (unsigned long long)BTDF_FULL_PATHS_MAX);
    btdf_full *f = calloc(1, sizeof *f);
    if (!f)
        return core_say(BTDF_ENOMEM, msg, msglen, "out of memory");
    f->n = n;
    f->s = s;
    f->alpha = 2.0 / s; /* D of Eq. 25: exp(-tan^2 / alpha^2) with alpha^2 = 4/s^2 */
    f->paths = o.paths;
    f->seed = o.seed;
    full_make_poly(f->poly);
    /* the ladder: the base angles, and for n < 1 the ones about the critical angle;
       a node within 0.25 degrees of one kept is dropped */
    double cand[FULL_NODES_MAX];
    int nc = 0;
    for (int k = 0; k < FULL_BASE; k++)
        cand[nc++] = full_base_deg[k];
    if (n < 1.0) {
        double tc = asin(n) * (180.0 / M_PI); /* n < 1: asin is defined */
        for (int k = 0; k < FULL_CRIT; k++) {
            double t = tc + full_crit_off[k];
            if (t > 0.0 && t < 89.9)
                cand[nc++] = t;
        }
    }
    for (int i = 1; i < nc; i++) /* insertion sort: a few dozen values */
        for (int j = i; j > 0 && cand[j] < cand[j - 1]; j--) {
            double t = cand[j];
            cand[j] = cand[j - 1];
            cand[j - 1] = t;
        }
    f->nodes = 0;
    for (int i = 0; i < nc; i++)
        if (f->nodes == 0 || cand[i] - f->node_deg[f->nodes - 1] > 0.25 || i == nc - 1) {
            if (f->nodes > 0 && cand[i] - f->node_deg[f->nodes - 1] <= 0.25)
                f->nodes--; /* keep the last node, 89.9, in place of a near one */
            f->node_deg[f->nodes++] = cand[i];
        }
    full_job jb;
    jb.f = f;
    jb.chunks = (o.paths + FULL_CHUNK - 1) / FULL_CHUNK;
    size_t nitems = (size_t)jb.chunks * f->nodes;
    jb.items = malloc(nitems * sizeof *jb.items);
    if (!jb.items) {
        free(f);
        return core_say(BTDF_ENOMEM, msg, msglen, "out of memory");
    }
    double t0 = core_now();
    core_parallel_for(o.threads, nitems, full_run_item, &jb);
    f->seconds = core_now() - t0;
    double np = (double)o.paths;
    for (int node = 0; node < f->nodes; node++) {
        full_item sum;
        memset(&sum, 0, sizeof sum);
        for (uint64_t c = 0; c < jb.chunks; c++) { /* in chunk order: fixed bits */
            const full_item *it = &jb.items[(size_t)node * jb.chunks + c];
            for (int h = 0; h < 2; h++) {
                for (int b = 0; b < FULL_NB; b++)
                    sum.c[h][b] += it->c[h][b];
                sum.e1[h] += it->e1[h];
                sum.ems[h] += it->ems[h];
            }
            sum.lost += it->lost;
        }
        for (int h = 0; h < 2; h++) {
            for (int k = 0; k < FULL_K; k++)
                for (int m = 0; m < FULL_M; m++) /* a_km = <f, p_k cos m phi> / N_m */
                    f->coef[node][h][k][m] =
                        sum.c[h][k * FULL_M + m] / np / (m == 0 ? 2.0 * M_PI : M_PI);
            /* Normal incidence: the light has no azimuth, so the scattered light has
               none; the tallied cos(m phi) modes, m >= 1, are the walks' noise alone */
            if (f->node_deg[node] == 0.0)
                for (int k = 0; k < FULL_K; k++)
                    for (int m = 1; m < FULL_M; m++)
                        f->coef[node][h][k][m] = 0.0;
            f->e1[node][h] = sum.e1[h] / np;
            f->ems[node][h] = sum.ems[h] / np;
            double q = f->ems[node][h]; /* binomial standard error of a fraction */
            f->ems_se[node][h] = sqrt(q * (1.0 - q) / np);
        }
        f->lost[node] = sum.lost / np;
    }
    free(jb.items);
    if (!full_set_clip_scale(f)) {
        free(f);
        return core_say(BTDF_ENOMEM, msg, msglen, "out of memory");
    }
    *out = f;
    return BTDF_OK;
}

/* The clipped and plain integrals of the series over its hemisphere at FULL_SUB + 1
   points of each ladder interval (the coefficients interpolated as full_ms does: the
   dips of the two nodes need not meet, so a factor per node would not hold between
   them; measured 0.7 % of R short at n = 1/1.5, s = 0.5, ti = 85), by the
   midpoint rule on FULL_QU x FULL_QP cells in (mu, phi in [0, pi], doubled): the series
   is sum_m A_m(mu) cos(m phi) with A_m(mu) = sin^m t sum_k q_km(mu) c_km, so the cells
   need the A_m of each mu row and five products each. Both integrals use the same
   cells: their ratio corrects the clipping alone, whatever the rule's own error. */
#define FULL_QU 192
#define FULL_QP 96
bool full_set_clip_scale(btdf_full *f)
{
    /* 60 kB of tables, made per call (60,000 products: nothing beside the series) */
    double (*P)[FULL_K][FULL_M] = malloc(sizeof(double[FULL_QU][FULL_K][FULL_M]));
    double C[FULL_QP][FULL_M];
    if (!P)
        return false;
    for (int i = 0; i < FULL_QU; i++) {
        double mu = (i + 0.5) / FULL_QU, st = sqrt(1.0 - mu * mu), sm = 1.0; /* mu < 1 */
        for (int m = 0; m < FULL_M; m++) {
            for (int k = 0; k < FULL_K; k++) {
                double v = 0.0;
                for (int j = FULL_K - 1; j >= 0; j--)
                    v = v * mu + f->poly[m][k][j];
                P[i][k][m] = v * sm;
            }
            sm *= st;
        }
    }
    for (int j = 0; j < FULL_QP; j++)
        for (int m = 0; m < FULL_M; m++)
            C[j][m] = cos(m * M_PI * (j + 0.5) / FULL_QP);
    for (int k = 0; k + 1 < f->nodes; k++)
        for (int sub = 0; sub <= FULL_SUB; sub++)
            for (int h = 0; h < 2; h++) {
                double w = (double)sub / FULL_SUB, clip = 0.0, plain = 0.0;
                for (int i = 0; i < FULL_QU; i++) {
                    double A[FULL_M], mu = (i + 0.5) / FULL_QU, rc = 0.0, rp = 0.0;
                    for (int m = 0; m < FULL_M; m++) {
                        A[m] = 0.0;
                        for (int q = 0; q < FULL_K; q++)
                            A[m] += P[i][q][m] * ((1.0 - w) * f->coef[k][h][q][m] +
                                                  w * f->coef[k + 1][h][q][m]);
                    }
                    for (int j = 0; j < FULL_QP; j++) {
                        double v = 0.0;
                        for (int m = 0; m < FULL_M; m++)
                            v += A[m] * C[j][m];
                        rp += v;
                        rc += v > 0.0 ? v : 0.0;
                    }
                    clip += rc * mu;
                    plain += rp * mu;
                }
                /* clip >= plain (the dips removed); no energy at all (clip 0) needs no
                   scale; a plain integral <= 0 is noise without a lobe: nothing kept */
                double r = clip > 0.0 ? plain / clip : 1.0;
                f->cscale[k][sub][h] = r < 0.0 ? 0.0 : r > 1.0 ? 1.0 : r;
            }
    free(P);
    return true;
}

BTDF_API void btdf_full_free(btdf_full *f)
{
    free(f);
}

/* The node interval of ti (degrees) and the weight of its upper end. */
int full_locate(const btdf_full *f, double ti_deg, double *w)
{
    int k = 0;
    while (k < f->nodes - 2 && ti_deg > f->node_deg[k + 1])
        k++;
    double a = f->node_deg[k], b = f->node_deg[k + 1];
    double t = (ti_deg - a) / (b - a); /* nodes are distinct: b > a */
    *w = t < 0.0 ? 0.0 : t > 1.0 ? 1.0 : t; /* past 89.9 the last node holds */
    return k;
}

/* The multiply scattered part alone, side h (0 T, 1 R), mu = |cos to|, in degrees. */
double full_ms(const btdf_full *f, int h, double ti_deg, double mu, double cphi)
{
    double w;
    int k0 = full_locate(f, ti_deg, &w);
    double b[FULL_NB];
    full_basis(f, mu, cphi, b);
    double v = 0.0;
    for (int k = 0; k < FULL_K; k++)
        for (int m = 0; m < FULL_M; m++)
            v += b[k * FULL_M + m] *
                 ((1.0 - w) * f->coef[k0][h][k][m] + w * f->coef[k0 + 1][h][k][m]);
    v *= full_clip_factor(f, k0, w, h); /* > 0: it commutes with the clip below */
    /* a truncated series may dip below 0 where the lobe is near 0: a BSDF is not
       negative (the factor above gives the clipped series back its tallied energy) */
    return v > 0.0 ? v : 0.0;
}

/* Declared in full.h. */
void full_ms_modes(const btdf_full *f, int h, double ti_deg, double mu, double *a)
{
    double w;
    int k0 = full_locate(f, ti_deg, &w);
    double st = sqrt(fmax(0.0, 1.0 - mu * mu)), sm = 1.0; /* as full_basis */
    double cf = full_clip_factor(f, k0, w, h); /* > 0: it commutes with the clip */
    for (int m = 0; m < FULL_M; m++) {
        double v = 0.0;
        for (int k = 0; k < FULL_K; k++) {
            double q = 0.0;
            for (int j = FULL_K - 1; j >= 0; j--)
                q = q * mu + f->poly[m][k][j];
            v += q * ((1.0 - w) * f->coef[k0][h][k][m] + w * f->coef[k0 + 1][h][k][m]);
        }
        a[m] = v * sm * cf;
        sm *= st;
    }
}

void full_rho_row_deg(const btdf_full *f, int h, double ti, double to, int np, double *out)
{
    double so, co;
    model_sincos_deg(to, &so, &co);
    (void)so;
    int ok = h ? (ti >= 0.0 && ti < 90.0 && to >= 0.0 && to <= 90.0 && co != 0.0)
               : (ti >= 0.0 && ti < 90.0 && to >= 90.0 && to <= 180.0 && co != 0.0);
    double a[FULL_M];
    if (ok)
        full_ms_modes(f, h, ti, h ? co : -co, a);
    for (int p = 0; p < np; p++) {
        if (!ok) { /* grazing in or out: no flux crosses (MODEL.md 3.5) */
            out[p] = 0.0;
            continue;
        }
        double phd = np > 1 ? 180.0 * p / (np - 1) : 0.0, sp, cp;
        model_sincos_deg(phd, &sp, &cp);
        (void)sp;
        double one = h ? btdf_rho_r_smith_deg(f->n, f->s, ti, to, ti == 0.0 ? 0.0 : phd)
                       : btdf_rho_smith_deg(f->n, f->s, ti, to, ti == 0.0 ? 0.0 : phd);
        out[p] = one + full_ms_at(a, cp);
    }
}

static int full_ok_t(double ti, double to, double phi)
{
    return ti >= 0.0 && ti <= 90.0 && to >= 90.0 && to <= 180.0 && isfinite(phi);
}

BTDF_API double btdf_full_rho_deg(const btdf_full *f, double ti, double to, double phi)
{
    if (!f || !full_ok_t(ti, to, phi))
        return 0.0;
    double sto, cto, sp, cp;
    model_sincos_deg(to, &sto, &cto);
    model_sincos_deg(phi, &sp, &cp);
    (void)sto;
    (void)sp;
    if (ti == 90.0 || cto == 0.0)
        return 0.0; /* grazing in or out: no flux crosses (MODEL.md 3.5) */
    /* normal incidence has no azimuth: smith's value there without the rounding of one
       (its sin and cos of phi move the last bit) */
    return btdf_rho_smith_deg(f->n, f->s, ti, to, ti == 0.0 ? 0.0 : phi) +
           full_ms(f, 0, ti, -cto, cp);
}

BTDF_API double btdf_full_rho_r_deg(const btdf_full *f, double ti, double tr, double phi)
{
    if (!f || !(ti >= 0.0 && ti <= 90.0 && tr >= 0.0 && tr <= 90.0 && isfinite(phi)))
        return 0.0;
    double s_, ctr, sp, cp;
    model_sincos_deg(tr, &s_, &ctr);
    model_sincos_deg(phi, &sp, &cp);
    (void)s_;
    (void)sp;
    if (ti == 90.0 || ctr == 0.0)
        return 0.0; /* grazing in or out */
    return btdf_rho_r_smith_deg(f->n, f->s, ti, tr, ti == 0.0 ? 0.0 : phi) +
           full_ms(f, 1, ti, ctr, cp); /* ti = 0: as above */
}

BTDF_API double btdf_full_rho(const btdf_full *f, double ti, double to, double phi)
{
    return btdf_full_rho_deg(f, ti * (180.0 / M_PI), to * (180.0 / M_PI), phi * (180.0 / M_PI));
}

BTDF_API double btdf_full_rho_r(const btdf_full *f, double ti, double tr, double phi)
{
    return btdf_full_rho_r_deg(f, ti * (180.0 / M_PI), tr * (180.0 / M_PI),
                               phi * (180.0 / M_PI));
}

BTDF_API btdf_status btdf_full_albedo(const btdf_full *f, double ti, btdf_full_albedos *a)
{
    if (!f || !a)
        return BTDF_EINVAL;
    if (!(ti >= 0.0 && ti <= M_PI / 2))
        return BTDF_EDOMAIN;
    btdf_params p;
    btdf_params_default(&p);
    p.ior[0] = f->n;
    p.smoothness = f->s;
    p.model = BTDF_MODEL_SMITH;
    double T1, R1;
    btdf_transmittance(&p, ti, &T1);
    btdf_reflectance(&p, ti, &R1);
    double w;
    int k = full_locate(f, ti * (180.0 / M_PI), &w);
    memset(a, 0, sizeof *a);
    a->T1 = T1;
    a->R1 = R1;
    a->Tms = (1.0 - w) * f->ems[k][0] + w * f->ems[k + 1][0];
    a->Rms = (1.0 - w) * f->ems[k][1] + w * f->ems[k + 1][1];
    a->Tms_se = fmax(f->ems_se[k][0], f->ems_se[k + 1][0]);
    a->Rms_se = fmax(f->ems_se[k][1], f->ems_se[k + 1][1]);
    a->T = T1 + a->Tms;
    a->R = R1 + a->Rms;
    return BTDF_OK;
}

BTDF_API void btdf_full_info(const btdf_full *f, btdf_full_stats *st)
{
    memset(st, 0, sizeof *st);
    if (!f)
        return;
    st->nodes = f->nodes;
    st->paths = f->paths;
    st->seconds = f->seconds;
    for (int k = 0; k < f->nodes; k++) {
        st->lost = fmax(st->lost, f->lost[k]);
        /* the walk's own R + T - 1 at order 1 against the quadrature of smith */
        btdf_params p;
        btdf_params_default(&p);
        p.ior[0] = f->n;
        p.smoothness = f->s;
        p.model = BTDF_MODEL_SMITH;
        double T1, R1, ti = f->node_deg[k] * (M_PI / 180.0);
        btdf_transmittance(&p, ti, &T1);
        btdf_reflectance(&p, ti, &R1);
        double d = fabs(T1 + R1 - f->e1[k][0] - f->e1[k][1]);
        st->order1_gap = fmax(st->order1_gap, d);
    }
}

BTDF_API btdf_status btdf_full_get_series(const btdf_full *f, btdf_full_series *out)
{
    if (!f || !out)
        return BTDF_EINVAL;
    memset(out, 0, sizeof *out);
    out->nodes = f->nodes;
    memcpy(out->node_deg, f->node_deg, sizeof f->node_deg);
    memcpy(out->poly, f->poly, sizeof f->poly);
    memcpy(out->coef, f->coef, sizeof f->coef);
    memcpy(out->clip, f->cscale, sizeof f->cscale); /* the same layout (checks above) */
    return BTDF_OK;
}

/* ------------------------------------------------------------------------- */
/* One entry point for every model                                           */
/* ------------------------------------------------------------------------- */

struct btdf_model_ctx {
    btdf_params p;
    btdf_full *full[BTDF_MAX_CHANNELS]; /* model full only */
};

BTDF_API btdf_status btdf_model_ctx_new(const btdf_params *p, const btdf_full_opts *opts,
                                        btdf_model_ctx **out, char *msg, size_t msglen)
{
    if (!p || !out)
        return core_say(BTDF_EINVAL, msg, msglen, "btdf_model_ctx_new: NULL argument");
    btdf_params q = *p;
    int full = p->model == BTDF_MODEL_FULL;
    if (full)
        q.model = BTDF_MODEL_SMITH; /* full has the parameters of smith */
    btdf_status st = btdf_params_check(&q, msg, msglen);
    if (st != BTDF_OK)
        return st;
    btdf_model_ctx *m = calloc(1, sizeof *m);
    if (!m)
        return core_say(BTDF_ENOMEM, msg, msglen, "out of memory");
    m->p = *p;
    for (int c = 0; full && c < p->channels; c++) {
        st = btdf_full_new(p->ior[c], p->smoothness, opts, &m->full[c], msg, msglen);
        if (st != BTDF_OK) {
            btdf_model_ctx_free(m);
            return st;
        }
    }
    *out = m;
    return BTDF_OK;
}

BTDF_API void btdf_model_ctx_free(btdf_model_ctx *m)
{
    if (!m)
        return;
    for (int c = 0; c < BTDF_MAX_CHANNELS; c++)
        btdf_full_free(m->full[c]);
    free(m);
}

BTDF_API const btdf_params *btdf_model_ctx_params(const btdf_model_ctx *m)
{
    return m ? &m->p : NULL;
}

BTDF_API const btdf_full *btdf_model_ctx_full(const btdf_model_ctx *m, int ch)
{
    return m && ch >= 0 && ch < m->p.channels ? m->full[ch] : NULL;
}

BTDF_API double btdf_model_ctx_rho_deg(const btdf_model_ctx *m, int ch, double ti, double to,
                                       double phi)
{
    if (!m || ch < 0 || ch >= m->p.channels)
        return 0.0;
    if (m->p.model == BTDF_MODEL_FULL)
        return btdf_full_rho_deg(m->full[ch], ti, to, phi);
    return btdf_rho_model_deg(m->p.model, m->p.ior[ch], m->p.smoothness, m->p.k0, ti, to, phi);
}

BTDF_API double btdf_model_ctx_rho_r_deg(const btdf_model_ctx *m, int ch, double ti,
                                         double tr, double phi)
{
    if (!m || ch < 0 || ch >= m->p.channels)
        return 0.0;
    if (m->p.model == BTDF_MODEL_FULL)
        return btdf_full_rho_r_deg(m->full[ch], ti, tr, phi);
    return btdf_rho_r_model_deg(m->p.model, m->p.ior[ch], m->p.smoothness, m->p.k0, ti, tr,
                                phi);
}

BTDF_API btdf_status btdf_model_ctx_albedo(const btdf_model_ctx *m, double ti, double *T,
                                           double *R)
{
    if (!m || !T || !R)
        return BTDF_EINVAL;
    if (!(ti >= 0.0 && ti <= M_PI / 2))
        return BTDF_EDOMAIN;
    if (m->p.model != BTDF_MODEL_FULL) {
        btdf_status st = btdf_transmittance(&m->p, ti, T);
        return st != BTDF_OK ? st : btdf_reflectance(&m->p, ti, R);
    }
    for (int c = 0; c < m->p.channels; c++) {
        btdf_full_albedos a;
        btdf_status st = btdf_full_albedo(m->full[c], ti, &a);
        if (st != BTDF_OK)
            return st;
        T[c] = a.T;
        R[c] = a.R;
    }
    return BTDF_OK;
}
