/* SPDX-License-Identifier: MIT */
/* report_json.c: a btdf_report as JSON, for tables, .bsdf and .xml alike. */
#define _GNU_SOURCE /* open_memstream */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <btdf/btdf.h>
#include <btdf/btdf_io.h>
#include <btdf/btdf_scatfun.h>

#include "report_json.h"
#include "run.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static int fail(const char *prog, const char *path, const char *what)
{
    fprintf(stderr, "%s: %s: %s\n", prog, path, what);
    return 1;
}

/* The shortest decimal that reads back as x (btdf_format_double); four at a time. */
static const char *num(double x)
{
    static char b[4][40];
    static int k;
    k = (k + 1) % 4;
    btdf_format_double(x, b[k], sizeof b[k]);
    return b[k];
}

/* Writes the text in buf atomically at path and frees it; bad: the stream failed. */
static int write_text(const char *prog, const char *path, char *buf, size_t len, int bad)
{
    char msg[512] = "";
    btdf_status st = bad ? BTDF_ENOMEM : btdf_write_buffer(path, ".json", buf, len, msg, sizeof msg);
    free(buf);
    if (st != BTDF_OK)
        return fail(prog, path, msg[0] ? msg : btdf_strerror(st));
    return 0;
}

/* ------------------------------------------------------------------------- */
/* tables                                                                    */
/* ------------------------------------------------------------------------- */

/* The numbers of one part's report, as "key": value lines at the given indent. */
static void json_part(FILE *f, const char *ind, btdf_table_kind kind, const btdf_report *r)
{
    int refl = kind == BTDF_TABLE_FACET_REFLECTION;
    fprintf(f, "%s\"part\": \"%s\",\n%s\"kind\": \"%s\",\n", ind,
            refl ? "reflection" : "transmission", ind, btdf_table_kind_name(kind));
    fprintf(f, "%s\"met\": %s,\n%s\"slices\": %zu,\n%s\"samples\": %zu,\n", ind,
            r->met ? "true" : "false", ind, r->slices, ind, r->samples);
    fprintf(f, "%s\"test_angles\": %zu,\n%s\"test_points\": %zu,\n", ind, r->test_angles, ind,
            r->test_points);
    fprintf(f, "%s\"seconds_estimate\": %.6f,\n", ind, r->seconds_estimate);
    fprintf(f, "%s\"e_l1\": {\"max\": %.6g, \"mean\": %.6g},\n", ind, r->e_l1_max, r->e_l1_mean);
    fprintf(f, "%s\"e_max\": {\"max\": %.6g, \"mean\": %.6g, \"angles\": %zu},\n", ind,
            r->e_max_max, r->e_max_mean, r->e_max_angles);
    fprintf(f, "%s\"e_t\": {\"max\": %.6g, \"mean\": %.6g},\n", ind, r->e_t_max, r->e_t_mean);
    fprintf(f, "%s\"per_theta_i\": [\n", ind);
    for (size_t k = 0; k < r->test_angles; k++) {
        const btdf_ti_error *e = &r->per_ti[k];
        fprintf(f,
                "%s  {\"theta_i_deg\": %.6f, \"%s\": %.9g, \"%s_table\": %.9g, \"e_l1\": %.6g, "
                "\"e_t\": %.6g, \"e_max\": %.6g}%s\n",
                ind, e->ti * 180 / M_PI, refl ? "R" : "T", e->T, refl ? "R" : "T", e->T_table,
                e->e_l1, e->e_t, e->e_max, k + 1 < r->test_angles ? "," : "");
    }
    fprintf(f, "%s]", ind);
}

