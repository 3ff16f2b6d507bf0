/* SPDX-License-Identifier: MIT */
/* cmd_simulate.c: btdftab simulate: options into btdf_sim_opts, the run with a
   progress bar, the summary on standard error and the JSON report (written whole or
   not at all, by btdf_write_buffer); the distribution's CSV and EXR and the preview
   are written by simulate_out.c. */
#include "cmd_simulate.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <btdf/btdf.h>
#include <btdf/btdf_io.h>
#include <btdf/btdf_preview.h>
#include <btdf/btdf_sim.h>

#include "cmd_simulate_pane.h"
#include "numparse.h"
#include "options.h"
#include "run.h"
#include "simchart.h"
#include "simulate_out.h"
#include "textout.h"

static const char *prog_name = "btdftab";
double deg_given[MAX_ANGLES]; /* the angles as given, for the report */
int profile_1d;               /* --profile 1d: bins measure radians of theta_o, not sr */

int simulate_vfail(int code, const char *fmt, va_list ap)
{
    fprintf(stderr, "%s: simulate: ", prog_name);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    return code;
}

/* s ends in ext, in any case (as the formats' registry reads extensions) */
static int ext_is(const char *s, const char *ext)
{
    size_t n = strlen(s), l = strlen(ext);
    if (n < l)
        return 0;
    for (size_t i = 0; i < l; i++)
        if (tolower((unsigned char)s[n - l + i]) != tolower((unsigned char)ext[i]))
            return 0;
    return 1;
}

static int fail(int code, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    code = simulate_vfail(code, fmt, ap);
    va_end(ap);
    return code;
}

/* A, A,B,..., or A:B:STEP (degrees) into ti (radians). 0 after a usage error. */
static int parse_angles(const char *v, double *ti, size_t *n)
{
    double a[MAX_ANGLES];
    int k = 0;
    if (strchr(v, ':')) {
        char *buf = malloc(strlen(v) + 1); /* any length: no silent cut */
        double lo, hi, st;
        if (!buf)
            return fail(1, "out of memory"), 0;
        strcpy(buf, v);
        char *c1 = strchr(buf, ':'), *c2 = c1 ? strchr(c1 + 1, ':') : NULL;
        if (!c2) {
            free(buf);
            return fail(2, "--theta-i: '%s': expected A:B:STEP in degrees, e.g. 0:80:10", v), 0;
        }
        *c1 = *c2 = 0;
        int bad = num_double(buf, &lo) || num_double(c1 + 1, &hi) || num_double(c2 + 1, &st);
        free(buf);
        if (bad || !(st > 0) || !(hi >= lo) || (hi - lo) / st >= MAX_ANGLES)
            return fail(2, "--theta-i: '%s': need A <= B and STEP > 0, at most %d angles", v,
                        MAX_ANGLES), 0;
        for (double t = lo; t <= hi + 1e-9 * st; t = lo + st * (double)k)
            a[k++] = t;
    } else {
        const char *why = num_double_list(v, a, 1, MAX_ANGLES, &k);
        if (why)
            return fail(2, "--theta-i: '%s': %s", v, why), 0;
    }
    for (int i = 0; i < k; i++) {
        if (!(a[i] >= 0.0 && a[i] < 90.0))
            return fail(2, "--theta-i: %g: must lie in [0, 90) degrees", a[i]), 0;
        ti[i] = a[i] * DEG;
        deg_given[i] = a[i];
    }
    *n = (size_t)k;
    return 1;
}

static int parse_u64(const char *flag, const char *v, size_t lo, size_t hi, size_t *out)
{
    const char *why = num_size(v, lo, hi, out);
    if (why)
        fail(2, "%s: '%s': %s", flag, v, why);
    return !why;
}

static void progress(void *ctx, uint64_t done, uint64_t total, double t_se)
{
    char stage[64];
    if (isfinite(t_se))
        snprintf(stage, sizeof stage, "rays, T error %.2g", t_se);
    else
        snprintf(stage, sizeof stage, "rays");
    run_progress_cb(ctx, stage, (size_t)done, (size_t)(total - done));
}

/* "key": value for one case, or [values] for several. */
static void jfield(FILE *f, const char *key, const btdf_sim_result *r, size_t off, int se)
{
    fprintf(f, "  \"%s\": %s", key, r->count > 1 ? "[" : "");
    for (size_t k = 0; k < r->count; k++) {
        const btdf_sim_est *e = (const btdf_sim_est *)((const char *)&r->tally[k] + off);
        if (k)
            fputs(", ", f);
        text_num(f, se ? e->se : e->mean);
    }
    fprintf(f, "%s,\n", r->count > 1 ? "]" : "");
}

