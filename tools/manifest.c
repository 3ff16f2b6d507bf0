/* SPDX-License-Identifier: MIT */
/* manifest.c: `btdftab build scene.ini`, the outputs of a scene's materials and nothing more. */
#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "inifile.h"
#include "numparse.h"

#include <btdf/btdf.h>
#include <btdf/btdf_pane.h>

#include "manifest.h"
#include "pane_write.h"
#include "pathnorm.h"
#include "run.h"
#include "stamp.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/*
 * A manifest is an INI file (read by inifile.c): one section per material.
 *
 *   [frosted]                  ; the material's name
 *   ior = 1.5                  ; n, or R,G,B
 *   smoothness = 3
 *   k0 = 0.7                   ; optional
 *   model = smith              ; optional: xu-sun (the default), smith or full, as --model
 *   theta_i = 0:90             ; optional incidence range, degrees
 *   tolerance = 1e-3           ; optional
 *   metric = l1                ; optional, l1 or max
 *   part = both                ; optional: the lobes the outputs hold, transmission,
 *                              ; reflection or both; as tabulate's --part: tables
 *                              ; default to transmission, a .bsdf to both
 *   enter = a.csv a.exr m.png  ; tables for light entering (index n): .csv .exr .png
 *   leave = b.exr              ; tables for light leaving (index 1/n)
 *   bsdf = glass.bsdf          ; a renderer file (SCATFUN v1)
 *   sides = both               ; which sides the .bsdf holds: enter, leave or both
 *   xml = glazing.xml          ; a Radiance BSDF XML (both parts, light from either side)
 *   basis = tree3              ; its basis, as --basis: tree3 (the default), klems-full,
 *                              ; klems-half or klems-quarter
 *   back = smooth              ; a pane (xml, grid, bsdf): its back face, smooth or S,
 *   thickness = 4              ; as --back; with thickness (mm) and absorption (per mm) as
 *                              ; the options
 *   grid = door.csv door.exr   ; a pane's system on a grid (tabulate --back -o F.csv|.exr)
 *   grid_size = 46,46,37       ; optional, its nodes NI,NO,NPHI, as --grid
 *
 * Only the tables an output needs are built, once per material and side, and shared
 * by its outputs. An output is skipped when it exists and its stamp (a hidden file
 * beside it) records the same parameters and program version.
 *
 * Output paths that are not absolute are relative to the manifest's folder, so a
 * manifest gives the same files from any working directory; missing folders are
 * created. The work comes in jobs, in manifest order: per material, its enter
 * tables, its leave tables, then each .bsdf, each .xml, each grid. --shard K/N does
 * jobs K-1, K-1+N, ...: every output belongs to exactly one job, so N shards write
 * disjoint files.
 */

#include "manifest_impl.h"

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
    /* only when not the transmission: the stamps written before the key existed hold */
    size_t used = strlen(buf);
    if (m->part == BTDF_PART_REFLECTION || m->part == BTDF_PART_BOTH)
        snprintf(buf + used, len - used, "part %s\n", btdf_part_name(m->part));
    /* only when not xu-sun, for the same reason */
    used = strlen(buf);
    if (p->model != BTDF_MODEL_XU_SUN)
        snprintf(buf + used, len - used, "model %s\n", btdf_model_name(p->model));
}

/* Dry run: one line per output, what would be done and why. */
static void plan(const char *name, const char *out, const char *why)
{
    printf("%s: %s: %s\n", name, out, why ? why : "up to date");
}

