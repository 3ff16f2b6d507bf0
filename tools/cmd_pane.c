/* SPDX-License-Identifier: MIT */
/* cmd_pane.c: a pane's system BSDF (--back, --thickness, --absorption): tabulate writes it
   to a Radiance/WINDOW .xml, albedo prints its T and R from either side (docs/pane.md). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "btdf.h"
#include "btdf_pane.h"
#include "cli.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* The depth of a pane's tree3: 2^6 cells along each of the three axes, 262144 leaves a
   block; the system's lobes are as wide as its roughest face's (2/s rad), so at s = 3
   a cell (1/64 of the disk's side) is well inside them. */
#define PANE_TREE_DEPTH 6

int apply_pane(cli *c, int id, const char *v)
{
    switch (id) {
    case OPT_BACK:
        if (!strcmp(v, "smooth")) {
            c->back_smooth = 1;
            return 1;
        }
        c->back_smooth = 0;
        if (!parse_double("--back", v, &c->back_s))
            return 0;
        if (!(c->back_s >= BTDF_S_MIN && c->back_s <= BTDF_S_MAX)) {
            fail(EXIT_USAGE, "--back: %g: give smooth, or a smoothness in [%g, %g]", c->back_s,
                 BTDF_S_MIN, BTDF_S_MAX);
            return 0;
        }
        return 1;
    case OPT_THICKNESS:
        if (!parse_double("--thickness", v, &c->thickness))
            return 0;
        if (!(c->thickness >= 0.0 && c->thickness <= BTDF_PANE_THICKNESS_MAX)) {
            fail(EXIT_USAGE, "--thickness: %g mm: must lie in [0, %g]", c->thickness,
                 BTDF_PANE_THICKNESS_MAX);
            return 0;
        }
        return 1;
    default:
        if (!parse_double("--absorption", v, &c->absorption))
            return 0;
        if (!(c->absorption >= 0.0 && c->absorption <= BTDF_PANE_ABSORPTION_MAX)) {
            fail(EXIT_USAGE, "--absorption: %g per mm: must lie in [0, %g]", c->absorption,
                 BTDF_PANE_ABSORPTION_MAX);
            return 0;
        }
        return 1;
    }
}

static int make_pane(const cli *c, btdf_pane **out)
{
    btdf_pane_opts o;
    btdf_pane_opts_default(&o);
    o.front = c->p;
    o.back_smooth = c->back_smooth;
    o.back_smoothness = c->back_smooth ? c->p.smoothness : c->back_s;
    o.thickness_mm = GIVEN(c, OPT_THICKNESS) ? c->thickness : 4.0; /* simulate's default too */
    o.absorption_per_mm = c->absorption;
    o.threads = c->threads;
    char msg[512] = "";
    btdf_status st = btdf_pane_opts_check(&o, msg, sizeof msg);
    if (st != BTDF_OK)
        return fail(EXIT_USAGE, "%s", msg);
    st = btdf_pane_new(&o, out, msg, sizeof msg);
    if (st != BTDF_OK)
        return fail(1, "%s", msg[0] ? msg : btdf_strerror(st));
    return 0;
}

static int pane_albedo(const cli *c, const btdf_pane *P)
{
    double angles[256];
    int na = 0;
    if (c->npos > 256)
        return fail(EXIT_USAGE, "albedo: at most 256 angles");
    for (int k = 0; k < c->npos; k++) {
        if (!parse_double("theta-i", c->pos[k], &angles[na]))
            return EXIT_USAGE;
        if (!(angles[na] >= 0.0 && angles[na] <= 90.0))
            return fail(EXIT_USAGE, "theta-i %g: must lie in [0, 90] degrees", angles[na]);
        na++;
    }
    if (na == 0)
        for (int k = 0; k <= 8; k++)
            angles[na++] = 10.0 * k;
    int nch = c->p.channels;
    printf("theta_i_deg");
    for (int ch = 0; ch < nch; ch++) {
        const char *x = nch == 1 ? "" : (const char *[]){"_r", "_g", "_b"}[ch];
        printf(",T_front%s,R_front%s,R+T_front%s,T_back%s,R_back%s,R+T_back%s", x, x, x, x, x,
               x);
    }
    printf("\n");
    for (int k = 0; k < na; k++) {
        printf("%s", num(angles[k]));
        for (int ch = 0; ch < nch; ch++)
            for (int sd = BTDF_PANE_FRONT; sd <= BTDF_PANE_BACK; sd++) {
                double T, R;
                btdf_pane_albedo(P, (btdf_pane_side)sd, ch, angles[k] * M_PI / 180.0, &T, &R);
                /* the system's T and R hold to about 1e-3 (docs/pane.md): 6 digits */
                printf(",%.6g,%.6g,%.6g", T, R, T + R);
            }
        printf("\n");
    }
    return stdout_done(0);
}

/* Radiance's blocks (btdf_radiance.h): 0 light from +Z through the back face, 1 from -Z
   through the front, 2 reflected on -Z (front), 3 on +Z (back). */
static btdf_pane_side block_side(int k) { return k == 1 || k == 2 ? BTDF_PANE_FRONT : BTDF_PANE_BACK; }

