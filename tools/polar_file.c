/* SPDX-License-Identifier: MIT */
/* polar_file.c: the polar picture of a written file (.csv, .exr, .bsdf, .xml) read
   back, for `polar --table F` and `tabulate -o F.bsdf|F.xml --preview P.png`: the
   curves are the file's values, read as `eval --table` reads them. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <btdf/btdf.h>

#include "cli.h"

/* The file read back: exactly one of in's members is set. */
typedef struct file_curves {
    btdf_input in;
    const btdf_table *part[2]; /* a table's transmission [0] and reflection [1] */
    int channels;
    double fold[BTDF_MAX_CHANNELS]; /* a colour .bsdf's transmission: (n_c / n_G)^2 */
} file_curves;

/* The preview's evaluator (btdf_preview_opts.eval): the file's rho or rho_r. */
static void file_curves_eval(void *user, int reflection, double ti, double to, double phi,
                             double *out)
{
    const file_curves *f = user;
    if (f->in.table) {
        btdf_table_eval(f->part[reflection != 0], ti, to, phi, out);
    } else if (f->in.scatfun) {
        /* light entering through the top (index n), as eval --table reads a .bsdf */
        btdf_scatfun_block b = reflection ? BTDF_SCATFUN_R_TOP : BTDF_SCATFUN_T_ENTER;
        if (btdf_scatfun_eval_side(f->in.scatfun, (btdf_side)b, BTDF_SCATFUN_DIRECT, ti, to,
                                   phi, out) != BTDF_OK)
            for (int ch = 0; ch < f->channels; ch++)
                out[ch] = 0.0; /* out of the file's range: nothing drawn there */
        /* a colour file stores T_ENTER times (n_G / n_c)^2 (btdf_scatfun.h): undone */
        for (int ch = 0; ch < f->channels && !reflection; ch++)
            out[ch] *= f->fold[ch];
    } else {
        /* light entering the dense medium (index n), as Radiance reads the file */
        for (int ch = 0; ch < f->channels; ch++)
            out[ch] = btdf_rad_render(f->in.radiance, BTDF_SIDE_ENTER,
                                      f->channels == 3 ? ch : -1, ti, to, phi);
    }
}

/* The number after "key": in a .bsdf's metadata JSON; for "ior" either one number or
   an array of up to 3. The count read, 0 when the key is missing or not a number. */
static int json_numbers(const char *json, const char *key, double *v, int max)
{
    char pat[40];
    snprintf(pat, sizeof pat, "\"%s\":", key);
    const char *s = strstr(json, pat);
    if (!s)
        return 0;
    s += strlen(pat);
    while (*s == ' ')
        s++;
    int arr = *s == '[', n = 0;
    s += arr;
    while (n < max) {
        char *end;
        double x = strtod(s, &end);
        if (end == s || !isfinite(x))
            break;
        v[n++] = x;
        s = end;
        while (*s == ' ')
            s++;
        if (!arr || *s != ',')
            break;
        s++;
    }
    return n;
}

/* The fold factors (n_c / n_G)^2 of a colour .bsdf's transmission blocks, from the
   indices its metadata gives (btdf_scatfun.h: T_ENTER of channel c is stored times
   (n_G / n_c)^2); 1 for a one-channel file. 0 when a colour file's metadata gives no
   three positive indices (a file not written by btdftab): fold is then all 1. */
int scatfun_fold(const btdf_scatfun *f, double fold[BTDF_MAX_CHANNELS])
{
    const char *meta = btdf_scatfun_metadata(f);
    double ior[3];
    for (int ch = 0; ch < BTDF_MAX_CHANNELS; ch++)
        fold[ch] = 1.0;
    if (btdf_scatfun_channels(f) != 3)
        return 1;
    if (!meta || json_numbers(meta, "ior", ior, 3) != 3 || !(ior[0] > 0.0) ||
        !(ior[1] > 0.0) || !(ior[2] > 0.0))
        return 0; /* ior[1] > 0 checked: it divides below */
    for (int ch = 0; ch < 3; ch++)
        fold[ch] = (ior[ch] / ior[1]) * (ior[ch] / ior[1]);
    return 1;
}

/* The material of a .bsdf from its metadata (btdftab writes ior, smoothness and k0
   there); 0 and a message when it is not there. */
static int scatfun_params(const char *file, const btdf_scatfun *f, btdf_params *p)
{
    const char *meta = btdf_scatfun_metadata(f);
    int channels = btdf_scatfun_channels(f);
    double ior[3], s, k0;
    btdf_params_default(p);
    if (!meta || json_numbers(meta, "ior", ior, 3) < (channels == 3 ? 3 : 1) ||
        json_numbers(meta, "smoothness", &s, 1) != 1) {
        fail(1, "%s: its metadata does not give the material (\"ior\" and \"smoothness\", "
                "as btdftab writes them): a polar picture needs them for its legend", file);
        return 0;
    }
    p->channels = channels;
    for (int ch = 0; ch < channels; ch++)
        p->ior[ch] = ior[ch];
    p->smoothness = s;
    if (json_numbers(meta, "k0", &k0, 1) == 1)
        p->k0 = k0;
    if (strstr(meta, "\"model\": \"smith\""))
        p->model = BTDF_MODEL_SMITH;
    else if (strstr(meta, "\"model\": \"full\""))
        p->model = BTDF_MODEL_FULL;
    return 1;
}

