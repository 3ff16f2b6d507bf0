/* SPDX-License-Identifier: MIT */
/* densescan.c: a table's true error on a dense grid of incident angles, against the report. */
/*
 * Usage: btdf-densescan [--ior N[,G,B]] [-s S] [--k0 K] [--tolerance E] [--metric l1|max]
 *                       [--theta-i A:B] [--step DEG] [--nu N] [--npsi N] [--threads N]
 *                       [--part transmission|reflection|both]
 *
 * Builds the table as btdftab tabulate does, takes the library's error report
 * (btdf_table_estimate, the tool's seed), and scans the incidence range on a grid of
 * --step degrees (default 0.25) plus every 0.02 degrees around the five worst angles
 * found. At each angle it integrates |rho~ - rho| |cos to| d(omega_o) over the outgoing
 * hemisphere with its own rule, sharing nothing with the library's estimator but the
 * public evaluators btdf_rho and btdf_table_eval:
 *  - a midpoint product rule over facet slopes u in [0, 7] (tan tn = 2u/s, the units in
 *    which the Beckmann factor is exp(-u^2), so the lobe is covered for every s) and
 *    facet azimuths psi in [0, pi] (doubled for the mirror half);
 *  - the outgoing direction of each facet by refraction written out here, and the
 *    measure |cos to| d(cos to) d(phi) by a numerical Jacobian (central differences) of
 *    that map, not by the closed form the library uses;
 *  - for n <= 1/1.01 (the facet measure diverges at the critical angle) a midpoint rule
 *    over (cos to, phi) with twice the counts instead;
 *  - the rest of the hemisphere (directions no facet with u < 7 reaches, where a file or
 *    table may still ring) by a midpoint rule over (cos to, phi) with twice the counts;
 *  - T by the same rule (so the floor max(T, 0.01) is this program's own), e_max as
 *    max |rho~ - rho| / max rho over the points, where T >= 0.01 (MODEL.md section 6).
 * With --bsdf FILE (a written .bsdf of the material given by --ior, -s, --k0) it scans
 * that file instead, through btdf_scatfun_eval_side for one transmission block
 * (--block enter, the default, or leave: index 1/n), against btdf_scatfun_report for
 * that block with the seed btdftab tabulate uses; --tolerance is then the file's.
 * --mode direct|adjoint|both (default both, as the report): the light in the slow
 * index (pbrt-v3's importance mode), in the fast index (its radiance mode, which path
 * tracers' camera rays use), or the worse of the two at each angle.
 * The reflection (--part reflection, MODEL.md section 8) is scanned the same way: the
 * mirror direction of each facet written out here, its measure cos tr d(cos tr) d(phi)
 * by the same numerical Jacobian (the mirror map's measure is bounded for every n, so
 * the facet rule serves n < 1 too), rho_r by btdf_rho_r and R by the same rule.
 * --part both builds one table holding both parts and scans each.
 * Prints one line per part: the reported max, the dense max and where, their ratio,
 * whether the report said "met" and whether the dense max is above the tolerance.
 */
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <btdf/btdf.h>
#include <btdf/btdf_scatfun.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define REPORT_SEED 20081231u /* the seed btdftab tabulate reports with */
#define U_MAX 7.0

typedef struct scan {
    const btdf_table *t;
    const btdf_scatfun *f; /* scanned instead of t when set */
    btdf_side side;
    const btdf_params *p;
    int nu, npsi;
    int refl; /* 1: t is a reflection table, scanned against rho_r */
    int mode; /* a file's reading: 0 DIRECT, 1 ADJOINT, 2 both (the worse per angle) */
} scan;

typedef struct ang_err {
    double ti, T, e_l1, e_max;
} ang_err;

/* The refracted direction through facet (tn, psi) for light from (ti, azimuth 0), or 0
   when the facet is back-facing, totally reflects, or sends the light upwards. */
