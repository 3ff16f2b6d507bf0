/* SPDX-License-Identifier: MIT */
/* btdftab.c: the command-line tool: reads its options through the one table of
   options.c and calls libbtdf through its installed headers only. */
#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <unistd.h>

#include <btdf/btdf.h>

#include "cmd_simulate.h"
#include "evalstream.h"
#include "fastnum.h"
#include "manifest.h"
#include "numparse.h"
#include "options.h"
#include "run.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* Exit statuses (README "Exit status"). */
enum { EXIT_USAGE = 2, EXIT_BUDGET = 3 };

static const char *prog = "btdftab";

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

/* ------------------------------------------------------------------------- */
/* Values                                                                    */
/* ------------------------------------------------------------------------- */

/* Every number of the command line goes through tools/numparse.c. */
static int parse_double(const char *flag, const char *s, double *out)
{
    const char *why = num_double(s, out);
    if (why)
        fail(EXIT_USAGE, "%s: '%s' %s", flag, s, why);
    return !why;
}

static int parse_size(const char *flag, const char *s, size_t lo, size_t hi, size_t *out)
{
    const char *why = num_size(s, lo, hi, out);
    if (why)
        fail(EXIT_USAGE, "%s: '%s': %s", flag, s, why);
    return !why;
}

/* N or R,G,B */
static int parse_ior(const char *val, btdf_params *p)
{
    int k = 0;
    const char *why = num_double_list(val, p->ior, 1, 3, &k);
    if (why || k == 2) {
        fail(EXIT_USAGE, "--ior: '%s': %s", val, why ? why : "give 1 value or 3 (R,G,B)");
        return 0;
    }
    p->channels = k;
    return 1;
}

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
    const char *x = strchr(s, 'x');
    char buf[32];
    size_t W = 0, H = 0;
    if (x && (size_t)(x - s) < sizeof buf)
        snprintf(buf, sizeof buf, "%.*s", (int)(x - s), s);
    if (!x || (size_t)(x - s) >= sizeof buf ||
        num_size(buf, 64, BTDF_PREVIEW_MAX_SIDE, &W) ||
        num_size(x + 1, 64, BTDF_PREVIEW_MAX_SIDE, &H)) {
        fail(EXIT_USAGE, "--size: '%s': expected WxH, each in [64, %d] pixels", s,
             BTDF_PREVIEW_MAX_SIDE);
        return 0;
    }
    *w = (int)W;
    *h = (int)H;
    return 1;
}

/* ------------------------------------------------------------------------- */
/* The options of every command, parsed once                                 */
/* ------------------------------------------------------------------------- */

typedef struct cli {
    unsigned char given[OPT_COUNT]; /* how often each option was given */
    btdf_params p;
    int threads, quiet, force, best_effort, sides, reflection, dry_run, shard_k, shard_n;
    btdf_rad_basis basis;
    btdf_part part; /* --part: a table's lobes (default transmission); a .bsdf's blocks
                       (default both when not given) */
    const char *table, *out, *report;
    btdf_table_opts o; /* tolerance, metric, grid, max_samples */
    size_t mib;
    double ti0, ti1, to0, to1, ph0, ph1;
    double log_decades; /* render previews: 0 linear */
    double zoom;        /* render previews: 0 the whole face */
    int digits;         /* albedo: significant digits (default 7) */
    preview_req previews[MAX_PREVIEWS + 1]; /* + 1: -o F.png */
    int npreview, pic_w, pic_h;
    double mat_n[BTDF_PREVIEW_MAX_CURVES], mat_s[BTDF_PREVIEW_MAX_CURVES];
    double angles[BTDF_PREVIEW_MAX_CURVES];
    size_t nm, na;
    const char *pos[512]; /* positional arguments */
    int npos;
} cli;

#define GIVEN(c, id) ((c)->given[(id)-OPT_HELP])

static void cli_defaults(cli *c)
{
    memset(c, 0, sizeof *c);
    btdf_params_default(&c->p);
    btdf_table_opts_default(&c->o);
    c->part = BTDF_PART_TRANSMISSION;
    c->digits = 7;
    c->mib = 256;
    c->ti1 = 90.0;
    c->to0 = 90.0;
    c->to1 = 180.0;
    c->ph1 = 180.0;
}

