/* SPDX-License-Identifier: MIT */
/* btdftab.c: the command-line tool; parses arguments and calls libbtdf. */
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <signal.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>
#include <unistd.h>

#include "btdf.h"
#include "formats.h"
#include "manifest.h"
#include "table_impl.h"
#include "tmpfile.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* Exit statuses (README "Exit status"). */
enum { EXIT_USAGE = 2, EXIT_BUDGET = 3 };

static const char *prog = "btdftab";

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Peak resident memory of this process so far, in bytes (Linux reports KiB). */
static size_t peak_rss(void)
{
    struct rusage ru;
    return getrusage(RUSAGE_SELF, &ru) == 0 ? (size_t)ru.ru_maxrss * 1024u : 0;
}

static int fail(int code, const char *fmt, ...)
{
    va_list ap;
    fprintf(stderr, "%s: ", prog);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
    return code;
}

static int ends_with(const char *s, const char *suffix)
{
    size_t ls = strlen(s), lx = strlen(suffix);
    return ls >= lx && strcmp(s + ls - lx, suffix) == 0;
}

static void usage(FILE *f, int verbose)
{
    fprintf(f,
            "usage: btdftab eval [options] [TI TO PHI]     rho at angles (degrees), or rows on stdin\n"
            "       btdftab tabulate [options] -o FILE      write a table (.csv%s)\n"
            "       btdftab albedo [options] [TI ...]       T(ti) and the flat Ft(ti)\n"
            "       btdftab polar [options] -o FILE.png     lobes in the plane of incidence\n"
            "       btdftab build [--force] SCENE.ini       the outputs a scene manifest lists\n"
            "       btdftab inspect FILE                    header and statistics of a file\n"
            "       btdftab --help | --version\n",
            btdf_format_available("exr") ? ", .exr" : "");
    if (!verbose) {
        fprintf(f, "Try 'btdftab --help' for more.\n");
        return;
    }
    fprintf(f,
            "\nModel: Xu & Sun (2008), Eq. 25, the single-scattering BTDF of a Gaussian rough\n"
            "interface; rho in 1/sr without a cosine factor. Angles in degrees: theta_i in\n"
            "[0, 90], theta_o in [90, 180] (transmitted side), phi = 180 the forward plane.\n"
            "\nMaterial options (all commands):\n"
            "  --ior N | R,G,B      relative index n = n_lower / n_upper (default 1.5); n != 1\n"
            "  -s, --smoothness S   s = correlation length / RMS height (default 3)\n"
            "  --k0 K               shadowing constant (default 0.7)\n"
            "\neval:\n"
            "  --table FILE         evaluate a written table (.csv%s, .bsdf) instead of Eq. 25\n"
            "\ntabulate:\n"
            "  -o, --output FILE    .csv, .exr, .png, or .bsdf (pbrt-v3/Mitsuba tabulated,\n"
            "                       built from Eq. 25 directly); '-' writes CSV to stdout\n"
            "  --tolerance E        target error of the adaptive table (default 1e-3)\n"
            "  --metric l1|max      which error must meet E (default l1)\n"
            "  --grid NI,NO,NPHI    a plain regular grid in (theta_i, theta_o, phi) instead\n"
            "  --side S             enter (index n, default), leave (index 1/n); for .bsdf\n"
            "                       also both (the default there)\n"
            "  --theta-i A:B        incidence range in degrees (default 0:90)\n"
            "  --theta-o A:B        --grid only: outgoing range, within 90:180 (default)\n"
            "  --phi A:B            --grid only: azimuth range, within 0:180 (default; rho\n"
            "                       depends on cos phi, so 0:180 holds every azimuth)\n"
            "  --max-samples N      node budget (default 8000000); for .bsdf, when\n"
            "                       given, the stored coefficients\n"
            "  --max-memory MIB     memory cap for the nodes (default 256); for .bsdf,\n"
            "                       when given, the builder's series\n"
            "  --threads N          worker threads, 0 = all cores (default 0)\n"
            "  --report FILE.json   write the error report as JSON\n"
            "  --best-effort        write the table even if the budget stopped refinement\n"
            "  --preview [KIND=]F.png  a picture of the table; KIND is montage (default),\n"
            "                       render (the paper's Figs. 10-11) or render-analytic\n"
            "                       (with Eq. 25 and the difference beside it); repeatable;\n"
            "                       -o F.png is the same as --preview F.png\n"
            "  --size WxH           picture size in pixels (default: per kind)\n"
            "\nbuild:\n"
            "  --force              redo outputs that are up to date\n"
            "  (also --threads, --quiet, --best-effort; docs/pipelines.md has the manifest)\n"
            "\npolar:\n"
            "  --material N:S       one material (repeatable, at most 8 curves in all);\n"
            "                       default: --ior and --smoothness\n"
            "  --angles A,B,...     incident angles in degrees (default 30)\n"
            "  -q, --quiet          no report line on standard error\n"
            "\nExit status: 0 success, 1 failed run, 2 usage error, 3 tolerance not met.\n",
            btdf_format_available("exr") ? ", .exr" : "");
}

/* ------------------------------------------------------------------------- */
/* Argument helpers                                                          */
/* ------------------------------------------------------------------------- */

static int parse_double(const char *flag, const char *s, double *out)
{
    char *e;
    errno = 0;
    double v = strtod(s, &e);
    if (e == s || *e || errno == ERANGE) {
        fail(EXIT_USAGE, "%s: '%s' is not a number", flag, s);
        return 0;
    }
    if (!isfinite(v)) {
        fail(EXIT_USAGE, "%s: '%s': must be a finite number", flag, s);
        return 0;
    }
    *out = v;
    return 1;
}

static int parse_size(const char *flag, const char *s, size_t lo, size_t hi, size_t *out)
{
    char *e;
    errno = 0;
    unsigned long long v = strtoull(s, &e, 10);
    if (e == s || *e || errno == ERANGE || s[0] == '-' || v < lo || v > hi) {
        fail(EXIT_USAGE, "%s: '%s': must be an integer in [%zu, %zu]", flag, s, lo, hi);
        return 0;
    }
    *out = (size_t)v;
    return 1;
}

typedef struct common {
    btdf_params p;
    int threads;
    int quiet;
} common;