static void jorders(FILE *f, const btdf_sim_tally *t, int T, int se)
{
    const btdf_sim_est *e = T ? t->T_order : t->R_order;
    fputc('[', f);
    for (int o = 0; o < BTDF_SIM_ORDERS; o++) {
        if (o)
            fputs(", ", f);
        text_num(f, se ? e[o].se : e[o].mean);
    }
    fputc(']', f);
}

/* The options a run's numbers depend on, as one string: shards and a merge must agree
   on it (threads, memory and the hierarchy change no number). */
static void fingerprint(const btdf_sim_opts *o, char *out, size_t len)
{
    char b[40];
    size_t at = 0;
#define PUT(...) at += (size_t)snprintf(out + at, at < len ? len - at : 0, __VA_ARGS__)
    PUT("n");
    for (int c = 0; c < o->channels; c++) {
        btdf_format_double(o->ior[c], b, sizeof b);
        PUT("%s%s", c ? "," : "=", b);
    }
    btdf_format_double(o->smoothness, b, sizeof b);
    PUT(" s=%s ti", b);
    for (size_t k = 0; k < o->n_theta; k++) {
        btdf_format_double(o->theta_i[k], b, sizeof b);
        PUT("%s%s", k ? "," : "=", b);
    }
    if (o->profile)
        PUT(" profile=1d");
    PUT(" rays=%llu seed=%llu cells=%d tile=%d bins=%d,%d", (unsigned long long)o->rays,
        (unsigned long long)o->seed, o->cells_per_tau, o->tile_tau, o->theta_bins,
        o->theta_bins ? o->phi_bins : 0);
    at += (size_t)simpane_fingerprint(o, out + at, at < len ? len - at : 0);
#undef PUT
}

static void write_raw(FILE *f, const btdf_sim_opts *o, const btdf_sim_result *r)
{
    static char big[1024 + 40 * MAX_ANGLES];
    fingerprint(o, big, sizeof big);
    uint64_t nb = r->batch_end - r->batch_first;
    size_t hlen = r->raw_hist ? r->count * 4 * (size_t)r->theta_bins * (size_t)r->phi_bins * 3 : 0;
    fprintf(f, "  \"run\": \"%s\",\n  \"raw\": {\"batches\": [%llu, %llu, %llu], \"counts\": [",
            big, (unsigned long long)r->batch_first, (unsigned long long)r->batch_end,
            (unsigned long long)r->batches_total);
    for (size_t i = 0; i < r->count * nb * BTDF_SIM_RAW_Q; i++)
        fprintf(f, "%s%llu", i ? "," : "", (unsigned long long)r->raw_counts[i]);
    fputs("], \"hist\": [", f);
    for (size_t i = 0; i < hlen; i++)
        fprintf(f, "%s%llu", i ? "," : "", (unsigned long long)r->raw_hist[i]);
    fputs("], \"stats\": [", f);
    for (size_t i = 0; i < nb * 3; i++) {
        if (i)
            fputc(',', f);
        text_num(f, r->raw_stats[i]);
    }
    fputs("]},\n", f);
}

/* The comparisons of each case (btdf_sim_compare): the simulated tally against Eq. 25
   (all orders and one hit) and the Walter/Smith BTDF (one hit), for T and R. */
#define NCMP 6
static const struct {
    const char *key;
    btdf_sim_part part;
    int one_hit;
    btdf_model model;
} cmp_def[NCMP] = {
    {"eq25_T", BTDF_SIM_TRANSMISSION, 0, BTDF_MODEL_XU_SUN},
    {"eq25_T1", BTDF_SIM_TRANSMISSION, 1, BTDF_MODEL_XU_SUN},
    {"smith_T1", BTDF_SIM_TRANSMISSION, 1, BTDF_MODEL_SMITH},
    {"eq25_R", BTDF_SIM_REFLECTION, 0, BTDF_MODEL_XU_SUN},
    {"eq25_R1", BTDF_SIM_REFLECTION, 1, BTDF_MODEL_XU_SUN},
    {"smith_R1", BTDF_SIM_REFLECTION, 1, BTDF_MODEL_SMITH},
};

