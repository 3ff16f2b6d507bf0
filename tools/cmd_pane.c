/* SPDX-License-Identifier: MIT */
/* cmd_pane.c: a pane's system BSDF (--back, --thickness, --absorption): tabulate writes it
   to a Radiance/WINDOW .xml, albedo prints its T and R from either side, eval its values,
   polar its lobes (docs/pane.md). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "btdf.h"
#include "btdf_pane.h"
#include "cli.h"
#include "numparse.h"
#include "pane_write.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* The depth of a pane's tree3: 2^6 cells along each of the three axes, 262144 leaves a
   block; the system's lobes are as wide as its roughest face's (2/s rad), so at s = 3
   a cell (1/64 of the disk's side) is well inside them. */
#define PANE_TREE_DEPTH 6

void pane_spec_default(pane_spec *ps)
{
    ps->back_smooth = 1;
    ps->back_s = 0.0;
    ps->thickness = 4.0; /* simulate's default too */
    ps->absorption = 0.0;
}

/* key as the user wrote it ("--back" or "back"); the messages name it so. */
int pane_spec_set(pane_spec *ps, const char *key, const char *value, char *why, size_t len)
{
    const char *k = key;
    while (*k == '-')
        k++;
    double x = 0.0;
    if (!strcmp(k, "back") && !strcmp(value, "smooth")) {
        ps->back_smooth = 1;
        return 1;
    }
    const char *bad = num_double(value, &x);
    if (bad) {
        snprintf(why, len, "%s: '%s' %s", key, value, bad);
        return 0;
    }
    if (!strcmp(k, "back")) {
        if (!(x >= BTDF_S_MIN && x <= BTDF_S_MAX)) {
            snprintf(why, len, "%s: %g: give smooth, or a smoothness in [%g, %g]", key, x,
                     BTDF_S_MIN, BTDF_S_MAX);
            return 0;
        }
        ps->back_smooth = 0;
        ps->back_s = x;
    } else if (!strcmp(k, "thickness")) {
        if (!(x >= 0.0 && x <= BTDF_PANE_THICKNESS_MAX)) {
            snprintf(why, len, "%s: %g mm: must lie in [0, %g]", key, x, BTDF_PANE_THICKNESS_MAX);
            return 0;
        }
        ps->thickness = x;
    } else {
        if (!(x >= 0.0 && x <= BTDF_PANE_ABSORPTION_MAX)) {
            snprintf(why, len, "%s: %g per mm: must lie in [0, %g]", key, x,
                     BTDF_PANE_ABSORPTION_MAX);
            return 0;
        }
        ps->absorption = x;
    }
    return 1;
}

const char *pane_keys_refusal(int back, int thick_abs, int interface_outputs,
                              int table_keys, int channels, int bsdf_outputs, int back_smooth)
{
    if (!back)
        return thick_abs ? "thickness and absorption describe a pane: give back = smooth|S "
                           "as well"
                         : NULL;
    if (interface_outputs > 0)
        return "back: a pane's system is written to xml, grid and bsdf (enter and leave take "
               "the interface)";
    if (table_keys)
        return "back: theta_i, metric, part and sides do not apply to a pane's xml, grid or "
               "bsdf (they hold the system, both parts, light from either side), nor "
               "tolerance without a bsdf output (it sets the .bsdf's error)";
    if (bsdf_outputs > 0 && back_smooth)
        return "back = smooth with a bsdf output: a flat back reflects light falling on it as "
               "a mirror, a delta that a .bsdf's series in azimuth cannot hold; give the back "
               "a smoothness (back = S) or write xml, which holds the delta";
    if (bsdf_outputs > 0 && channels != 1)
        return "back: a pane's bsdf has one channel (give one index; a colour pane goes to a "
               "Klems xml)";
    return channels != 1 ? "back: a colour pane .xml takes the Klems bases (basis = "
                           "klems-full, klems-half or klems-quarter); its tree3 has one channel"
                         : NULL;
}

