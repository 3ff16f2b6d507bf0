/* SPDX-License-Identifier: MIT */
/* full.c: what a Radiance file of the model full needs beside smith's: its tallies (at
   n and 1/n per channel), their look-up by index, and the model's value a block serves
   (docs/model.md, "Radiance files of full"). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "radiance/radiance_impl.h"

btdf_full *rad_ms(const btdf_rad *r, int c, double n)
{
    if (!r || r->p.model != BTDF_MODEL_FULL || c < 0 || c >= BTDF_MAX_CHANNELS)
        return NULL;
    for (int h = 0; h < 2; h++) /* the blocks' indices are ior[c] and 1.0 / ior[c] */
        if (r->ms[c][h] && r->ms[c][h]->n == n)
            return r->ms[c][h];
    return NULL;
}

BTDF_API double btdf_rad_model_rho(const btdf_rad *r, int k, int c, double ti, double to,
                                   double phi)
{
    if (!r || k < 0 || k >= r->nblocks || c < 0 || c >= (r->channels == 3 ? 3 : 1))
        return 0.0;
    double nl = rad_n_light(r, k, c);
    const btdf_full *ms = rad_ms(r, c, nl);
    if (r->p.model == BTDF_MODEL_FULL && !ms)
        return 0.0; /* a file read back: the tally is not kept */
    if (r->b[k].reflect)
        return ms ? btdf_full_rho_r(ms, ti, to, phi)
                  : btdf_rho_r_model(r->p.model, nl, r->p.smoothness, r->p.k0, ti, to, phi);
    return ms ? btdf_full_rho(ms, ti, to, phi)
              : btdf_rho_model(r->p.model, nl, r->p.smoothness, r->p.k0, ti, to, phi);
}

btdf_params rad_single(const btdf_params *p)
{
    btdf_params q = *p;
    if (q.model == BTDF_MODEL_FULL)
        q.model = BTDF_MODEL_SMITH;
    return q;
}

int rad_block_ms(const btdf_rad *r, int k, btdf_full *ms[3], btdf_full *ms_light[3])
{
    for (int c = 0; c < 3; c++) {
        ms[c] = ms_light[c] = NULL;
        if (c >= r->channels || r->p.model != BTDF_MODEL_FULL)
            continue;
        rad_block bc;
        rad_block_of(k, r->p.ior[c], &bc);
        ms[c] = rad_ms(r, c, bc.n);
        ms_light[c] = rad_ms(r, c, bc.n_light);
    }
    return r->p.model == BTDF_MODEL_FULL;
}

/* Model full: each channel's tally at its index and at the inverse (the blocks serve
   light from both sides), with the defaults of btdf_full_opts on the build's threads,
   as a table of full makes its own (table/build.c). A channel whose index an earlier
   one has shares its tallies' copies. */
btdf_status rad_make_ms(btdf_rad *r, int threads, btdf_progress_fn progress,
                               void *user, char *msg, size_t msglen)
{
    if (r->p.model != BTDF_MODEL_FULL)
        return BTDF_OK;
    btdf_full_opts fo;
    btdf_full_opts_default(&fo);
    fo.threads = threads;
    for (int c = 0; c < r->channels; c++) {
        int same = -1;
        for (int d = 0; d < c; d++)
            if (r->p.ior[d] == r->p.ior[c])
                same = d;
        for (int h = 0; h < 2; h++) {
            if (same >= 0) {
                r->ms[c][h] = full_clone(r->ms[same][h]);
                if (!r->ms[c][h])
                    return core_say(BTDF_ENOMEM, msg, msglen, "out of memory");
                continue;
            }
            if (progress)
                progress(user, "multiple scattering tally", (size_t)(2 * c + h),
                         (size_t)(2 * r->channels - 2 * c - h));
            double n = h ? 1.0 / r->p.ior[c] : r->p.ior[c]; /* as rad_block_of forms it */
            btdf_status st = btdf_full_new(n, r->p.smoothness, &fo, &r->ms[c][h], msg, msglen);
            if (st != BTDF_OK)
                return st;
        }
    }
    return BTDF_OK;
}