/* The request's lines of a table's JSON report: material, range, tolerance, met. */
static void json_request(FILE *f, const btdf_table_opts *o, const btdf_report *r, int met)
{
    fprintf(f, "  \"ior\": [");
    for (int c = 0; c < o->params.channels; c++)
        fprintf(f, "%s%s", c ? ", " : "", num(o->params.ior[c]));
    fprintf(f, "],\n  \"smoothness\": %s,\n  \"k0\": %s,\n", num(o->params.smoothness),
            num(o->params.k0));
    /* the model the errors are measured against */
    fprintf(f, "  \"model\": \"%s\",\n", btdf_model_name(o->params.model));
    /* full: the noise floor of the tally it is measured against (btdf_report) */
    if (o->params.model == BTDF_MODEL_FULL)
        fprintf(f, "  \"ms_noise\": %s,\n", num(r->ms_noise));
    fprintf(f, "  \"theta_i_deg\": [%s, %s],\n", num(o->ti_min * 180 / M_PI),
            num(o->ti_max * 180 / M_PI));
    fprintf(f, "  \"tolerance\": %s,\n  \"metric\": \"%s\",\n  \"met\": %s,\n",
            num(r->tolerance), r->metric == BTDF_METRIC_MAX ? "max" : "l1",
            met ? "true" : "false");
}

/* r2: the reflection's report of a table holding both parts, or NULL. */
static void json_table(FILE *f, const btdf_table_opts *o, btdf_table_kind kind,
                       const btdf_report *r, const char *provenance, const btdf_report *r2)
{
    if (kind == BTDF_TABLE_FACET_REFLECTION || r2) {
        /* reflection or both: one object per part, under "parts" */
        run_json_open(f, provenance);
        json_request(f, o, r, r->met && (!r2 || r2->met));
        fprintf(f, "  \"seconds_tabulation\": %.6f,\n  \"peak_bytes\": %zu,\n",
                r->seconds_build, r->peak_bytes);
        fprintf(f, "  \"parts\": [\n    {\n");
        json_part(f, "      ", kind, r);
        if (r2) {
            fprintf(f, "\n    },\n    {\n");
            json_part(f, "      ", BTDF_TABLE_FACET_REFLECTION, r2);
        }
        fprintf(f, "\n    }\n  ]\n}\n");
        return;
    }
    run_json_open(f, provenance);
    fprintf(f, "  \"kind\": \"%s\",\n", btdf_table_kind_name(kind));
    json_request(f, o, r, r->met);
    fprintf(f, "  \"slices\": %zu,\n  \"samples\": %zu,\n", r->slices, r->samples);
    fprintf(f, "  \"seconds_tabulation\": %.6f,\n  \"seconds_estimate\": %.6f,\n"
               "  \"estimate_within_tabulation\": %s,\n",
            r->seconds_build, r->seconds_estimate, r->estimate_in_build ? "true" : "false");
    fprintf(f, "  \"test_angles\": %zu,\n  \"test_points\": %zu,\n", r->test_angles,
            r->test_points);
    fprintf(f, "  \"peak_bytes\": %zu,\n", r->peak_bytes);
    fprintf(f, "  \"e_l1\": {\"max\": %.6g, \"mean\": %.6g},\n", r->e_l1_max, r->e_l1_mean);
    fprintf(f, "  \"e_max\": {\"max\": %.6g, \"mean\": %.6g, \"angles\": %zu},\n", r->e_max_max,
            r->e_max_mean, r->e_max_angles);
    fprintf(f, "  \"e_t\": {\"max\": %.6g, \"mean\": %.6g},\n", r->e_t_max, r->e_t_mean);
    fprintf(f, "  \"per_theta_i\": [\n");
    for (size_t k = 0; k < r->test_angles; k++) {
        const btdf_ti_error *e = &r->per_ti[k];
        fprintf(f,
                "    {\"theta_i_deg\": %.6f, \"T\": %.9g, \"T_table\": %.9g, \"e_l1\": %.6g, "
                "\"e_t\": %.6g, \"e_max\": %.6g}%s\n",
                e->ti * 180 / M_PI, e->T, e->T_table, e->e_l1, e->e_t, e->e_max,
                k + 1 < r->test_angles ? "," : "");
    }
    fprintf(f, "  ]\n}\n");
}

int report_json_table(const char *prog, const char *path, const btdf_table_opts *o,
                      btdf_table_kind kind, const btdf_report *r, const char *prov,
                      const btdf_report *r2)
{
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    if (!f)
        return fail(prog, path, "out of memory");
    json_table(f, o, kind, r, prov, r2);
    int bad = fclose(f) != 0;
    return write_text(prog, path, buf, len, bad);
}

