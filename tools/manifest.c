/* SPDX-License-Identifier: MIT */
/* manifest.c: `btdftab build scene.ini`, the outputs of a scene's materials and nothing more. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <ini.h>

#include <btdf/btdf.h>

#include "manifest.h"
#include "run.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/*
 * A manifest is an INI file (read with inih): one section per material.
 *
 *   [frosted]                  ; the material's name
 *   ior = 1.5                  ; n, or R,G,B
 *   smoothness = 3
 *   k0 = 0.7                   ; optional
 *   theta_i = 0:90             ; optional incidence range, degrees
 *   tolerance = 1e-3           ; optional
 *   metric = l1                ; optional, l1 or max
 *   enter = a.csv a.exr m.png  ; tables for light entering (index n): .csv .exr .png
 *   leave = b.exr              ; tables for light leaving (index 1/n)
 *   bsdf = glass.bsdf          ; a renderer file (SCATFUN v1)
 *   sides = both               ; which sides the .bsdf holds: enter, leave or both
 *
 * Only the tables an output needs are built, once per material and side, and shared
 * by its outputs. An output is skipped when it exists and its stamp (a hidden file
 * beside it) records the same parameters and program version.
 */

#define MAX_MATERIALS 64
#define MAX_OUTPUTS 8

typedef struct material {
    char name[64];
    btdf_params p;
    double ti0, ti1, tol;
    btdf_metric metric;
    int sides; /* btdf_side */
    int has_ior, has_s;
    char *enter[MAX_OUTPUTS], *leave[MAX_OUTPUTS], *bsdf[MAX_OUTPUTS];
    int nenter, nleave, nbsdf;
} material;

typedef struct manifest {
    material m[MAX_MATERIALS];
    int n;
    char why[256]; /* reason for the first error */
} manifest;

static int set_why(manifest *mf, const char *fmt, const char *a, const char *b)
{
    if (!mf->why[0])
        snprintf(mf->why, sizeof mf->why, fmt, a, b);
    return 0; /* inih: an error at this line */
}

static int num(const char *s, double *out)
{
    char *e;
    errno = 0;
    double v = strtod(s, &e);
    while (*e == ' ' || *e == '\t')
        e++;
    if (e == s || *e || errno == ERANGE || !isfinite(v))
        return 0;
    *out = v;
    return 1;
}

static int split_outputs(manifest *mf, const char *key, const char *value, char **list, int *n)
{
    char buf[2048];
    snprintf(buf, sizeof buf, "%s", value);
    for (char *tok = strtok(buf, " \t,"); tok; tok = strtok(NULL, " \t,")) {
        if (*n == MAX_OUTPUTS)
            return set_why(mf, "'%s': at most 8 outputs%s", key, "");
        list[*n] = malloc(strlen(tok) + 1);
        if (!list[*n])
            return set_why(mf, "out of memory%s%s", "", "");
        strcpy(list[(*n)++], tok);
    }
    return 1;
}

static int ends_with(const char *s, const char *x)
{
    size_t ls = strlen(s), lx = strlen(x);
    return ls >= lx && strcmp(s + ls - lx, x) == 0;
}