static void jcmp(FILE *f, const btdf_sim_cmp *c)
{
    fputs("{\"model\": ", f);
    text_num(f, c->model_total);
    fputs(", \"model_in_bins\": ", f);
    text_num(f, c->model_in_bins);
    fputs(", \"e_T\": ", f);
    text_num(f, c->e_T);
    fputs(", \"e_T_floor\": ", f);
    text_num(f, c->e_T_floor);
    fputs(", \"e_L1\": ", f);
    text_num(f, c->e_L1);
    fputs(", \"e_L1_floor\": ", f);
    text_num(f, c->e_L1_floor);
    fputs(", \"e_L1_floor_sd\": ", f);
    text_num(f, c->e_L1_floor_sd);
    fputs(", \"chi2\": ", f);
    text_num(f, c->chi2);
    fprintf(f, ", \"dof\": %d}", c->dof);
}

static int write_report(const char *path, const char *prov, const btdf_sim_opts *o,
                        const btdf_sim_result *r, const double *eqT, const double *eqR,
                        const btdf_sim_cmp *cmp)
{
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    if (!f)
        return fail(1, "%s: out of memory for the report", path);
    run_json_open(f, prov);
    fprintf(f, "  \"smoothness\": ");
    text_num(f, o->smoothness);
    fprintf(f, ",\n  \"cases\": [");
    for (size_t k = 0; k < r->count; k++) {
        fprintf(f, "%s{\"theta_i\": ", k ? ", " : "");
        text_num(f, deg_given[k % o->n_theta]);
        fprintf(f, ", \"channel\": %d, \"ior\": ", r->tally[k].channel);
        text_num(f, r->tally[k].ior);
        fputc('}', f);
    }
    fprintf(f, "],\n");
    jfield(f, "R", r, offsetof(btdf_sim_tally, R), 0);
    jfield(f, "T", r, offsetof(btdf_sim_tally, T), 0);
    jfield(f, "R_se", r, offsetof(btdf_sim_tally, R), 1);
    jfield(f, "T_se", r, offsetof(btdf_sim_tally, T), 1);
    jfield(f, "mean_hits", r, offsetof(btdf_sim_tally, mean_hits), 0);
    simpane_json(f, o, r);
    fprintf(f, "  \"orders\": {");
    const char *keys[4] = {"T", "T_se", "R", "R_se"};
    for (int q = 0; q < 4; q++) {
        fprintf(f, "%s\"%s\": %s", q ? ", " : "", keys[q], r->count > 1 ? "[" : "");
        for (size_t k = 0; k < r->count; k++) {
            if (k)
                fputs(", ", f);
            jorders(f, &r->tally[k], q < 2, q & 1);
        }
        fprintf(f, "%s", r->count > 1 ? "]" : "");
    }
    fprintf(f, "},\n  \"eq25\": {\"T\": %s", r->count > 1 ? "[" : "");
    for (size_t k = 0; k < r->count; k++) {
        if (k)
            fputs(", ", f);
        text_num(f, eqT[k]);
    }
    fprintf(f, "%s, \"R\": %s", r->count > 1 ? "]" : "", r->count > 1 ? "[" : "");
    for (size_t k = 0; k < r->count; k++) {
        if (k)
            fputs(", ", f);
        text_num(f, eqR[k]);
    }
    fprintf(f, "%s},\n", r->count > 1 ? "]" : "");
    if (o->profile || o->pane) {
        fputs(o->profile ? "  \"profile\": \"1d\",\n  \"compare\": null,\n"
                         : "  \"compare\": null,\n", f);
        goto surface;
    }
    fputs("  \"compare\": {", f);
    for (int q = 0; q < NCMP; q++) {
        fprintf(f, "%s\"%s\": %s", q ? ", " : "", cmp_def[q].key, r->count > 1 ? "[" : "");
        for (size_t k = 0; k < r->count; k++) {
            if (k)
                fputs(", ", f);
            jcmp(f, &cmp[k * NCMP + (size_t)q]);
        }
        fputs(r->count > 1 ? "]" : "", f);
    }
    fputs("},\n", f);
surface:;
    const btdf_sim_surface *s = &r->surface;
    fprintf(f, "  \"surface\": {\"points_per_side\": %d, \"spacing\": ", s->n);
    text_num(f, s->dx);
    fprintf(f, ", \"tile\": ");
    text_num(f, s->tile);
    fprintf(f, ", \"realisations_measured\": %d, \"rms_height\": ", s->realisations);
    text_num(f, s->rms_height);
    fprintf(f, ", \"rms_slope\": ");
    text_num(f, s->rms_slope);
    fprintf(f, ", \"rms_slope_target\": ");
    text_num(f, (o->profile ? 1.4142135623730951 : 2.0) / o->smoothness);
    fprintf(f, ", \"corr_length\": ");
    text_num(f, s->corr_length);
    fprintf(f, ", \"tile_bytes\": %zu},\n", s->tile_bytes);
    fprintf(f, "  \"rays\": %llu,\n  \"batches\": %llu,\n  \"lost\": %llu,\n  \"seed\": %llu,\n",
            (unsigned long long)o->rays, (unsigned long long)r->tally[0].batches,
            (unsigned long long)r->tally[0].lost, (unsigned long long)o->seed);
    write_raw(f, o, r);
    fprintf(f, "  \"seconds\": ");
    text_num(f, r->seconds);
    fprintf(f, "\n}\n");
    if (fclose(f) != 0) {
        free(buf);
        return fail(1, "%s: out of memory for the report", path);
    }
    char msg[512];
    btdf_status st = btdf_write_buffer(path, ".json", buf, len, msg, sizeof msg);
    free(buf);
    if (st != BTDF_OK)
        return fail(1, "%s: %s", path, msg);
    return 0;
}

