/* SPDX-License-Identifier: MIT */
/* report_json.c: a btdf_report as JSON, for tables, .bsdf and .xml alike. */
#define _GNU_SOURCE /* open_memstream */
#include <stdio.h>
#include <stdlib.h>

#include <btdf/btdf.h>
#include <btdf/btdf_io.h>

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