static int on_entry(void *user, const char *section, const char *key, const char *value)
{
    manifest *mf = user;
    if (!section[0])
        return set_why(mf, "'%s' before any [material] section%s", key, "");
    material *m = mf->n > 0 ? &mf->m[mf->n - 1] : NULL;
    if (!m || strcmp(m->name, section) != 0) {
        for (int i = 0; i < mf->n; i++)
            if (!strcmp(mf->m[i].name, section))
                return set_why(mf, "material [%s] appears twice%s", section, "");
        if (mf->n == MAX_MATERIALS)
            return set_why(mf, "more than 64 materials%s%s", "", "");
        if (strlen(section) >= sizeof m->name)
            return set_why(mf, "material name '%s' is longer than 63 bytes%s", section, "");
        m = &mf->m[mf->n++];
        memset(m, 0, sizeof *m);
        snprintf(m->name, sizeof m->name, "%s", section);
        btdf_params_default(&m->p);
        m->ti0 = 0.0;
        m->ti1 = 90.0;
        m->tol = 1e-3;
        m->metric = BTDF_METRIC_L1;
        m->sides = BTDF_SIDE_BOTH;
    }
    if (!strcmp(key, "ior")) {
        char buf[256];
        snprintf(buf, sizeof buf, "%s", value);
        int k = 0;
        for (char *tok = strtok(buf, ","); tok; tok = strtok(NULL, ",")) {
            if (k == 3 || !num(tok, &m->p.ior[k++]))
                return set_why(mf, "ior '%s': expected one number or three (R,G,B)%s", value, "");
        }
        if (k != 1 && k != 3)
            return set_why(mf, "ior '%s': expected one number or three (R,G,B)%s", value, "");
        m->p.channels = k;
        m->has_ior = 1;
    } else if (!strcmp(key, "smoothness")) {
        if (!num(value, &m->p.smoothness))
            return set_why(mf, "smoothness '%s' is not a number%s", value, "");
        m->has_s = 1;
    } else if (!strcmp(key, "k0")) {
        if (!num(value, &m->p.k0))
            return set_why(mf, "k0 '%s' is not a number%s", value, "");
    } else if (!strcmp(key, "tolerance")) {
        if (!num(value, &m->tol) || !(m->tol >= 1e-7 && m->tol <= 1.0))
            return set_why(mf, "tolerance '%s': must be a number in [1e-7, 1]%s", value, "");
    } else if (!strcmp(key, "metric")) {
        if (!run_parse_metric(value, &m->metric))
            return set_why(mf, "metric '%s': must be l1 or max%s", value, "");
    } else if (!strcmp(key, "theta_i")) {
        char a[64], b[64];
        const char *colon = strchr(value, ':');
        if (!colon || (size_t)(colon - value) >= sizeof a)
            return set_why(mf, "theta_i '%s': expected A:B in degrees%s", value, "");
        snprintf(a, sizeof a, "%.*s", (int)(colon - value), value);
        snprintf(b, sizeof b, "%s", colon + 1);
        if (!num(a, &m->ti0) || !num(b, &m->ti1) || !(m->ti0 >= 0 && m->ti0 <= m->ti1 && m->ti1 <= 90))
            return set_why(mf, "theta_i '%s': need 0 <= A <= B <= 90 degrees%s", value, "");
    } else if (!strcmp(key, "sides")) {
        if (!(m->sides = run_parse_side(value)))
            return set_why(mf, "sides '%s': must be enter, leave or both%s", value, "");
    } else if (!strcmp(key, "enter") || !strcmp(key, "leave")) {
        char **list = key[0] == 'e' ? m->enter : m->leave;
        int *n = key[0] == 'e' ? &m->nenter : &m->nleave;
        int before = *n;
        if (!split_outputs(mf, key, value, list, n))
            return 0;
        for (int i = before; i < *n; i++)
            if (!ends_with(list[i], ".csv") && !ends_with(list[i], ".exr") &&
                !ends_with(list[i], ".png"))
                return set_why(mf, "output '%s': tables are .csv, .exr or .png%s", list[i], "");
    } else if (!strcmp(key, "bsdf")) {
        int before = m->nbsdf;
        if (!split_outputs(mf, key, value, m->bsdf, &m->nbsdf))
            return 0;
        for (int i = before; i < m->nbsdf; i++)
            if (!ends_with(m->bsdf[i], ".bsdf"))
                return set_why(mf, "output '%s': must end in .bsdf%s", m->bsdf[i], "");
    } else {
        return set_why(mf, "unknown key '%s' (known: ior, smoothness, k0, theta_i, tolerance, "
                           "metric, sides, enter, leave, bsdf)%s", key, "");
    }
    return 1;
}

static void free_manifest(manifest *mf)
{
    for (int i = 0; i < mf->n; i++) {
        material *m = &mf->m[i];
        for (int k = 0; k < m->nenter; k++)
            free(m->enter[k]);
        for (int k = 0; k < m->nleave; k++)
            free(m->leave[k]);
        for (int k = 0; k < m->nbsdf; k++)
            free(m->bsdf[k]);
    }
}

/* The stamp of an output: what it was made from. Same text = up to date. */
static void stamp_text(char *buf, size_t len, const material *m, const btdf_params *p,
                       const char *what)
{
    int k = snprintf(buf, len, "btdftab %s\n%s\nchannels %d\nior", BTDF_VERSION_STRING, what,
                     p->channels);
    for (int c = 0; c < p->channels && k > 0 && (size_t)k < len; c++)
        k += snprintf(buf + k, len - (size_t)k, " %.17g", p->ior[c]);
    if (k > 0 && (size_t)k < len)
        snprintf(buf + k, len - (size_t)k,
                 "\nsmoothness %.17g\nk0 %.17g\ntheta_i %.17g %.17g\ntolerance %.17g\n"
                 "metric %d\nsides %d\n",
                 p->smoothness, p->k0, m->ti0, m->ti1, m->tol, (int)m->metric, m->sides);
}

static void stamp_path(char *buf, size_t len, const char *out)
{
    const char *base = strrchr(out, '/');
    base = base ? base + 1 : out;
    snprintf(buf, len, "%.*s.%s.btdftab-stamp", (int)(base - out), out, base);
}

