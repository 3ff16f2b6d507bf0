/* SPDX-License-Identifier: MIT */
/* cmd_model.c: the commands of the model itself: eval, albedo, polar. */
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

/* check_params for the commands that evaluate the model full too (eval, albedo, polar):
   full has the parameters of smith; its tally is made by the command. */
static int check_params_full(const btdf_params *p)
{
    btdf_params q = *p;
    if (q.model == BTDF_MODEL_FULL)
        q.model = BTDF_MODEL_SMITH;
    return check_params(&q);
}

/* The model object of p (the tally of model full, on the command's threads); 0 and a
   message on failure. */
static int make_ctx(const btdf_params *p, int threads, btdf_model_ctx **mx)
{
    btdf_full_opts fo;
    btdf_full_opts_default(&fo);
    fo.threads = threads;
    char msg[256];
    if (btdf_model_ctx_new(p, &fo, mx, msg, sizeof msg) != BTDF_OK) {
        fail(1, "%s", msg);
        return 0;
    }
    return 1;
}

/* A .bsdf for eval: its fold factors (a warning when a colour file's metadata lacks its
   indices); 0 after the message when it holds no block eval reads. */
static int eval_scatfun_open(const char *file, const btdf_scatfun *f, double *fold)
{
    if (!scatfun_fold(f, fold))
        fprintf(stderr, "btdftab: %s: warning: its metadata gives no three indices, so "
                        "the R and B values are printed as stored (times (n_G / n_c)^2)\n",
                file);
    if (!(btdf_scatfun_sides(f) & BTDF_SIDE_ENTER)) {
        /* eval reads light entering through the top (index n); the file has no
           such block, and a 0 would read as a measured value */
        fail(1, "%s: the file holds no 'enter' side (light entering, index n), "
                "which eval reads; it was written with --side leave", file);
        return 0;
    }
    return 1;
}

int cmd_eval(const cli *c)
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
    btdf_input in = {NULL, NULL, NULL};
    double fold[BTDF_MAX_CHANNELS] = {1.0, 1.0, 1.0}; /* a colour .bsdf's, divided out */
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
        } else if (in.radiance) {
            if (c->reflection) {
                btdf_rad_free(in.radiance);
                return fail(1, "%s: --part reflection: eval reads the transmission of a .xml "
                               "(its reflection blocks are for renderers)", c->table);
            }
            p = *btdf_rad_get_params(in.radiance);
        } else if (c->reflection) {
            btdf_scatfun_free(in.scatfun);
            return fail(1, "%s: --part reflection: eval reads the transmission of a .bsdf (its "
                           "reflection blocks are for renderers)", c->table);
        } else {
            p.channels = btdf_scatfun_channels(in.scatfun);
            if (!eval_scatfun_open(c->table, in.scatfun, fold)) {
                btdf_scatfun_free(in.scatfun);
                return 1;
            }
        }
    } else if (!check_params_full(&p)) {
        return EXIT_USAGE;
    }
    btdf_model_ctx *mx = NULL; /* model full: its tally, made once for every row */
    if (!in.table && !in.scatfun && !in.radiance && p.model == BTDF_MODEL_FULL &&
        !make_ctx(&p, c->threads, &mx))
        return 1;
    if (npos == 0 && !in.table && !in.scatfun && !in.radiance && !mx) { /* the model on rows from stdin */
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
        } else if (mx) {
            for (int ch = 0; ch < p.channels; ch++)
                out[ch] = c->reflection ? btdf_model_ctx_rho_r_deg(mx, ch, v[0], v[1], v[2])
                                        : btdf_model_ctx_rho_deg(mx, ch, v[0], v[1], v[2]);
        } else if (c->reflection) {
            for (int ch = 0; ch < p.channels; ch++)
                out[ch] = btdf_rho_r_model_deg(p.model, p.ior[ch], p.smoothness, p.k0, v[0],
                                               v[1], v[2]);
        } else if (in.scatfun) {
            /* light entering through the top (index n), as pbrt-v3 would read it, with
               a colour file's fold factors divided out: rho per channel */
            btdf_scatfun_eval(in.scatfun, ti, to, phi, out);
            for (int ch = 0; ch < p.channels; ch++)
                out[ch] *= fold[ch];
        } else if (in.radiance) {
            /* light entering the dense medium (index n), as Radiance reads the file */
            for (int ch = 0; ch < p.channels; ch++)
                out[ch] = btdf_rad_render(in.radiance, BTDF_SIDE_ENTER, p.channels == 3 ? ch : -1,
                                          ti, to, phi);
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
    btdf_model_ctx_free(mx);
    btdf_table_free(in.table);
    btdf_scatfun_free(in.scatfun);
    btdf_rad_free(in.radiance);
    return stdout_done(code);
}