int apply_pane(cli *c, int id, const char *v)
{
    pane_spec ps = {c->back_smooth, c->back_s, c->thickness, c->absorption};
    char why[256];
    const char *key = id == OPT_BACK ? "--back" : id == OPT_THICKNESS ? "--thickness"
                                                                       : "--absorption";
    if (!pane_spec_set(&ps, key, v, why, sizeof why)) {
        fail(EXIT_USAGE, "%s", why);
        return 0;
    }
    c->back_smooth = ps.back_smooth;
    c->back_s = ps.back_s;
    c->thickness = ps.thickness;
    c->absorption = ps.absorption;
    return 1;
}

static int make_pane(const btdf_params *p, const pane_spec *ps, int threads, btdf_pane **out)
{
    btdf_pane_opts o;
    btdf_pane_opts_default(&o);
    o.front = *p;
    o.back_smooth = ps->back_smooth;
    o.back_smoothness = ps->back_smooth ? p->smoothness : ps->back_s;
    o.thickness_mm = ps->thickness;
    o.absorption_per_mm = ps->absorption;
    o.threads = threads;
    char msg[512] = "";
    btdf_status st = btdf_pane_opts_check(&o, msg, sizeof msg);
    if (st != BTDF_OK)
        return fail(EXIT_USAGE, "%s", msg);
    st = btdf_pane_new(&o, out, msg, sizeof msg);
    if (st != BTDF_OK)
        return fail(1, "%s", msg[0] ? msg : btdf_strerror(st));
    return 0;
}

int pane_make(const btdf_params *p, const pane_spec *ps, int threads, btdf_pane **out)
{
    return make_pane(p, ps, threads, out);
}

/* The options of c as a pane_spec (--thickness defaults to 4 mm). */
static pane_spec cli_spec(const cli *c)
{
    pane_spec ps;
    pane_spec_default(&ps);
    ps.back_smooth = c->back_smooth;
    ps.back_s = c->back_s;
    if (GIVEN(c, OPT_THICKNESS))
        ps.thickness = c->thickness;
    ps.absorption = c->absorption;
    return ps;
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
    /* the system's T and R hold to about 1e-3 (docs/pane.md): 6 digits unless --digits
       asks for more (17: the doubles themselves) */
    int d = GIVEN(c, OPT_DIGITS) ? c->digits : 6;
    for (int k = 0; k < na; k++) {
        printf("%s", num(angles[k]));
        for (int ch = 0; ch < nch; ch++)
            for (int sd = BTDF_PANE_FRONT; sd <= BTDF_PANE_BACK; sd++) {
                double T, R;
                btdf_pane_albedo(P, (btdf_pane_side)sd, ch, angles[k] * M_PI / 180.0, &T, &R);
                printf(",%.*g,%.*g,%.*g", d, T, d, R, d, T + R);
            }
        printf("\n");
    }
    return stdout_done(0);
}

static int eval_row(const btdf_pane *P, btdf_pane_side sd, btdf_part part, int nch,
                    const double a[3])
{
    int refl = part == BTDF_PART_REFLECTION;
    if (!(a[0] >= 0.0 && a[0] <= 90.0) || !(refl ? a[1] >= 0.0 && a[1] <= 90.0
                                                  : a[1] >= 90.0 && a[1] <= 180.0) ||
        !(a[2] >= -360.0 && a[2] <= 360.0))
        return fail(EXIT_USAGE, "eval: %g %g %g: need TI in [0, 90], %s and PHI in [-360, "
                                "360] degrees", a[0], a[1], a[2],
                    refl ? "TR in [0, 90]" : "TO in [90, 180]");
    for (int ch = 0; ch < nch; ch++)
        printf("%s%s", ch ? " " : "", num(btdf_pane_eval(P, sd, part, ch, a[0] * M_PI / 180.0,
                                                         a[1] * M_PI / 180.0,
                                                         a[2] * M_PI / 180.0)));
    printf("\n");
    return 0;
}

/* --light: 0 and the face the light falls on (front by default), or the exit status
   after the message. */
static int lit_side(const cli *c, btdf_pane_side *sd)
{
    if (c->light && strcmp(c->light, "front") && strcmp(c->light, "back"))
        return fail(EXIT_USAGE, "--light: '%s': front or back (the face the light falls on)",
                    c->light);
    *sd = c->light && !strcmp(c->light, "back") ? BTDF_PANE_BACK : BTDF_PANE_FRONT;
    return 0;
}