static int up_to_date(const char *out, const char *stamp)
{
    char sp[4200], have[4096];
    if (access(out, F_OK) != 0)
        return 0;
    stamp_path(sp, sizeof sp, out);
    FILE *f = fopen(sp, "r");
    if (!f)
        return 0;
    size_t n = fread(have, 1, sizeof have - 1, f);
    fclose(f);
    have[n] = 0;
    return strcmp(have, stamp) == 0;
}

static int write_stamp(const char *out, const char *stamp)
{
    char sp[4200];
    stamp_path(sp, sizeof sp, out);
    return btdf_write_buffer(sp, NULL, stamp, strlen(stamp), NULL, 0) == BTDF_OK;
}

static int fail(const char *prog, const char *fmt, const char *a, const char *b)
{
    fprintf(stderr, "%s: ", prog);
    fprintf(stderr, fmt, a, b);
    fputc('\n', stderr);
    return 1;
}

/* Builds one side's table and writes every output of that side that is stale. */
static int do_side(const manifest_opts *mo, const material *m, int leave, char **outs,
                   int nouts, int *done, int total)
{
    btdf_params p = m->p;
    if (leave)
        for (int c = 0; c < p.channels; c++)
            p.ior[c] = 1.0 / p.ior[c];
    const char *side = leave ? "leave" : "enter";
    char stamp[4096], msg[512] = "";
    int stale = 0;
    for (int k = 0; k < nouts; k++) {
        stamp_text(stamp, sizeof stamp, m, &p, side);
        if (mo->force || !up_to_date(outs[k], stamp))
            stale++;
    }
    if (stale == 0) {
        *done += nouts;
        if (!mo->quiet)
            fprintf(stderr, "%s: %s (%s): %d output(s) up to date\n", mo->prog, m->name, side,
                    nouts);
        return 0;
    }
    if (mo->progress)
        fprintf(stderr, "%s: [%d/%d] %s (%s): tabulating...\n", mo->prog, *done + 1, total,
                m->name, side);
    btdf_table_opts o;
    btdf_table_opts_default(&o);
    o.params = p;
    o.ti_min = m->ti0 * M_PI / 180.0;
    o.ti_max = m->ti1 * M_PI / 180.0;
    o.tolerance = m->tol;
    o.metric = m->metric;
    o.threads = mo->threads;
    btdf_table *t = NULL;
    btdf_status st = btdf_table_build(&o, &t, msg, sizeof msg);
    if (st != BTDF_OK && !(st == BTDF_EBUDGET && mo->best_effort)) {
        btdf_table_free(t);
        fprintf(stderr, "%s: %s (%s): %s\n", mo->prog, m->name, side,
                msg[0] ? msg : btdf_strerror(st));
        return st == BTDF_EBUDGET ? 3 : 1;
    }
    btdf_report r;
    memset(&r, 0, sizeof r);
    btdf_table_estimate(t, o.ti_min, o.ti_max, 0, 0, REPORT_SEED, o.threads, &r);
    r.tolerance = o.tolerance;
    r.metric = o.metric;
    r.met = (o.metric == BTDF_METRIC_MAX ? r.e_max_max : r.e_l1_max) <= o.tolerance;
    if (!mo->quiet)
        fprintf(stderr, "%s: %s (%s): %zu slices, %zu samples; e_L1 max %.3g, e_max max %.3g, "
                        "e_T max %.3g%s\n",
                mo->prog, m->name, side, r.slices, r.samples, r.e_l1_max, r.e_max_max,
                r.e_t_max, r.met ? "" : "; TOLERANCE NOT MET");
    int code = 0;
    if (!r.met && !mo->best_effort) {
        fprintf(stderr, "%s: %s (%s): nothing written (tolerance %g not met)\n", mo->prog,
                m->name, side, o.tolerance);
        code = 3;
    }
    char prov[256];
    snprintf(prov, sizeof prov, "btdftab build, material [%s], side %s", m->name, side);
    for (int k = 0; k < nouts && code == 0; k++) {
        stamp_text(stamp, sizeof stamp, m, &p, side);
        (*done)++;
        if (!mo->force && up_to_date(outs[k], stamp))
            continue;
        /* A table file, or a .png montage of the table: the registry picks by extension. */
        btdf_preview_opts po;
        btdf_preview_opts_default(&po);
        po.kind = BTDF_PREVIEW_MONTAGE;
        po.table = t;
        btdf_write_opts w = {&r, prov};
        btdf_output what = {t, NULL, &po, &w, NULL};
        st = btdf_write(&what, outs[k], msg, sizeof msg);
        if (st != BTDF_OK) {
            fprintf(stderr, "%s: %s: %s\n", mo->prog, outs[k], msg[0] ? msg : btdf_strerror(st));
            code = 1;
        } else if (!write_stamp(outs[k], stamp)) {
            fprintf(stderr, "%s: %s: cannot write its stamp: %s\n", mo->prog, outs[k],
                    strerror(errno));
            code = 1;
        }
    }
    btdf_report_clear(&r);
    btdf_table_free(t);
    return code;
}