/* Whether job number j (0-based, manifest order) belongs to this shard. */
static int mine(const manifest_opts *mo, int j)
{
    return mo->shard_n <= 1 || j % mo->shard_n == mo->shard_k - 1;
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
    char stamp[4096];
    int stale = 0;
    for (int k = 0; k < nouts; k++) {
        stamp_text(stamp, sizeof stamp, m, &p, side);
        if (mo->force || !up_to_date(outs[k], stamp))
            stale++;
    }
    if (mo->dry_run) {
        stamp_text(stamp, sizeof stamp, m, &p, side);
        char what[128];
        snprintf(what, sizeof what, "%s (%s)", m->name, side);
        for (int k = 0; k < nouts; k++)
            plan(what, outs[k], why_stale(outs[k], stamp, mo->force));
        *done += nouts;
        return 0;
    }
    if (stale == 0) {
        *done += nouts;
        if (!mo->quiet)
            fprintf(stderr, "%s: %s (%s): %d output(s) up to date\n", mo->prog, m->name, side,
                    nouts);
        return 0;
    }
    for (int k = 0; k < nouts; k++)
        if (!make_parents(outs[k])) {
            fprintf(stderr, "%s: %s: cannot create its folder: %s\n", mo->prog, outs[k],
                    strerror(errno));
            return 1;
        }
    char label[128];
    snprintf(label, sizeof label, "[%d/%d] %s (%s)", *done + 1, total, m->name, side);
    run_progress pr;
    run_progress_start(&pr, mo->progress, label);
    btdf_table_opts o;
    btdf_table_opts_default(&o);
    o.params = p;
    o.ti_min = m->ti0 * M_PI / 180.0;
    o.ti_max = m->ti1 * M_PI / 180.0;
    o.tolerance = m->tol;
    o.metric = m->metric;
    o.part = m->part;
    o.threads = mo->threads;
    o.progress = run_progress_cb;
    o.progress_user = &pr;
    /* The stale outputs, written together by the run tabulate takes: a table file, or
       a .png montage of the table (the registry picks by extension). */
    btdf_preview_opts po;
    btdf_preview_opts_default(&po);
    po.kind = BTDF_PREVIEW_MONTAGE;
    run_table_out todo[MAX_OUTPUTS];
    int ntodo = 0;
    for (int k = 0; k < nouts; k++)
        if (mo->force || !up_to_date(outs[k], stamp))
            todo[ntodo++] = (run_table_out){outs[k], &po, 1};
    char prov[256], who[256];
    snprintf(prov, sizeof prov, "btdftab build, material [%s], side %s", m->name, side);
    snprintf(who, sizeof who, "%s: %s (%s)", mo->prog, m->name, side);
    int missed = 0;
    run_table_req rq = {who, NULL, o, m->part != BTDF_PART_TRANSMISSION, todo, ntodo, NULL,
                        prov, mo->quiet, mo->best_effort, &pr, &missed};
    int code = run_table(&rq);
    *done += nouts;
    /* written above its tolerance (--best-effort): no stamp, so that it is not called
       up to date later */
    if (code == 0 && missed && !mo->quiet)
        fprintf(stderr, "%s: %s (%s): written with --best-effort above its tolerance: no "
                        "stamp, so the next build makes it again\n", mo->prog, m->name, side);
    char why[512] = "";
    for (int k = 0; k < ntodo && code == 0 && !missed; k++)
        if (!write_stamp_for(todo[k].path, stamp, why, sizeof why)) {
            fprintf(stderr, "%s: %s: cannot write its stamp: %s\n", mo->prog, todo[k].path,
                    why);
            code = 1;
        }
    return code;
}

/* Writes the stale .bsdf outputs of one material: blocks as run_series_blocks
   gives them, and their tolerance. */