/* Reads file and checks that it holds what the picture draws (part, angles); fills f
   and the material p. 0, or the exit status after the message. */
static int file_curves_open(const char *file, btdf_part part, const double *angles, size_t na,
                            file_curves *f, btdf_params *p)
{
    char msg[512];
    memset(f, 0, sizeof *f);
    btdf_status st = btdf_read(file, &f->in, msg, sizeof msg);
    if (st != BTDF_OK)
        return fail(1, "%s: %s", file, msg);
    int refl = part == BTDF_PART_REFLECTION || part == BTDF_PART_BOTH;
    int trans = part != BTDF_PART_REFLECTION;
    if (f->in.table) {
        *p = *btdf_table_get_params(f->in.table);
        f->part[0] = btdf_table_part(f->in.table, BTDF_PART_TRANSMISSION);
        f->part[1] = btdf_table_part(f->in.table, BTDF_PART_REFLECTION);
        if ((trans && !f->part[0]) || (refl && !f->part[1])) {
            int holds = (int)btdf_table_parts(f->in.table);
            return fail(1, "%s: the table holds the %s only; give --part %s", file,
                        btdf_part_name((btdf_part)holds), btdf_part_name((btdf_part)holds));
        }
        for (int h = 0; h < 2; h++) {
            double range[2] = {0.0, 90.0}; /* degrees */
            if (!f->part[h] || (h == 0 ? !trans : !refl))
                continue;
            table_ti_range(f->part[h], range);
            for (size_t k = 0; k < na; k++) /* 1e-9: as eval, the rounding of the ends */
                if (!(angles[k] >= range[0] - 1e-9 && angles[k] <= range[1] + 1e-9))
                    return fail(EXIT_USAGE, "--angles %g: outside the incidence range of %s, "
                                "%.6g:%.6g degrees", angles[k], file, range[0], range[1]);
        }
    } else if (f->in.radiance) {
        if (refl)
            return fail(1, "%s: --part %s: a polar picture of a .xml draws its transmission "
                           "(as eval reads it); give --part transmission", file,
                        btdf_part_name(part));
        *p = *btdf_rad_get_params(f->in.radiance);
    } else {
        int sides = btdf_scatfun_sides(f->in.scatfun);
        if (trans && !(sides & BTDF_SCATFUN_T_ENTER))
            return fail(1, "%s: the file holds no 'enter' side (light entering, index n), "
                           "which the picture draws; it was written with --side leave", file);
        if (refl && !(sides & BTDF_SCATFUN_R_TOP))
            return fail(1, "%s: --part %s: the file holds no reflection of light entering "
                           "(it was written with --part transmission or --side leave)", file,
                        btdf_part_name(part));
        if (!scatfun_params(file, f->in.scatfun, p))
            return 1;
    }
    f->channels = p->channels;
    for (int ch = 0; ch < BTDF_MAX_CHANNELS; ch++)
        f->fold[ch] = 1.0;
    if (f->in.scatfun)
        scatfun_fold(f->in.scatfun, f->fold); /* its indices were read just above */
    return 0;
}

static void file_curves_close(file_curves *f)
{
    btdf_table_free(f->in.table);
    btdf_scatfun_free(f->in.scatfun);
    btdf_rad_free(f->in.radiance);
}

int polar_of_file(const char *file, const char *png, btdf_part part, const double *angles,
                  size_t na, int width, int height)
{
    file_curves f;
    btdf_params p;
    int rc = file_curves_open(file, part, angles, na, &f, &p);
    if (rc) {
        file_curves_close(&f);
        return rc;
    }
    const char *base = strrchr(file, '/');
    base = base ? base + 1 : file;
    char title[320];
    snprintf(title, sizeof title, "%s read back: %s in the plane of incidence", base,
             part == BTDF_PART_REFLECTION ? "\xcf\x81r |cos \xce\xb8r|"
             : part == BTDF_PART_BOTH    ? "\xcf\x81 |cos \xce\xb8o| below, \xcf\x81r |cos "
                                           "\xce\xb8r| above"
                                         : "\xcf\x81 |cos \xce\xb8o|");
    btdf_preview_opts po;
    btdf_preview_opts_default(&po);
    po.kind = BTDF_PREVIEW_POLAR;
    po.materials = &p;
    po.nmaterials = 1;
    po.ti_deg = angles;
    po.nti = na;
    po.width = width;
    po.height = height;
    po.part = part;
    po.title = title;
    po.eval = file_curves_eval;
    po.eval_user = &f;
    char msg[512] = "";
    btdf_output what = {NULL, NULL, &po, NULL, NULL, NULL};
    btdf_status st = btdf_write(&what, png, msg, sizeof msg);
    file_curves_close(&f);
    if (st != BTDF_OK)
        return fail(st == BTDF_EINVAL ? EXIT_USAGE : 1, "%s: %s", png,
                    msg[0] ? msg : btdf_strerror(st));
    return 0;
}