/* --merge's reports (the positional arguments), --shard K/N */
static const char *merge_files[256];
static int merge_n = -1; /* -1: no --merge */
static unsigned long shard_k, shard_n;

static int parse_shard(const char *v)
{
    char *e1 = NULL, *e2 = NULL;
    int digits = v[0] >= '0' && v[0] <= '9';
    shard_k = strtoul(v, &e1, 10);
    if (digits && *e1 == '/' && e1[1] >= '0' && e1[1] <= '9')
        shard_n = strtoul(e1 + 1, &e2, 10);
    if (!digits || !e2 || *e2 || shard_n < 1 || shard_k < 1 || shard_k > shard_n ||
        shard_n > 100000)
        return fail(2, "--shard '%s': expected K/N with 1 <= K <= N <= 100000, e.g. 3/8", v);
    return -1;
}

static int parse_bins(const char *v, int *nt, int *np)
{
    double b[2];
    int n = 0;
    const char *why = num_double_list(v, b, 1, 2, &n);
    if (why)
        return fail(2, "--bins: '%s': %s", v, why);
    for (int i = 0; i < n; i++)
        if (!(b[i] >= 1 && b[i] <= 3600 && b[i] == floor(b[i])))
            return fail(2, "--bins: '%s': each count must be a whole number in [1, 3600]", v);
    *nt = (int)b[0];
    *np = n > 1 ? (int)b[1] : 18;
    return -1;
}

static int parse_output(const char *v, const char **out)
{
    size_t n = strlen(v);
    if (n < 5 || (!ext_is(v, ".csv") && !ext_is(v, ".exr")))
        return fail(2, "-o '%s': the distribution is written as .csv or .exr", v);
    if (ext_is(v, ".exr") && !btdf_format_available(".exr"))
        return fail(2, "-o '%s': this build has no OpenEXR (meson -Dopenexr=enabled)", v);
    *out = v;
    return -1;
}

/* Reads n numbers of the JSON array that follows key in text (integers into u or
   doubles into d); 0 when the array holds exactly n of them. */
static int read_array(const char *text, const char *key, size_t n, uint64_t *u, double *d)
{
    const char *p = strstr(text, key);
    if (!p)
        return -1;
    p = strchr(p + strlen(key), '[');
    if (!p)
        return -1;
    p++;
    for (size_t i = 0; i < n; i++) {
        while (*p == ' ' || *p == ',')
            p++;
        char *end = NULL;
        if (u)
            u[i] = strtoull(p, &end, 10);
        else
            d[i] = strtod(p, &end);
        if (end == p)
            return -1;
        p = end;
    }
    while (*p == ' ')
        p++;
    return *p == ']' ? 0 : -1;
}

/* One shard's report into a part for btdf_sim_merge (only the raw fields and the
   counts are set). Returns 0, or the exit status after a message. */