/* Consumes a material or common option at argv[*i]; 1 if taken, 0 if not ours, -1 on error. */
static int common_opt(common *c, int argc, char **argv, int *i)
{
    const char *a = argv[*i];
    const char *val = NULL;
#define NEED_VAL()                                                                         \
    do {                                                                                   \
        if (*i + 1 >= argc) {                                                              \
            fail(EXIT_USAGE, "%s: missing value", a);                                      \
            return -1;                                                                     \
        }                                                                                  \
        val = argv[++*i];                                                                  \
    } while (0)
    if (!strcmp(a, "--ior") || !strcmp(a, "-n")) {
        NEED_VAL();
        char buf[256];
        snprintf(buf, sizeof buf, "%s", val);
        int k = 0;
        for (char *tok = strtok(buf, ","); tok; tok = strtok(NULL, ",")) {
            if (k == 3) {
                fail(EXIT_USAGE, "--ior: '%s': give 1 value or 3 (R,G,B)", val);
                return -1;
            }
            if (!parse_double("--ior", tok, &c->p.ior[k++]))
                return -1;
        }
        if (k != 1 && k != 3) {
            fail(EXIT_USAGE, "--ior: '%s': give 1 value or 3 (R,G,B)", val);
            return -1;
        }
        c->p.channels = k;
        return 1;
    }
    if (!strcmp(a, "--smoothness") || !strcmp(a, "-s")) {
        NEED_VAL();
        return parse_double("--smoothness", val, &c->p.smoothness) ? 1 : -1;
    }
    if (!strcmp(a, "--k0")) {
        NEED_VAL();
        return parse_double("--k0", val, &c->p.k0) ? 1 : -1;
    }
    if (!strcmp(a, "--threads")) {
        NEED_VAL();
        size_t v;
        if (!parse_size("--threads", val, 0, 256, &v))
            return -1;
        c->threads = (int)v;
        return 1;
    }
    if (!strcmp(a, "--quiet") || !strcmp(a, "-q")) {
        c->quiet = 1;
        return 1;
    }
    return 0;
#undef NEED_VAL
}

static int check_params(const btdf_params *p)
{
    char msg[256];
    if (btdf_params_check(p, msg, sizeof msg) != BTDF_OK) {
        fail(EXIT_USAGE, "%s", msg);
        return 0;
    }
    return 1;
}

static int check_angles(double ti, double to, double phi, long line)
{
    char where[48] = "";
    if (line > 0)
        snprintf(where, sizeof where, "line %ld: ", line);
    if (!(ti >= 0.0 && ti <= 90.0)) {
        fail(EXIT_USAGE, "%stheta-i %g: must lie in [0, 90] degrees", where, ti);
        return 0;
    }
    if (!(to >= 90.0 && to <= 180.0)) {
        fail(EXIT_USAGE,
             "%stheta-o %g: must lie in [90, 180] degrees (the transmitted hemisphere)", where,
             to);
        return 0;
    }
    if (!isfinite(phi)) {
        fail(EXIT_USAGE, "%sphi %g: must be finite", where, phi);
        return 0;
    }
    return 1;
}

/* Reads up to `want` numbers separated by blanks or commas; returns how many, -1 on junk. */
static int read_row(const char *line, double *v, int want)
{
    int n = 0;
    const char *s = line;
    for (;;) {
        while (*s == ' ' || *s == '\t' || *s == ',' || *s == '\r' || *s == '\n')
            s++;
        if (!*s || *s == '#')
            return n;
        if (n == want)
            return -1;
        char *e;
        double x = strtod(s, &e);
        if (e == s || !isfinite(x))
            return -1;
        v[n++] = x;
        s = e;
    }
}

/* ------------------------------------------------------------------------- */
/* eval                                                                      */
/* ------------------------------------------------------------------------- */

static void print_values(const double *v, int n)
{
    for (int c = 0; c < n; c++)
        printf(c ? " %.17g" : "%.17g", v[c]);
    putchar('\n');
}

static int cmd_eval(int argc, char **argv)
{
    common c = {0};
    btdf_params_default(&c.p);
    const char *table_path = NULL;
    double pos[3];
    int npos = 0;
    for (int i = 1; i < argc; i++) {
        int r = common_opt(&c, argc, argv, &i);
        if (r < 0)
            return EXIT_USAGE;
        if (r)
            continue;
        if (!strcmp(argv[i], "--table")) {
            if (i + 1 >= argc)
                return fail(EXIT_USAGE, "--table: missing value");
            table_path = argv[++i];
        } else if (argv[i][0] == '-' && argv[i][1] && !(argv[i][1] >= '0' && argv[i][1] <= '9') &&
                   argv[i][1] != '.') {
            fail(EXIT_USAGE, "eval: unknown option '%s'", argv[i]);
            usage(stderr, 0);
            return EXIT_USAGE;
        } else {
            if (npos == 3)
                return fail(EXIT_USAGE, "eval: give exactly three angles TI TO PHI");
            if (!parse_double("angle", argv[i], &pos[npos++]))
                return EXIT_USAGE;
        }
    }
    if (npos != 0 && npos != 3)
        return fail(EXIT_USAGE, "eval: give exactly three angles TI TO PHI, or none to read rows");
    btdf_table *t = NULL;
    btdf_scatfun *sf = NULL;
    if (table_path && ends_with(table_path, ".bsdf")) {
        char msg[512];
        btdf_status st = btdf_scatfun_read(table_path, &sf, msg, sizeof msg);
        if (st != BTDF_OK)
            return fail(1, "%s: %s", table_path, msg);
        c.p.channels = btdf_scatfun_channels(sf);
        if (!(btdf_scatfun_sides(sf) & BTDF_SIDE_ENTER)) {
            btdf_scatfun_free(sf);
            /* eval reads light entering through the top (index n); the file has no such
               block, and a 0 would read as a measured value */
            return fail(1, "%s: the file holds no 'enter' side (light entering, index n), "
                           "which eval reads; it was written with --side leave", table_path);
        }
    } else if (table_path) {
        char msg[512];
        btdf_status st = btdf_table_read(table_path, &t, msg, sizeof msg);
        if (st != BTDF_OK)
            return fail(1, "%s: %s", table_path, msg);
        c.p = *btdf_table_get_params(t);
    } else if (!check_params(&c.p)) {
        return EXIT_USAGE;
    }
    int code = 0;
    double out[BTDF_MAX_CHANNELS];
    char line[1024];
    long ln = 0;
    for (;;) {
        double v[3];
        if (npos == 3) {
            if (ln++ > 0)
                break;
            memcpy(v, pos, sizeof v);
        } else {
            if (!fgets(line, sizeof line, stdin))
                break;
            ln++;
            int k = read_row(line, v, 3);
            if (k == 0)
                continue; /* blank or comment line */
            if (k != 3) {
                code = fail(EXIT_USAGE, "line %ld: expected three angles 'TI TO PHI'", ln);
                break;
            }
        }
        if (!check_angles(v[0], v[1], v[2], npos == 3 ? 0 : ln)) {
            code = EXIT_USAGE;
            break;
        }
        if (t) {
            btdf_table_eval(t, v[0] * M_PI / 180.0, v[1] * M_PI / 180.0, v[2] * M_PI / 180.0, out);
        } else if (sf) {
            /* light entering through the top (index n), as pbrt-v3 would read it */
            btdf_scatfun_eval(sf, v[0] * M_PI / 180.0, v[1] * M_PI / 180.0, v[2] * M_PI / 180.0,
                              out);
        } else {
            for (int ch = 0; ch < c.p.channels; ch++)
                out[ch] = btdf_rho_deg(c.p.ior[ch], c.p.smoothness, c.p.k0, v[0], v[1], v[2]);
        }
        print_values(out, c.p.channels);
    }
    btdf_table_free(t);
    btdf_scatfun_free(sf);
    if (fflush(stdout) != 0 && code == 0)
        code = fail(1, "standard output: %s", strerror(errno));
    return code;
}