static int manifest_bsdf(const manifest_opts *mo, const char *name, const btdf_params *p,
                         double tol, int sides, int blocks, char **outs, int nouts, int *done,
                         int total, int *job)
{
    /* The stamp: everything the file depends on (theta_i does not apply); the parts
       only when the file holds reflection, so that older stamps of transmission-only
       files hold. */
    material m;
    memset(&m, 0, sizeof m);
    m.tol = tol;
    m.sides = sides;
    m.part = (blocks & ~BTDF_SIDE_BOTH) ? ((blocks & BTDF_SIDE_BOTH) ? BTDF_PART_BOTH
                                                                     : BTDF_PART_REFLECTION)
                                        : BTDF_PART_TRANSMISSION;
    char stamp[4096], prov[256];
    stamp_text(stamp, sizeof stamp, &m, p, "bsdf");
    snprintf(prov, sizeof prov, "btdftab build, material [%s]", name);
    for (int k = 0; k < nouts; k++) {
        (*done)++;
        if (!mine(mo, (*job)++))
            continue;
        if (mo->dry_run) {
            plan(name, outs[k], why_stale(outs[k], stamp, mo->force));
            continue;
        }
        if (!mo->force && up_to_date(outs[k], stamp)) {
            if (!mo->quiet)
                fprintf(stderr, "%s: %s: up to date\n", mo->prog, outs[k]);
            continue;
        }
        if (!make_parents(outs[k])) {
            fprintf(stderr, "%s: %s: cannot create its folder: %s\n", mo->prog, outs[k],
                    strerror(errno));
            return 1;
        }
        char label[128];
        snprintf(label, sizeof label, "[%d/%d] %s", *done, total, outs[k]);
        run_progress pr;
        run_progress_start(&pr, mo->progress, label);
        int code = run_series(mo->prog, outs[k], p, tol, blocks, mo->threads, mo->quiet,
                              mo->best_effort, prov, &pr);
        if (code != 0)
            return code;
        char why[512] = "";
        if (!write_stamp_for(outs[k], stamp, why, sizeof why)) {
            fprintf(stderr, "%s: %s: cannot write its stamp: %s\n", mo->prog, outs[k], why);
            return 1;
        }
    }
    return 0;
}

/* What an output's job does before it builds: plans it (--dry-run) or reports it up to
   date, 1 (skip it); creates its folder, 0 (build it); -1 after a message when the folder
   cannot be made. */
static int output_prelude(const manifest_opts *mo, const char *name, const char *out,
                          const char *stamp)
{
    if (mo->dry_run) {
        plan(name, out, why_stale(out, stamp, mo->force));
        return 1;
    }
    if (!mo->force && up_to_date(out, stamp)) {
        if (!mo->quiet)
            fprintf(stderr, "%s: %s: up to date\n", mo->prog, out);
        return 1;
    }
    if (!make_parents(out)) {
        fprintf(stderr, "%s: %s: cannot create its folder: %s\n", mo->prog, out,
                strerror(errno));
        return -1;
    }
    return 0;
}

/* Writes the stale .xml outputs of one material: every block in its basis, with the
   tolerance tabulate -o F.xml takes (a tree's: the key's, or 0.2; a Klems matrix has
   none). theta_i, metric, part and sides do not apply: the file holds both parts and
   light from either side. */
static int manifest_xml(const manifest_opts *mo, const material *mat, int *done, int total,
                        int *job)
{
    double tol = mat->basis != BTDF_RAD_TREE3 ? 0.0 : mat->key_line[K_TOL] ? mat->tol : 0.2;
    material m; /* the stamp's: only what the file depends on */
    memset(&m, 0, sizeof m);
    m.tol = tol;
    char stamp[4096], what[64], prov[256];
    snprintf(what, sizeof what, "xml %s", btdf_rad_basis_name(mat->basis));
    stamp_text(stamp, sizeof stamp, &m, &mat->p, what);
    int pane = mat->key_line[K_BACK] != 0, used = (int)strlen(stamp);
    if (pane) /* only for a pane: the interface's stamps hold */
        snprintf(stamp + used, sizeof stamp - (size_t)used, "pane %d %.17g %.17g %.17g\n",
                 mat->pane.back_smooth, mat->pane.back_s, mat->pane.thickness,
                 mat->pane.absorption);
    snprintf(prov, sizeof prov, "btdftab build, material [%s]", mat->name);
    for (int k = 0; k < mat->nxml; k++) {
        const char *out = mat->xml[k];
        (*done)++;
        if (!mine(mo, (*job)++))
            continue;
        int pre = output_prelude(mo, mat->name, out, stamp);
        if (pre < 0)
            return 1;
        if (pre > 0)
            continue;
        char label[128];
        snprintf(label, sizeof label, "[%d/%d] %s", *done, total, out);
        run_progress pr;
        run_progress_start(&pr, mo->progress, label);
        int code = pane ? pane_write_xml(out, &mat->p, &mat->pane, mat->basis, 0.0,
                                         mo->threads, mo->quiet, prov)
                        : run_radiance(mo->prog, out, NULL, &mat->p, mat->basis,
                                       tol > 0.0 ? tol : 0.2, mo->threads, mo->quiet,
                                       mo->best_effort, prov, &pr);
        if (code != 0)
            return code;
        char why[512] = "";
        if (!write_stamp_for(out, stamp, why, sizeof why)) {
            fprintf(stderr, "%s: %s: cannot write its stamp: %s\n", mo->prog, out, why);
            return 1;
        }
    }
    return 0;
}

