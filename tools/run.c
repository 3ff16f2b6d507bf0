/* SPDX-License-Identifier: MIT */
/* run.c: building, reporting and writing a .bsdf, for `tabulate -o F.bsdf` and `build`. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "run.h"

double run_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int run_parse_side(const char *word)
{
    static const char *const names[4] = {NULL, "enter", "leave", "both"};
    for (int s = BTDF_SIDE_ENTER; s <= BTDF_SIDE_BOTH; s++)
        if (!strcmp(word, names[s]))
            return s;
    return 0;
}

int run_parse_metric(const char *word, btdf_metric *metric)
{
    if (strcmp(word, "l1") && strcmp(word, "max"))
        return 0;
    *metric = word[0] == 'l' ? BTDF_METRIC_L1 : BTDF_METRIC_MAX;
    return 1;
}

static int fail(const char *prog, int code, const char *path, const char *what)
{
    fprintf(stderr, "%s: %s: %s\n", prog, path, what);
    return code;
}

int run_series(const char *prog, const char *path, const btdf_params *p, double tol, int sides,
               int threads, int quiet, int best_effort, const char *prov)
{
    char msg[512] = "";
    btdf_scatfun *f = NULL;
    double t0 = run_now();
    btdf_status st = btdf_scatfun_build(p, tol, (btdf_side)sides, threads, &f, msg, sizeof msg);
    double t1 = run_now();
    if (st != BTDF_OK && st != BTDF_EBUDGET)
        return fail(prog, st == BTDF_EINVAL ? 2 : 1, path, msg[0] ? msg : btdf_strerror(st));
    if (!f)
        return fail(prog, 1, path, msg[0] ? msg : btdf_strerror(st));
    /* The error a renderer will see: the format's own evaluation, per side. */
    int met = 1;
    char meta[1024];
    int k = snprintf(meta, sizeof meta, "{\"program\": \"btdftab %s\", \"tolerance\": %g",
                     btdf_version_string(), tol);
    for (int s = BTDF_SIDE_ENTER; s <= BTDF_SIDE_LEAVE; s++) {
        if (!(sides & s))
            continue;
        btdf_report r;
        memset(&r, 0, sizeof r);
        double e0 = run_now();
        btdf_status es = btdf_scatfun_report(f, p, (btdf_side)s, 0, 0, REPORT_SEED, threads, &r);
        double e1 = run_now();
        if (es != BTDF_OK) {
            btdf_scatfun_free(f);
            fprintf(stderr, "%s: %s: error estimate: %s\n", prog, path, btdf_strerror(es));
            return 1;
        }
        int ok = r.e_l1_max <= tol;
        met = met && ok;
        const char *name = s == BTDF_SIDE_ENTER ? "enter" : "leave";
        if (!quiet)
            fprintf(stderr,
                    "%s: %s (%s, as a renderer reads it): %zu nodes, %zu coefficients; "
                    "build %.3f s, estimate %.3f s (%zu angles, %zu points); e_L1 max %.3g "
                    "mean %.3g; e_max max %.3g; e_T max %.3g%s\n",
                    prog, path, name, btdf_scatfun_node_count(f), btdf_scatfun_coeff_count(f),
                    t1 - t0, e1 - e0, r.test_angles, r.test_points, r.e_l1_max, r.e_l1_mean,
                    r.e_max_max, r.e_t_max, ok ? "; tolerance met" : "; TOLERANCE NOT MET");
        if (k > 0 && (size_t)k < sizeof meta)
            k += snprintf(meta + k, sizeof meta - (size_t)k,
                          ", \"%s\": {\"e_l1_max\": %.4g, \"e_max_max\": %.4g, \"e_t_max\": %.4g}",
                          name, r.e_l1_max, r.e_max_max, r.e_t_max);
        btdf_report_clear(&r);
    }
    if (k > 0 && (size_t)k < sizeof meta)
        snprintf(meta + k, sizeof meta - (size_t)k, ", \"command\": \"%s\"}", prov ? prov : "");
    int code = 0;
    if (!met && !best_effort) {
        fprintf(stderr, "%s: %s: tolerance %g not met%s%s; nothing written (pass --best-effort "
                        "to write it anyway)\n",
                prog, path, tol, msg[0] ? ": " : "", msg);
        code = 3;
    } else {
        btdf_output what = {NULL, f, NULL, NULL, meta, NULL};
        st = btdf_write(&what, path, msg, sizeof msg);
        if (st != BTDF_OK)
            code = fail(prog, 1, path, msg[0] ? msg : btdf_strerror(st));
    }
    btdf_scatfun_free(f);
    return code;
}

/* The JSON report of a .xml: per block the error report and probes, the directions
   at which Radiance's own lookup must return the value the file holds. */
#define RAD_PROBES 1000