/* eval --back: the spread part of the system's BSDF (1/sr, no cosine), rows TI TO PHI
   (or TI TR PHI with --part reflection) from the arguments or stdin. */
static int pane_eval(const cli *c, const btdf_pane *P)
{
    btdf_pane_side sd = BTDF_PANE_FRONT;
    int lc = lit_side(c, &sd);
    if (lc)
        return lc;
    if (c->part == BTDF_PART_BOTH)
        return fail(EXIT_USAGE, "--part both: eval reads one part at a time");
    btdf_part part = c->reflection ? BTDF_PART_REFLECTION : BTDF_PART_TRANSMISSION;
    double a[3];
    if (c->npos != 0 && c->npos != 3)
        return fail(EXIT_USAGE, "eval: give exactly three angles TI TO PHI, or none to read rows");
    if (c->npos == 3) {
        for (int k = 0; k < 3; k++)
            if (!parse_double("angle", c->pos[k], &a[k]))
                return EXIT_USAGE;
        int code = eval_row(P, sd, part, c->p.channels, a);
        return code ? code : stdout_done(0);
    }
    char line[1024];
    while (fgets(line, sizeof line, stdin)) {
        char *t[4] = {NULL}, *save = NULL;
        int n = 0;
        for (char *w = strtok_r(line, " \t,\r\n", &save); w && n < 4;
             w = strtok_r(NULL, " \t,\r\n", &save))
            t[n++] = w;
        if (n == 0 || t[0][0] == '#')
            continue;
        if (n != 3)
            return fail(EXIT_USAGE, "eval: a row needs three angles TI TO PHI");
        for (int k = 0; k < 3; k++)
            if (!parse_double("angle", t[k], &a[k]))
                return EXIT_USAGE;
        int code = eval_row(P, sd, part, c->p.channels, a);
        if (code)
            return code;
    }
    return stdout_done(0);
}

/* polar --back: the system's lobes in the plane of incidence, light on the face --light
   names; the preview draws them (btdf_preview_opts.pane: the guides of a pane in air). */
typedef struct pane_curves {
    const btdf_pane *P;
    btdf_pane_side side;
    int channels;
} pane_curves;

static void pane_curves_eval(void *user, int reflection, double ti, double to, double phi,
                             double *out)
{
    const pane_curves *pc = user;
    for (int ch = 0; ch < pc->channels; ch++)
        out[ch] = btdf_pane_eval(pc->P, pc->side,
                                 reflection ? BTDF_PART_REFLECTION : BTDF_PART_TRANSMISSION, ch,
                                 ti, to, phi);
}

/* The checks of polar --back, before the system is built: 0 or the exit status. */
static int pane_polar_checks(const cli *c)
{
    if (c->npos)
        return fail(EXIT_USAGE, "polar: unexpected argument '%s' (the picture is -o FILE.png)",
                    c->pos[0]);
    if (!c->out || !ends_with(c->out, ".png"))
        return fail(EXIT_USAGE, "polar: give -o FILE.png");
    if (c->table || c->nm)
        return fail(EXIT_USAGE, "--back: the polar picture of a pane takes its faces from "
                                "--ior and --smoothness, not --%s", c->table ? "table" : "material");
    btdf_pane_side sd;
    int lc = lit_side(c, &sd);
    if (lc)
        return lc;
    if ((size_t)c->p.channels * (c->na ? c->na : 1) > BTDF_PREVIEW_MAX_CURVES)
        return fail(EXIT_USAGE, "polar: %d channels x %zu angles: at most %d curves",
                    c->p.channels, c->na, BTDF_PREVIEW_MAX_CURVES);
    return folder_writable(c->out) ? 0 : 1;
}