/* ------------------------------------------------------------------------- */
/* albedo                                                                    */
/* ------------------------------------------------------------------------- */

/* One warning line when R(ti) + T(ti) < ALBEDO_WARN for some channel; `what` says
   where the angle comes from. */
void warn_albedo(const btdf_params *p, double ti_deg, double rt, const char *what)
{
    fprintf(stderr,
            "%s: warning: R + T = %.3g at theta_i %s degrees (%s; n = %g, s = %g): the "
            "model loses %.0f%% of the light there, to its shadowing term; it holds for "
            "smoother surfaces and smaller angles (docs/model.md, \"Where the model "
            "holds\"; --quiet silences this)\n",
            prog, rt, num(ti_deg), what, p->ior[0], p->smoothness, 100.0 * (1.0 - rt));
}

/* The smallest R + T over the channels at ti (radians). */
double albedo_min(const btdf_params *p, double ti)
{
    double T[BTDF_MAX_CHANNELS], R[BTDF_MAX_CHANNELS], lo = 1.0;
    btdf_transmittance(p, ti, T);
    btdf_reflectance(p, ti, R);
    for (int ch = 0; ch < p->channels; ch++)
        lo = R[ch] + T[ch] < lo ? R[ch] + T[ch] : lo;
    return lo;
}

int cmd_albedo(const cli *c)
{
    double angles[256];
    int na = 0;
    if (c->npos > 256)
        return fail(EXIT_USAGE, "albedo: at most 256 angles");
    for (int k = 0; k < c->npos; k++)
        if (!parse_double("theta-i", c->pos[k], &angles[na++]))
            return EXIT_USAGE;
    if (!check_params_full(&c->p))
        return EXIT_USAGE;
    if (na == 0)
        for (int k = 0; k <= 8; k++)
            angles[na++] = 10.0 * k;
    for (int k = 0; k < na; k++)
        if (!(angles[k] >= 0.0 && angles[k] <= 90.0))
            return fail(EXIT_USAGE, "theta-i %g: must lie in [0, 90] degrees", angles[k]);
    const btdf_params *p = &c->p;
    for (int k = 0; k < na; k++)
        if (!(angles[k] >= 0.0 && angles[k] <= 90.0))
            return fail(EXIT_USAGE, "theta-i %g: must lie in [0, 90] degrees", angles[k]);
    btdf_model_ctx *mx = NULL;
    if (!make_ctx(p, c->threads, &mx))
        return 1;
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
        btdf_model_ctx_albedo(mx, ti, T, R);
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
    btdf_model_ctx_free(mx);
    if (low >= 0 && !c->quiet)
        warn_albedo(p, angles[low], low_rt, "the lowest of these angles");
    return stdout_done(0);
}

/* ------------------------------------------------------------------------- */
/* polar, inspect, build                                                     */
/* ------------------------------------------------------------------------- */

int cmd_polar(const cli *c)
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
        if (!check_params_full(&mats[nm]))
            return EXIT_USAGE;
    }
    if (nm == 0) {
        if (!check_params_full(&c->p))
            return EXIT_USAGE;
        mats[nm++] = c->p;
    }
    memcpy(angles, c->angles, sizeof angles);
    if (na == 0)
        angles[na++] = 30.0;
    if (c->table) { /* the file gives the material and the values */
        if (c->nm || GIVEN(c, OPT_IOR) || GIVEN(c, OPT_SMOOTHNESS) || GIVEN(c, OPT_K0) ||
            GIVEN(c, OPT_MODEL))
            return fail(EXIT_USAGE, "polar: --material, --ior, --smoothness, --k0 and --model "
                                    "do not apply with --table (the file gives the material)");
        if (!folder_writable(c->out))
            return 1;
        return polar_of_file(c->table, c->out, c->part, angles, na, c->pic_w, c->pic_h);
    }
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