static int refract_dir(double n, double ti, double tn, double psi, double *mu, double *phi)
{
    double ix = sin(ti), iz = cos(ti);
    double mx = sin(tn) * cos(psi), my = sin(tn) * sin(psi), mz = cos(tn);
    double c = ix * mx + iz * mz;
    if (!(c > 0.0))
        return 0;
    double eta = 1.0 / n, k = 1.0 - eta * eta * (1.0 - c * c);
    if (!(k > 0.0))
        return 0; /* total internal reflection */
    double a = eta * c - sqrt(k);
    double tx = -eta * ix + a * mx, ty = a * my, tz = -eta * iz + a * mz;
    double len = sqrt(tx * tx + ty * ty + tz * tz);
    if (!(len > 0.0) || !(tz < 0.0))
        return 0;
    *mu = tz / len;
    *phi = atan2(ty, tx);
    return 1;
}

/* The evaluation under test: the table, or the file's block as pbrt-v3 reads it. */
static void eval_under_test(const scan *sc, double ti, double to, double ph, double *tab)
{
    if (sc->f) {
        if (btdf_scatfun_eval_side(sc->f, sc->side,
                                   sc->mode == 1 ? BTDF_SCATFUN_ADJOINT : BTDF_SCATFUN_DIRECT,
                                   ti, to, ph, tab) != BTDF_OK)
            tab[0] = tab[1] = tab[2] = 0.0;
    } else {
        btdf_table_eval(sc->t, ti, to, ph, tab);
    }
}

/* The mirror direction of light from (ti, azimuth 0) on facet (tn, psi), or 0 when the
   facet is back-facing or mirrors the light into the lower medium. */
static int reflect_dir(double ti, double tn, double psi, double *mu, double *phi)
{
    double ix = sin(ti), iz = cos(ti);
    double mx = sin(tn) * cos(psi), my = sin(tn) * sin(psi), mz = cos(tn);
    double c = ix * mx + iz * mz;
    if (!(c > 0.0))
        return 0;
    double rx = 2.0 * c * mx - ix, ry = 2.0 * c * my, rz = 2.0 * c * mz - iz;
    double len = sqrt(rx * rx + ry * ry + rz * rz);
    if (!(len > 0.0) || !(rz > 0.0))
        return 0;
    *mu = rz / len;
    *phi = atan2(ry, rx);
    return 1;
}

/* Through the facet: refraction for the transmission, the mirror for the reflection. */
static int facet_dir(int refl, double n, double ti, double tn, double psi, double *mu,
                     double *phi)
{
    return refl ? reflect_dir(ti, tn, psi, mu, phi) : refract_dir(n, ti, tn, psi, mu, phi);
}

/* One channel's sums over the points of an incident angle: T, the L1 of the error,
   the largest error and the largest value. */
typedef struct acc {
    double T, l1, dmax, vmax;
} acc;

/* Adds the point (to, ph) of weight w (measure times |cos to|) of channel c. */
static void add_point(const scan *sc, int c, double ti, double to, double ph, double w, acc *a)
{
    const btdf_params *p = sc->p;
    double n = p->ior[c], s = p->smoothness;
    double rho = sc->refl ? btdf_rho_r(n, s, p->k0, ti, to, ph) : btdf_rho(n, s, p->k0, ti, to, ph);
    double tab[3] = {0, 0, 0};
    eval_under_test(sc, ti, to, ph, tab);
    double d = fabs(tab[c] - rho);
    a->T += rho * w;
    a->l1 += d * w;
    a->dmax = fmax(a->dmax, d);
    a->vmax = fmax(a->vmax, rho);
}