/* The grid outputs of a pane's section (bsdf = 0), or its .bsdf outputs (bsdf = 1): the
   system is built once, when some output is stale, and written to each (tabulate --back
   -o F.csv|.exr --grid NI,NO,NPHI, or -o F.bsdf --tolerance E). */
static int manifest_pane_out(const manifest_opts *mo, const material *mat, int bsdf, int *done,
                             int total, int *job)
{
    material m; /* the stamp's: only what the file depends on */
    memset(&m, 0, sizeof m);
    char stamp[4096], what[96], prov[256];
    double tol = mat->key_line[K_TOL] ? mat->tol : 1e-2; /* tabulate's default */
    if (bsdf) {
        m.tol = tol;
        snprintf(what, sizeof what, "pane bsdf");
    } else {
        snprintf(what, sizeof what, "grid %zu %zu %zu", mat->grid_n[0], mat->grid_n[1],
                 mat->grid_n[2]);
    }
    stamp_text(stamp, sizeof stamp, &m, &mat->p, what);
    int used = (int)strlen(stamp);
    snprintf(stamp + used, sizeof stamp - (size_t)used, "pane %d %.17g %.17g %.17g\n",
             mat->pane.back_smooth, mat->pane.back_s, mat->pane.thickness,
             mat->pane.absorption);
    snprintf(prov, sizeof prov, "btdftab build, material [%s]", mat->name);
    struct btdf_pane *P = NULL;
    int code = 0;
    int nout = bsdf ? mat->nbsdf : mat->ngrid;
    for (int k = 0; k < nout && code == 0; k++) {
        const char *out = bsdf ? mat->bsdf[k] : mat->grid[k];
        (*done)++;
        if (!mine(mo, (*job)++))
            continue;
        int pre = output_prelude(mo, mat->name, out, stamp);
        if (pre < 0) {
            code = 1;
            break;
        }
        if (pre > 0)
            continue;
        if (!mo->quiet)
            fprintf(stderr, "%s: [%d/%d] %s\n", mo->prog, *done, total, out);
        if (!P && (code = pane_make(&mat->p, &mat->pane, mo->threads, &P)) != 0)
            break;
        code = bsdf ? pane_write_bsdf(out, P, tol, mo->threads, mo->quiet, prov)
                    : pane_write_table(out, P, mat->grid_n[0], mat->grid_n[1], mat->grid_n[2],
                                       mo->quiet, prov);
        char why[512] = "";
        if (code == 0 && !write_stamp_for(out, stamp, why, sizeof why)) {
            fprintf(stderr, "%s: %s: cannot write its stamp: %s\n", mo->prog, out, why);
            code = 1;
        }
    }
    btdf_pane_free(P);
    return code;
}

/* A .bsdf's blocks and tolerance from the keys as tabulate takes them from its options
   (run.h): part and tolerance apply when given; without part, the file holds both
   parts, as tabulate -o F.bsdf without --part. */
static int bsdf_part(const material *m)
{
    return m->key_line[K_PART] ? (int)m->part : 0;
}