static int pane_polar(const cli *c, const btdf_pane *P)
{
    double angles[BTDF_PREVIEW_MAX_CURVES];
    size_t na = c->na;
    memcpy(angles, c->angles, sizeof angles);
    if (na == 0)
        angles[na++] = 30.0; /* polar's default */
    pane_curves pc = {P, BTDF_PANE_FRONT, c->p.channels};
    lit_side(c, &pc.side); /* checked in pane_polar_checks */
    const btdf_pane_opts *o = btdf_pane_get_opts(P);
    char back[64], title[600];
    if (o->back_smooth)
        snprintf(back, sizeof back, "flat");
    else
        snprintf(back, sizeof back, "rough, s = %.4g", o->back_smoothness);
    int refl = c->part == BTDF_PART_REFLECTION || c->part == BTDF_PART_BOTH;
    int n = snprintf(title, sizeof title,
                     "A pane in air (front face: model %s, n = %.4g, s = %.4g; back face %s; "
                     "%.4g mm, absorption %.4g per mm), light on its %s face: %s in the "
                     "plane of incidence", btdf_model_name(o->front.model), o->front.ior[0],
                     o->front.smoothness, back, o->thickness_mm, o->absorption_per_mm,
                     pc.side == BTDF_PANE_BACK ? "back" : "front",
                     !refl ? "\xcf\x81 |cos \xce\xb8o|"
                     : c->part == BTDF_PART_REFLECTION ? "\xcf\x81r |cos \xce\xb8r|"
                     : "\xcf\x81 |cos \xce\xb8o| below, \xcf\x81r |cos \xce\xb8r| above");
    /* a flat face's delta parts are not curves: their weights are said (channel 0) */
    for (size_t k = 0; k < na; k++)
        for (int h = 0; h < 2; h++) {
            if (h == 0 ? c->part == BTDF_PART_REFLECTION : !refl)
                continue;
            double w = btdf_pane_specular(P, pc.side, h ? BTDF_PART_REFLECTION
                                                        : BTDF_PART_TRANSMISSION,
                                          0, angles[k] * M_PI / 180.0);
            if (w > 0.0 && n >= 0 && (size_t)n < sizeof title)
                n += snprintf(title + n, sizeof title - (size_t)n, "; not drawn: a delta %s "
                              "of weight %.3g at \xce\xb8i = %.4g\xc2\xb0",
                              h ? "in the mirror direction" : "straight through", w, angles[k]);
        }
    btdf_preview_opts po;
    btdf_preview_opts_default(&po);
    po.kind = BTDF_PREVIEW_POLAR;
    po.materials = &c->p;
    po.nmaterials = 1;
    po.ti_deg = angles;
    po.nti = na;
    po.width = c->pic_w;
    po.height = c->pic_h;
    po.part = c->part;
    po.title = title;
    po.eval = pane_curves_eval;
    po.eval_user = &pc;
    po.pane = 1;
    char msg[512] = "";
    btdf_output what = {NULL, NULL, &po, NULL, NULL, NULL};
    btdf_status st = btdf_write(&what, c->out, msg, sizeof msg);
    if (st != BTDF_OK)
        return fail(st == BTDF_EINVAL ? EXIT_USAGE : 1, "%s: %s", c->out,
                    msg[0] ? msg : btdf_strerror(st));
    return 0;
}

/* Radiance's blocks (btdf_radiance.h): 0 light from +Z through the back face, 1 from -Z
   through the front, 2 reflected on -Z (front), 3 on +Z (back). */
static btdf_pane_side block_side(int k) { return k == 1 || k == 2 ? BTDF_PANE_FRONT : BTDF_PANE_BACK; }

/* The user of the source's calls: the pane and the channel asked. */
typedef struct pane_ch {
    const btdf_pane *P;
    int ch;
} pane_ch;

static double src_eval(void *user, int k, double ti, double to, double phi)
{
    const pane_ch *u = user;
    if (k >= 2)
        return btdf_pane_eval(u->P, block_side(k), BTDF_PART_REFLECTION, u->ch, ti, to, phi);
    return btdf_pane_eval(u->P, block_side(k), BTDF_PART_TRANSMISSION, u->ch, ti, M_PI - to,
                          phi);
}

static void src_eval_phis(void *user, int k, double ti, double to, size_t count,
                          const double *phi, double *out)
{
    const pane_ch *u = user;
    if (k >= 2)
        btdf_pane_eval_phis(u->P, block_side(k), BTDF_PART_REFLECTION, u->ch, ti, to, count,
                            phi, out);
    else
        btdf_pane_eval_phis(u->P, block_side(k), BTDF_PART_TRANSMISSION, u->ch, ti, M_PI - to,
                            count, phi, out);
}