/* Takes one option's value into c; 0 after a usage error. */
static int apply(cli *c, const opt_hit *h)
{
    const char *v = h->value;
    switch (h->id) {
    case OPT_IOR: return parse_ior(v, &c->p);
    case OPT_SMOOTHNESS: return parse_double("--smoothness", v, &c->p.smoothness);
    case OPT_K0: return parse_double("--k0", v, &c->p.k0);
    case OPT_MODEL:
        if (!btdf_model_parse(v, &c->p.model)) {
            fail(EXIT_USAGE, "--model: '%s': must be xu-sun or smith", v);
            return 0;
        }
        if (c->p.model == BTDF_MODEL_FULL) {
            fail(EXIT_USAGE, "--model full: not available in this build (xu-sun or smith)");
            return 0;
        }
        return 1;
    case OPT_TABLE: c->table = v; return 1;
    case OPT_PART:
        if (btdf_part_parse(v, &c->part)) {
            c->reflection = c->part == BTDF_PART_REFLECTION;
            return 1;
        }
        fail(EXIT_USAGE, "--part: '%s': must be transmission, reflection or both", v);
        return 0;
    case OPT_OUTPUT: c->out = v; return 1;
    case OPT_REPORT: c->report = v; return 1;
    case OPT_TOLERANCE: return parse_double("--tolerance", v, &c->o.tolerance);
    case OPT_METRIC:
        if (run_parse_metric(v, &c->o.metric))
            return 1;
        fail(EXIT_USAGE, "--metric: '%s': must be l1 or max", v);
        return 0;
    case OPT_GRID: {
        size_t n3[3];
        const char *why = num_size_list(v, 1, 100000, n3, 3);
        if (why) {
            fail(EXIT_USAGE, "--grid: '%s': %s (NI,NO,NPHI)", v, why);
            return 0;
        }
        c->o.kind = BTDF_TABLE_GRID;
        c->o.grid_ti = n3[0];
        c->o.grid_to = n3[1];
        c->o.grid_phi = n3[2];
        return 1;
    }
    case OPT_BASIS:
        if (btdf_rad_basis_parse(v, &c->basis))
            return 1;
        fail(EXIT_USAGE, "--basis: '%s': must be tree3, klems-full, klems-half or klems-quarter",
             v);
        return 0;
    case OPT_SIDE:
        if ((c->sides = run_parse_side(v)) != 0)
            return 1;
        fail(EXIT_USAGE, "--side: '%s': must be enter, leave or both", v);
        return 0;
    case OPT_THETA_I: return parse_range("--theta-i", v, 0.0, 90.0, 0, &c->ti0, &c->ti1);
    case OPT_THETA_O: return parse_range("--theta-o", v, 90.0, 180.0, 1, &c->to0, &c->to1);
    case OPT_PHI: return parse_range("--phi", v, 0.0, 180.0, 1, &c->ph0, &c->ph1);
    case OPT_MAX_SAMPLES:
        return parse_size("--max-samples", v, 1000, (size_t)1 << 40, &c->o.max_samples);
    case OPT_MAX_MEMORY: return parse_size("--max-memory", v, 1, 1u << 20, &c->mib);
    case OPT_THREADS: {
        size_t n;
        if (!parse_size("--threads", v, 0, 256, &n))
            return 0;
        c->threads = (int)n;
        return 1;
    }
    case OPT_PREVIEW:
        if (c->npreview == MAX_PREVIEWS) {
            fail(EXIT_USAGE, "--preview: at most %d pictures", MAX_PREVIEWS);
            return 0;
        }
        return parse_preview(v, &c->previews[c->npreview++]);
    case OPT_SIZE: return parse_picture_size(v, &c->pic_w, &c->pic_h);
    case OPT_LOG_DECADES:
        if (!parse_double("--log-decades", v, &c->log_decades))
            return 0;
        if (!(c->log_decades >= 1.0 && c->log_decades <= 12.0)) {
            fail(EXIT_USAGE, "--log-decades: '%s': must lie in [1, 12]", v);
            return 0;
        }
        return 1;
    case OPT_ZOOM:
        if (!parse_double("--zoom", v, &c->zoom))
            return 0;
        if (!(c->zoom >= 1.0 && c->zoom <= 1000.0)) {
            fail(EXIT_USAGE, "--zoom: '%s': must lie in [1, 1000]", v);
            return 0;
        }
        return 1;
    case OPT_MATERIAL: {
        const char *colon = strchr(v, ':');
        char buf[64];
        if (!colon || c->nm == BTDF_PREVIEW_MAX_CURVES) {
            fail(EXIT_USAGE, "--material: '%s': expected N:S (at most %d)", v,
                 BTDF_PREVIEW_MAX_CURVES);
            return 0;
        }
        snprintf(buf, sizeof buf, "%.*s", (int)(colon - v), v);
        if (!parse_double("--material", buf, &c->mat_n[c->nm]) ||
            !parse_double("--material", colon + 1, &c->mat_s[c->nm]))
            return 0;
        c->nm++;
        return 1;
    }
    case OPT_ANGLES: {
        int k = 0;
        const char *why = num_double_list(v, c->angles, 1, BTDF_PREVIEW_MAX_CURVES, &k);
        if (why) {
            fail(EXIT_USAGE, "--angles: '%s': %s", v, why);
            return 0;
        }
        for (int i = 0; i < k; i++)
            if (!(c->angles[i] >= 0.0 && c->angles[i] < 90.0)) {
                fail(EXIT_USAGE, "--angles: %g: must lie in [0, 90) degrees", c->angles[i]);
                return 0;
            }
        c->na = (size_t)k;
        return 1;
    }
    case OPT_FORCE: c->force = 1; return 1;
    case OPT_DRY_RUN: c->dry_run = 1; return 1;
    case OPT_SHARD: {
        /* digits only on both sides of the slash, at most 6 each (N <= 100000): no
           blanks, no signs, nothing sscanf's %d would wrap */
        long k = 0, n = 0;
        const char *q = v;
        int dk = 0, dn = 0;
        for (; *q >= '0' && *q <= '9' && dk < 7; q++, dk++)
            k = k * 10 + (*q - '0');
        int slash = *q == '/';
        if (slash)
            q++;
        for (; *q >= '0' && *q <= '9' && dn < 7; q++, dn++)
            n = n * 10 + (*q - '0');
        if (!slash || *q || dk == 0 || dn == 0 || dk > 6 || dn > 6 || n < 1 || n > 100000 ||
            k < 1 || k > n) {
            fail(EXIT_USAGE, "--shard: '%s': expected K/N with 1 <= K <= N, e.g. 3/8", v);
            return 0;
        }
        c->shard_k = (int)k;
        c->shard_n = (int)n;
        return 1;
    }
    case OPT_BEST_EFFORT: c->best_effort = 1; return 1;
    case OPT_ESTIMATE:
        if (!strcmp(v, "full"))
            c->o.estimate = BTDF_ESTIMATE_FULL;
        else if (!strcmp(v, "fast"))
            c->o.estimate = BTDF_ESTIMATE_FAST;
        else if (!strcmp(v, "none"))
            c->o.estimate = BTDF_ESTIMATE_NONE;
        else {
            fail(EXIT_USAGE, "--estimate: '%s': must be full, fast or none", v);
            return 0;
        }
        return 1;
    case OPT_QUIET: c->quiet = 1; return 1;
    case OPT_DIGITS: {
        size_t d;
        if (!parse_size("--digits", v, 1, 17, &d))
            return 0;
        c->digits = (int)d;
        return 1;
    }
    case OPT_RAYS: /* simulate's own: tools/cmd_simulate.c */
    case OPT_SEED:
    case OPT_CELLS:
    case OPT_TILE:
    case OPT_HELP:
    case OPT_END: break;
    }
    return 1;
}