static int read_part(const char *path, const btdf_sim_opts *o, btdf_sim_result *r)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return fail(1, "--merge %s: cannot read it", path);
    size_t cap = 1 << 16, len = 0;
    char *text = malloc(cap);
    for (;;) {
        if (!text)
            break;
        len += fread(text + len, 1, cap - len - 1, f);
        if (len < cap - 1)
            break;
        char *t = realloc(text, cap *= 2);
        if (!t) {
            free(text);
            text = NULL;
            break;
        }
        text = t;
    }
    int bad = ferror(f);
    fclose(f);
    if (!text || bad) {
        free(text);
        return fail(1, "--merge %s: cannot read it", path);
    }
    text[len] = 0;
    static char want[1024 + 40 * MAX_ANGLES];
    fingerprint(o, want, sizeof want);
    const char *run = strstr(text, "\"run\": \"");
    size_t wl = strlen(want);
    if (!run || strncmp(run + 8, want, wl) != 0 || run[8 + wl] != '"') {
        free(text);
        return fail(2, "--merge %s: not a report of these options (its \"run\" must read "
                       "\"%s\")", path, want);
    }
    uint64_t b[3];
    const char *raw = strstr(run, "\"raw\": {"); /* the raw section follows the run line */
    raw = raw ? raw : "";
    size_t jobs = (size_t)o->channels * o->n_theta;
    size_t hlen = o->theta_bins ? jobs * 4 * (size_t)o->theta_bins * (size_t)o->phi_bins * 3 : 0;
    int code = 0;
    if (read_array(raw, "\"batches\":", 3, b, NULL) != 0 || b[0] >= b[1] || b[1] > b[2] ||
        b[2] != btdf_sim_batch_count(o)) /* also bounds the arrays below */
        code = fail(2, "--merge %s: no batch range (\"raw\": {\"batches\": [first, end, "
                       "total]})", path);
    else {
        uint64_t nb = b[1] - b[0];
        r->batch_first = b[0];
        r->batch_end = b[1];
        r->batches_total = b[2];
        r->count = jobs;
        r->theta_bins = o->theta_bins;
        r->phi_bins = o->theta_bins ? o->phi_bins : 0;
        r->raw_counts = calloc(jobs * nb * BTDF_SIM_RAW_Q, sizeof *r->raw_counts);
        r->raw_stats = calloc(nb * 3, sizeof *r->raw_stats);
        r->raw_hist = hlen ? calloc(hlen, sizeof *r->raw_hist) : NULL;
        const char *sec = strstr(text, "\"seconds\": ");
        r->seconds = sec ? strtod(sec + 11, NULL) : 0.0;
        r->seconds = isfinite(r->seconds) ? r->seconds : 0.0;
        if (!r->raw_counts || !r->raw_stats || (hlen && !r->raw_hist))
            code = fail(1, "--merge %s: out of memory", path);
        else if (read_array(raw, "\"counts\":", jobs * nb * BTDF_SIM_RAW_Q, r->raw_counts,
                            NULL) != 0 ||
                 (hlen && read_array(raw, "\"hist\":", hlen, r->raw_hist, NULL) != 0) ||
                 read_array(raw, "\"stats\":", nb * 3, NULL, r->raw_stats) != 0)
            code = fail(2, "--merge %s: its raw tallies do not have the lengths of these "
                           "options", path);
    }
    free(text);
    return code;
}

/* Options into o; -1 to go on, or an exit status. */
static const char *preview_path;

