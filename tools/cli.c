/* SPDX-License-Identifier: MIT */
/* cli.c: the command line into struct cli (through the option table of
   options.c), and the checks and helpers several commands share. */
#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <btdf/btdf.h>

#include "cli.h"
#include "cmd_simulate.h"
#include "evalstream.h"
#include "fastnum.h"
#include "manifest.h"
#include "numparse.h"
#include "options.h"
#include "run.h"

const char *prog = "btdftab";

int fail(int code, const char *fmt, ...)
{
    va_list ap;
    fprintf(stderr, "%s: ", prog);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
    return code;
}

int ends_with(const char *s, const char *suffix)
{
    size_t ls = strlen(s), lx = strlen(suffix);
    if (ls < lx)
        return 0;
    for (size_t i = 0; i < lx; i++) /* extensions in any case, as the formats' registry */
        if (tolower((unsigned char)s[ls - lx + i]) != tolower((unsigned char)suffix[i]))
            return 0;
    return 1;
}

/* ------------------------------------------------------------------------- */
/* Values                                                                    */
/* ------------------------------------------------------------------------- */

/* Every number of the command line goes through tools/numparse.c. */
int parse_double(const char *flag, const char *s, double *out)
{
    const char *why = num_double(s, out);
    if (why)
        fail(EXIT_USAGE, "%s: '%s' %s", flag, s, why);
    return !why;
}

int parse_size(const char *flag, const char *s, size_t lo, size_t hi, size_t *out)
{
    const char *why = num_size(s, lo, hi, out);
    if (why)
        fail(EXIT_USAGE, "%s: '%s': %s", flag, s, why);
    return !why;
}

/* N or R,G,B */
int parse_ior(const char *val, btdf_params *p)
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

/* The n bytes at s as a string of its own (malloc'd), or NULL when out of memory. */
static char *span_copy(const char *s, size_t n)
{
    char *b = malloc(n + 1);
    if (b) {
        memcpy(b, s, n);
        b[n] = '\0';
    }
    return b;
}

/* A:B in degrees within [lo, hi], A <= B (A < B when strict). */
int parse_range(const char *flag, const char *s, double lo, double hi, int strict,
                double *a, double *b)
{
    const char *colon = strchr(s, ':');
    if (!colon) {
        fail(EXIT_USAGE, "%s: '%s': expected A:B in degrees, e.g. %g:%g", flag, s, lo, hi);
        return 0;
    }
    char *buf = span_copy(s, (size_t)(colon - s)); /* any length: no silent cut */
    if (!buf) {
        fail(1, "out of memory");
        return 0;
    }
    int good = parse_double(flag, buf, a) && parse_double(flag, colon + 1, b);
    free(buf);
    if (!good)
        return 0;
    if (!(*a >= lo && *b <= hi && (strict ? *a < *b : *a <= *b))) {
        fail(EXIT_USAGE, "%s: '%s': need %g <= A %s B <= %g degrees", flag, s, lo,
             strict ? "<" : "<=", hi);
        return 0;
    }
    return 1;
}

/* [montage|render|render-analytic=]FILE.png */
int parse_preview(const char *s, preview_req *r)
{
    const char *eq = strchr(s, '=');
    r->kind = BTDF_PREVIEW_MONTAGE;
    r->analytic = 0;
    r->named = eq != NULL;
    r->path = eq ? eq + 1 : s;
    if (eq) {
        size_t l = (size_t)(eq - s);
        if (l == 7 && !strncmp(s, "montage", 7)) {
            r->kind = BTDF_PREVIEW_MONTAGE;
        } else if (l == 5 && !strncmp(s, "polar", 5)) {
            r->kind = BTDF_PREVIEW_POLAR; /* .bsdf and .xml: their file read back */
        } else if (l == 6 && !strncmp(s, "render", 6)) {
            r->kind = BTDF_PREVIEW_RENDER;
        } else if (l == 15 && !strncmp(s, "render-analytic", 15)) {
            r->kind = BTDF_PREVIEW_RENDER;
            r->analytic = 1;
        } else {
            fail(EXIT_USAGE, "--preview: '%.*s': kind must be montage, render, "
                             "render-analytic or polar", (int)l, s);
            return 0;
        }
    }
    if (!ends_with(r->path, ".png")) {
        fail(EXIT_USAGE, "--preview: '%s': the picture's name must end in .png", r->path);
        return 0;
    }
    return 1;
}

int parse_picture_size(const char *s, int *w, int *h)
{
    const char *x = strchr(s, 'x');
    char *buf = x ? span_copy(s, (size_t)(x - s)) : NULL; /* any length, as every number */
    size_t W = 0, H = 0;
    int bad = !buf || num_size(buf, 64, BTDF_PREVIEW_MAX_SIDE, &W) ||
              num_size(x + 1, 64, BTDF_PREVIEW_MAX_SIDE, &H);
    free(buf);
    if (bad) {
        fail(EXIT_USAGE, "--size: '%s': expected WxH, each in [64, %d] pixels", s,
             BTDF_PREVIEW_MAX_SIDE);
        return 0;
    }
    *w = (int)W;
    *h = (int)H;
    return 1;
}

void cli_defaults(cli *c)
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

