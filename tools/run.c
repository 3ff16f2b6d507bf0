/* SPDX-License-Identifier: MIT */
/* run.c: building, reporting and writing a .bsdf, for `tabulate -o F.bsdf` and `build`. */
#define _GNU_SOURCE /* open_memstream, as tools/btdftab.c uses it */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <btdf/btdf_io.h>
#include <btdf/btdf_scatfun.h>

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

/* One side's report as JSON (the fields of a table's report, docs/tables.md). */
static void json_side(FILE *f, const char *name, const btdf_report *r, double tol, int last)
{
    fprintf(f, "    \"%s\": {\"met\": %s, \"e_l1\": {\"max\": %.6g, \"mean\": %.6g}, "
               "\"e_max\": {\"max\": %.6g, \"mean\": %.6g}, \"e_t\": {\"max\": %.6g, "
               "\"mean\": %.6g}, \"seconds_estimate\": %.6f, \"test_angles\": %zu, "
               "\"test_points\": %zu,\n      \"per_theta_i\": [\n",
            name, r->e_l1_max <= tol ? "true" : "false", r->e_l1_max, r->e_l1_mean,
            r->e_max_max, r->e_max_mean, r->e_t_max, r->e_t_mean, r->seconds_estimate,
            r->test_angles, r->test_points);
    for (size_t k = 0; k < r->test_angles; k++) {
        const btdf_ti_error *e = &r->per_ti[k];
        fprintf(f,
                "        {\"theta_i_deg\": %.6f, \"T\": %.9g, \"T_table\": %.9g, \"e_l1\": %.6g, "
                "\"e_t\": %.6g, \"e_max\": %.6g}%s\n",
                e->ti * 180 / M_PI, e->T, e->T_table, e->e_l1, e->e_t, e->e_max,
                k + 1 < r->test_angles ? "," : "");
    }
    fprintf(f, "      ]}%s\n", last ? "" : ",");
}

/* The .bsdf's JSON report, written atomically like every output. */
static int write_series_report(const char *prog, const char *report, const btdf_params *p,
                               const btdf_scatfun *f, const btdf_report reps[2], double tol,
                               double seconds, int met, const char *prov)
{
    char *buf = NULL;
    size_t len = 0;
    FILE *m = open_memstream(&buf, &len);
    if (!m)
        return fail(prog, 1, report, "out of memory");
    fprintf(m, "{\n  \"program\": \"btdftab\",\n  \"version\": \"%s\",\n  \"command\": \"",
            btdf_version_string());
    for (const char *s = prov ? prov : ""; *s; s++) {
        if (*s == '"' || *s == '\\')
            fputc('\\', m);
        if ((unsigned char)*s >= 0x20)
            fputc(*s, m);
    }
    fprintf(m, "\",\n  \"kind\": \"scatfun\",\n  \"ior\": [");
    for (int c = 0; c < p->channels; c++)
        fprintf(m, "%s%.17g", c ? ", " : "", p->ior[c]);
    double peak = btdf_scatfun_a0_peak(f);
    fprintf(m, "],\n  \"smoothness\": %.17g,\n  \"k0\": %.17g,\n  \"tolerance\": %.17g,\n"
               "  \"metric\": \"l1\",\n  \"met\": %s,\n  \"nodes\": %zu,\n  \"coefficients\": %zu,\n"
               "  \"max_order\": %zu,\n  \"seconds_build\": %.6f,\n  \"a0_peak\": %.6g,\n"
               "  \"pbrt_v3_single_precision_safe\": %s,\n  \"sides\": {\n",
            p->smoothness, p->k0, tol, met ? "true" : "false", btdf_scatfun_node_count(f),
            btdf_scatfun_coeff_count(f), btdf_scatfun_max_order(f), seconds, peak,
            peak <= BTDF_SCATFUN_PBRT_FLOAT_SAFE_A0 ? "true" : "false");
    if (reps[0].test_angles)
        json_side(m, "enter", &reps[0], tol, reps[1].test_angles == 0);
    if (reps[1].test_angles)
        json_side(m, "leave", &reps[1], tol, 1);
    fprintf(m, "  }\n}\n");
    int bad = fclose(m) != 0;
    char msg[512] = "";
    btdf_status st = bad ? BTDF_ENOMEM : btdf_write_buffer(report, ".json", buf, len, msg, sizeof msg);
    free(buf);
    if (st != BTDF_OK)
        return fail(prog, 1, report, msg[0] ? msg : btdf_strerror(st));
    return 0;
}