static void rad_json(FILE *f, const btdf_rad *x, const btdf_params *p, const btdf_report *rep,
                     const char *prov)
{
    fprintf(f, "{\n  \"program\": \"btdftab\",\n  \"version\": \"%s\",\n  \"command\": \"",
            btdf_version_string());
    for (const char *s = prov ? prov : ""; *s; s++) {
        if (*s == '"' || *s == '\\')
            fputc('\\', f);
        if ((unsigned char)*s >= 0x20)
            fputc(*s, f);
    }
    fprintf(f, "\",\n  \"format\": \"radiance-xml\",\n  \"basis\": \"%s\",\n",
            btdf_rad_basis_name(btdf_rad_get_basis(x)));
    fprintf(f, "  \"ior\": [%.17g],\n  \"smoothness\": %.17g,\n  \"k0\": %.17g,\n", p->ior[0],
            p->smoothness, p->k0);
    fprintf(f, "  \"seconds_build\": %.6f,\n  \"blocks\": [\n", btdf_rad_seconds_build(x));
    const double d2r = 3.14159265358979323846 / 180.0;
    int nb = btdf_rad_block_count(x);
    for (int k = 0; k < nb; k++) {
        const btdf_report *r = &rep[k];
        btdf_rad_block_info b;
        btdf_rad_block(x, k, &b);
        fprintf(f, "   {\"label\": \"%s\", \"side\": \"%s\", \"n\": %.17g,\n", b.label,
                b.light == BTDF_SIDE_ENTER ? "enter" : "leave", b.n_light);
        fprintf(f, "    \"values\": %zu, \"depth\": %d, \"tolerance\": %.9g, \"met\": %s,\n",
                b.values, b.depth, r->tolerance, r->met ? "true" : "false");
        fprintf(f, "    \"seconds_estimate\": %.6f, \"test_angles\": %zu, \"test_points\": %zu,\n",
                r->seconds_estimate, r->test_angles, r->test_points);
        fprintf(f, "    \"e_l1\": {\"max\": %.6g, \"max_to_%g_deg\": %.6g, \"mean\": %.6g},\n",
                r->e_l1_max, BTDF_RAD_TI_CHECKED_DEG, btdf_rad_e_l1_checked(r), r->e_l1_mean);
        fprintf(f, "    \"e_max\": {\"max\": %.6g, \"mean\": %.6g, \"angles\": %zu},\n",
                r->e_max_max, r->e_max_mean, r->e_max_angles);
        fprintf(f, "    \"e_t\": {\"max\": %.6g, \"mean\": %.6g},\n    \"per_theta_i\": [\n",
                r->e_t_max, r->e_t_mean);
        for (size_t a = 0; a < r->test_angles; a++) {
            const btdf_ti_error *e = &r->per_ti[a];
            fprintf(f,
                    "     {\"theta_i_deg\": %.6f, \"T\": %.9g, \"T_file\": %.9g, \"e_l1\": %.6g, "
                    "\"e_t\": %.6g, \"e_max\": %.6g}%s\n",
                    e->ti / d2r, e->T, e->T_table, e->e_l1, e->e_t, e->e_max,
                    a + 1 < r->test_angles ? "," : "");
        }
        /* Probes [theta_p, phi_p, theta_q, phi_q, value, rho]: degrees (theta from +Z,
           phi from +X) in Radiance's frame; p on the block's side (the view), q the
           light; value is what Radiance's lookup gives, rho Eq. 25 for light from q to
           p. Half spread over the hemisphere, half near the straight-through direction. */
        fprintf(f, "    ],\n    \"probes\": [\n");
        uint64_t z = 0x9e3779b97f4a7c15ull * (uint64_t)(k + 1);
        double sg = b.light == BTDF_SIDE_LEAVE ? -1.0 : 1.0; /* p's side */
        for (int i = 0; i < RAD_PROBES; i++) {
            double u[4];
            for (int d = 0; d < 4; d++) {
                z = z * 6364136223846793005ull + 1442695040888963407ull;
                u[d] = (double)(z >> 11) * (1.0 / 9007199254740992.0);
            }
            double tp = floor(89.0 * u[0] * 1e4 + 0.5) / 1e4;
            double pp = floor(360.0 * u[1] * 1e4 + 0.5) / 1e4, tq, pq;
            if (i % 2) {
                tq = floor(89.0 * sqrt(u[2]) * 1e4 + 0.5) / 1e4;
                pq = floor(360.0 * u[3] * 1e4 + 0.5) / 1e4;
            } else {
                tq = floor(fmin(89.0, tp * (0.7 + 0.6 * u[2])) * 1e4 + 0.5) / 1e4;
                pq = floor((pp + 180.0 + 40.0 * (u[3] - 0.5)) * 1e4 + 0.5) / 1e4;
            }
            double th_p = sg > 0 ? tp : 180.0 - tp, th_q = sg > 0 ? 180.0 - tq : tq;
            double pv[3] = {sin(th_p * d2r) * cos(pp * d2r), sin(th_p * d2r) * sin(pp * d2r),
                            cos(th_p * d2r)};
            double qv[3] = {sin(th_q * d2r) * cos(pq * d2r), sin(th_q * d2r) * sin(pq * d2r),
                            cos(th_q * d2r)};
            double v = btdf_rad_lookup(x, k, pv, qv);
            /* Eq. 25 for the light at q in its own frame (rho depends on cos phi only) */
            double truth = btdf_rho(b.n_light, p->smoothness, p->k0, tq * d2r,
                                    (180.0 - tp) * d2r, (pp - pq) * d2r);
            fprintf(f, "     [%.4f, %.4f, %.4f, %.4f, %.9g, %.9g]%s\n", th_p, pp, th_q, pq, v,
                    truth, i + 1 < RAD_PROBES ? "," : "");
        }
        fprintf(f, "    ]}%s\n", k + 1 < nb ? "," : "");
    }
    fprintf(f, "  ]\n}\n");
}