/* --grid NI,NO,NPHI: a plain regular grid */
static int apply_grid(cli *c, const char *v)
{
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

/* --material N:S, repeatable */
static int apply_material(cli *c, const char *v)
{
    const char *colon = strchr(v, ':');
    if (!colon || c->nm == BTDF_PREVIEW_MAX_CURVES) {
        fail(EXIT_USAGE, "--material: '%s': expected N:S (at most %d)", v,
             BTDF_PREVIEW_MAX_CURVES);
        return 0;
    }
    char *buf = span_copy(v, (size_t)(colon - v)); /* any length: no silent cut */
    if (!buf) {
        fail(1, "out of memory");
        return 0;
    }
    int good = parse_double("--material", buf, &c->mat_n[c->nm]) &&
               parse_double("--material", colon + 1, &c->mat_s[c->nm]);
    free(buf);
    if (!good)
        return 0;
    c->nm++;
    return 1;
}

/* --angles A,B,...: the polar plot's incidences, in [0, 90) */
static int apply_angles(cli *c, const char *v)
{
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

/* --shard K/N */
static int apply_shard(cli *c, const char *v)
{
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

/* --estimate full|fast|none */
static int apply_estimate(cli *c, const char *v)
{
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
}

/* Takes one option's value into c; 0 after a usage error. */
int apply(cli *c, const opt_hit *h)
{
    const char *v = h->value;
    switch (h->id) {
    case OPT_IOR: return parse_ior(v, &c->p);
    case OPT_SMOOTHNESS: return parse_double("--smoothness", v, &c->p.smoothness);
    case OPT_K0: return parse_double("--k0", v, &c->p.k0);
    case OPT_MODEL:
        if (!btdf_model_parse(v, &c->p.model)) {
            fail(EXIT_USAGE, "--model: '%s': must be xu-sun, smith or full", v);
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
    case OPT_REPORT:
        if (!strcmp(v, "-")) /* not standard output: it may carry the table (-o -) */
            return fail(EXIT_USAGE, "--report: '-': the report is a file; give FILE.json"), 0;
        c->report = v;
        return 1;
    case OPT_TOLERANCE: return parse_double("--tolerance", v, &c->o.tolerance);
    case OPT_METRIC:
        if (run_parse_metric(v, &c->o.metric))
            return 1;
        fail(EXIT_USAGE, "--metric: '%s': must be l1 or max", v);
        return 0;
    case OPT_GRID: return apply_grid(c, v);
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
    case OPT_MATERIAL: return apply_material(c, v);
    case OPT_ANGLES: return apply_angles(c, v);
    case OPT_FORCE: c->force = 1; return 1;
    case OPT_DRY_RUN: c->dry_run = 1; return 1;
    case OPT_SHARD: return apply_shard(c, v);
    case OPT_BEST_EFFORT: c->best_effort = 1; return 1;
    case OPT_ESTIMATE: return apply_estimate(c, v);
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
    case OPT_BINS:
    case OPT_BACK:
    case OPT_THICKNESS:
    case OPT_ABSORPTION: return apply_pane(c, h->id, v);
    case OPT_LIGHT: c->light = v; break; /* simulate checks its own; eval's: cmd_pane.c */
    case OPT_MERGE:
    case OPT_PROFILE:
    case OPT_HELP:
    case OPT_END: break;
    }
    return 1;
}

/* Parses the command's arguments into c. Returns -1 to go on, or an exit status
   (0 after --help). */
int parse_command(const cmd_def *cmd, int argc, char **argv, cli *c)
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
            return stdout_done(0);
        }
    for (int k = 0; k < nh; k++) {
        GIVEN(c, hits[k].id)++;
        if (!apply(c, &hits[k]))
            return EXIT_USAGE;
    }
    return -1;
}

int check_params(const btdf_params *p)
{
    char msg[256];
    if (p->model == BTDF_MODEL_FULL) { /* eval, albedo and polar check it themselves */
        fail(EXIT_USAGE, "--model full: eval, albedo, polar and the .csv, .exr and .xml files "
                         "take it; this output does not yet (give --model xu-sun or smith)");
        return 0;
    }
    if (btdf_params_check(p, msg, sizeof msg) != BTDF_OK) {
        fail(EXIT_USAGE, "%s", msg);
        return 0;
    }
    return 1;
}

/* The folder of path exists and can take a new file: checked before the work. */
/* An output may be written (btdf_output_check: its folder takes a new file, and what
   is there now is a regular file), checked before the work. */
int folder_writable(const char *path)
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

int check_angles(double ti, double to, double phi, long line)
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
int check_angles_r(double ti, double tr, double phi, long line)
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
int read_row(const char *line, double *v, int want)
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
        char small[64], *tok = len < sizeof small ? small : malloc(len + 1);
        if (!tok) /* a token of any length, as eval's stream reads it */
            return -1;
        memcpy(tok, s, len);
        tok[len] = 0;
        const char *why = num_double(tok, &v[n]);
        if (tok != small)
            free(tok);
        if (why != NULL)
            return -1;
        n++;
        s += len;
    }
}

/* Everything printed reached standard output (a full disk, a closed pipe are
   errors): code, or 1 with a message. */
int stdout_done(int code)
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
void table_ti_range(const btdf_table *t, double *range)
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
const char *num(double x)
{
    static char b[4][40];
    static int k;
    k = (k + 1) % 4;
    btdf_format_double(x, b[k], sizeof b[k]);
    return b[k];
}

/* One row of %.17g values (fastnum_g17 gives printf's bytes, faster). */
void print_values(const double *v, int n)
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