static int bsdf_blocks(const material *m)
{
    return run_series_blocks(m->sides, bsdf_part(m));
}

static double bsdf_tol(const material *m)
{
    return run_series_tolerance(bsdf_part(m), m->key_line[K_TOL] != 0, m->tol);
}

/* The line of key k of m, or of its header when the key was not given. */
static int line_of(const material *m, int k)
{
    return m->key_line[k] ? m->key_line[k] : m->line;
}

/* Every value against the library's own checks, and every output against the file
   system and the other outputs, before any work: 0, or the line of the first error
   with why set. */
static int validate(const manifest_opts *mo, const manifest *mf, char *why, size_t whylen)
{
    char msg[512];
    for (int i = 0; i < mf->n; i++) {
        const material *m = &mf->m[i];
        for (int leave = 0; leave <= 1; leave++) {
            if (!(leave ? m->nleave : m->nenter))
                continue;
            btdf_table_opts o;
            btdf_table_opts_default(&o);
            o.params = m->p;
            if (leave)
                for (int c = 0; c < o.params.channels; c++)
                    o.params.ior[c] = 1.0 / o.params.ior[c];
            o.ti_min = m->ti0 * M_PI / 180.0;
            o.ti_max = m->ti1 * M_PI / 180.0;
            o.tolerance = m->tol;
            o.metric = m->metric;
            o.part = m->part;
            if (btdf_table_opts_check(&o, msg, sizeof msg) != BTDF_OK) {
                snprintf(why, whylen, "material [%s]: %.400s", m->name, msg);
                return !strncmp(msg, "tolerance", 9) ? line_of(m, K_TOL)
                       : !strncmp(msg, "theta", 5)   ? line_of(m, K_THETA)
                                                     : m->line;
            }
        }
        if (m->nbsdf && btdf_scatfun_check(&m->p, bsdf_tol(m), (btdf_side)bsdf_blocks(m), msg,
                                           sizeof msg) != BTDF_OK) {
            snprintf(why, whylen, "material [%s]: %.400s (for its .bsdf output)", m->name, msg);
            return !strncmp(msg, "tolerance", 9) ? line_of(m, K_TOL)
                   : !strncmp(msg, "side", 4)    ? line_of(m, K_SIDES)
                                                 : m->line;
        }
        for (int k = 0; k < n_outputs(m); k++) {
            int key;
            const char *out = output_at(m, k, &key);
            /* a missing folder is created at build time: what is above it must allow it */
            int dir_exists = 1, bad = !parents_creatable(out, &dir_exists, msg, sizeof msg);
            /* the name's own checks (its length, a folder or non-file there: EINVAL) hold
               before its folder exists too; a missing folder (EIO) is made at build time */
            if (!bad) {
                btdf_status oc = btdf_output_check(out, msg, sizeof msg);
                bad = dir_exists ? oc != BTDF_OK : oc == BTDF_EINVAL;
            }
            if (bad) {
                snprintf(why, whylen, "output '%.300s': %.400s", out, msg);
                return m->key_line[key];
            }
            char sp[4200];
            stamp_path(sp, sizeof sp, out);
            if (dir_exists && btdf_output_check(sp, msg, sizeof msg) == BTDF_EINVAL) {
                const char *sb = strrchr(sp, '/');
                snprintf(why, whylen, "output '%.200s': its stamp '%.100s' %.150s", out,
                         sb ? sb + 1 : sp, msg);
                return m->key_line[key];
            }
            if (btdf_same_file(out, mo->path)) {
                snprintf(why, whylen, "output '%.300s' is the manifest itself", out);
                return m->key_line[key];
            }
            /* every earlier output, of this material and the ones before */
            for (int j = 0; j <= i; j++) {
                const material *q = &mf->m[j];
                int nq = j < i ? n_outputs(q) : k;
                for (int r = 0; r < nq; r++) {
                    int qk;
                    const char *o2 = output_at(q, r, &qk);
                    if (path_same(out, o2)) {
                        snprintf(why, whylen, "output '%.300s' is also written by [%s] at line %d",
                                 out, q->name, q->key_line[qk]);
                        return m->key_line[key];
                    }
                }
            }
        }
    }
    return 0;
}