/* Parses the command's arguments into c. Returns -1 to go on, or an exit status
   (0 after --help). */
static int parse_command(const cmd_def *cmd, int argc, char **argv, cli *c)
{
    cli_defaults(c);
    opt_hit hits[512];
    if ((size_t)argc > sizeof c->pos / sizeof c->pos[0])
        return fail(EXIT_USAGE, "%s: at most %zu arguments", cmd->name,
                    sizeof c->pos / sizeof c->pos[0]);
    int nh = opt_parse(prog, cmd, argc, argv, hits, (int)(sizeof hits / sizeof hits[0]),
                       c->pos, &c->npos);
    if (nh < 0)
        return EXIT_USAGE;
    for (int k = 0; k < nh; k++)
        if (hits[k].id == OPT_HELP) {
            opt_help(stdout, cmd);
            return fflush(stdout) == 0 ? 0 : 1;
        }
    for (int k = 0; k < nh; k++) {
        GIVEN(c, hits[k].id)++;
        if (!apply(c, &hits[k]))
            return EXIT_USAGE;
    }
    return -1;
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

/* The folder of path exists and can take a new file: checked before the work. */
/* An output may be written (btdf_output_check: its folder takes a new file, and what
   is there now is a regular file), checked before the work. */
static int folder_writable(const char *path)
{
    char msg[512];
    if (btdf_output_check(path, msg, sizeof msg) != BTDF_OK) {
        fail(1, "%s: %s", path, msg);
        return 0;
    }
    return 1;
}

/* ------------------------------------------------------------------------- */
/* eval                                                                      */
/* ------------------------------------------------------------------------- */

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

/* The reflected side: theta-r in [0, 90] (MODEL.md section 8). */
static int check_angles_r(double ti, double tr, double phi, long line)
{
    char where[48] = "";
    if (line > 0)
        snprintf(where, sizeof where, "line %ld: ", line);
    if (!(ti >= 0.0 && ti <= 90.0))
        return fail(EXIT_USAGE, "%stheta-i %g: must lie in [0, 90] degrees", where, ti), 0;
    if (!(tr >= 0.0 && tr <= 90.0))
        return fail(EXIT_USAGE,
                    "%stheta-r %g: must lie in [0, 90] degrees (the reflected hemisphere)",
                    where, tr), 0;
    if (!isfinite(phi))
        return fail(EXIT_USAGE, "%sphi %g: must be finite", where, phi), 0;
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
        size_t len = strcspn(s, " \t,\r\n#");
        char tok[64];
        if (len >= sizeof tok)
            return -1;
        memcpy(tok, s, len);
        tok[len] = 0;
        if (num_double(tok, &v[n]) != NULL)
            return -1;
        n++;
        s += len;
    }
}

/* Everything printed reached standard output (a full disk, a closed pipe are
   errors): code, or 1 with a message. */
static int stdout_done(int code)
{
    int bad = fflush(stdout) != 0;
    bad |= ferror(stdout) != 0;
    if (bad && code == 0)
        return fail(1, "standard output: %s", errno ? strerror(errno) : "write error");
    return code;
}

/* The incidence range a table holds, in degrees: its first and last slices. A
   facet-reciprocal table (n < 1) is sliced by the outgoing direction instead, so its
   slices do not bound theta-i: the whole range is left open there. */
static void table_ti_range(const btdf_table *t, double *range)
{
    size_t ns = btdf_table_slice_count(t);
    btdf_slice first, last;
    if (ns == 0 || btdf_table_get_kind(t) == BTDF_TABLE_FACET_RECIPROCAL ||
        btdf_table_slice(t, 0, &first) != BTDF_OK || btdf_table_slice(t, ns - 1, &last) != BTDF_OK)
        return;
    range[0] = first.ti * 180.0 / M_PI;
    range[1] = last.ti * 180.0 / M_PI;
}

/* The shortest decimal that reads back to x (btdf_format_double), in a static buffer. */
static const char *num(double x)
{
    static char b[4][40];
    static int k;
    k = (k + 1) % 4;
    btdf_format_double(x, b[k], sizeof b[k]);
    return b[k];
}

/* One row of %.17g values (fastnum_g17 gives printf's bytes, faster). */
static void print_values(const double *v, int n)
{
    char buf[BTDF_MAX_CHANNELS * 32 + 2];
    int len = 0;
    for (int c = 0; c < n; c++) {
        if (c)
            buf[len++] = ' ';
        len += fastnum_g17(v[c], buf + len);
    }
    buf[len++] = '\n';
    fwrite(buf, 1, (size_t)len, stdout);
}