static int parse(const cmd_def *cmd, int argc, char **argv, btdf_sim_opts *o, double *ti,
                 const char **report, int *quiet, const char **dist, int *nt, int *np)
{
    opt_hit hits[64];
    const char *pos[64];
    int npos = 0;
    if (argc > 64)
        return fail(2, "at most 64 arguments");
    int nh = opt_parse(prog_name, cmd, argc, argv, hits, 64, pos, &npos);
    if (nh < 0)
        return 2;
    for (int k = 0; k < nh; k++)
        if (hits[k].id == OPT_HELP) {
            opt_help(stdout, cmd);
            if (fflush(stdout) != 0 || ferror(stdout)) /* a full disk, a closed pipe */
                return fail(1, "standard output: %s", strerror(errno));
            return 0;
        }
    int merging = 0;
    for (int k = 0; k < nh; k++)
        merging |= hits[k].id == OPT_MERGE;
    if (npos > 0 && !merging)
        return fail(2, "unexpected argument '%s' (angles go in --theta-i)", pos[0]);
    if (merging) {
        if (npos == 0)
            return fail(2, "--merge: give the shards' reports, e.g. --merge a.json b.json");
        if (npos > 256)
            return fail(2, "--merge: at most 256 reports");
        for (int k = 0; k < npos; k++)
            merge_files[k] = pos[k];
        merge_n = npos;
    }
    size_t v;
    int code;
    for (int k = 0; k < nh; k++) {
        const char *s = hits[k].value;
        switch (hits[k].id) {
        case OPT_IOR: {
            int n = 0;
            const char *why = num_double_list(s, o->ior, 1, 3, &n);
            if (why || n == 2)
                return fail(2, "--ior: '%s': %s", s, why ? why : "give 1 value or 3 (R,G,B)");
            o->channels = n;
            break;
        }
        case OPT_SMOOTHNESS:
            if (num_double(s, &o->smoothness))
                return fail(2, "--smoothness: '%s': not a number", s);
            break;
        case OPT_THETA_I:
            if (!parse_angles(s, ti, &o->n_theta))
                return 2;
            break;
        case OPT_RAYS:
            if (!parse_u64("--rays", s, 2, (size_t)BTDF_SIM_RAYS_MAX, &v))
                return 2;
            o->rays = v;
            break;
        case OPT_SEED:
            if (!parse_u64("--seed", s, 0, SIZE_MAX, &v))
                return 2;
            o->seed = v;
            break;
        case OPT_CELLS:
            if (!parse_u64("--cells-per-tau", s, BTDF_SIM_CELLS_PER_TAU_MIN,
                           BTDF_SIM_CELLS_PER_TAU_MAX, &v))
                return 2;
            o->cells_per_tau = (int)v;
            break;
        case OPT_TILE:
            if (!parse_u64("--tile", s, BTDF_SIM_TILE_TAU_MIN, BTDF_SIM_TILE_TAU_MAX, &v))
                return 2;
            o->tile_tau = (int)v;
            break;
        case OPT_THREADS:
            if (!parse_u64("--threads", s, 0, 256, &v))
                return 2;
            o->threads = (int)v;
            break;
        case OPT_MAX_MEMORY:
            if (!parse_u64("--max-memory", s, 1, (size_t)1 << 20, &v))
                return 2;
            o->max_memory = v << 20;
            break;
        case OPT_REPORT:
            if (!strcmp(s, "-")) /* not standard output, as tabulate's */
                return fail(2, "--report: '-': the report is a file; give FILE.json");
            *report = s;
            break;
        case OPT_QUIET: *quiet = 1; break;
        case OPT_PREVIEW: {
            size_t n = strlen(s);
            if (n < 5 || !ext_is(s, ".png"))
                return fail(2, "--preview '%s': the picture is a .png", s);
            if (!btdf_format_available(".png"))
                return fail(2, "--preview '%s': this build has no pictures (meson -Dpng=enabled)",
                            s);
            preview_path = s;
            break;
        }
        case OPT_PROFILE:
            if (strcmp(s, "1d") && strcmp(s, "2d"))
                return fail(2, "--profile '%s': 2d (the surface) or 1d (a profile)", s);
            o->profile = !strcmp(s, "1d");
            break;
        case OPT_OUTPUT:
            if ((code = parse_output(s, dist)) >= 0)
                return code;
            break;
        case OPT_BINS:
            if ((code = parse_bins(s, nt, np)) >= 0)
                return code;
            break;
        case OPT_SHARD:
            if ((code = parse_shard(s)) >= 0)
                return code;
            break;
        case OPT_BACK:
        case OPT_THICKNESS:
        case OPT_ABSORPTION:
        case OPT_LIGHT:
            if ((code = simpane_option(prog_name, hits[k].id, s, o)) >= 0)
                return code;
            break;
        default: break;
        }
    }
    return -1;
}

/* --merge: the reports read back and merged into *r (*st the merge's status); 0, or
   the exit status after a message. */
static int merge_parts(const btdf_sim_opts *o, btdf_sim_result **r, btdf_status *st,
                       char *msg, size_t msglen)
{
    btdf_sim_result *parts = calloc((size_t)merge_n, sizeof *parts);
    const btdf_sim_result **pp = calloc((size_t)merge_n, sizeof *pp);
    int rc = parts && pp ? 0 : fail(1, "out of memory");
    for (int k = 0; k < merge_n && rc == 0; k++) {
        rc = read_part(merge_files[k], o, &parts[k]);
        pp[k] = &parts[k];
    }
    if (rc == 0)
        *st = btdf_sim_merge(o, pp, (size_t)merge_n, r, msg, msglen);
    for (int k = 0; parts && k < merge_n; k++) {
        free(parts[k].raw_counts);
        free(parts[k].raw_hist);
        free(parts[k].raw_stats);
    }
    free(parts);
    free(pp);
    return rc;
}