static void one_angle(const scan *sc, double ti, ang_err *out)
{
    int refl = sc->refl;
    const btdf_params *p = sc->p;
    double s = p->smoothness, du = U_MAX / sc->nu, dpsi = M_PI / sc->npsi;
    out->ti = ti;
    out->T = out->e_l1 = out->e_max = 0.0;
    for (int c = 0; c < p->channels; c++) {
        double n = p->ior[c];
        /* n < 1: the facet map's measure diverges at the critical angle, which a product
           rule cannot integrate; the outgoing hemisphere is smooth there, and the lobes
           of light leaving the dense side are wide (the cases scanned have s <= 100).
           Except near n = 1 (1/n - 1 < 0.01): the lobe is about 2 (1/n - 1)/s rad wide,
           a few cells of the (cos to, phi) grid at most; there the facets' Fresnel factor
           falls to 0 well before the critical angle, and the facet rule is used. */
        int out_rule = !refl && n < 1.0 && 1.0 / n - 1.0 >= 0.01;
        acc a = {0.0, 0.0, 0.0, 0.0};
        for (int iu = 0; !out_rule && iu < sc->nu; iu++) {
            double u = (iu + 0.5) * du;
            double hu = 1e-6 * fmax(1.0, u);
            for (int ip = 0; ip < sc->npsi; ip++) {
                double psi = (ip + 0.5) * dpsi, hp = 1e-6;
                double mu, phi, m1, p1, m2, p2, m3, p3, m4, p4;
                if (!facet_dir(refl, n, ti, atan(2.0 * u / s), psi, &mu, &phi))
                    continue;
                if (!facet_dir(refl, n, ti, atan(2.0 * (u + hu) / s), psi, &m1, &p1) ||
                    !facet_dir(refl, n, ti, atan(2.0 * (u - hu) / s), psi, &m2, &p2) ||
                    !facet_dir(refl, n, ti, atan(2.0 * u / s), psi + hp, &m3, &p3) ||
                    !facet_dir(refl, n, ti, atan(2.0 * u / s), psi - hp, &m4, &p4))
                    continue; /* at the edge of the reachable set: a null set */
                double dmu_du = (m1 - m2) / (2 * hu), dmu_dp = (m3 - m4) / (2 * hp);
                double dph_du = remainder(p1 - p2, 2 * M_PI) / (2 * hu);
                double dph_dp = remainder(p3 - p4, 2 * M_PI) / (2 * hp);
                double jac = fabs(dmu_du * dph_dp - dmu_dp * dph_du);
                double w = fabs(mu) * jac * du * dpsi * 2.0;
                add_point(sc, c, ti, acos(mu), fabs(phi), w, &a);
            }
        }
        /* A midpoint rule over (cos to, phi), with twice the counts: the whole hemisphere
           for out_rule; otherwise the rest of it beside the facet rule, which covers only
           the directions some facet with u < U_MAX sends light to, while a file's series
           can ring anywhere (rho is below exp(-49) of its scale there, the file need not
           be): each point whose facet (the half vector) is beyond U_MAX or cannot send
           e_i there. */
        for (int im = 0; im < 2 * sc->nu; im++) {
            double dmu = 1.0 / (2 * sc->nu), mu = (im + 0.5) * dmu; /* |cos to| */
            double so = sqrt(1.0 - mu * mu); /* mu < 1 */
            for (int ip = 0; ip < 2 * sc->npsi; ip++) {
                double dph = M_PI / (2 * sc->npsi), ph = (ip + 0.5) * dph;
                if (!out_rule) {
                    double ix = sin(ti), iz = cos(ti);
                    double ox = so * cos(ph), oy = so * sin(ph), oz = refl ? mu : -mu;
                    double hx, hy, hz;
                    if (refl) {
                        hx = ix + ox, hy = oy, hz = iz + oz;
                    } else {
                        hx = ix + n * ox, hy = n * oy, hz = iz + n * oz;
                        if (hz < 0.0)
                            hx = -hx, hy = -hy, hz = -hz;
                    }
                    double ci = ix * hx + iz * hz, co = ox * hx + oy * hy + oz * hz;
                    int valid = hz > 0.0 && ci > 0.0 && (refl ? co > 0.0 : co < 0.0);
                    /* hz > 0 when valid: the facet's slope u = (s/2) tan(theta_h) */
                    if (valid && 0.5 * s * sqrt(hx * hx + hy * hy) / hz < U_MAX)
                        continue; /* the facet rule's */
                }
                add_point(sc, c, ti, refl ? acos(mu) : acos(-mu), ph, mu * dmu * dph * 2.0, &a);
            }
        }
        double T = a.T, l1 = a.l1, dmax = a.dmax, vmax = a.vmax;
        double fl = fmax(T, 0.01);
        if (c == 0)
            out->T = T;
        out->e_l1 = fmax(out->e_l1, l1 / fl);
        if (T >= 0.01 && vmax > 0.0)
            out->e_max = fmax(out->e_max, dmax / vmax);
    }
}