int run_series(const char *prog, const char *path, const btdf_params *p, double tol, int sides,
               int threads, int quiet, int best_effort, const char *prov)
{
    return run_series_ex(prog, path, p, tol, sides, threads, quiet, best_effort, prov, NULL, 0, 0);
}

int run_series_ex(const char *prog, const char *path, const btdf_params *p, double tol,
                  int sides, int threads, int quiet, int best_effort, const char *prov,
                  const char *report, size_t max_coeffs, size_t max_bytes)
{
    char msg[512] = "";
    btdf_scatfun *f = NULL;
    double t0 = run_now();
    btdf_status st = btdf_scatfun_build_limits(p, tol, (btdf_side)sides, threads, max_coeffs,
                                               max_bytes, &f, msg, sizeof msg);
    double t1 = run_now();
    if (st == BTDF_EBUDGET && !f) /* refused before any work: the request cannot be met */
        return fail(prog, 3, path, msg);
    if (st != BTDF_OK && st != BTDF_EBUDGET)
        return fail(prog, st == BTDF_EINVAL ? 2 : 1, path, msg[0] ? msg : btdf_strerror(st));
    if (!f)
        return fail(prog, 1, path, msg[0] ? msg : btdf_strerror(st));
    /* The error a renderer will see: the format's own evaluation, per side. */
    int met = 1;
    char meta[1024];
    int k = snprintf(meta, sizeof meta, "{\"program\": \"btdftab %s\", \"tolerance\": %g",
                     btdf_version_string(), tol);
    btdf_report reps[2];
    memset(reps, 0, sizeof reps);
    for (int s = BTDF_SIDE_ENTER; s <= BTDF_SIDE_LEAVE; s++) {
        if (!(sides & s))
            continue;
        btdf_report r;
        memset(&r, 0, sizeof r);
        double e0 = run_now();
        btdf_status es = btdf_scatfun_report(f, p, (btdf_side)s, 0, 0, REPORT_SEED, threads, &r);
        double e1 = run_now();
        if (es != BTDF_OK) {
            btdf_report_clear(&reps[0]);
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
        reps[s - 1] = r; /* cleared below */
    }
    double peak = btdf_scatfun_a0_peak(f);
    if (!quiet && peak > BTDF_SCATFUN_PBRT_FLOAT_SAFE_A0)
        fprintf(stderr,
                "%s: %s: warning: values reach %.4g (a_0 peak) > %g: pbrt-v3 built with "
                "single-precision floats (its default) can loop forever sampling this file; "
                "render it with pbrt-v3 built with PBRT_FLOAT_AS_DOUBLE (docs/scatfun.md)\n",
                prog, path, peak, BTDF_SCATFUN_PBRT_FLOAT_SAFE_A0);
    if (k > 0 && (size_t)k < sizeof meta)
        snprintf(meta + k, sizeof meta - (size_t)k, ", \"command\": \"%s\"}", prov ? prov : "");
    int code = 0;
    if (report)
        code = write_series_report(prog, report, p, f, reps, tol, t1 - t0, met, prov);
    btdf_report_clear(&reps[0]);
    btdf_report_clear(&reps[1]);
    if (code == 0 && !met && !best_effort) {
        fprintf(stderr, "%s: %s: tolerance %g not met%s%s; nothing written (pass --best-effort "
                        "to write it anyway)\n",
                prog, path, tol, msg[0] ? ": " : "", msg);
        code = 3;
    } else if (code == 0) {
        btdf_output what = {NULL, f, NULL, NULL, meta};
        st = btdf_write(&what, path, msg, sizeof msg);
        if (st != BTDF_OK) {
            code = fail(prog, 1, path, msg[0] ? msg : btdf_strerror(st));
        } else if (!met) {
            /* --best-effort wrote it, but the run did not do what was asked */
            fprintf(stderr, "%s: %s: tolerance %g not met%s%s; written anyway (--best-effort), "
                            "exit 3\n", prog, path, tol, msg[0] ? ": " : "", msg);
            code = 3;
        }
    }
    btdf_scatfun_free(f);
    return code;
}