/* The summary on standard error: per case T and R against Eq. 25 (and, for the
   histograms, the comparisons), then the surface and the rays. */
static void print_summary(const btdf_sim_opts *o, const btdf_sim_result *r, const double *eqT,
                          const double *eqR, const btdf_sim_cmp *cmp)
{
    for (size_t k = 0; k < r->count; k++) {
        const btdf_sim_tally *t = &r->tally[k];
        fprintf(stderr,
                "ti %g n %g s %g: T %.5f +- %.5f (orders %.5f %.5f %.5f), R %.5f +- %.5f; "
                "Eq. 25 T %.5f R %.5f; %.3f hits per ray\n",
                t->theta_i / DEG, t->ior, o->smoothness, t->T.mean, t->T.se,
                t->T_order[0].mean, t->T_order[1].mean, t->T_order[2].mean, t->R.mean,
                t->R.se, eqT[k], eqR[k], t->mean_hits.mean);
        const btdf_sim_cmp *a = &cmp[k * NCMP], *b = a + 1, *c = a + 2;
        if (o->pane)
            simpane_summary(stderr, o, t);
        else if (!o->profile)
            fprintf(stderr,
                "  T against Eq. 25: e_T %.3g (noise %.2g), e_L1 %.3g (noise %.2g +- %.2g); "
                "one hit (noise %.2g +- %.2g): Eq. 25 e_L1 %.3g chi2/dof %.3g, Smith e_L1 "
                "%.3g chi2/dof %.3g\n",
                a->e_T, a->e_T_floor, a->e_L1, a->e_L1_floor, a->e_L1_floor_sd,
                b->e_L1_floor, b->e_L1_floor_sd, b->e_L1, b->dof ? b->chi2 / b->dof : 0.0,
                c->e_L1, c->dof ? c->chi2 / c->dof : 0.0);
    }
    fprintf(stderr, "surface: %d x %d points, rms height %.4f, rms slope %.4f (target %.4f), "
                    "correlation length %.4f; %llu rays in %.2f s\n",
            r->surface.n, o->profile ? 1 : r->surface.n, r->surface.rms_height,
            r->surface.rms_slope,
            (o->profile ? 1.4142135623730951 : 2.0) / o->smoothness, r->surface.corr_length,
            (unsigned long long)r->rays_traced, r->seconds);
}