/* The keys of a pane's section as tabulate --back refuses the options (pane_keys_refusal)
   and the grid keys' own checks: 0, or 2 after a message naming the key and its line. */
static int pane_section_refusal(const manifest_opts *mo, const material *m)
{
    if ((m->ngrid || m->key_line[K_GRID_SIZE]) && !m->key_line[K_BACK]) {
        int gl = m->ngrid ? m->key_line[K_GRID] : m->key_line[K_GRID_SIZE];
        fprintf(stderr, "%s: %s:%d: material [%s]: %s: the grid of a pane's system: give "
                        "back = smooth|S as well (enter and leave take the interface's "
                        "tables)\n", mo->prog, mo->path, gl, m->name,
                m->ngrid ? "grid" : "grid_size");
        return 2;
    }
    double nv = 4.0 * m->p.channels * (double)m->grid_n[0] * (double)m->grid_n[1] *
                (double)m->grid_n[2];
    if (m->ngrid && nv > (double)((size_t)1 << 28)) { /* pane_write_table's limit */
        fprintf(stderr, "%s: %s:%d: material [%s]: grid_size %zu,%zu,%zu: %.0f values, more "
                        "than 2^28\n", mo->prog, mo->path, line_of(m, K_GRID_SIZE), m->name,
                m->grid_n[0], m->grid_n[1], m->grid_n[2], nv);
        return 2;
    }
    if (m->key_line[K_GRID_SIZE] && !m->ngrid) {
        fprintf(stderr, "%s: %s:%d: material [%s]: grid_size: sets the nodes of the grid "
                        "outputs, and the section has none (give grid = F.csv|F.exr)\n",
                mo->prog, mo->path, m->key_line[K_GRID_SIZE], m->name);
        return 2;
    }
    /* three channels: a pane's grid and Klems .xml hold them, its tree3 does not */
    const char *pw = pane_keys_refusal(
        m->key_line[K_BACK] != 0, m->key_line[K_THICK] || m->key_line[K_ABS],
        m->nenter + m->nleave,
        (m->key_line[K_TOL] && !m->nbsdf) || m->key_line[K_THETA] || m->key_line[K_METRIC] ||
            m->key_line[K_PART] || m->key_line[K_SIDES],
        (m->nxml && m->basis == BTDF_RAD_TREE3) || m->nbsdf ? m->p.channels : 1, m->nbsdf,
        m->pane.back_smooth);
    if (pw) {
        fprintf(stderr, "%s: %s:%d: material [%s]: %s\n", mo->prog, mo->path,
                m->key_line[K_BACK] ? m->key_line[K_BACK]
                : m->key_line[K_THICK] ? m->key_line[K_THICK] : m->key_line[K_ABS],
                m->name, pw);
        return 2;
    }
    return 0;
}