typedef struct work {
    const scan *sc;
    const double *ti;
    ang_err *res;
    size_t n, next;
    pthread_mutex_t lock;
} work;

static void *worker(void *arg)
{
    work *w = arg;
    for (;;) {
        pthread_mutex_lock(&w->lock);
        size_t k = w->next++;
        pthread_mutex_unlock(&w->lock);
        if (k >= w->n)
            return NULL;
        if (w->sc->f && w->sc->mode == 2) {
            /* both readings of the file, as its report does: the worse of each error */
            scan one = *w->sc;
            ang_err d, j;
            one.mode = 0;
            one_angle(&one, w->ti[k], &d);
            one.mode = 1;
            one_angle(&one, w->ti[k], &j);
            d.e_l1 = fmax(d.e_l1, j.e_l1);
            d.e_max = fmax(d.e_max, j.e_max);
            w->res[k] = d;
        } else {
            one_angle(w->sc, w->ti[k], &w->res[k]);
        }
    }
}

static void run(const scan *sc, const double *ti, ang_err *res, size_t n, int threads)
{
    work w = {sc, ti, res, n, 0, PTHREAD_MUTEX_INITIALIZER};
    pthread_t th[64];
    int nt = threads < 1 ? 1 : (threads > 64 ? 64 : threads);
    for (int i = 0; i < nt; i++)
        pthread_create(&th[i], NULL, worker, &w);
    for (int i = 0; i < nt; i++)
        pthread_join(th[i], NULL);
}

static int parse_range(const char *v, double *a, double *b)
{
    return sscanf(v, "%lf:%lf", a, b) == 2 && *a >= 0 && *b <= 90 && *a < *b;
}

static int scan_part(const btdf_table *t, const btdf_scatfun *f, btdf_side side, int refl,
                     const btdf_table_opts *op, double a, double b, double step, int nu,
                     int npsi, int threads, int dump, int mode);

