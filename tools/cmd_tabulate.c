/* SPDX-License-Identifier: MIT */
/* cmd_tabulate.c: tabulate (tables through run_table, .bsdf, .xml) and inspect. */
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

/* --preview of a .bsdf or .xml (`what`): the polar picture of the written file, the
   only kind it has (a montage or render shows a table's slices). Checked before the
   work, with the pictures' folders. 0, or the exit status after the message. */
static int series_previews_check(const cli *c, const char *what)
{
    for (int k = 0; k < c->npreview; k++)
        if (c->previews[k].kind != BTDF_PREVIEW_POLAR && c->previews[k].named)
            return fail(EXIT_USAGE, "--preview %s=%s: a %s has a polar picture of the file "
                        "(--preview F.png or polar=F.png); montage and render show a "
                        "table's slices", c->previews[k].analytic ? "render-analytic"
                        : c->previews[k].kind == BTDF_PREVIEW_RENDER ? "render" : "montage",
                        c->previews[k].path, what);
    if (c->npreview > 0 && !btdf_format_available("png"))
        return fail(1, "%s: PNG support was switched off at build time (-Dpng=disabled)",
                    c->previews[0].path);
    if (GIVEN(c, OPT_SIZE) && c->npreview == 0)
        return fail(EXIT_USAGE, "--size applies to pictures: give --preview F.png");
    if (c->npreview > 0 && c->sides == BTDF_SIDE_LEAVE)
        return fail(EXIT_USAGE, "--preview: the picture draws light entering (index n), "
                                "which --side leave does not write");
    for (int k = 0; k < c->npreview; k++)
        if (!folder_writable(c->previews[k].path))
            return 1;
    return distinct_outputs(c->out, c);
}

/* The pictures of a written .bsdf or .xml: its lobes at 30 degrees, read back. */
static int series_previews_draw(const cli *c, btdf_part part)
{
    static const double ti = 30.0; /* degrees: polar's default angle */
    for (int k = 0; k < c->npreview; k++) {
        int rc = polar_of_file(c->out, c->previews[k].path, part, &ti, 1, c->pic_w, c->pic_h);
        if (rc)
            return rc;
    }
    return 0;
}

/* A .bsdf is built from Eq. 25 directly: the table's options do not apply. */
static int tabulate_series(const cli *c, const char *prov)
{
    static const opt_id table_only[] = {OPT_THETA_I, OPT_GRID, OPT_THETA_O, OPT_PHI,
                                        OPT_METRIC, OPT_LOG_DECADES, OPT_ZOOM, OPT_ESTIMATE};
    for (size_t k = 0; k < sizeof table_only / sizeof table_only[0]; k++)
        if (GIVEN(c, table_only[k]))
            return fail(EXIT_USAGE, "%s: --theta-i, --theta-o, --phi, --grid, --metric, "
                                    "--log-decades, --zoom and --estimate do not apply to "
                                    ".bsdf (the file covers every direction of both "
                                    "hemispheres, and its blocks are always checked in full; "
                                    "--%s was given)",
                        c->out, opt_find(table_only[k])->name);
    int bad = series_previews_check(c, ".bsdf");
    if (bad)
        return bad;
    if (c->report && !folder_writable(c->report))
        return 1;
    btdf_params single = c->p; /* full has smith's parameters (the builder makes its tally) */
    if (single.model == BTDF_MODEL_FULL)
        single.model = BTDF_MODEL_SMITH;
    if (!check_params(&single))
        return EXIT_USAGE;
    char why[256];
    if (c->p.model == BTDF_MODEL_FULL && /* one index only: the library's reason */
        btdf_scatfun_check(&c->p, 0.05, (btdf_side)BTDF_SCATFUN_ALL, why, sizeof why) == BTDF_ENOTSUP)
        return fail(EXIT_USAGE, "%s: --ior %s: %s", c->out, "with three indices", why);
    if (!folder_writable(c->out))
        return 1;
    run_progress pr;
    run_progress_start(&pr, !c->quiet && isatty(2), c->out);
    /* --max-samples caps the stored coefficients, --max-memory the builder's series;
       each only when given (the format has its own budgets otherwise) */
    /* --side picks the light's sides, --part the parts (run.h) */
    int part = GIVEN(c, OPT_PART) ? (int)c->part : 0, blocks = run_series_blocks(c->sides, part);
    double tol = run_series_tolerance(part, GIVEN(c, OPT_TOLERANCE), c->o.tolerance);
    int rc = run_series_ex(prog, c->out, &c->p, tol, blocks, c->threads, c->quiet,
                           c->best_effort, prov, c->report,
                           GIVEN(c, OPT_MAX_SAMPLES) ? c->o.max_samples : 0,
                           GIVEN(c, OPT_MAX_MEMORY) ? c->mib << 20 : 0, &pr);
    /* the picture draws what the file holds of light entering: both parts unless
       --part says one */
    return rc ? rc : series_previews_draw(c, part ? (btdf_part)part : BTDF_PART_BOTH);
}