static int cmd_eval(const cli *c)
{
    btdf_params p = c->p;
    double pos[3];
    int npos = c->npos;
    if (npos != 0 && npos != 3)
        return fail(EXIT_USAGE, "eval: give exactly three angles TI TO PHI, or none to read rows");
    for (int k = 0; k < npos; k++)
        if (!parse_double("angle", c->pos[k], &pos[k]))
            return EXIT_USAGE;
    if (c->table && (GIVEN(c, OPT_IOR) || GIVEN(c, OPT_SMOOTHNESS) || GIVEN(c, OPT_K0)))
        return fail(EXIT_USAGE, "--ior, --smoothness and --k0 do not apply with --table "
                                "(the table gives the material)");
    if (c->part == BTDF_PART_BOTH)
        return fail(EXIT_USAGE, "--part both: eval reads one part at a time, transmission or "
                                "reflection");
    btdf_input in = {NULL, NULL};
    const btdf_table *tpart = NULL; /* the part of in.table that is evaluated */
    double ti_range[2] = {0.0, 90.0}; /* degrees */
    if (c->table) {
        char msg[512];
        btdf_status st = btdf_read(c->table, &in, msg, sizeof msg);
        if (st != BTDF_OK)
            return fail(1, "%s: %s", c->table, msg);
        if (in.table) {
            p = *btdf_table_get_params(in.table);
            tpart = btdf_table_part(in.table, c->reflection ? BTDF_PART_REFLECTION
                                                            : BTDF_PART_TRANSMISSION);
            if (!tpart) {
                int holds = (int)btdf_table_parts(in.table);
                btdf_table_free(in.table);
                return fail(1, "%s: the table holds the %s only; give --part %s",
                            c->table, btdf_part_name((btdf_part)holds),
                            btdf_part_name((btdf_part)holds));
            }
            table_ti_range(tpart, ti_range);
        } else if (c->reflection) {
            btdf_scatfun_free(in.scatfun);
            return fail(1, "%s: --part reflection: eval reads the transmission of a .bsdf (its "
                           "reflection blocks are for renderers)", c->table);
        } else {
            p.channels = btdf_scatfun_channels(in.scatfun);
            if (!(btdf_scatfun_sides(in.scatfun) & BTDF_SIDE_ENTER)) {
                btdf_scatfun_free(in.scatfun);
                /* eval reads light entering through the top (index n); the file has no
                   such block, and a 0 would read as a measured value */
                return fail(1, "%s: the file holds no 'enter' side (light entering, index n), "
                               "which eval reads; it was written with --side leave", c->table);
            }
        }
    } else if (!check_params(&p)) {
        return EXIT_USAGE;
    }
    if (npos == 0 && !in.table && !in.scatfun) { /* the model on rows from stdin */
        char err[256];
        int rc = eval_stream(stdin, stdout, &p, c->reflection, c->threads, err, sizeof err);
        if (rc)
            fail(rc, "%s", err);
        if (fflush(stdout) != 0 && rc == 0)
            rc = fail(1, "standard output: %s", strerror(errno));
        return rc;
    }
    int code = 0;
    double out[BTDF_MAX_CHANNELS];
    char *line = NULL; /* rows of any length */
    size_t cap = 0;
    long ln = 0;
    for (;;) {
        double v[3];
        if (npos == 3) {
            if (ln++ > 0)
                break;
            memcpy(v, pos, sizeof v);
        } else {
            if (getline(&line, &cap, stdin) < 0)
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
        if (c->reflection ? !check_angles_r(v[0], v[1], v[2], npos == 3 ? 0 : ln)
                          : !check_angles(v[0], v[1], v[2], npos == 3 ? 0 : ln)) {
            code = EXIT_USAGE;
            break;
        }
        /* the slices' angles are radians turned into degrees: the rounding of that
           must not reject the range's own ends, so the ends get 1e-9 degrees */
        if (!(v[0] >= ti_range[0] - 1e-9 && v[0] <= ti_range[1] + 1e-9)) {
            char where[48] = "";
            if (npos != 3)
                snprintf(where, sizeof where, "line %ld: ", ln);
            code = fail(EXIT_USAGE, "%stheta-i %g: outside the incidence range of %s, %.6g:%.6g "
                        "degrees", where, v[0], c->table, ti_range[0], ti_range[1]);
            break;
        }
        double ti = v[0] * M_PI / 180.0, to = v[1] * M_PI / 180.0, phi = v[2] * M_PI / 180.0;
        if (tpart) {
            btdf_table_eval(tpart, ti, to, phi, out);
        } else if (c->reflection) {
            for (int ch = 0; ch < p.channels; ch++)
                out[ch] = btdf_rho_r_model_deg(p.model, p.ior[ch], p.smoothness, p.k0, v[0],
                                               v[1], v[2]);
        } else if (in.scatfun) {
            /* light entering through the top (index n), as pbrt-v3 would read it */
            btdf_scatfun_eval(in.scatfun, ti, to, phi, out);
        } else {
            for (int ch = 0; ch < p.channels; ch++)
                out[ch] = btdf_rho_model_deg(p.model, p.ior[ch], p.smoothness, p.k0, v[0],
                                             v[1], v[2]);
        }
        print_values(out, p.channels);
        if (ferror(stdout))
            break; /* the reader is gone: stdout_done says so */
    }
    free(line);
    btdf_table_free(in.table);
    btdf_scatfun_free(in.scatfun);
    return stdout_done(code);
}

/* ------------------------------------------------------------------------- */
/* albedo                                                                    */
/* ------------------------------------------------------------------------- */

/* Below this R + T the model has lost more light than a user would guess: its single
   scattering and the shadowing term V(ti) V(to) drop what real rough surfaces scatter
   again (docs/model.md, "Where the model holds"). */
#define ALBEDO_WARN 0.9

/* One warning line when R(ti) + T(ti) < ALBEDO_WARN for some channel; `what` says
   where the angle comes from. */
static void warn_albedo(const btdf_params *p, double ti_deg, double rt, const char *what)
{
    fprintf(stderr,
            "%s: warning: R + T = %.3g at theta_i %s degrees (%s; n = %g, s = %g): the "
            "model loses %.0f%% of the light there, to its shadowing term; it holds for "
            "smoother surfaces and smaller angles (docs/model.md, \"Where the model "
            "holds\"; --quiet silences this)\n",
            prog, rt, num(ti_deg), what, p->ior[0], p->smoothness, 100.0 * (1.0 - rt));
}

/* The smallest R + T over the channels at ti (radians). */
static double albedo_min(const btdf_params *p, double ti)
{
    double T[BTDF_MAX_CHANNELS], R[BTDF_MAX_CHANNELS], lo = 1.0;
    btdf_transmittance(p, ti, T);
    btdf_reflectance(p, ti, R);
    for (int ch = 0; ch < p->channels; ch++)
        lo = R[ch] + T[ch] < lo ? R[ch] + T[ch] : lo;
    return lo;
}

static int cmd_albedo(const cli *c)
{
    double angles[256];
    int na = 0;
    if (c->npos > 256)
        return fail(EXIT_USAGE, "albedo: at most 256 angles");
    for (int k = 0; k < c->npos; k++)
        if (!parse_double("theta-i", c->pos[k], &angles[na++]))
            return EXIT_USAGE;
    if (!check_params(&c->p))
        return EXIT_USAGE;
    if (na == 0)
        for (int k = 0; k <= 8; k++)
            angles[na++] = 10.0 * k;
    for (int k = 0; k < na; k++)
        if (!(angles[k] >= 0.0 && angles[k] <= 90.0))
            return fail(EXIT_USAGE, "theta-i %g: must lie in [0, 90] degrees", angles[k]);
    const btdf_params *p = &c->p;
    printf("theta_i_deg");
    for (int ch = 0; ch < p->channels; ch++) {
        char sfx[3] = {'_', "rgb"[ch], 0};
        const char *x = p->channels == 1 ? "" : sfx;
        printf(",T%s,Ft%s,R%s,R+T%s", x, x, x, x);
    }
    printf("\n");
    int low = -1; /* the angle of the lowest R + T below ALBEDO_WARN */
    double low_rt = ALBEDO_WARN;
    for (int k = 0; k < na; k++) {
        double ti = angles[k] * M_PI / 180.0, T[BTDF_MAX_CHANNELS], R[BTDF_MAX_CHANNELS];
        btdf_transmittance(p, ti, T);
        btdf_reflectance(p, ti, R);
        /* 7 significant digits by default: T and R are accurate to 1e-7 absolute or
           better (btdf.h), and a small value keeps its digits (8.01e-06, not
           0.000008010); --digits 17 prints the doubles themselves */
        int d = c->digits;
        printf("%s", num(angles[k]));
        for (int ch = 0; ch < p->channels; ch++) {
            printf(",%.*g,%.*g,%.*g,%.*g", d, T[ch], d, btdf_fresnel_t(p->ior[ch], ti), d,
                   R[ch], d, R[ch] + T[ch]);
            if (R[ch] + T[ch] < low_rt) {
                low = k;
                low_rt = R[ch] + T[ch];
            }
        }
        printf("\n");
    }
    if (low >= 0 && !c->quiet)
        warn_albedo(p, angles[low], low_rt, "the lowest of these angles");
    return stdout_done(0);
}

/* ------------------------------------------------------------------------- */
/* tabulate                                                                  */
/* ------------------------------------------------------------------------- */

/* Two outputs of one run must be two files, whatever the format: -o (unless standard
   output), --report and every --preview. 0, or the exit code after the message. */
static int distinct_outputs(const char *out, const cli *c)
{
    const char *outs[MAX_PREVIEWS + 3];
    int nouts = 0;
    if (out && strcmp(out, "-"))
        outs[nouts++] = out;
    if (c->report)
        outs[nouts++] = c->report;
    for (int k = 0; k < c->npreview; k++)
        outs[nouts++] = c->previews[k].path;
    for (int i = 0; i < nouts; i++)
        for (int j = 0; j < i; j++)
            if (btdf_same_file(outs[i], outs[j]))
                return fail(EXIT_USAGE, "'%s' and '%s' are the same file: each output of a run "
                                        "needs its own", outs[j], outs[i]);
    return 0;
}

/* A .bsdf is built from Eq. 25 directly: the table's options do not apply. */
static int tabulate_series(const cli *c, const char *prov)
{
    static const opt_id table_only[] = {OPT_THETA_I, OPT_GRID, OPT_PREVIEW, OPT_THETA_O,
                                        OPT_PHI, OPT_METRIC, OPT_SIZE, OPT_LOG_DECADES,
                                        OPT_ZOOM};
    for (size_t k = 0; k < sizeof table_only / sizeof table_only[0]; k++)
        if (GIVEN(c, table_only[k]))
            return fail(EXIT_USAGE, "%s: --theta-i, --theta-o, --phi, --grid, --metric, "
                                    "--preview, --size, --log-decades and --zoom do not apply "
                                    "to .bsdf (the file covers every direction of both "
                                    "hemispheres; --%s was given)",
                        c->out, opt_find(table_only[k])->name);
    if (c->report && !folder_writable(c->report))
        return 1;
    if (!check_params(&c->p))
        return EXIT_USAGE;
    if (!folder_writable(c->out))
        return 1;
    run_progress pr;
    run_progress_start(&pr, !c->quiet && isatty(2), c->out);
    /* --max-samples caps the stored coefficients, --max-memory the builder's series;
       each only when given (the format has its own budgets otherwise) */
    /* --side picks the light's sides, --part the parts (run.h) */
    int part = GIVEN(c, OPT_PART) ? (int)c->part : 0, blocks = run_series_blocks(c->sides, part);
    double tol = run_series_tolerance(part, GIVEN(c, OPT_TOLERANCE), c->o.tolerance);
    return run_series_ex(prog, c->out, &c->p, tol, blocks, c->threads, c->quiet,
                         c->best_effort, prov, c->report,
                         GIVEN(c, OPT_MAX_SAMPLES) ? c->o.max_samples : 0,
                         GIVEN(c, OPT_MAX_MEMORY) ? c->mib << 20 : 0, &pr);
}

/* A Radiance .xml is built from Eq. 25 (and rho_r) directly: all its blocks. */
static int tabulate_radiance(const cli *c, const char *prov)
{
    static const opt_id table_only[] = {OPT_THETA_I, OPT_GRID, OPT_PREVIEW, OPT_THETA_O,
                                        OPT_PHI, OPT_METRIC, OPT_MAX_SAMPLES, OPT_MAX_MEMORY,
                                        OPT_SIZE, OPT_SIDE};
    for (size_t k = 0; k < sizeof table_only / sizeof table_only[0]; k++)
        if (GIVEN(c, table_only[k]))
            return fail(EXIT_USAGE, "%s: --%s does not apply to .xml (it holds every "
                                    "direction, light from either side)",
                        c->out, opt_find(table_only[k])->name);
    if (GIVEN(c, OPT_TOLERANCE) && c->basis != BTDF_RAD_TREE3)
        return fail(EXIT_USAGE, "--tolerance: a Klems matrix holds exact patch averages; its "
                                "error is set by the basis, not by a tolerance");
    if (!check_params(&c->p))
        return EXIT_USAGE;
    if (!folder_writable(c->out) || (c->report && !folder_writable(c->report)))
        return 1;
    run_progress pr;
    run_progress_start(&pr, !c->quiet && isatty(2), c->out);
    return run_radiance(prog, c->out, c->report, &c->p, c->basis,
                        GIVEN(c, OPT_TOLERANCE) ? c->o.tolerance : 0.2, c->threads, c->quiet,
                        c->best_effort, prov, &pr);
}

static int cmd_tabulate(cli *c, const char *prov)
{
    if (c->npos)
        return fail(EXIT_USAGE, "tabulate: unexpected argument '%s' (the output is -o FILE)",
                    c->pos[0]);
    /* the table builders and their error estimates evaluate Eq. 25's separable
       shadowing; until they carry the model, a smith table is refused, not written
       as Eq. 25 */
    if (c->p.model != BTDF_MODEL_XU_SUN)
        return fail(EXIT_USAGE, "tabulate --model %s: tables of this model are not available "
                    "in this build (eval, albedo and polar take it)", btdf_model_name(c->p.model));
    /* The light the model loses at the table's first incidence angle (normal incidence
       by default): a warning, not an error, since the table is Eq. 25 all the same. */
    if (!c->quiet && btdf_params_check(&c->p, NULL, 0) == BTDF_OK) {
        double rt = albedo_min(&c->p, c->ti0 * M_PI / 180.0);
        if (rt < ALBEDO_WARN)
            warn_albedo(&c->p, c->ti0, rt, "the table's first incidence angle");
    }
    btdf_format_info fi = {0};
    const char *out = c->out;
    if (out && strcmp(out, "-")) {
        if (!btdf_format_find(out, &fi))
            return fail(EXIT_USAGE, "%s: unknown output format: use %s", out,
                        btdf_format_list());
        /* an .xml holds every block (both parts, light from either side) */
        if (fi.needs == BTDF_NEEDS_RADIANCE && GIVEN(c, OPT_PART))
            return fail(EXIT_USAGE, "%s: --part %s applies to .csv, .exr and .bsdf; an .xml "
                                    "holds both parts, light from either side", out,
                        btdf_part_name(c->part));
        int same = distinct_outputs(out, c);
        if (same)
            return same;
        if (fi.needs == BTDF_NEEDS_SERIES)
            return tabulate_series(c, prov);
        if (fi.needs == BTDF_NEEDS_RADIANCE)
            return tabulate_radiance(c, prov);
    }
    if (GIVEN(c, OPT_BASIS))
        return fail(EXIT_USAGE, "--basis applies to .xml output only");
    btdf_table_opts o = c->o;
    btdf_params p = c->p;
    if (c->sides && c->sides != BTDF_SIDE_ENTER && out) {
        /* Tables hold one side: light leaving is the table of index 1/n. */
        if (c->sides == BTDF_SIDE_BOTH)
            return fail(EXIT_USAGE, "--side both: a table holds one side; write two tables, "
                                    "or a .bsdf, which holds both");
        for (int ch = 0; ch < p.channels; ch++)
            p.ior[ch] = 1.0 / p.ior[ch];
    }
    if (out && fi.needs == BTDF_NEEDS_PICTURE) { /* -o F.png is a montage preview */
        preview_req *r = &c->previews[c->npreview++];
        r->kind = BTDF_PREVIEW_MONTAGE;
        r->analytic = 0;
        r->path = out;
        out = NULL;
    }
    if (!out && c->npreview == 0)
        return fail(EXIT_USAGE, "tabulate: no output: give -o FILE (or -o - for CSV on stdout)");
    if (!check_params(&p))
        return EXIT_USAGE;
    if (out && strcmp(out, "-") && !fi.available)
        return fail(1, "%s: %s support was switched off at build time (-D%s=disabled)", out,
                    fi.name, fi.feature);
    if (c->npreview > 0 && !btdf_format_available("png"))
        return fail(1, "%s: PNG support was switched off at build time (-Dpng=disabled)",
                    c->previews[0].path);
    if ((GIVEN(c, OPT_THETA_O) || GIVEN(c, OPT_PHI)) && o.kind != BTDF_TABLE_GRID)
        return fail(EXIT_USAGE, "--theta-o and --phi apply to --grid tables (an adaptive table "
                                "covers every outgoing direction)");
    if (c->part != BTDF_PART_TRANSMISSION && o.kind == BTDF_TABLE_GRID)
        return fail(EXIT_USAGE, "--part %s: --grid tables hold the transmission only; the "
                                "reflection is tabulated adaptively (drop --grid)",
                    btdf_part_name(c->part));
    if ((GIVEN(c, OPT_TOLERANCE) || GIVEN(c, OPT_METRIC)) && o.kind == BTDF_TABLE_GRID)
        return fail(EXIT_USAGE, "--tolerance and --metric apply to adaptive tables and .bsdf, "
                                "not to --grid (a grid has the spacing it is given)");
    if (o.estimate == BTDF_ESTIMATE_NONE && c->report)
        return fail(EXIT_USAGE, "--report with --estimate none: there is no error to report");
    if (GIVEN(c, OPT_SIZE) && c->npreview == 0)
        return fail(EXIT_USAGE, "--size applies to pictures: give --preview F.png or -o F.png");
    int renders = 0;
    for (int k = 0; k < c->npreview; k++)
        renders += c->previews[k].kind == BTDF_PREVIEW_RENDER;
    if ((GIVEN(c, OPT_LOG_DECADES) || GIVEN(c, OPT_ZOOM)) && renders == 0)
        return fail(EXIT_USAGE, "--%s applies to renders: give --preview render=F.png",
                    GIVEN(c, OPT_ZOOM) ? "zoom" : "log-decades");
    /* Fail before the work: every output's folder must take a new file. */
    if (out && strcmp(out, "-") && !folder_writable(out))
        return 1;
    if (c->report && !folder_writable(c->report))
        return 1;
    for (int k = 0; k < c->npreview; k++)
        if (!folder_writable(c->previews[k].path))
            return 1;
    int same = distinct_outputs(out, c);
    if (same)
        return same;
    o.params = p;
    o.threads = c->threads;
    o.ti_min = c->ti0 * M_PI / 180.0;
    o.ti_max = c->ti1 * M_PI / 180.0;
    o.to_min = c->to0 * M_PI / 180.0;
    o.to_max = c->to1 * M_PI / 180.0;
    o.phi_min = c->ph0 * M_PI / 180.0;
    o.phi_max = c->ph1 * M_PI / 180.0;
    o.max_bytes = c->mib << 20;
    o.part = c->part;
    /* A progress bar on a terminal (run.h): the build, the estimate, the writes. */
    run_progress pr;
    run_progress_start(&pr, !c->quiet && isatty(2),
                       out ? (strcmp(out, "-") ? out : "standard output") : c->previews[0].path);
    o.progress = run_progress_cb;
    o.progress_user = &pr;
    /* The table first, then its pictures. */
    run_table_out outs[MAX_PREVIEWS + 1];
    btdf_preview_opts pos[MAX_PREVIEWS];
    int nouts = 0;
    if (out)
        outs[nouts++] = (run_table_out){out, NULL, 0};
    for (int k = 0; k < c->npreview; k++) {
        btdf_preview_opts *po = &pos[k];
        btdf_preview_opts_default(po);
        po->kind = c->previews[k].kind;
        po->analytic = c->previews[k].analytic;
        po->log_decades = po->kind == BTDF_PREVIEW_RENDER ? c->log_decades : 0.0;
        po->zoom = po->kind == BTDF_PREVIEW_RENDER ? c->zoom : 0.0;
        po->width = c->pic_w;
        po->height = c->pic_h;
        outs[nouts++] = (run_table_out){c->previews[k].path, po, 0};
    }
    run_table_req rq = {prog, out, o, c->part != BTDF_PART_TRANSMISSION, outs, nouts,
                        c->report, prov, c->quiet, c->best_effort, &pr};
    return run_table(&rq);
}

/* ------------------------------------------------------------------------- */
/* polar, inspect, build                                                     */
/* ------------------------------------------------------------------------- */

static int cmd_polar(const cli *c)
{
    if (c->npos)
        return fail(EXIT_USAGE, "polar: unexpected argument '%s' (the picture is -o FILE.png)",
                    c->pos[0]);
    if (c->nm && (GIVEN(c, OPT_IOR) || GIVEN(c, OPT_SMOOTHNESS)))
        return fail(EXIT_USAGE, "polar: --ior and --smoothness do not apply with --material "
                                "(give each material as N:S)");
    btdf_params mats[BTDF_PREVIEW_MAX_CURVES];
    double angles[BTDF_PREVIEW_MAX_CURVES];
    size_t nm = 0, na = c->na;
    if (!c->out || !ends_with(c->out, ".png"))
        return fail(EXIT_USAGE, "polar: give -o FILE.png");
    for (; nm < c->nm; nm++) {
        btdf_params_default(&mats[nm]);
        mats[nm].ior[0] = c->mat_n[nm];
        mats[nm].smoothness = c->mat_s[nm];
        mats[nm].k0 = c->p.k0;
        mats[nm].model = c->p.model;
        if (!check_params(&mats[nm]))
            return EXIT_USAGE;
    }
    if (nm == 0) {
        if (!check_params(&c->p))
            return EXIT_USAGE;
        mats[nm++] = c->p;
    }
    memcpy(angles, c->angles, sizeof angles);
    if (na == 0)
        angles[na++] = 30.0;
    if (nm * na > BTDF_PREVIEW_MAX_CURVES)
        return fail(EXIT_USAGE, "polar: %zu materials x %zu angles: at most %d curves", nm, na,
                    BTDF_PREVIEW_MAX_CURVES);
    if (!folder_writable(c->out))
        return 1;
    btdf_preview_opts po;
    btdf_preview_opts_default(&po);
    po.kind = BTDF_PREVIEW_POLAR;
    po.materials = mats;
    po.nmaterials = nm;
    po.ti_deg = angles;
    po.nti = na;
    po.width = c->pic_w;
    po.height = c->pic_h;
    po.part = c->part;
    char msg[512] = "";
    btdf_output what = {NULL, NULL, &po, NULL, NULL, NULL};
    btdf_status st = btdf_write(&what, c->out, msg, sizeof msg);
    if (st != BTDF_OK)
        return fail(st == BTDF_EINVAL ? EXIT_USAGE : 1, "%s: %s", c->out,
                    msg[0] ? msg : btdf_strerror(st));
    return 0;
}

static int cmd_inspect(const cli *c)
{
    if (c->npos != 1)
        return fail(EXIT_USAGE, "inspect: give one file, e.g. btdftab inspect glass.bsdf");
    const char *path = c->pos[0];
    char msg[512] = "";
    btdf_status st = btdf_inspect(path, stdout, msg, sizeof msg);
    if (st != BTDF_OK)
        return fail(1, "%s: %s", path, msg[0] ? msg : btdf_strerror(st));
    return stdout_done(0);
}

static int cmd_build(const cli *c)
{
    if (c->npos == 0)
        return fail(EXIT_USAGE, "build: give a manifest, e.g. btdftab build scene.ini");
    if (c->npos > 1)
        return fail(EXIT_USAGE, "build: give one manifest, not '%s' and '%s'", c->pos[0],
                    c->pos[1]);
    manifest_opts mo;
    memset(&mo, 0, sizeof mo);
    mo.prog = prog;
    mo.path = c->pos[0];
    mo.force = c->force;
    mo.best_effort = c->best_effort;
    mo.quiet = c->quiet;
    mo.threads = c->threads;
    mo.progress = !c->quiet && isatty(2); /* progress bars only for a person watching */
    mo.dry_run = c->dry_run;
    mo.shard_k = c->shard_k;
    mo.shard_n = c->shard_n;
    return manifest_run(&mo);
}

/* ------------------------------------------------------------------------- */
/* main                                                                      */
/* ------------------------------------------------------------------------- */

/* SIGINT, SIGTERM, SIGHUP: remove the files being written, then die of the signal, so
   an interrupted run leaves no partial output (make and shells see the signal). */
static void on_signal(int sig)
{
    btdf_remove_partial_files(); /* async-signal-safe: flags and unlink */
    signal(sig, SIG_DFL);
    raise(sig);
}

static int print_version(void)
{
    printf("btdftab %s (OpenEXR %s, PNG %s)\n", btdf_version_string(),
           btdf_format_available("exr") ? "on" : "off",
           btdf_format_available("png") ? "on" : "off");
    return stdout_done(0);
}

static int short_usage(void)
{
    for (const cmd_def *c = cmd_table; c->name; c++)
        fprintf(stderr, "%s btdftab %s %s\n", c == cmd_table ? "usage:" : "      ", c->name,
                c->synopsis);
    fprintf(stderr, "Try 'btdftab --help' for more.\n");
    return EXIT_USAGE;
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
    /* A closed pipe (btdftab eval | head -1) is a write error, exit status 1 with a
       message, as for a full disk; not a silent death by SIGPIPE. */
    signal(SIGPIPE, SIG_IGN);
    if (argc < 2)
        return short_usage();
    const char *name = argv[1];
    int alone = !strcmp(name, "--help") || !strcmp(name, "-h") || !strcmp(name, "--version") ||
                !strcmp(name, "-V") || !strcmp(name, "--man");
    if (alone && argc > 2)
        return fail(EXIT_USAGE, "%s takes nothing after it, not '%s'", name, argv[2]);
    if (!strcmp(name, "--help") || !strcmp(name, "-h")) {
        opt_help(stdout, NULL);
        return stdout_done(0);
    }
    if (!strcmp(name, "--version") || !strcmp(name, "-V"))
        return print_version();
    if (!strcmp(name, "--completion")) {
        if (argc != 3 || strcmp(argv[2], "bash"))
            return fail(EXIT_USAGE, "--completion: give 'bash' (the only shell supported)");
        opt_bash(stdout);
        return fflush(stdout) == 0 ? 0 : 1;
    }
    if (!strcmp(name, "--man")) {
        opt_man(stdout, btdf_version_string());
        return stdout_done(0);
    }
    if (!strcmp(name, "help")) {
        if (argc > 3)
            return fail(EXIT_USAGE, "help: give one command at most");
        const cmd_def *cmd = argc == 3 ? cmd_find(argv[2]) : NULL;
        if (argc == 3 && !cmd)
            return fail(EXIT_USAGE, "help: unknown command '%s'", argv[2]);
        opt_help(stdout, cmd);
        return stdout_done(0);
    }
    const cmd_def *cmd = cmd_find(name);
    if (!cmd) {
        const cmd_def *near = cmd_nearest(name);
        if (near)
            fail(EXIT_USAGE, "unknown command '%s'; did you mean '%s'?", name, near->name);
        else
            fail(EXIT_USAGE, "unknown command '%s'", name);
        return short_usage();
    }
    /* The command line, recorded in outputs as their provenance. */
    char prov[2048] = "btdftab";
    for (int i = 1; i < argc; i++) {
        size_t l = strlen(prov);
        snprintf(prov + l, sizeof prov - l, " %s", argv[i]);
    }
    if (cmd->bit == CMD_SIMULATE)
        return cmd_simulate(prog, argc - 1, argv + 1, prov);
    static cli c; /* large: off the stack */
    int code = parse_command(cmd, argc - 1, argv + 1, &c);
    if (code >= 0)
        return code;
    switch (cmd->bit) {
    case CMD_EVAL: return cmd_eval(&c);
    case CMD_TABULATE: return cmd_tabulate(&c, prov);
    case CMD_ALBEDO: return cmd_albedo(&c);
    case CMD_POLAR: return cmd_polar(&c);
    case CMD_BUILD: return cmd_build(&c);
    default: return cmd_inspect(&c);
    }
}