int main(int argc, char **argv)
{
    btdf_table_opts o;
    btdf_table_opts_default(&o);
    double step = 0.25, a = 0.0, b = 90.0;
    int nu = 256, npsi = 192, threads = 2, dump = 0;
    const char *bsdf = NULL;
    btdf_side side = BTDF_SIDE_ENTER;
    btdf_part part = BTDF_PART_TRANSMISSION;
    int mode = 2;
    for (int i = 1; i < argc; i++) {
        const char *k = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!v) {
            fprintf(stderr, "btdf-densescan: %s: missing value\n", k);
            return 2;
        }
        i++;
        if (!strcmp(k, "--ior")) {
            int m = sscanf(v, "%lf,%lf,%lf", &o.params.ior[0], &o.params.ior[1],
                           &o.params.ior[2]);
            if (m != 1 && m != 3) {
                fprintf(stderr, "btdf-densescan: --ior %s: one or three numbers\n", v);
                return 2;
            }
            o.params.channels = m;
        } else if (!strcmp(k, "-s")) {
            o.params.smoothness = atof(v);
        } else if (!strcmp(k, "--k0")) {
            o.params.k0 = atof(v);
        } else if (!strcmp(k, "--tolerance")) {
            o.tolerance = atof(v);
        } else if (!strcmp(k, "--metric")) {
            o.metric = !strcmp(v, "max") ? BTDF_METRIC_MAX : BTDF_METRIC_L1;
        } else if (!strcmp(k, "--theta-i")) {
            if (!parse_range(v, &a, &b)) {
                fprintf(stderr, "btdf-densescan: --theta-i %s: A:B within 0:90\n", v);
                return 2;
            }
        } else if (!strcmp(k, "--step")) {
            step = atof(v);
        } else if (!strcmp(k, "--nu")) {
            nu = atoi(v);
        } else if (!strcmp(k, "--npsi")) {
            npsi = atoi(v);
        } else if (!strcmp(k, "--dump")) {
            dump = atoi(v); /* 1: every angle's T and errors on standard output */
        } else if (!strcmp(k, "--bsdf")) {
            bsdf = v;
        } else if (!strcmp(k, "--block")) {
            if (strcmp(v, "enter") && strcmp(v, "leave")) {
                fprintf(stderr, "btdf-densescan: --block %s: enter or leave\n", v);
                return 2;
            }
            side = v[0] == 'e' ? BTDF_SIDE_ENTER : BTDF_SIDE_LEAVE;
        } else if (!strcmp(k, "--mode")) {
            if (strcmp(v, "direct") && strcmp(v, "adjoint") && strcmp(v, "both")) {
                fprintf(stderr, "btdf-densescan: --mode %s: direct, adjoint or both\n", v);
                return 2;
            }
            mode = v[0] == 'd' ? 0 : v[0] == 'a' ? 1 : 2;
        } else if (!strcmp(k, "--threads")) {
            threads = atoi(v);
        } else if (!strcmp(k, "--part")) {
            if (!btdf_part_parse(v, &part)) {
                fprintf(stderr, "btdf-densescan: --part %s: transmission, reflection or both\n",
                        v);
                return 2;
            }
        } else {
            fprintf(stderr, "btdf-densescan: unknown option %s\n", k);
            return 2;
        }
    }
    if (!(step >= 0.001 && step <= 10) || nu < 8 || npsi < 8) {
        fprintf(stderr, "btdf-densescan: --step in [0.001, 10], --nu and --npsi >= 8\n");
        return 2;
    }
    o.ti_min = a * M_PI / 180;
    o.ti_max = b * M_PI / 180;
    o.part = part;
    char msg[512] = "";
    if (bsdf) {
        /* a .bsdf's transmission block (--block), against its own report */
        btdf_scatfun *f = NULL;
        if (part != BTDF_PART_TRANSMISSION) {
            fprintf(stderr, "btdf-densescan: --bsdf scans a transmission block; --part "
                            "does not apply\n");
            return 2;
        }
        if (btdf_scatfun_read(bsdf, &f, msg, sizeof msg) != BTDF_OK) {
            fprintf(stderr, "btdf-densescan: %s: %s\n", bsdf, msg);
            return 1;
        }
        int bad = scan_part(NULL, f, side, 0, &o, a, b, step, nu, npsi, threads, dump, mode);
        btdf_scatfun_free(f);
        return bad;
    }
    btdf_table *tab = NULL;
    btdf_status st = btdf_table_build(&o, &tab, msg, sizeof msg);
    if (st != BTDF_OK && st != BTDF_EBUDGET) {
        fprintf(stderr, "btdf-densescan: build: %s\n", msg);
        return 1;
    }
    int bad = 0;
    for (int pk = 0; pk < 2; pk++) {
        btdf_part want = pk == 0 ? BTDF_PART_TRANSMISSION : BTDF_PART_REFLECTION;
        const btdf_table *t = btdf_table_part(tab, want);
        if (!t)
            continue;
        bad |= scan_part(t, NULL, BTDF_SIDE_ENTER, pk == 1, &o, a, b, step, nu, npsi, threads,
                         dump, 0);
    }
    btdf_table_free(tab);
    return bad;
}

/* Scans one part (of the table t, or the block side of the file f) against its report;
   0, or 1 when something failed. */
