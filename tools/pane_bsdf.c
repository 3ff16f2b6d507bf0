/* SPDX-License-Identifier: MIT */
/* pane_bsdf.c: a pane's system BSDF as a SCATFUN v1 file (.bsdf) for pbrt-v3's "fourier"
   material and Mitsuba 0.5's "tabulated": its series handed to the library's builder
   (btdf_scatfun_build_source) block by block, with the file's error against the system
   (docs/pane.md, "A .bsdf of a pane"). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "btdf.h"
#include "btdf_io.h"
#include "btdf_pane.h"
#include "btdf_scatfun.h"
#include "cli.h"
#include "pane_write.h"
#include "run.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* SCATFUN's blocks are the pane's with the front face up (+z, the shading normal):
   T_ENTER light on the front, transmitted; T_LEAVE light on the back; R_TOP the front's
   reflection; R_BOTTOM the back's. Each in the frame of the lit face (btdf_pane.h),
   which is the block's own (btdf_scatfun.h). */
static void pane_modes_at(void *user, int block, double mu_l, double mu_v, double *c)
{
    const btdf_pane *P = user;
    btdf_pane_side side = block == BTDF_SCATFUN_T_ENTER || block == BTDF_SCATFUN_R_TOP
                              ? BTDF_PANE_FRONT
                              : BTDF_PANE_BACK;
    btdf_part part = block == BTDF_SCATFUN_T_ENTER || block == BTDF_SCATFUN_T_LEAVE
                         ? BTDF_PART_TRANSMISSION
                         : BTDF_PART_REFLECTION;
    btdf_pane_modes(P, side, part, 0, mu_l, mu_v, c);
}

static const char *block_name(int b)
{
    return b == BTDF_SCATFUN_T_ENTER   ? "front transmission"
           : b == BTDF_SCATFUN_T_LEAVE ? "back transmission"
           : b == BTDF_SCATFUN_R_TOP   ? "front reflection"
                                       : "back reflection";
}

/* The file's metadata: what the pane is, the tolerance and the error reached, the
   command. The keys of the front face are front_*, not an interface's ior and
   smoothness, so no reader takes the file for one face's. */
static char *pane_meta(const btdf_pane *P, double tol, const btdf_scatfun_source_error *e,
                       const char *prov)
{
    const btdf_pane_opts *o = btdf_pane_get_opts(P);
    char nb[7][40];
    btdf_format_double(o->front.ior[0], nb[0], sizeof nb[0]);
    btdf_format_double(o->front.smoothness, nb[1], sizeof nb[1]);
    btdf_format_double(o->back_smoothness, nb[2], sizeof nb[2]);
    btdf_format_double(o->thickness_mm, nb[3], sizeof nb[3]);
    btdf_format_double(o->absorption_per_mm, nb[4], sizeof nb[4]);
    btdf_format_double(tol, nb[5], sizeof nb[5]);
    snprintf(nb[6], sizeof nb[6], "%.3g", e->e_l1);
    size_t lp = prov ? strlen(prov) : 0, len = 1024 + 6 * lp;
    char *m = malloc(len);
    if (!m)
        return NULL;
    int k = snprintf(m, len,
                     "{\"program\": \"btdftab %s\", \"system\": \"pane\", \"front_ior\": %s, "
                     "\"front_smoothness\": %s, \"model\": \"%s\", \"back\": %s%s%s, "
                     "\"thickness_mm\": %s, \"absorption_per_mm\": %s, \"tolerance\": %s, "
                     "\"e_l1\": %s, \"command\": \"",
                     btdf_version_string(), nb[0], nb[1], btdf_model_name(o->front.model),
                     o->back_smooth ? "\"" : "", o->back_smooth ? "flat" : nb[2],
                     o->back_smooth ? "\"" : "", nb[3], nb[4], nb[5], nb[6]);
    if (k < 0 || (size_t)k >= len - 6 * lp - 4) {
        free(m);
        return NULL;
    }
    size_t q = (size_t)k + run_json_escape(prov ? prov : "", m + k);
    memcpy(m + q, "\"}", 3);
    return m;
}

int pane_write_bsdf(const char *path, const btdf_pane *P, double tol, int threads, int quiet,
                    const char *prov)
{
    const double *mu, *coef;
    int nodes, modes;
    if (btdf_pane_get_series(P, BTDF_PANE_FRONT, BTDF_PART_TRANSMISSION, 0, &mu, &coef, &nodes,
                             &modes) != BTDF_OK)
        return fail(1, "%s: the pane has no series", path);
    const btdf_pane_opts *o = btdf_pane_get_opts(P);
    btdf_scatfun_source src = {(void *)P, BTDF_SCATFUN_ALL, modes, pane_modes_at, mu,
                               (size_t)nodes, 1.0, 0.0};
    /* air on both sides: eta 1, so pbrt-v3's radiance-mode factor e^2 is 1; alpha, which
       pbrt-v3 does not read, is the front's RMS slope 2/s (MODEL.md 2; s > 0 checked) */
    src.alpha = 2.0 / o->front.smoothness;
    btdf_scatfun *f = NULL;
    btdf_scatfun_source_error e;
    char msg[512] = "";
    btdf_status st = btdf_scatfun_build_source(&src, tol, threads, &f, &e, msg, sizeof msg);
    if (st == BTDF_EBUDGET) {
        btdf_scatfun_free(f);
        return fail(3, "%s: %s; no file written", path, msg);
    }
    if (st != BTDF_OK)
        return fail(1, "%s: %s", path, msg[0] ? msg : btdf_strerror(st));
    char *meta = pane_meta(P, tol, &e, prov);
    if (!meta) {
        btdf_scatfun_free(f);
        return fail(1, "%s: out of memory", path);
    }
    btdf_output what = {NULL, f, NULL, NULL, meta, NULL};
    st = btdf_write(&what, path, msg, sizeof msg);
    if (st == BTDF_OK && !quiet)
        fprintf(stderr,
                "btdftab: %s: pane system %d nodes x %d modes in %.3f s; .bsdf %zu half nodes, "
                "%zu coefficients, %zu bytes in %.3f s; against the system e_L1 %.3g (%s, "
                "ti %.1f deg), e_T %.3g, tolerance %.3g\n",
                path, nodes, modes, btdf_pane_seconds_build(P), e.half_nodes,
                btdf_scatfun_coeff_count(f), btdf_scatfun_file_size(f, meta),
                e.seconds, e.e_l1, block_name(e.block),
                e.e_l1_ti * 180.0 / M_PI, e.e_t, tol);
    free(meta);
    btdf_scatfun_free(f);
    if (st != BTDF_OK)
        return fail(1, "%s: %s", path, msg[0] ? msg : btdf_strerror(st));
    return 0;
}