int run_radiance(const char *prog, const char *path, const char *report, const btdf_params *p,
                 btdf_rad_basis basis, double tol, int threads, int quiet, int best_effort,
                 const char *prov)
{
    char msg[512] = "";
    btdf_rad *x = NULL;
    btdf_status st = btdf_rad_build(p, basis, tol, threads, &x, msg, sizeof msg);
    if (st != BTDF_OK && st != BTDF_EBUDGET)
        return fail(prog, st == BTDF_EINVAL ? 2 : 1, path, msg[0] ? msg : btdf_strerror(st));
    /* The material's name in the scene: the file's base name without .xml. */
    const char *base = strrchr(path, '/');
    base = base ? base + 1 : path;
    char name[128];
    size_t len = strlen(base) > 4 ? strlen(base) - 4 : strlen(base);
    snprintf(name, sizeof name, "%.*s", (int)(len < sizeof name ? len : sizeof name - 1), base);
    btdf_rad_set_name(x, name);
    btdf_report rep[4];
    memset(rep, 0, sizeof rep);
    int met = 1, code = 0, nb = btdf_rad_block_count(x);
    for (int k = 0; k < nb && code == 0; k++) {
        btdf_rad_block_info b;
        btdf_rad_block(x, k, &b);
        btdf_status es = btdf_rad_report(x, k, 0, 0, REPORT_SEED, threads, &rep[k]);
        if (es != BTDF_OK) {
            code = fail(prog, 1, path, btdf_strerror(es));
            break;
        }
        btdf_rad_set_errors(x, k, rep[k].e_l1_max, rep[k].e_t_max);
        met = met && rep[k].met;
        if (!quiet)
            fprintf(stderr,
                    "%s: %s: %s (light %s, as Radiance reads it): %zu %s; build %.3f s, "
                    "estimate %.3f s (%zu angles, %zu points); e_L1 max %.3g (%.3g up to %g "
                    "deg) mean %.3g; e_max max %.3g; e_T max %.3g%s\n",
                    prog, path, b.label, b.light == BTDF_SIDE_ENTER ? "entering, n" : "leaving, 1/n",
                    b.values, basis == BTDF_RAD_TREE3 ? "leaves" : "entries",
                    btdf_rad_seconds_build(x), rep[k].seconds_estimate, rep[k].test_angles,
                    rep[k].test_points, rep[k].e_l1_max, btdf_rad_e_l1_checked(&rep[k]),
                    BTDF_RAD_TI_CHECKED_DEG, rep[k].e_l1_mean, rep[k].e_max_max, rep[k].e_t_max,
                    basis != BTDF_RAD_TREE3 ? ""
                                            : (rep[k].met ? "; tolerance met" : "; TOLERANCE NOT MET"));
    }
    if (code == 0 && !met && !best_effort) {
        fprintf(stderr, "%s: %s: tolerance %g not met%s%s; nothing written (pass --best-effort "
                        "to write it anyway)\n",
                prog, path, tol, msg[0] ? ": " : "", msg);
        code = 3;
    }
    char *buf = NULL;
    size_t blen = 0;
    if (code == 0 && report) {
        FILE *f = open_memstream(&buf, &blen);
        if (!f) {
            code = fail(prog, 1, report, "out of memory");
        } else {
            rad_json(f, x, p, rep, prov);
            if (fclose(f) != 0)
                code = fail(prog, 1, report, "out of memory");
        }
    }
    if (code == 0) { /* the file and its report appear together or not at all */
        btdf_outputs_begin();
        btdf_write_opts w = {NULL, prov};
        btdf_output what = {NULL, NULL, NULL, &w, NULL, x};
        st = btdf_write(&what, path, msg, sizeof msg);
        if (st == BTDF_OK && report)
            st = btdf_write_buffer(report, ".json", buf, blen, msg, sizeof msg);
        if (st == BTDF_OK)
            st = btdf_outputs_commit(msg, sizeof msg);
        else
            btdf_outputs_abort();
        if (st != BTDF_OK)
            code = fail(prog, 1, path, msg[0] ? msg : btdf_strerror(st));
    }
    free(buf);
    for (int k = 0; k < 4; k++)
        btdf_report_clear(&rep[k]);
    btdf_rad_free(x);
    return code;
}