static double src_eval(void *user, int k, double ti, double to, double phi)
{
    const btdf_pane *P = user;
    if (k >= 2)
        return btdf_pane_eval(P, block_side(k), BTDF_PART_REFLECTION, 0, ti, to, phi);
    return btdf_pane_eval(P, block_side(k), BTDF_PART_TRANSMISSION, 0, ti, M_PI - to, phi);
}

static void src_eval_phis(void *user, int k, double ti, double to, size_t count,
                          const double *phi, double *out)
{
    const btdf_pane *P = user;
    if (k >= 2)
        btdf_pane_eval_phis(P, block_side(k), BTDF_PART_REFLECTION, 0, ti, to, count, phi, out);
    else
        btdf_pane_eval_phis(P, block_side(k), BTDF_PART_TRANSMISSION, 0, ti, M_PI - to, count,
                            phi, out);
}

static double src_specular(void *user, int k, double ti)
{
    return btdf_pane_specular(user, block_side(k),
                              k >= 2 ? BTDF_PART_REFLECTION : BTDF_PART_TRANSMISSION, 0, ti);
}

static int pane_xml(const cli *c, const btdf_pane *P, const char *prov)
{
    static const opt_id no[] = {OPT_THETA_I, OPT_GRID, OPT_PREVIEW, OPT_THETA_O, OPT_PHI,
                                OPT_METRIC, OPT_MAX_SAMPLES, OPT_MAX_MEMORY, OPT_SIZE,
                                OPT_SIDE, OPT_PART, OPT_TOLERANCE, OPT_REPORT};
    for (size_t k = 0; k < sizeof no / sizeof no[0]; k++)
        if (GIVEN(c, no[k]))
            return fail(EXIT_USAGE, "%s: --%s does not apply to a pane's .xml (it holds the "
                                    "system, both parts, light from either side)",
                        c->out, opt_find(no[k])->name);
    if (c->p.channels != 1)
        return fail(EXIT_USAGE, "--back: a pane's .xml has one channel: give one --ior");
    if (!folder_writable(c->out))
        return 1;
    char desc[400];
    const btdf_pane_opts *o = btdf_pane_get_opts(P);
    char back[64];
    if (o->back_smooth)
        snprintf(back, sizeof back, "flat");
    else
        snprintf(back, sizeof back, "rough, s = %.9g", o->back_smoothness);
    snprintf(desc, sizeof desc,
             "a pane in air (front face: model %s, n = %.9g, s = %.9g; back face %s; "
             "thickness %.9g mm, absorption %.9g per mm)",
             btdf_model_name(o->front.model), o->front.ior[0], o->front.smoothness, back,
             o->thickness_mm, o->absorption_per_mm);
    btdf_rad_source src = {(void *)P, src_eval, src_specular, src_eval_phis, desc};
    btdf_rad *x = NULL;
    char msg[512] = "";
    btdf_status st = btdf_rad_build_source(&src, &c->p, c->basis, PANE_TREE_DEPTH, c->threads,
                                           &x, msg, sizeof msg);
    if (st != BTDF_OK)
        return fail(1, "%s: %s", c->out, msg[0] ? msg : btdf_strerror(st));
    /* the material's name: the file's base name without its extension */
    const char *base = strrchr(c->out, '/');
    base = base ? base + 1 : c->out;
    const char *dot = strrchr(base, '.');
    char name[128];
    snprintf(name, sizeof name, "%.*s", (int)(dot ? (size_t)(dot - base) : strlen(base)), base);
    btdf_rad_set_name(x, name);
    btdf_write_opts w = {NULL, prov, NULL};
    btdf_output what = {NULL, NULL, NULL, &w, NULL, x};
    st = btdf_write(&what, c->out, msg, sizeof msg);
    double secs = btdf_rad_seconds_build(x);
    btdf_rad_free(x);
    if (st != BTDF_OK)
        return fail(1, "%s: %s", c->out, msg[0] ? msg : btdf_strerror(st));
    if (!c->quiet) {
        int n, m;
        btdf_pane_size(P, &n, &m);
        fprintf(stderr, "btdftab: %s: %s; system %d nodes x %d modes in %.3f s, %s in %.3f s\n",
                c->out, desc, n, m, btdf_pane_seconds_build(P), btdf_rad_basis_name(c->basis),
                secs);
    }
    return 0;
}

int cmd_pane(const cli *c, unsigned cmd, const char *prov)
{
    if (!GIVEN(c, OPT_BACK))
        return fail(EXIT_USAGE, "--%s describes a pane: give --back smooth|S as well",
                    GIVEN(c, OPT_THICKNESS) ? "thickness" : "absorption");
    if (cmd == CMD_TABULATE) {
        if (c->npos)
            return fail(EXIT_USAGE, "tabulate: unexpected argument '%s' (the output is -o FILE)",
                        c->pos[0]);
        if (!c->out || !ends_with(c->out, ".xml"))
            return fail(EXIT_USAGE, "%s: --back: a pane's system is written to .xml (Klems or "
                                    "tree3, --basis); other formats take the interface only",
                        c->out ? c->out : "no -o");
    } else if (cmd != CMD_ALBEDO) {
        return fail(EXIT_USAGE, "--back applies to tabulate and albedo");
    }
    btdf_pane *P = NULL;
    int code = make_pane(c, &P);
    if (code)
        return code;
    code = cmd == CMD_ALBEDO ? pane_albedo(c, P) : pane_xml(c, P, prov);
    btdf_pane_free(P);
    return code;
}