/* ------------------------------------------------------------------------- */
/* .bsdf                                                                     */
/* ------------------------------------------------------------------------- */

/* The .bsdf's blocks as reports and messages name them, by bit (btdf_scatfun_block). */
const char *const report_block_name[4] = {"enter", "leave", "reflection_top",
                                          "reflection_bottom"};

/* One side's report as JSON (the fields of a table's report, docs/tables.md). */
static void json_side(FILE *f, const char *name, btdf_model model, const btdf_report *r,
                      double tol, int last)
{
    fprintf(f, "    \"%s\": {", name);
    if (model == BTDF_MODEL_FULL) /* the noise floor of the tally it is measured against */
        fprintf(f, "\"ms_noise\": %s, ", num(r->ms_noise));
    fprintf(f, "\"met\": %s, \"e_l1\": {\"max\": %.6g, \"mean\": %.6g}, "
               "\"e_max\": {\"max\": %.6g, \"mean\": %.6g}, \"e_t\": {\"max\": %.6g, "
               "\"mean\": %.6g}, \"seconds_estimate\": %.6f, \"test_angles\": %zu, "
               "\"test_points\": %zu,\n      \"per_theta_i\": [\n",
            r->e_l1_max <= tol ? "true" : "false", r->e_l1_max, r->e_l1_mean,
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
int report_json_series(const char *prog, const char *report, const btdf_params *p,
                       const btdf_scatfun *f, const btdf_report reps[4], double tol,
                       double seconds, int met, const char *prov)
{
    char *buf = NULL;
    size_t len = 0;
    FILE *m = open_memstream(&buf, &len);
    if (!m)
        return fail(prog, report, "out of memory");
    run_json_open(m, prov);
    fprintf(m, "  \"kind\": \"scatfun\",\n  \"ior\": [");
    for (int c = 0; c < p->channels; c++)
        fprintf(m, "%s%s", c ? ", " : "", num(p->ior[c]));
    double peak = btdf_scatfun_a0_peak(f);
    fprintf(m, "],\n  \"smoothness\": %s,\n  \"k0\": %s,\n  \"model\": \"%s\",\n"
               "  \"tolerance\": %s,\n"
               "  \"metric\": \"l1\",\n  \"met\": %s,\n  \"nodes\": %zu,\n  \"coefficients\": %zu,\n"
               "  \"max_order\": %zu,\n  \"seconds_build\": %.6f,\n  \"a0_peak\": %.6g,\n"
               "  \"pbrt_v3_single_precision_safe\": %s,\n  \"sides\": {\n",
            num(p->smoothness), num(p->k0), btdf_model_name(p->model), num(tol),
            met ? "true" : "false",
            btdf_scatfun_node_count(f),
            btdf_scatfun_coeff_count(f), btdf_scatfun_max_order(f), seconds, peak,
            peak <= BTDF_SCATFUN_PBRT_FLOAT_SAFE_A0 ? "true" : "false");
    int last = -1;
    for (int b = 0; b < 4; b++)
        if (reps[b].test_angles)
            last = b;
    for (int b = 0; b < 4; b++)
        if (reps[b].test_angles)
            json_side(m, report_block_name[b], p->model, &reps[b], tol, b == last);
    fprintf(m, "  }\n}\n");
    int bad = fclose(m) != 0;
    char msg[512] = "";
    btdf_status st = bad ? BTDF_ENOMEM : btdf_write_buffer(report, ".json", buf, len, msg, sizeof msg);
    free(buf);
    if (st != BTDF_OK)
        return fail(prog, report, msg[0] ? msg : btdf_strerror(st));
    return 0;
}

/* ------------------------------------------------------------------------- */
/* .xml                                                                      */
/* ------------------------------------------------------------------------- */

/* The JSON report of a .xml: per block the error report and probes, the directions
   at which Radiance's own lookup must return the value the file holds. */
#define RAD_PROBES 1000
const char *const report_rad_channel[3] = {"R", "G", "B"};

/* One report's summary and per-angle rows (4 spaces of indent for the fields). */
static void rad_json_report(FILE *f, const btdf_report *r, const btdf_report *coarse,
                            const char *ind)
{
    const double d2r = 3.14159265358979323846 / 180.0;
    fprintf(f, "%s\"seconds_estimate\": %.6f, \"test_angles\": %zu, \"test_points\": %zu,\n",
            ind, r->seconds_estimate, r->test_angles, r->test_points);
    fprintf(f, "%s\"e_l1\": {\"max\": %.6g, \"max_to_%g_deg\": %.6g, \"mean\": %.6g},\n", ind,
            r->e_l1_max, BTDF_RAD_TI_CHECKED_DEG, btdf_rad_e_l1_checked(r), r->e_l1_mean);
    fprintf(f, "%s\"e_max\": {\"max\": %.6g, \"mean\": %.6g, \"angles\": %zu},\n", ind,
            r->e_max_max, r->e_max_mean, r->e_max_angles);
    fprintf(f, "%s\"e_t\": {\"max\": %.6g, \"mean\": %.6g},\n%s\"per_theta_i\": [\n", ind,
            r->e_t_max, r->e_t_mean, ind);
    for (size_t a = 0; a < r->test_angles; a++) {
        const btdf_ti_error *e = &r->per_ti[a];
        char tc[40] = "null";
        for (size_t b = 0; coarse && b < coarse->test_angles; b++)
            if (coarse->per_ti[b].ti == e->ti)
                snprintf(tc, sizeof tc, "%.9g", coarse->per_ti[b].T_table);
        fprintf(f,
                "%s {\"theta_i_deg\": %.6f, \"T\": %.9g, \"T_file\": %.9g, \"T_file_coarse\": %s, "
                "\"e_l1\": %.6g, \"e_t\": %.6g, \"e_max\": %.6g}%s\n",
                ind, e->ti / d2r, e->T, e->T_table, tc, e->e_l1, e->e_t, e->e_max,
                a + 1 < r->test_angles ? "," : "");
    }
    fprintf(f, "%s]", ind);
}

void report_json_radiance(FILE *f, const btdf_rad *x, const btdf_params *p,
                          const btdf_report *rep, const btdf_report *coarse, const char *prov)
{
    run_json_open(f, prov);
    int nch = btdf_rad_channels(x);
    fprintf(f, "  \"format\": \"radiance-xml\",\n  \"basis\": \"%s\",\n",
            btdf_rad_basis_name(btdf_rad_get_basis(x)));
    fprintf(f, "  \"ior\": [");
    for (int c = 0; c < nch; c++)
        fprintf(f, "%s%s", c ? ", " : "", num(p->ior[c]));
    fprintf(f, "],\n  \"smoothness\": %s,\n  \"k0\": %s,\n  \"model\": \"%s\",\n",
            num(p->smoothness), num(p->k0), btdf_model_name(p->model));
    if (nch == 3) {
        double m[3][3];
        btdf_rad_rgb_to_xyz(m);
        fprintf(f, "  \"rgb_to_xyz\": [");
        for (int i = 0; i < 3; i++)
            fprintf(f, "%s[%s, %s, %s]", i ? ", " : "", num(m[i][0]), num(m[i][1]), num(m[i][2]));
        fprintf(f, "],\n");
    }
    fprintf(f, "  \"seconds_build\": %.6f,\n  \"blocks\": [\n", btdf_rad_seconds_build(x));
    const double d2r = 3.14159265358979323846 / 180.0;
    int nb = btdf_rad_block_count(x);
    for (int k = 0; k < nb; k++) {
        btdf_rad_block_info b;
        btdf_rad_block(x, k, &b);
        int refl = strncmp(b.label, "Reflection", 10) == 0;
        fprintf(f, "   {\"label\": \"%s\", \"side\": \"%s\", \"reflection\": %s, \"n\": %s,\n",
                b.label, b.light == BTDF_SIDE_ENTER ? "enter" : "leave", refl ? "true" : "false",
                num(b.n_light));
        const btdf_report *r0 = &rep[k * 3];
        fprintf(f, "    \"values\": %zu, \"depth\": %d, \"tolerance\": %.9g, \"met\": %s,\n",
                b.values, b.depth, r0->tolerance, r0->met ? "true" : "false");
        if (p->model == BTDF_MODEL_FULL) /* the tally's noise floor, the worst channel's */
            fprintf(f, "    \"ms_noise\": %s,\n",
                    num(fmax(r0->ms_noise, fmax(nch == 3 ? rep[k * 3 + 1].ms_noise : 0.0,
                                                nch == 3 ? rep[k * 3 + 2].ms_noise : 0.0))));
        if (nch == 1) {
            rad_json_report(f, r0, &coarse[k * 3], "    ");
            fprintf(f, ",\n");
        } else {
            /* per channel: R, G, B recovered from the file's X, Y, Z, each against
               Eq. 25 at its own index */
            fprintf(f, "    \"channels\": [\n");
            for (int c = 0; c < 3; c++) {
                double nl = b.light == BTDF_SIDE_ENTER ? p->ior[c] : 1.0 / p->ior[c];
                fprintf(f, "     {\"channel\": \"%s\", \"n\": %s,\n", report_rad_channel[c], num(nl));
                rad_json_report(f, &rep[k * 3 + c], &coarse[k * 3 + c], "      ");
                fprintf(f, "}%s\n", c < 2 ? "," : "");
            }
            fprintf(f, "    ],\n");
        }
        /* Probes [theta_p, phi_p, theta_q, phi_q, value, rho]: degrees (theta from +Z,
           phi from +X) in Radiance's frame; p on the block's side (the view), q the
           light (on the other side, or for a reflection block the same); value is what
           Radiance's lookup gives, rho Eq. 25 (or rho_r) for light from q to p. Half
           spread over the hemisphere, half near the straight-through (or specular)
           direction. A three-channel file: value is the file's CIE Y and rho the Y of
           the three channels' Eq. 25, then the file's X and Z follow. */
        fprintf(f, "    \"probes\": [\n");
        uint64_t z = 0x9e3779b97f4a7c15ull * (uint64_t)(k + 1);
        /* p's side: the view's; for reflection the light's side too */
        double sg = (b.light == BTDF_SIDE_LEAVE) != refl ? -1.0 : 1.0;
        double m[3][3];
        btdf_rad_rgb_to_xyz(m);
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
            double th_p = sg > 0 ? tp : 180.0 - tp;
            double th_q = (sg > 0) != refl ? 180.0 - tq : tq;
            double pv[3] = {sin(th_p * d2r) * cos(pp * d2r), sin(th_p * d2r) * sin(pp * d2r),
                            cos(th_p * d2r)};
            double qv[3] = {sin(th_q * d2r) * cos(pq * d2r), sin(th_q * d2r) * sin(pq * d2r),
                            cos(th_q * d2r)};
            double xyz[3];
            btdf_rad_lookup_xyz(x, k, pv, qv, xyz);
            /* the model for the light at q in its own frame (rho depends on cos phi only) */
            double truth = 0.0;
            for (int c = 0; c < nch; c++) {
                double t = btdf_rad_model_rho(x, k, c, tq * d2r,
                                              (refl ? tp : 180.0 - tp) * d2r, (pp - pq) * d2r);
                truth += nch == 1 ? t : m[1][c] * t;
            }
            fprintf(f, "     [%.4f, %.4f, %.4f, %.4f, %.9g, %.9g", th_p, pp, th_q, pq, xyz[1],
                    truth);
            if (nch == 3)
                fprintf(f, ", %.9g, %.9g", xyz[0], xyz[2]);
            fprintf(f, "]%s\n", i + 1 < RAD_PROBES ? "," : "");
        }
        fprintf(f, "    ]}%s\n", k + 1 < nb ? "," : "");
    }
    fprintf(f, "  ]\n}\n");
}