static double src_specular(void *user, int k, double ti)
{
    const pane_ch *u = user;
    return btdf_pane_specular(u->P, block_side(k),
                              k >= 2 ? BTDF_PART_REFLECTION : BTDF_PART_TRANSMISSION, u->ch, ti);
}

/* What applies to an interface's table does not apply to a pane's .xml (the system,
   both parts, light from either side) nor to its grid (.csv, .exr), where --grid sets
   the nodes in place of --basis. */
static int pane_out_checks(const cli *c, int grid)
{
    static const opt_id no[] = {OPT_THETA_I, OPT_PREVIEW, OPT_THETA_O, OPT_PHI, OPT_METRIC,
                                OPT_MAX_SAMPLES, OPT_MAX_MEMORY, OPT_SIZE, OPT_SIDE, OPT_PART,
                                OPT_TOLERANCE, OPT_REPORT, OPT_GRID};
    size_t count = sizeof no / sizeof no[0] - (grid ? 1 : 0); /* a grid takes --grid */
    for (size_t k = 0; k < count; k++) {
        if (!GIVEN(c, no[k]) || (no[k] == OPT_TOLERANCE && !grid && c->basis == BTDF_RAD_TREE3))
            continue;
        if (no[k] == OPT_TOLERANCE && !grid)
            return fail(EXIT_USAGE, "%s: --tolerance: a pane's Klems .xml holds exact patch "
                                    "averages; --tolerance merges the leaves of a tree3",
                        c->out);
        return fail(EXIT_USAGE, grid ? "%s: --%s does not apply to a pane's grid (every "
                                       "block, light from either side; --grid sets its "
                                       "nodes)"
                                     : "%s: --%s does not apply to a pane's .xml (it "
                                       "holds the system, both parts, light from either "
                                       "side)",
                    c->out, opt_find(no[k])->name);
    }
    /* a tree3 takes --tolerance: its leaves merge within it (btdf_rad_source.merge) */
    if (!grid && GIVEN(c, OPT_TOLERANCE) && !(c->o.tolerance > 0.0 && c->o.tolerance <= 0.5))
        return fail(EXIT_USAGE, "%s: --tolerance %g: a pane's tree3 merges its leaves within "
                                "a tolerance in (0, 0.5]", c->out, c->o.tolerance);
    if (grid && GIVEN(c, OPT_BASIS))
        return fail(EXIT_USAGE, "%s: --basis does not apply to a pane's grid (--grid sets "
                                "its nodes)",
                    c->out);
    if (!grid && c->p.channels != 1 && c->basis == BTDF_RAD_TREE3)
        return fail(EXIT_USAGE, "%s: --ior %s: a colour pane .xml takes the Klems bases "
                                "(--basis klems-full|klems-half|klems-quarter); its tree3 "
                                "has one channel", c->out, "with three indices");
    if (grid && ends_with(c->out, ".exr") && !btdf_format_available("exr"))
        return fail(EXIT_USAGE, "%s: this btdftab was built without OpenEXR: write .csv",
                    c->out);
    return folder_writable(c->out) ? 0 : 1;
}