/* ------------------------------------------------------------------------- */
/* albedo                                                                    */
/* ------------------------------------------------------------------------- */

static int cmd_albedo(int argc, char **argv)
{
    common c = {0};
    btdf_params_default(&c.p);
    double angles[256];
    int na = 0;
    for (int i = 1; i < argc; i++) {
        int r = common_opt(&c, argc, argv, &i);
        if (r < 0)
            return EXIT_USAGE;
        if (r)
            continue;
        if (argv[i][0] == '-' && argv[i][1] && !(argv[i][1] >= '0' && argv[i][1] <= '9')) {
            fail(EXIT_USAGE, "albedo: unknown option '%s'", argv[i]);
            usage(stderr, 0);
            return EXIT_USAGE;
        }
        if (na == 256)
            return fail(EXIT_USAGE, "albedo: at most 256 angles");
        if (!parse_double("theta-i", argv[i], &angles[na]))
            return EXIT_USAGE;
        na++;
    }
    if (!check_params(&c.p))
        return EXIT_USAGE;
    if (na == 0)
        for (int k = 0; k <= 8; k++)
            angles[na++] = 10.0 * k;
    printf("theta_i_deg");
    for (int ch = 0; ch < c.p.channels; ch++)
        printf(c.p.channels == 1 ? ",T,Ft" : ",T_%c,Ft_%c", "rgb"[ch], "rgb"[ch]);
    printf("\n");
    for (int k = 0; k < na; k++) {
        if (!(angles[k] >= 0.0 && angles[k] <= 90.0))
            return fail(EXIT_USAGE, "theta-i %g: must lie in [0, 90] degrees", angles[k]);
        double ti = angles[k] * M_PI / 180.0, T[BTDF_MAX_CHANNELS];
        btdf_transmittance(&c.p, ti, T);
        printf("%.10g", angles[k]);
        for (int ch = 0; ch < c.p.channels; ch++)
            printf(",%.9f,%.9f", T[ch], btdf_fresnel_t(c.p.ior[ch], ti));
        printf("\n");
    }
    return 0;
}

/* ------------------------------------------------------------------------- */
/* tabulate                                                                  */
/* ------------------------------------------------------------------------- */