int cmd_simulate(const char *prog, int argc, char **argv, const char *prov)
{
    prog_name = prog;
    const cmd_def *cmd = cmd_find("simulate");
    static double ti[MAX_ANGLES];
    btdf_sim_opts o;
    btdf_sim_opts_default(&o);
    o.max_memory = (size_t)1024 << 20;
    ti[0] = 30.0 * DEG;
    deg_given[0] = 30.0;
    o.theta_i = ti;
    o.n_theta = 1;
    const char *report = NULL, *dist = NULL;
    int quiet = 0, nt = 45, np = 18; /* 2 degrees in theta_o, 10 in |phi| */
    int code = parse(cmd, argc, argv, &o, ti, &report, &quiet, &dist, &nt, &np);
    if (code >= 0 || (code = simpane_finish(prog_name, &o, dist, preview_path)) >= 0)
        return code;
    /* the histograms always: the comparison with the models (e_L1, chi2) needs them;
       a profile's directions are in the plane: |phi| 0 (backward) or 180 (forward) */
    o.theta_bins = nt;
    o.phi_bins = o.profile ? 2 : np;
    profile_1d = o.profile;
    if (merge_n >= 0 && shard_n)
        return fail(2, "--merge and --shard: a merge takes every shard's report");
    if ((merge_n >= 0 || shard_n) && !report)
        return fail(2, "%s needs --report F.json (%s)", shard_n ? "--shard" : "--merge",
                    shard_n ? "the shard's tallies go there" : "the merged report");
    char msg[512];
    btdf_status st = btdf_sim_opts_check(&o, msg, sizeof msg);
    if (st != BTDF_OK)
        return fail(st == BTDF_EBUDGET ? 3 : 2, "%s", msg);
    if (shard_n) {
        /* shards are ranges of batches (realisations): shard K of N takes
           [nb (K-1) / N, nb K / N), so together they hold each batch once */
        uint64_t nb = btdf_sim_batch_count(&o);
        if (shard_n > nb)
            return fail(2, "--shard %lu/%lu: these options make %llu batches, so at most %llu "
                           "shards", shard_k, shard_n, (unsigned long long)nb,
                        (unsigned long long)nb);
        o.batch_first = nb * (shard_k - 1) / shard_n;
        o.batch_end = nb * shard_k / shard_n;
    }
    if (report && btdf_output_check(report, msg, sizeof msg) != BTDF_OK)
        return fail(1, "%s: %s", report, msg);
    if (dist && btdf_output_check(dist, msg, sizeof msg) != BTDF_OK)
        return fail(1, "%s: %s", dist, msg);
    /* an EXR table's slices need distinct angles: said before the run, not after it */
    if (dist && ext_is(dist, ".exr"))
        for (size_t i = 0; i < o.n_theta; i++)
            for (size_t j = 0; j < i; j++)
                if (o.theta_i[i] == o.theta_i[j])
                    return fail(2, "-o %s: angle %g deg given twice (a table's slices need "
                                   "distinct angles)", dist, deg_given[i]);
    if (preview_path && btdf_output_check(preview_path, msg, sizeof msg) != BTDF_OK)
        return fail(1, "%s: %s", preview_path, msg);
    if (preview_path && (size_t)o.channels * o.n_theta > BTDF_CHART_MAX_PANELS)
        return fail(2, "--preview: %zu cases (angles x channels): at most %d panels",
                    (size_t)o.channels * o.n_theta, BTDF_CHART_MAX_PANELS);
    run_progress pr;
    run_progress_start(&pr, !quiet && isatty(2), "simulate");
    o.progress = progress;
    o.progress_ctx = &pr;
    btdf_sim_result *r = NULL;
    if (merge_n >= 0) {
        int rc = merge_parts(&o, &r, &st, msg, sizeof msg);
        run_progress_end(&pr);
        if (rc)
            return rc;
    } else {
        st = btdf_sim_run(&o, &r, msg, sizeof msg);
        run_progress_end(&pr);
    }
    if (st != BTDF_OK)
        return fail(st == BTDF_EBUDGET ? 3 : st == BTDF_EINVAL ? 2 : 1, "%s", msg);
    double *eqT = calloc(r->count, sizeof *eqT), *eqR = calloc(r->count, sizeof *eqR);
    btdf_sim_cmp *cmp = calloc(r->count * NCMP, sizeof *cmp);
    if (!eqT || !eqR || !cmp) {
        free(eqT);
        free(eqR);
        free(cmp);
        btdf_sim_result_free(r);
        return fail(1, "out of memory");
    }
    for (size_t k = 0; k < r->count; k++) {
        btdf_params p;
        btdf_params_default(&p);
        p.ior[0] = r->tally[k].ior;
        p.smoothness = o.smoothness;
        if (btdf_transmittance(&p, r->tally[k].theta_i, &eqT[k]) != BTDF_OK)
            eqT[k] = 0.0;
        if (btdf_reflectance(&p, r->tally[k].theta_i, &eqR[k]) != BTDF_OK)
            eqR[k] = 0.0;
        for (int q = 0; q < NCMP && !o.profile && !o.pane; q++)
            if (btdf_sim_compare(r, k, cmp_def[q].part, cmp_def[q].one_hit, cmp_def[q].model,
                                 p.k0, &cmp[k * NCMP + (size_t)q], msg, sizeof msg) != BTDF_OK) {
                free(eqT);
                free(eqR);
                free(cmp);
                btdf_sim_result_free(r);
                return fail(1, "comparison with the models: %s", msg);
            }
    }
    if (!quiet)
        print_summary(&o, r, eqT, eqR, cmp);
    code = report ? write_report(report, prov, &o, r, eqT, eqR, cmp) : 0;
    if (code == 0 && dist)
        code = !ext_is(dist, ".exr") ? write_dist(dist, prov, &o, r)
                                     : write_dist_exr(dist, prov, &o, r);
    if (code == 0 && preview_path)
        code = write_preview(preview_path, r);
    free(eqT);
    free(eqR);
    free(cmp);
    btdf_sim_result_free(r);
    return code;
}