static int write_system(const btdf_pane *P, const char *path, const btdf_params *p,
                        btdf_rad_basis basis, double merge, int threads, int quiet,
                        const char *prov)
{
    char desc[400];
    const btdf_pane_opts *o = btdf_pane_get_opts(P);
    char back[64];
    if (o->back_smooth)
        snprintf(back, sizeof back, "flat");
    else
        snprintf(back, sizeof back, "rough, s = %.9g", o->back_smoothness);
    char ns[96];
    if (p->channels == 3)
        snprintf(ns, sizeof ns, "n = %.9g (R), %.9g (G), %.9g (B)", o->front.ior[0],
                 o->front.ior[1], o->front.ior[2]);
    else
        snprintf(ns, sizeof ns, "n = %.9g", o->front.ior[0]);
    snprintf(desc, sizeof desc,
             "a pane in air (front face: model %s, %s, s = %.9g; back face %s; "
             "thickness %.9g mm, absorption %.9g per mm)",
             btdf_model_name(o->front.model), ns, o->front.smoothness, back,
             o->thickness_mm, o->absorption_per_mm);
    pane_ch u[3] = {{P, 0}, {P, 1}, {P, 2}};
    btdf_rad_source src = {&u[0], src_eval, src_specular, src_eval_phis, desc,
                           {&u[0], &u[1], &u[2]}, 0.0};
    if (p->channels != 3)
        src.user_ch[0] = src.user_ch[1] = src.user_ch[2] = NULL;
    src.merge = basis == BTDF_RAD_TREE3 ? merge : 0.0;
    btdf_rad *x = NULL;
    char msg[512] = "";
    btdf_status st = btdf_rad_build_source(&src, p, basis, PANE_TREE_DEPTH, threads,
                                           &x, msg, sizeof msg);
    if (st != BTDF_OK)
        return fail(1, "%s: %s", path, msg[0] ? msg : btdf_strerror(st));
    /* the material's name: the file's base name without its extension */
    const char *base = strrchr(path, '/');
    base = base ? base + 1 : path;
    const char *dot = strrchr(base, '.');
    char name[128];
    snprintf(name, sizeof name, "%.*s", (int)(dot ? (size_t)(dot - base) : strlen(base)), base);
    btdf_rad_set_name(x, name);
    btdf_write_opts w = {NULL, prov, NULL};
    btdf_output what = {NULL, NULL, NULL, &w, NULL, x};
    st = btdf_write(&what, path, msg, sizeof msg);
    double secs = btdf_rad_seconds_build(x);
    btdf_rad_block_info bi;
    size_t leaves_left = btdf_rad_block(x, 1, &bi) == BTDF_OK ? bi.values : 0;
    btdf_rad_free(x);
    if (st != BTDF_OK)
        return fail(1, "%s: %s", path, msg[0] ? msg : btdf_strerror(st));
    if (!quiet) {
        int n, m;
        btdf_pane_size(P, &n, &m);
        fprintf(stderr, "btdftab: %s: %s; system %d nodes x %d modes in %.3f s, %s in %.3f s",
                path, desc, n, m, btdf_pane_seconds_build(P), btdf_rad_basis_name(basis),
                secs);
        if (src.merge > 0.0)
            fprintf(stderr, ", leaves merged within %g: %zu of %zu left (transmission from "
                            "the front)", src.merge, leaves_left, (size_t)1 << (3 * PANE_TREE_DEPTH));
        fputc('\n', stderr);
    }
    return 0;
}

int pane_write_xml(const char *path, const btdf_params *p, const pane_spec *ps,
                   btdf_rad_basis basis, double merge, int threads, int quiet, const char *prov)
{
    if (p->channels != 1 && basis == BTDF_RAD_TREE3)
        return fail(EXIT_USAGE, "%s: a colour pane .xml takes the Klems bases (basis "
                                "klems-full, klems-half or klems-quarter); its tree3 has one "
                                "channel", path);
    btdf_pane *P = NULL;
    int code = make_pane(p, ps, threads, &P);
    if (!code)
        code = write_system(P, path, p, basis, merge, threads, quiet, prov);
    btdf_pane_free(P);
    return code;
}