static void json_report(FILE *f, const btdf_table_opts *o, btdf_table_kind kind,
                        const btdf_report *r, const char *provenance)
{
    fprintf(f, "{\n  \"program\": \"btdftab\",\n  \"version\": \"%s\",\n", BTDF_VERSION_STRING);
    fprintf(f, "  \"command\": \"");
    for (const char *s = provenance; *s; s++) {
        if (*s == '"' || *s == '\\')
            fputc('\\', f);
        if ((unsigned char)*s >= 0x20)
            fputc(*s, f);
    }
    fprintf(f, "\",\n  \"kind\": \"%s\",\n", table_kind_name(kind));
    fprintf(f, "  \"ior\": [");
    for (int c = 0; c < o->params.channels; c++)
        fprintf(f, "%s%.17g", c ? ", " : "", o->params.ior[c]);
    fprintf(f, "],\n  \"smoothness\": %.17g,\n  \"k0\": %.17g,\n", o->params.smoothness,
            o->params.k0);
    fprintf(f, "  \"theta_i_deg\": [%.17g, %.17g],\n", o->ti_min * 180 / M_PI,
            o->ti_max * 180 / M_PI);
    fprintf(f, "  \"tolerance\": %.17g,\n  \"metric\": \"%s\",\n  \"met\": %s,\n",
            r->tolerance, r->metric == BTDF_METRIC_MAX ? "max" : "l1",
            r->met ? "true" : "false");
    fprintf(f, "  \"slices\": %zu,\n  \"samples\": %zu,\n", r->slices, r->samples);
    fprintf(f, "  \"seconds_tabulation\": %.6f,\n  \"seconds_estimate\": %.6f,\n",
            r->seconds_build, r->seconds_estimate);
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

/* Seed of the reported estimate; the builder checks itself with a different one. */
#define REPORT_SEED 20081231u

/* A:B in degrees within [lo, hi], A <= B (A < B when strict). */
static int parse_range(const char *flag, const char *s, double lo, double hi, int strict,
                       double *a, double *b)
{
    const char *colon = strchr(s, ':');
    if (!colon) {
        fail(EXIT_USAGE, "%s: '%s': expected A:B in degrees, e.g. %g:%g", flag, s, lo, hi);
        return 0;
    }
    char buf[128];
    snprintf(buf, sizeof buf, "%.*s", (int)(colon - s), s);
    if (!parse_double(flag, buf, a) || !parse_double(flag, colon + 1, b))
        return 0;
    if (!(*a >= lo && *b <= hi && (strict ? *a < *b : *a <= *b))) {
        fail(EXIT_USAGE, "%s: '%s': need %g <= A %s B <= %g degrees", flag, s, lo,
             strict ? "<" : "<=", hi);
        return 0;
    }
    return 1;
}

#define MAX_PREVIEWS 4

typedef struct preview_req {
    btdf_preview_kind kind;
    int analytic;
    const char *path;
} preview_req;

/* [montage|render|render-analytic=]FILE.png */
static int parse_preview(const char *s, preview_req *r)
{
    const char *eq = strchr(s, '=');
    r->kind = BTDF_PREVIEW_MONTAGE;
    r->analytic = 0;
    r->path = eq ? eq + 1 : s;
    if (eq) {
        size_t l = (size_t)(eq - s);
        if (l == 7 && !strncmp(s, "montage", 7)) {
            r->kind = BTDF_PREVIEW_MONTAGE;
        } else if (l == 6 && !strncmp(s, "render", 6)) {
            r->kind = BTDF_PREVIEW_RENDER;
        } else if (l == 15 && !strncmp(s, "render-analytic", 15)) {
            r->kind = BTDF_PREVIEW_RENDER;
            r->analytic = 1;
        } else {
            fail(EXIT_USAGE, "--preview: '%.*s': kind must be montage, render or "
                             "render-analytic", (int)l, s);
            return 0;
        }
    }
    if (!ends_with(r->path, ".png")) {
        fail(EXIT_USAGE, "--preview: '%s': the picture's name must end in .png", r->path);
        return 0;
    }
    return 1;
}

static int parse_picture_size(const char *s, int *w, int *h)
{
    char tail;
    if (sscanf(s, "%dx%d%c", w, h, &tail) != 2 || *w < 64 || *h < 64 ||
        *w > BTDF_PREVIEW_MAX_SIDE || *h > BTDF_PREVIEW_MAX_SIDE) {
        fail(EXIT_USAGE, "--size: '%s': expected WxH, each in [64, %d] pixels", s,
             BTDF_PREVIEW_MAX_SIDE);
        return 0;
    }
    return 1;
}

typedef struct json_job {
    const btdf_table_opts *o;
    btdf_table_kind kind;
    const btdf_report *r;
    const char *prov;
} json_job;

static btdf_status json_writer(void *ctx, const char *tmp, char *msg, size_t msglen)
{
    const json_job *j = ctx;
    FILE *f = fopen(tmp, "w");
    if (!f) {
        snprintf(msg, msglen, "cannot create: %s", strerror(errno));
        return BTDF_EIO;
    }
    json_report(f, j->o, j->kind, j->r, j->prov);
    int bad = ferror(f);
    bad |= fclose(f) != 0;
    if (bad) {
        snprintf(msg, msglen, "writing failed: %s", strerror(errno));
        return BTDF_EIO;
    }
    return BTDF_OK;
}

static int write_text_atomic(const char *path, const btdf_table_opts *o, btdf_table_kind kind,
                             const btdf_report *r, const char *prov)
{
    json_job j = {o, kind, r, prov};
    char msg[512] = "";
    if (btdf_write_file_atomic(path, ".json", json_writer, &j, msg, sizeof msg) != BTDF_OK)
        return fail(1, "%s: %s", path, msg);
    return 0;
}

/* One side's report as JSON (the fields of a table's report, docs/tables.md). */
static void json_side(FILE *f, const char *name, const btdf_report *r, int last)
{
    fprintf(f, "    \"%s\": {\"met\": %s, \"e_l1\": {\"max\": %.6g, \"mean\": %.6g}, "
               "\"e_max\": {\"max\": %.6g, \"mean\": %.6g}, \"e_t\": {\"max\": %.6g, "
               "\"mean\": %.6g}, \"seconds_estimate\": %.6f, \"test_angles\": %zu, "
               "\"test_points\": %zu,\n      \"per_theta_i\": [\n",
            name, r->e_l1_max <= r->tolerance ? "true" : "false", r->e_l1_max, r->e_l1_mean,
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

typedef struct bsdf_json {
    const btdf_params *p;
    const btdf_scatfun *f;
    const btdf_report *r; /* [2]: enter, leave; test_angles 0 when not built */
    double tol, seconds;
    int met;
    const char *prov;
} bsdf_json;

static btdf_status bsdf_json_writer(void *ctx, const char *tmp, char *msg, size_t msglen)
{
    const bsdf_json *j = ctx;
    FILE *f = fopen(tmp, "w");
    if (!f) {
        snprintf(msg, msglen, "cannot create: %s", strerror(errno));
        return BTDF_EIO;
    }
    fprintf(f, "{\n  \"program\": \"btdftab\",\n  \"version\": \"%s\",\n  \"command\": \"",
            BTDF_VERSION_STRING);
    for (const char *s = j->prov ? j->prov : ""; *s; s++) {
        if (*s == '"' || *s == '\\')
            fputc('\\', f);
        if ((unsigned char)*s >= 0x20)
            fputc(*s, f);
    }
    fprintf(f, "\",\n  \"kind\": \"scatfun\",\n  \"ior\": [");
    for (int c = 0; c < j->p->channels; c++)
        fprintf(f, "%s%.17g", c ? ", " : "", j->p->ior[c]);
    double peak = btdf_scatfun_a0_peak(j->f);
    fprintf(f, "],\n  \"smoothness\": %.17g,\n  \"k0\": %.17g,\n  \"tolerance\": %.17g,\n"
               "  \"metric\": \"l1\",\n  \"met\": %s,\n  \"nodes\": %zu,\n  \"coefficients\": %zu,\n"
               "  \"max_order\": %zu,\n  \"file_bytes\": %zu,\n  \"seconds_build\": %.6f,\n"
               "  \"a0_peak\": %.6g,\n  \"pbrt_v3_single_precision_safe\": %s,\n  \"sides\": {\n",
            j->p->smoothness, j->p->k0, j->tol, j->met ? "true" : "false",
            btdf_scatfun_node_count(j->f), btdf_scatfun_coeff_count(j->f),
            btdf_scatfun_max_order(j->f), btdf_scatfun_file_size(j->f, NULL), j->seconds, peak,
            peak <= BTDF_SCATFUN_PBRT_FLOAT_SAFE_A0 ? "true" : "false");
    int last = j->r[1].test_angles ? 1 : 0;
    if (j->r[0].test_angles)
        json_side(f, "enter", &j->r[0], !last);
    if (j->r[1].test_angles)
        json_side(f, "leave", &j->r[1], 1);
    fprintf(f, "  }\n}\n");
    int bad = ferror(f);
    bad |= fclose(f) != 0;
    if (bad) {
        snprintf(msg, msglen, "writing failed: %s", strerror(errno));
        return BTDF_EIO;
    }
    return BTDF_OK;
}

/* run_bsdf with the JSON report written to report (NULL: none). */
static int run_bsdf_report(const char *path, const btdf_params *p, double tol, int sides,
                           int threads, int quiet, int best_effort, const char *prov,
                           const char *report, size_t max_coeffs, size_t max_bytes)
{
    char msg[512] = "";
    btdf_scatfun *f = NULL;
    double t0 = now_seconds();
    btdf_status st = btdf_scatfun_build_limits(p, tol, (btdf_side)sides, threads, max_coeffs,
                                               max_bytes, &f, msg, sizeof msg);
    double t1 = now_seconds();
    if (st == BTDF_EBUDGET && !f) /* refused before any work: the request cannot be met */
        return fail(EXIT_BUDGET, "%s: %s", path, msg);
    if (st != BTDF_OK && st != BTDF_EBUDGET)
        return fail(st == BTDF_EINVAL ? EXIT_USAGE : 1, "%s: %s", path,
                    msg[0] ? msg : btdf_strerror(st));
    if (!f)
        return fail(1, "%s: %s", path, msg[0] ? msg : btdf_strerror(st));
    /* The error a renderer will see: the format's own evaluation, per side. */
    int met = 1;
    char meta[1024];
    int k = snprintf(meta, sizeof meta, "{\"program\": \"btdftab %s\", \"tolerance\": %g",
                     BTDF_VERSION_STRING, tol);
    btdf_report reps[2];
    memset(reps, 0, sizeof reps);
    for (int s = BTDF_SIDE_ENTER; s <= BTDF_SIDE_LEAVE; s++) {
        if (!(sides & s))
            continue;
        btdf_report r;
        memset(&r, 0, sizeof r);
        double e0 = now_seconds();
        btdf_status es = btdf_scatfun_report(f, p, (btdf_side)s, 0, 0, REPORT_SEED, threads, &r);
        double e1 = now_seconds();
        if (es != BTDF_OK) {
            btdf_report_clear(&reps[0]);
            btdf_scatfun_free(f);
            return fail(1, "%s: error estimate: %s", path, btdf_strerror(es));
        }
        r.tolerance = tol;
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
    if (report) {
        bsdf_json j = {p, f, reps, tol, t1 - t0, met, prov};
        char jm[512] = "";
        if (btdf_write_file_atomic(report, ".json", bsdf_json_writer, &j, jm, sizeof jm) !=
            BTDF_OK)
            code = fail(1, "%s: %s", report, jm);
    }
    btdf_report_clear(&reps[0]);
    btdf_report_clear(&reps[1]);
    if (code == 0 && !met && !best_effort) {
        fprintf(stderr, "%s: %s: tolerance %g not met%s%s; nothing written (pass --best-effort "
                        "to write it anyway)\n",
                prog, path, tol, msg[0] ? ": " : "", msg);
        code = EXIT_BUDGET;
    } else if (code == 0) {
        st = btdf_scatfun_write(f, path, meta, msg, sizeof msg);
        if (st != BTDF_OK)
            code = fail(1, "%s: %s", path, msg[0] ? msg : btdf_strerror(st));
        else if (!met) {
            /* --best-effort wrote it, but the run did not do what was asked */
            fprintf(stderr, "%s: %s: tolerance %g not met%s%s; written anyway (--best-effort), "
                            "exit 3\n", prog, path, tol, msg[0] ? ": " : "", msg);
            code = EXIT_BUDGET;
        }
    }
    btdf_scatfun_free(f);
    return code;
}

int run_bsdf(const char *path, const btdf_params *p, double tol, int sides, int threads,
             int quiet, int best_effort, const char *prov)
{
    return run_bsdf_report(path, p, tol, sides, threads, quiet, best_effort, prov, NULL, 0, 0);
}

/* The options of tabulate that take a value. */
static int takes_value(const char *a)
{
    static const char *const with[] = {"-o", "--output", "--tolerance", "--metric", "--grid",
                                       "--theta-i", "--theta-o", "--phi", "--max-samples",
                                       "--max-memory", "--report", "--side", "--preview",
                                       "--size"};
    for (size_t k = 0; k < sizeof with / sizeof with[0]; k++)
        if (!strcmp(a, with[k]))
            return 1;
    return 0;
}

static int cmd_tabulate(int argc, char **argv, const char *prov)
{
    common c = {0};
    btdf_params_default(&c.p);
    btdf_table_opts o;
    btdf_table_opts_default(&o);
    const char *out = NULL, *report = NULL;
    int best_effort = 0, npreview = 0, pic_w = 0, pic_h = 0, sides = 0, theta_given = 0;
    preview_req previews[MAX_PREVIEWS];
    double ti0 = 0.0, ti1 = 90.0, to0 = 90.0, to1 = 180.0, ph0 = 0.0, ph1 = 180.0;
    int grid_range = 0, samples_given = 0, mem_given = 0;
    size_t mib = 256;
    for (int i = 1; i < argc; i++) {
        int r = common_opt(&c, argc, argv, &i);
        if (r < 0)
            return EXIT_USAGE;
        if (r)
            continue;
        const char *a = argv[i];
        if (takes_value(a) && i + 1 >= argc)
            return fail(EXIT_USAGE, "%s: missing value", a);
        if (!strcmp(a, "-o") || !strcmp(a, "--output")) {
            out = argv[++i];
        } else if (!strcmp(a, "--tolerance")) {
            if (!parse_double(a, argv[++i], &o.tolerance))
                return EXIT_USAGE;
        } else if (!strcmp(a, "--metric")) {
            const char *m = argv[++i];
            if (!strcmp(m, "l1"))
                o.metric = BTDF_METRIC_L1;
            else if (!strcmp(m, "max"))
                o.metric = BTDF_METRIC_MAX;
            else
                return fail(EXIT_USAGE, "--metric: '%s': must be l1 or max", m);
        } else if (!strcmp(a, "--grid")) {
            const char *g = argv[++i];
            unsigned long x, y, z;
            char tail;
            if (sscanf(g, "%lu,%lu,%lu%c", &x, &y, &z, &tail) != 3 || strchr(g, '-'))
                return fail(EXIT_USAGE, "--grid: '%s': expected three counts NI,NO,NPHI", g);
            o.kind = BTDF_TABLE_GRID;
            o.grid_ti = x;
            o.grid_to = y;
            o.grid_phi = z;
        } else if (!strcmp(a, "--theta-i")) {
            if (!parse_range(a, argv[++i], 0.0, 90.0, 0, &ti0, &ti1))
                return EXIT_USAGE;
            theta_given = 1;
        } else if (!strcmp(a, "--theta-o")) {
            if (!parse_range(a, argv[++i], 90.0, 180.0, 1, &to0, &to1))
                return EXIT_USAGE;
            grid_range = 1;
        } else if (!strcmp(a, "--phi")) {
            if (!parse_range(a, argv[++i], 0.0, 180.0, 1, &ph0, &ph1))
                return EXIT_USAGE;
            grid_range = 1;
        } else if (!strcmp(a, "--max-samples")) {
            if (!parse_size(a, argv[++i], 1000, (size_t)1 << 40, &o.max_samples))
                return EXIT_USAGE;
            samples_given = 1;
        } else if (!strcmp(a, "--max-memory")) {
            if (!parse_size(a, argv[++i], 1, 1u << 20, &mib))
                return EXIT_USAGE;
            mem_given = 1;
        } else if (!strcmp(a, "--report")) {
            report = argv[++i];
        } else if (!strcmp(a, "--best-effort")) {
            best_effort = 1;
        } else if (!strcmp(a, "--side")) {
            const char *v = argv[++i];
            if (!strcmp(v, "enter"))
                sides = BTDF_SIDE_ENTER;
            else if (!strcmp(v, "leave"))
                sides = BTDF_SIDE_LEAVE;
            else if (!strcmp(v, "both"))
                sides = BTDF_SIDE_BOTH;
            else
                return fail(EXIT_USAGE, "--side: '%s': must be enter, leave or both", v);
        } else if (!strcmp(a, "--preview")) {
            if (npreview == MAX_PREVIEWS)
                return fail(EXIT_USAGE, "--preview: at most %d pictures", MAX_PREVIEWS);
            if (!parse_preview(argv[++i], &previews[npreview++]))
                return EXIT_USAGE;
        } else if (!strcmp(a, "--size")) {
            if (!parse_picture_size(argv[++i], &pic_w, &pic_h))
                return EXIT_USAGE;
        } else {
            fail(EXIT_USAGE, "tabulate: unknown option '%s'", a);
            usage(stderr, 0);
            return EXIT_USAGE;
        }
    }
    if (out && ends_with(out, ".bsdf")) {
        /* A renderer file is built from Eq. 25 directly: no table is needed. */
        if (!check_params(&c.p))
            return EXIT_USAGE;
        if (theta_given || o.kind == BTDF_TABLE_GRID || npreview)
            return fail(EXIT_USAGE, "%s: --theta-i, --grid and --preview do not apply to .bsdf "
                                    "(the file covers every direction of both hemispheres)", out);
        /* --max-samples caps the stored coefficients, --max-memory the builder's
           series; each only when given (the format has its own budgets otherwise) */
        return run_bsdf_report(out, &c.p, o.tolerance, sides ? sides : BTDF_SIDE_BOTH,
                               c.threads, c.quiet, best_effort, prov, report,
                               samples_given ? o.max_samples : 0,
                               mem_given ? mib << 20 : 0);
    }
    if (sides && sides != BTDF_SIDE_ENTER && out) {
        /* Tables hold one side: light leaving is the table of index 1/n. */
        if (sides == BTDF_SIDE_BOTH)
            return fail(EXIT_USAGE, "--side both: a table holds one side; write two tables, "
                                    "or a .bsdf, which holds both");
        for (int ch = 0; ch < c.p.channels; ch++)
            c.p.ior[ch] = 1.0 / c.p.ior[ch];
    }
    if (out && ends_with(out, ".png")) { /* -o F.png is a montage preview */
        if (npreview == MAX_PREVIEWS)
            return fail(EXIT_USAGE, "--preview: at most %d pictures", MAX_PREVIEWS);
        previews[npreview].kind = BTDF_PREVIEW_MONTAGE;
        previews[npreview].analytic = 0;
        previews[npreview++].path = out;
        out = NULL;
    }
    if (!out && npreview == 0)
        return fail(EXIT_USAGE, "tabulate: no output: give -o FILE (or -o - for CSV on stdout)");
    if (!check_params(&c.p))
        return EXIT_USAGE;
    const btdf_format_ops *fmt = NULL;
    if (out) {
        fmt = strcmp(out, "-") ? btdf_format_for_path(out) : &btdf_format_csv;
        if (!fmt)
            return fail(EXIT_USAGE, "%s: unknown output format: use .csv, .exr, .png or .bsdf", out);
        if (!fmt->available)
            return fail(1, "%s: %s support was switched off at build time (-D%s=disabled)", out,
                        fmt->name, fmt->feature);
    }
    if (npreview > 0 && !BTDF_HAVE_PNG)
        return fail(1, "%s: PNG support was switched off at build time (-Dpng=disabled)",
                    previews[0].path);
    if (grid_range && o.kind != BTDF_TABLE_GRID)
        return fail(EXIT_USAGE, "--theta-o and --phi apply to --grid tables (an adaptive table "
                                "covers every outgoing direction)");
    o.params = c.p;
    o.threads = c.threads;
    o.ti_min = ti0 * M_PI / 180.0;
    o.ti_max = ti1 * M_PI / 180.0;
    o.to_min = to0 * M_PI / 180.0;
    o.to_max = to1 * M_PI / 180.0;
    o.phi_min = ph0 * M_PI / 180.0;
    o.phi_max = ph1 * M_PI / 180.0;
    o.max_bytes = mib << 20;
    char msg[512] = "";
    btdf_table *t = NULL;
    double t0 = now_seconds();
    btdf_status st = btdf_table_build(&o, &t, msg, sizeof msg);
    double t1 = now_seconds();
    if (st != BTDF_OK && st != BTDF_EBUDGET)
        return fail(st == BTDF_EINVAL ? EXIT_USAGE : 1, "%s", msg[0] ? msg : btdf_strerror(st));
    if (!t)
        return fail(1, "%s", msg[0] ? msg : btdf_strerror(st));
    btdf_report r;
    memset(&r, 0, sizeof r);
    btdf_status es = btdf_table_estimate(t, o.ti_min, o.ti_max, 0, 0, REPORT_SEED, o.threads, &r);
    if (es != BTDF_OK) {
        btdf_table_free(t);
        return fail(1, "error estimate: %s", btdf_strerror(es));
    }
    r.seconds_build = t1 - t0;
    r.peak_bytes = peak_rss();
    r.tolerance = o.kind == BTDF_TABLE_GRID ? 0.0 : o.tolerance;
    r.metric = o.metric;
    double e = o.metric == BTDF_METRIC_MAX ? r.e_max_max : r.e_l1_max;
    r.met = o.kind == BTDF_TABLE_GRID ? 1 : e <= o.tolerance;
    char emax[96];
    if (r.e_max_angles)
        snprintf(emax, sizeof emax, "e_max max %.3g mean %.3g", r.e_max_max, r.e_max_mean);
    else
        snprintf(emax, sizeof emax, "e_max n/a (T < 0.01 at every test angle)");
    if (!c.quiet)
        fprintf(stderr,
                "%s: table: %zu slices, %zu samples; tabulation %.3f s, estimate %.3f s "
                "(%zu angles, %zu points); e_L1 max %.3g mean %.3g; %s; "
                "e_T max %.3g mean %.3g; peak memory %.1f MiB%s\n",
                prog, r.slices, r.samples, r.seconds_build, r.seconds_estimate, r.test_angles,
                r.test_points, r.e_l1_max, r.e_l1_mean, emax, r.e_t_max,
                r.e_t_mean, (double)r.peak_bytes / 1048576.0,
                o.kind == BTDF_TABLE_GRID ? "" : (r.met ? "; tolerance met" : "; TOLERANCE NOT MET"));
    int code = 0;
    if (o.kind != BTDF_TABLE_GRID && !r.met) {
        fprintf(stderr, "%s: %s: the table reached %s error %.3g, above the tolerance %g%s%s\n",
                prog, out, o.metric == BTDF_METRIC_MAX ? "max" : "L1", e, o.tolerance,
                st == BTDF_EBUDGET ? ": " : "", st == BTDF_EBUDGET ? msg : "");
        if (!best_effort) {
            fprintf(stderr, "%s: nothing written; raise --max-samples/--max-memory, loosen "
                            "--tolerance, or pass --best-effort\n", prog);
            code = EXIT_BUDGET;
        }
    }
    if (code == 0 && out) {
        btdf_write_opts w = {&r, prov};
        btdf_output_ctx ctx = {t, &w};
        if (!strcmp(out, "-")) {
            st = btdf_format_csv.write_stream(&ctx, stdout, msg, sizeof msg);
            if (st == BTDF_OK && fflush(stdout) != 0)
                st = BTDF_EIO;
        } else {
            st = btdf_write_atomic(fmt, &ctx, out, msg, sizeof msg);
        }
        if (st != BTDF_OK)
            code = fail(1, "%s: %s", out, msg[0] ? msg : btdf_strerror(st));
    }
    for (int k = 0; k < npreview && code == 0; k++) {
        btdf_preview_opts po;
        btdf_preview_opts_default(&po);
        po.kind = previews[k].kind;
        po.analytic = previews[k].analytic;
        po.table = t;
        po.width = pic_w;
        po.height = pic_h;
        st = btdf_preview_write(&po, previews[k].path, msg, sizeof msg);
        if (st != BTDF_OK)
            code = fail(1, "%s: %s", previews[k].path, msg[0] ? msg : btdf_strerror(st));
    }
    if (code == 0 && report)
        code = write_text_atomic(report, &o, btdf_table_get_kind(t), &r, prov);
    btdf_report_clear(&r);
    btdf_table_free(t);
    return code;
}

/* ------------------------------------------------------------------------- */
/* polar                                                                     */
/* ------------------------------------------------------------------------- */

static int cmd_polar(int argc, char **argv)
{
    common c = {0};
    btdf_params_default(&c.p);
    btdf_params mats[BTDF_PREVIEW_MAX_CURVES];
    double angles[BTDF_PREVIEW_MAX_CURVES];
    size_t nm = 0, na = 0;
    const char *out = NULL;
    int w = 0, h = 0;
    for (int i = 1; i < argc; i++) {
        int r = common_opt(&c, argc, argv, &i);
        if (r < 0)
            return EXIT_USAGE;
        if (r)
            continue;
        const char *a = argv[i];
        if (i + 1 >= argc && (!strcmp(a, "-o") || !strcmp(a, "--material") ||
                              !strcmp(a, "--angles") || !strcmp(a, "--size")))
            return fail(EXIT_USAGE, "%s: missing value", a);
        if (!strcmp(a, "-o") || !strcmp(a, "--output")) {
            out = argv[++i];
        } else if (!strcmp(a, "--material")) {
            const char *v = argv[++i];
            const char *colon = strchr(v, ':');
            char buf[64];
            if (!colon || nm == BTDF_PREVIEW_MAX_CURVES)
                return fail(EXIT_USAGE, "--material: '%s': expected N:S (at most %d)", v,
                            BTDF_PREVIEW_MAX_CURVES);
            btdf_params_default(&mats[nm]);
            snprintf(buf, sizeof buf, "%.*s", (int)(colon - v), v);
            if (!parse_double("--material", buf, &mats[nm].ior[0]) ||
                !parse_double("--material", colon + 1, &mats[nm].smoothness))
                return EXIT_USAGE;
            mats[nm].k0 = c.p.k0;
            if (!check_params(&mats[nm]))
                return EXIT_USAGE;
            nm++;
        } else if (!strcmp(a, "--angles")) {
            char buf[256];
            snprintf(buf, sizeof buf, "%s", argv[++i]);
            na = 0;
            for (char *tok = strtok(buf, ","); tok; tok = strtok(NULL, ",")) {
                if (na == BTDF_PREVIEW_MAX_CURVES)
                    return fail(EXIT_USAGE, "--angles: at most %d", BTDF_PREVIEW_MAX_CURVES);
                if (!parse_double("--angles", tok, &angles[na]))
                    return EXIT_USAGE;
                if (!(angles[na] >= 0.0 && angles[na] < 90.0))
                    return fail(EXIT_USAGE, "--angles: %g: must lie in [0, 90) degrees",
                                angles[na]);
                na++;
            }
        } else if (!strcmp(a, "--size")) {
            if (!parse_picture_size(argv[++i], &w, &h))
                return EXIT_USAGE;
        } else {
            fail(EXIT_USAGE, "polar: unknown option '%s'", a);
            usage(stderr, 0);
            return EXIT_USAGE;
        }
    }
    if (!out || !ends_with(out, ".png"))
        return fail(EXIT_USAGE, "polar: give -o FILE.png");
    if (nm == 0) {
        if (!check_params(&c.p))
            return EXIT_USAGE;
        mats[nm++] = c.p;
    }
    if (na == 0)
        angles[na++] = 30.0;
    if (nm * na > BTDF_PREVIEW_MAX_CURVES)
        return fail(EXIT_USAGE, "polar: %zu materials x %zu angles: at most %d curves", nm, na,
                    BTDF_PREVIEW_MAX_CURVES);
    btdf_preview_opts po;
    btdf_preview_opts_default(&po);
    po.kind = BTDF_PREVIEW_POLAR;
    po.materials = mats;
    po.nmaterials = nm;
    po.ti_deg = angles;
    po.nti = na;
    po.width = w;
    po.height = h;
    char msg[512] = "";
    btdf_status st = btdf_preview_write(&po, out, msg, sizeof msg);
    if (st != BTDF_OK)
        return fail(st == BTDF_EINVAL ? EXIT_USAGE : 1, "%s: %s", out,
                    msg[0] ? msg : btdf_strerror(st));
    return 0;
}

static int cmd_inspect(int argc, char **argv)
{
    if (argc != 2 || argv[1][0] == '-')
        return fail(EXIT_USAGE, "inspect: give one file, e.g. btdftab inspect glass.bsdf");
    const char *path = argv[1];
    char msg[512] = "";
    if (ends_with(path, ".bsdf")) {
        btdf_scatfun *f = NULL;
        btdf_status st = btdf_scatfun_read(path, &f, msg, sizeof msg);
        if (st != BTDF_OK)
            return fail(1, "%s: %s", path, msg);
        st = btdf_scatfun_info(f, stdout);
        btdf_scatfun_free(f);
        return st == BTDF_OK ? 0 : fail(1, "standard output: %s", strerror(errno));
    }
    btdf_table *t = NULL;
    btdf_status st = btdf_table_read(path, &t, msg, sizeof msg);
    if (st != BTDF_OK)
        return fail(1, "%s: %s", path, msg);
    const btdf_params *p = btdf_table_get_params(t);
    printf("kind: %s\nchannels: %d\nior:", table_kind_name(btdf_table_get_kind(t)), p->channels);
    for (int ch = 0; ch < p->channels; ch++)
        printf(" %.17g", p->ior[ch]);
    printf("\nsmoothness: %.17g\nk0: %.17g\nslices: %zu\nnodes: %zu\n", p->smoothness, p->k0,
           btdf_table_slice_count(t), btdf_table_node_count(t));
    for (size_t k = 0; k < btdf_table_slice_count(t); k++) {
        btdf_slice s;
        btdf_table_slice(t, k, &s);
        printf("slice %zu: index %.6f deg, %zu x %zu\n", k, s.ti * 180.0 / M_PI, s.nrows,
               s.ncols);
    }
    btdf_table_free(t);
    return 0;
}

static int cmd_build(int argc, char **argv)
{
    manifest_opts mo;
    memset(&mo, 0, sizeof mo);
    mo.prog = prog;
    common c = {0};
    btdf_params_default(&c.p);
    for (int i = 1; i < argc; i++) {
        int r = common_opt(&c, argc, argv, &i);
        if (r < 0)
            return EXIT_USAGE;
        if (r)
            continue;
        if (!strcmp(argv[i], "--force")) {
            mo.force = 1;
        } else if (!strcmp(argv[i], "--best-effort")) {
            mo.best_effort = 1;
        } else if (argv[i][0] == '-' && argv[i][1]) {
            fail(EXIT_USAGE, "build: unknown option '%s'", argv[i]);
            usage(stderr, 0);
            return EXIT_USAGE;
        } else if (mo.path) {
            return fail(EXIT_USAGE, "build: give one manifest, not '%s' and '%s'", mo.path, argv[i]);
        } else {
            mo.path = argv[i];
        }
    }
    if (!mo.path)
        return fail(EXIT_USAGE, "build: give a manifest, e.g. btdftab build scene.ini");
    mo.quiet = c.quiet;
    mo.threads = c.threads;
    mo.progress = !c.quiet && isatty(2); /* progress lines only for a person watching */
    return manifest_run(&mo);
}

/* SIGINT, SIGTERM, SIGHUP: remove the files being written, then die of the signal, so
   an interrupted run leaves no partial output (make and shells see the signal). */
static void on_signal(int sig)
{
    btdf_tmp_remove_all(); /* async-signal-safe: flags and unlink */
    signal(sig, SIG_DFL);
    raise(sig);
}

int main(int argc, char **argv)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    sigaction(SIGHUP, &sa, NULL);
    if (argc < 2) {
        usage(stderr, 0);
        return EXIT_USAGE;
    }
    const char *cmd = argv[1];
    if (!strcmp(cmd, "--help") || !strcmp(cmd, "-h")) {
        usage(stdout, 1);
        return 0;
    }
    if (!strcmp(cmd, "--version")) {
        printf("btdftab %s (OpenEXR %s, PNG %s)\n", btdf_version_string(),
               btdf_format_available("exr") ? "on" : "off", BTDF_HAVE_PNG ? "on" : "off");
        return 0;
    }
    /* The command line, recorded in outputs as their provenance. */
    char prov[2048] = "btdftab";
    for (int i = 1; i < argc; i++) {
        size_t l = strlen(prov);
        snprintf(prov + l, sizeof prov - l, " %s", argv[i]);
    }
    for (int i = 2; i < argc; i++) {
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            usage(stdout, 1);
            return 0;
        }
    }
    if (!strcmp(cmd, "eval"))
        return cmd_eval(argc - 1, argv + 1);
    if (!strcmp(cmd, "tabulate"))
        return cmd_tabulate(argc - 1, argv + 1, prov);
    if (!strcmp(cmd, "albedo"))
        return cmd_albedo(argc - 1, argv + 1);
    if (!strcmp(cmd, "polar"))
        return cmd_polar(argc - 1, argv + 1);
    if (!strcmp(cmd, "build"))
        return cmd_build(argc - 1, argv + 1);
    if (!strcmp(cmd, "inspect"))
        return cmd_inspect(argc - 1, argv + 1);
    fail(EXIT_USAGE, "unknown command '%s'", cmd);
    usage(stderr, 0);
    return EXIT_USAGE;
}