int manifest_run(const manifest_opts *mo)
{
    manifest *mf = calloc(1, sizeof *mf);
    if (!mf)
        return fail(mo->prog, "out of memory%s%s", "", "");
    char rwhy[256] = "";
    const char *slash = strrchr(mo->path, '/');
    if (slash) /* outputs are relative to the manifest's folder */
        snprintf(mf->dir, sizeof mf->dir, "%.*s/", (int)(slash - mo->path), mo->path);
    int line = ini_read(mo->path, manifest_on_entry, mf, rwhy, sizeof rwhy);
    if (line == 0 && !manifest_check_not_empty(mf))
        line = mf->why_line;
    if (line < 0) {
        manifest_free(mf);
        free(mf);
        fprintf(stderr, "%s: %s: %s\n", mo->prog, mo->path, rwhy);
        return 1;
    }
    if (line > 0) {
        fprintf(stderr, "%s: %s:%d: %s\n", mo->prog, mo->path, mf->why_line ? mf->why_line : line,
                mf->why[0] ? mf->why : rwhy);
        manifest_free(mf);
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
            fprintf(stderr, "%s: %s:%d: material [%s]: missing '%s'\n", mo->prog, mo->path,
                    m->line, m->name, miss);
            manifest_free(mf);
            free(mf);
            return 2;
        }
        btdf_params single = m->p; /* full has smith's parameters (its tally is made */
        if (single.model == BTDF_MODEL_FULL) /* by the table builder) */
            single.model = BTDF_MODEL_SMITH;
        if (btdf_params_check(&single, why, sizeof why) != BTDF_OK) {
            fprintf(stderr, "%s: %s:%d: material [%s]: %s\n", mo->prog, mo->path, m->line,
                    m->name, why);
            manifest_free(mf);
            free(mf);
            return 2;
        }
        for (int k = 0; k < m->nenter + m->nleave + m->ngrid; k++) {
            const char *o = k < m->nenter             ? m->enter[k]
                            : k < m->nenter + m->nleave ? m->leave[k - m->nenter]
                                                        : m->grid[k - m->nenter - m->nleave];
            btdf_format_info fi;
            if (btdf_format_find(o, &fi) && !fi.available) {
                fprintf(stderr, "%s: %s: material [%s]: %s: %s support was switched off at "
                                "build time\n",
                        mo->prog, mo->path, m->name, o, fi.name);
                manifest_free(mf);
                free(mf);
                return 1;
            }
        }
        if (pane_section_refusal(mo, m)) {
            manifest_free(mf);
            free(mf);
            return 2;
        }
        /* as tabulate refuses it: a tolerance for Klems matrices alone */
        if (m->key_line[K_TOL] && m->basis != BTDF_RAD_TREE3 && m->nxml > 0 &&
            m->nenter + m->nleave + m->nbsdf == 0) {
            fprintf(stderr, "%s: %s:%d: material [%s]: tolerance: a Klems matrix holds exact "
                            "patch averages; its error is set by the basis, not by a "
                            "tolerance\n", mo->prog, mo->path, m->key_line[K_TOL], m->name);
            manifest_free(mf);
            free(mf);
            return 2;
        }
        total += n_outputs(m);
    }
    if (mf->n == 0) {
        fprintf(stderr, "%s: %s: no [material] sections\n", mo->prog, mo->path);
        free(mf);
        return 2;
    }
    char vwhy[800];
    int vline = validate(mo, mf, vwhy, sizeof vwhy);
    if (vline) {
        fprintf(stderr, "%s: %s:%d: %s\n", mo->prog, mo->path, vline, vwhy);
        manifest_free(mf);
        free(mf);
        return 2;
    }
    int code = 0, done = 0, job = 0;
    for (int i = 0; i < mf->n && code == 0; i++) {
        material *m = &mf->m[i];
        if (m->nenter) {
            if (mine(mo, job++))
                code = do_side(mo, m, 0, m->enter, m->nenter, &done, total);
            else
                done += m->nenter;
        }
        if (code == 0 && m->nleave) {
            if (mine(mo, job++))
                code = do_side(mo, m, 1, m->leave, m->nleave, &done, total);
            else
                done += m->nleave;
        }
        if (code == 0 && m->nbsdf)
            code = m->key_line[K_BACK]
                       ? manifest_pane_out(mo, m, 1, &done, total, &job)
                       : manifest_bsdf(mo, m->name, &m->p, bsdf_tol(m), m->sides,
                                       bsdf_blocks(m), m->bsdf, m->nbsdf, &done, total, &job);
        if (code == 0 && m->nxml)
            code = manifest_xml(mo, m, &done, total, &job);
        if (code == 0 && m->ngrid)
            code = manifest_pane_out(mo, m, 0, &done, total, &job);
    }
    manifest_free(mf);
    free(mf);
    return code;
}