/* tabulate --back ... -o F.bsdf: the checks, then the file (tools/pane_bsdf.c). */
static int pane_bsdf(const cli *c, const char *prov)
{
    static const opt_id no[] = {OPT_THETA_I, OPT_PREVIEW, OPT_THETA_O, OPT_PHI, OPT_METRIC,
                                OPT_MAX_SAMPLES, OPT_MAX_MEMORY, OPT_SIZE, OPT_SIDE, OPT_PART,
                                OPT_REPORT, OPT_GRID, OPT_BASIS};
    for (size_t k = 0; k < sizeof no / sizeof no[0]; k++)
        if (GIVEN(c, no[k]))
            return fail(EXIT_USAGE, "%s: --%s does not apply to a pane's .bsdf (it holds the "
                                    "system, both parts, light from either side; --tolerance "
                                    "sets its error)",
                        c->out, opt_find(no[k])->name);
    if (c->p.channels != 1)
        return fail(EXIT_USAGE, "%s: --ior %s: a pane's .bsdf has one channel (give one "
                                "index; a colour pane goes to a Klems .xml)",
                    c->out, "with three indices");
    pane_spec ps = cli_spec(c);
    if (ps.back_smooth)
        return fail(EXIT_USAGE, "%s: --back smooth: a flat back reflects light falling on it "
                                "as a mirror, a delta that a .bsdf's series in azimuth "
                                "cannot hold (the file would render without it); give the "
                                "back a smoothness (--back S) or write .xml, which holds the "
                                "delta", c->out);
    if (!folder_writable(c->out))
        return 1;
    double tol = GIVEN(c, OPT_TOLERANCE) ? c->o.tolerance : 1e-2;
    if (!(tol >= 1e-6 && tol <= 0.5)) /* btdf_scatfun_build_source's range, before any work */
        return fail(EXIT_USAGE, "%s: --tolerance %g: a pane's .bsdf takes 1e-6 to 0.5", c->out,
                    tol);
    btdf_pane *P = NULL;
    int code = make_pane(&c->p, &ps, c->threads, &P);
    if (!code)
        code = pane_write_bsdf(c->out, P, tol, c->threads, c->quiet, prov);
    btdf_pane_free(P);
    return code;
}

int cmd_pane(const cli *c, unsigned cmd, const char *prov)
{
    if (!GIVEN(c, OPT_BACK))
        return fail(EXIT_USAGE, "--%s describes a pane: give --back smooth|S as well",
                    GIVEN(c, OPT_THICKNESS)   ? "thickness"
                    : GIVEN(c, OPT_ABSORPTION) ? "absorption"
                                               : "light");
    if (cmd == CMD_TABULATE) {
        if (c->npos)
            return fail(EXIT_USAGE, "tabulate: unexpected argument '%s' (the output is -o FILE)",
                        c->pos[0]);
        if (!c->out || !(ends_with(c->out, ".xml") || ends_with(c->out, ".csv") ||
                         ends_with(c->out, ".exr") || ends_with(c->out, ".bsdf")))
            return fail(EXIT_USAGE, "%s: --back: a pane's system is written to .xml (Klems or "
                                    "tree3, --basis), .csv or .exr (a grid, --grid) or .bsdf",
                        c->out ? c->out : "no -o");
        if (ends_with(c->out, ".bsdf"))
            return pane_bsdf(c, prov);
        if (!ends_with(c->out, ".xml")) {
            int code = pane_out_checks(c, 1);
            if (code)
                return code;
            pane_spec ps = cli_spec(c);
            btdf_pane *P = NULL;
            code = make_pane(&c->p, &ps, c->threads, &P);
            size_t nti = 46, nto = 46, nphi = 37; /* 2, 2 and 5 degrees */
            if (GIVEN(c, OPT_GRID)) {
                nti = c->o.grid_ti;
                nto = c->o.grid_to;
                nphi = c->o.grid_phi;
            }
            if (!code)
                code = pane_write_table(c->out, P, nti, nto, nphi, c->quiet, prov);
            btdf_pane_free(P);
            return code;
        }
    } else if (cmd == CMD_POLAR) {
        int code = pane_polar_checks(c);
        if (code)
            return code;
    } else if (cmd != CMD_ALBEDO && cmd != CMD_EVAL) {
        return fail(EXIT_USAGE, "--back applies to tabulate, albedo, eval and polar");
    } else if (cmd == CMD_EVAL && c->table) {
        return fail(EXIT_USAGE, "--back: eval of a pane takes its faces from --ior and "
                                "--smoothness, not --table");
    }
    pane_spec ps = cli_spec(c);
    if (cmd == CMD_TABULATE) {
        int code = pane_out_checks(c, 0);
        return code ? code
                    : pane_write_xml(c->out, &c->p, &ps, c->basis,
                                     GIVEN(c, OPT_TOLERANCE) ? c->o.tolerance : 0.0, c->threads,
                                     c->quiet, prov);
    }
    btdf_pane *P = NULL;
    int code = make_pane(&c->p, &ps, c->threads, &P);
    if (!code)
        code = cmd == CMD_ALBEDO ? pane_albedo(c, P)
               : cmd == CMD_POLAR ? pane_polar(c, P)
                                  : pane_eval(c, P);
    btdf_pane_free(P);
    return code;
}