/* Writes the stale .bsdf outputs of one material. */
static int manifest_bsdf(const manifest_opts *mo, const char *name, const btdf_params *p,
                         double tol, int sides, char **outs, int nouts, int *done, int total)
{
    /* The stamp: everything the file depends on (theta_i does not apply). */
    material m;
    memset(&m, 0, sizeof m);
    m.tol = tol;
    m.sides = sides;
    char stamp[4096], prov[256];
    stamp_text(stamp, sizeof stamp, &m, p, "bsdf");
    snprintf(prov, sizeof prov, "btdftab build, material [%s]", name);
    for (int k = 0; k < nouts; k++) {
        (*done)++;
        if (!mo->force && up_to_date(outs[k], stamp)) {
            if (!mo->quiet)
                fprintf(stderr, "%s: %s: up to date\n", mo->prog, outs[k]);
            continue;
        }
        if (mo->progress)
            fprintf(stderr, "%s: [%d/%d] %s: %s...\n", mo->prog, *done, total, name, outs[k]);
        int code = run_series(mo->prog, outs[k], p, tol, sides, mo->threads, mo->quiet,
                              mo->best_effort, prov);
        if (code != 0)
            return code;
        if (!write_stamp(outs[k], stamp)) {
            fprintf(stderr, "%s: %s: cannot write its stamp: %s\n", mo->prog, outs[k],
                    strerror(errno));
            return 1;
        }
    }
    return 0;
}

int manifest_run(const manifest_opts *mo)
{
    manifest *mf = calloc(1, sizeof *mf);
    if (!mf)
        return fail(mo->prog, "out of memory%s%s", "", "");
    int line = ini_parse(mo->path, on_entry, mf);
    if (line < 0) {
        free(mf);
        fprintf(stderr, "%s: %s: cannot read: %s\n", mo->prog, mo->path,
                line == -1 ? strerror(errno) : "out of memory");
        return 1;
    }
    if (line > 0) {
        fprintf(stderr, "%s: %s:%d: %s\n", mo->prog, mo->path, line,
                mf->why[0] ? mf->why : "syntax error (expected [section], key = value or ;comment)");
        free_manifest(mf);
        free(mf);
        return 2;
    }
    /* Checks that need the whole section, before any work. */
    int total = 0;
    for (int i = 0; i < mf->n; i++) {
        material *m = &mf->m[i];
        char why[256];
        const char *miss = !m->has_ior ? "ior" : (!m->has_s ? "smoothness" : NULL);
        if (miss) {
            fprintf(stderr, "%s: %s: material [%s]: missing '%s'\n", mo->prog, mo->path,
                    m->name, miss);
            free_manifest(mf);
            free(mf);
            return 2;
        }
        if (btdf_params_check(&m->p, why, sizeof why) != BTDF_OK) {
            fprintf(stderr, "%s: %s: material [%s]: %s\n", mo->prog, mo->path, m->name, why);
            free_manifest(mf);
            free(mf);
            return 2;
        }
        for (int k = 0; k < m->nenter + m->nleave; k++) {
            const char *o = k < m->nenter ? m->enter[k] : m->leave[k - m->nenter];
            btdf_format_info fi;
            if (btdf_format_find(o, &fi) && !fi.available) {
                fprintf(stderr, "%s: %s: material [%s]: %s: %s support was switched off at "
                                "build time\n",
                        mo->prog, mo->path, m->name, o, fi.name);
                free_manifest(mf);
                free(mf);
                return 1;
            }
        }
        total += m->nenter + m->nleave + m->nbsdf;
    }
    if (mf->n == 0) {
        fprintf(stderr, "%s: %s: no [material] sections\n", mo->prog, mo->path);
        free(mf);
        return 2;
    }
    int code = 0, done = 0;
    for (int i = 0; i < mf->n && code == 0; i++) {
        material *m = &mf->m[i];
        if (m->nenter)
            code = do_side(mo, m, 0, m->enter, m->nenter, &done, total);
        if (code == 0 && m->nleave)
            code = do_side(mo, m, 1, m->leave, m->nleave, &done, total);
        if (code == 0 && m->nbsdf)
            code = manifest_bsdf(mo, m->name, &m->p, m->tol, m->sides, m->bsdf, m->nbsdf, &done,
                                 total);
    }
    free_manifest(mf);
    free(mf);
    return code;
}