/* A Radiance .xml is built from Eq. 25 (and rho_r) directly: all its blocks. */
static int tabulate_radiance(const cli *c, const char *prov)
{
    static const opt_id table_only[] = {OPT_THETA_I, OPT_GRID, OPT_THETA_O, OPT_PHI,
                                        OPT_METRIC, OPT_MAX_SAMPLES, OPT_MAX_MEMORY,
                                        OPT_SIDE, OPT_LOG_DECADES, OPT_ZOOM, OPT_ESTIMATE};
    for (size_t k = 0; k < sizeof table_only / sizeof table_only[0]; k++)
        if (GIVEN(c, table_only[k]))
            return fail(EXIT_USAGE, "%s: --%s does not apply to .xml (it holds every "
                                    "direction, light from either side, and its blocks are "
                                    "always checked in full)",
                        c->out, opt_find(table_only[k])->name);
    if (GIVEN(c, OPT_TOLERANCE) && c->basis != BTDF_RAD_TREE3)
        return fail(EXIT_USAGE, "--tolerance: a Klems matrix holds exact patch averages; its "
                                "error is set by the basis, not by a tolerance");
    btdf_params single = c->p; /* full has smith's parameters (the builder makes its tally) */
    if (single.model == BTDF_MODEL_FULL)
        single.model = BTDF_MODEL_SMITH;
    if (!check_params(&single))
        return EXIT_USAGE;
    int bad = series_previews_check(c, ".xml");
    if (bad)
        return bad;
    if (!folder_writable(c->out) || (c->report && !folder_writable(c->report)))
        return 1;
    run_progress pr;
    run_progress_start(&pr, !c->quiet && isatty(2), c->out);
    int rc = run_radiance(prog, c->out, c->report, &c->p, c->basis,
                          GIVEN(c, OPT_TOLERANCE) ? c->o.tolerance : 0.2, c->threads, c->quiet,
                          c->best_effort, prov, &pr);
    /* the transmission, as eval reads a .xml */
    return rc ? rc : series_previews_draw(c, BTDF_PART_TRANSMISSION);
}

/* A table's parameters and model before the work: full has smith's parameters (the
   builder makes its tally); the builder refuses smith's and full's reflection and
   full's grid (ENOTSUP), and the analytic panels of a render take a btdf_params, which
   full's tally is not. 0, or the exit status after the message. */
static int check_table_model(const cli *c, const btdf_table_opts *o)
{
    btdf_params single = o->params;
    if (single.model == BTDF_MODEL_FULL)
        single.model = BTDF_MODEL_SMITH;
    if (!check_params(&single))
        return EXIT_USAGE;
    char why[256];
    if (btdf_table_opts_check(o, why, sizeof why) == BTDF_ENOTSUP)
        return fail(EXIT_USAGE, "%s%s: %s", o->kind == BTDF_TABLE_GRID ? "--grid" : "--part ",
                    o->kind == BTDF_TABLE_GRID ? "" : btdf_part_name(c->part), why);
    for (int k = 0; k < c->npreview; k++)
        if (o->params.model == BTDF_MODEL_FULL && c->previews[k].analytic)
            return fail(EXIT_USAGE, "--preview render-analytic=%s: --model full: not "
                        "available yet (render= and montage pictures of the table are)",
                        c->previews[k].path);
    return 0;
}

int cmd_tabulate(cli *c, const char *prov)
{
    if (c->npos)
        return fail(EXIT_USAGE, "tabulate: unexpected argument '%s' (the output is -o FILE)",
                    c->pos[0]);
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
    o.params = p;
    o.part = c->part;
    int bad = check_table_model(c, &o);
    if (bad)
        return bad;
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
    for (int k = 0; k < c->npreview; k++)
        if (c->previews[k].kind == BTDF_PREVIEW_POLAR)
            return fail(EXIT_USAGE, "--preview polar=%s: the polar picture of a written "
                        "file is for .bsdf and .xml; a table's lobes: btdftab polar --table "
                        "FILE", c->previews[k].path);
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
        /* without --zoom, a zoom chosen from the lobe's width (a narrow lobe is a dot
           on the whole face) */
        po->zoom = po->kind != BTDF_PREVIEW_RENDER ? 0.0 : GIVEN(c, OPT_ZOOM) ? c->zoom : -1.0;
        po->width = c->pic_w;
        po->height = c->pic_h;
        outs[nouts++] = (run_table_out){c->previews[k].path, po, 0};
    }
    run_table_req rq = {prog, out, o, c->part != BTDF_PART_TRANSMISSION, outs, nouts,
                        c->report, prov, c->quiet, c->best_effort, &pr, NULL};
    return run_table(&rq);
}

int cmd_inspect(const cli *c)
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