static int scan_part(const btdf_table *t, const btdf_scatfun *f, btdf_side side, int refl,
                     const btdf_table_opts *op, double a, double b, double step, int nu,
                     int npsi, int threads, int dump, int mode)
{
    btdf_table_opts o = *op;
    btdf_report r;
    memset(&r, 0, sizeof r);
    btdf_params truth = o.params; /* the scanned block's index: 1/n for light leaving */
    if (f) {
        if (side == BTDF_SIDE_LEAVE)
            for (int c = 0; c < truth.channels; c++)
                truth.ior[c] = 1.0 / truth.ior[c]; /* ior > 0: a file was built with it */
        if (btdf_scatfun_report(f, &o.params, side, 0, 0, REPORT_SEED, 0, &r) != BTDF_OK) {
            fprintf(stderr, "btdf-densescan: report failed (channels or block)\n");
            return 1;
        }
    } else if (btdf_table_estimate(t, o.ti_min, o.ti_max, 0, 0, REPORT_SEED, 0, &r) !=
               BTDF_OK) {
        fprintf(stderr, "btdf-densescan: estimate failed\n");
        return 1;
    }
    int is_max = o.metric == BTDF_METRIC_MAX;
    double reported = is_max ? r.e_max_max : r.e_l1_max;
    int met = reported <= o.tolerance;
    if (f && btdf_scatfun_channels(f) == 3 && mode == 2)
        mode = 1; /* three channels: the fold is right on the radiance path only */
    scan sc = {t, f, side, &truth, nu, npsi, refl, mode};
    size_t n0 = (size_t)floor((b - a) / step) + 1, cap = n0 + 1 + 5 * 27;
    double *ti = malloc(cap * sizeof *ti);
    ang_err *res = malloc(cap * sizeof *res);
    if (!ti || !res)
        return 1;
    size_t n = 0;
    for (size_t k = 0; k < n0; k++)
        ti[n++] = (a + step * (double)k) * M_PI / 180;
    if (a + step * (double)(n0 - 1) < b)
        ti[n++] = b * M_PI / 180;
    run(&sc, ti, res, n, threads);
    /* five worst local maxima: a finer grid of 0.02 deg around each */
    size_t nfine = n;
    for (int pick = 0; pick < 5; pick++) {
        size_t best = SIZE_MAX;
        double bv = -1;
        for (size_t k = 0; k < nfine; k++) {
            double e = is_max ? res[k].e_max : res[k].e_l1;
            int used = 0;
            for (size_t q = nfine; q < n; q++)
                used |= fabs(ti[q] - res[k].ti) < step * M_PI / 180;
            if (!used && e > bv) {
                bv = e;
                best = k;
            }
        }
        if (best == SIZE_MAX || bv <= 0)
            break;
        size_t from = n;
        for (int q = -13; q <= 13; q++) {
            double x = res[best].ti + q * 0.02 * M_PI / 180;
            if (q != 0 && x >= o.ti_min && x <= o.ti_max)
                ti[n++] = x;
        }
        run(&sc, ti + from, res + from, n - from, threads);
    }
    for (size_t k = 0; k < n && dump; k++)
        printf("ti %.4f T %.6g e_l1 %.4g e_max %.4g\n", res[k].ti * 180 / M_PI, res[k].T,
               res[k].e_l1, res[k].e_max);
    size_t w = 0;
    for (size_t k = 0; k < n; k++) {
        double e = is_max ? res[k].e_max : res[k].e_l1, ew = is_max ? res[w].e_max : res[w].e_l1;
        if (e > ew)
            w = k;
    }
    double dense = is_max ? res[w].e_max : res[w].e_l1;
    /* The rule's own T against the library's transmittance: how good the quadrature is. */
    double tdev = 0.0;
    for (size_t k = 0; k < n; k++) {
        double T[3];
        if (refl)
            btdf_reflectance(&truth, res[k].ti, T);
        else
            btdf_transmittance(&truth, res[k].ti, T);
        if (T[0] >= 0.01)
            tdev = fmax(tdev, fabs(res[k].T - T[0]) / T[0]);
    }
    printf("%sn %s%g s %g theta-i %g:%g tol %g %s: reported %.4g (%s, %zu angles), dense %.4g at "
           "%.3f deg (%zu angles), dense/reported %.3f, %s; quadrature %s within %.1e\n",
           refl ? "reflection: " : "", o.params.channels == 3 ? "RGB " : "", o.params.ior[0], o.params.smoothness, a, b,
           o.tolerance, is_max ? "max" : "l1", reported, met ? "met" : "NOT met", r.test_angles,
           dense, res[w].ti * 180 / M_PI, n, reported > 0 ? dense / reported : 0.0,
           met && dense > o.tolerance ? "DENSE ABOVE TOLERANCE" : "consistent",
           refl ? "R" : "T", tdev);
    btdf_report_clear(&r);
    free(ti);
    free(res);
    return 0;
}
