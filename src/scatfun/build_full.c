/* SPDX-License-Identifier: MIT */
/* build_full.c: what a .bsdf of the model full needs beside smith's series: the
   tallies of its indices (their multiply scattered part enters every sample:
   build_sample.c), and the parameters' check that takes full as smith plus a tally. */
#include <stddef.h>

#include "btdf.h"
#include "btdf_scatfun.h"
#include "core/core.h"
#include "scatfun/scatfun.h"
#include "scatfun/build.h"

static btdf_status make(build_ctx *c, int threads, btdf_full *own[2][3], char *msg,
                        size_t msglen);

btdf_status sf_check_params(const btdf_params *p, char *msg, size_t msglen)
{
    if (!p)
        return btdf_params_check(p, msg, msglen);
    btdf_params q = *p;
    if (q.model == BTDF_MODEL_FULL) /* smith plus a tally the builder makes */
        q.model = BTDF_MODEL_SMITH;
    return btdf_params_check(&q, msg, msglen);
}

/* Model full: the tallies of the indices the blocks asked light from (n above, 1/n
   below), each channel's, with the defaults of btdf_full_opts on the build's threads,
   as a table of full makes its own (table/build.c); a channel whose index an earlier
   one has shares its tally (a copy). c->ms points every block at its index's. */
btdf_status sf_make_tallies(build_ctx *c, int threads, btdf_progress_fn progress, void *user,
                            char *msg, size_t msglen)
{
    if (c->p->model != BTDF_MODEL_FULL)
        return BTDF_OK;
    if (progress)
        progress(user, "tally (model full)", 0, 0);
    btdf_status st = make(c, threads, c->own, msg, msglen);
    if (st != BTDF_OK)
        sf_free_tallies(c->own);
    return st;
}

static btdf_status make(build_ctx *c, int threads, btdf_full *own[2][3], char *msg,
                        size_t msglen)
{
    btdf_full_opts fo;
    btdf_full_opts_default(&fo);
    fo.threads = threads;
    for (int i = 0; i < 2; i++) {
        if (!c->want[blk_of_index[i][0]] && !c->want[blk_of_index[i][1]])
            continue;
        for (int k = 0; k < c->nc; k++) {
            double n = c->ior[blk_of_index[i][0]][k];
            const btdf_full *same = NULL;
            for (int d = 0; d < k; d++)
                if (c->ior[blk_of_index[i][0]][d] == n)
                    same = own[i][d];
            if (same) {
                own[i][k] = full_clone(same);
                if (!own[i][k])
                    return core_say(BTDF_ENOMEM, msg, msglen, "out of memory (tally copy)");
            } else {
                btdf_status st = btdf_full_new(n, c->p->smoothness, &fo, &own[i][k], msg, msglen);
                if (st != BTDF_OK)
                    return st;
            }
            for (int j = 0; j < 2; j++)
                c->ms[blk_of_index[i][j]][k] = own[i][k];
        }
    }
    return BTDF_OK;
}

void sf_free_tallies(btdf_full *own[2][3])
{
    for (int i = 0; i < 2; i++)
        for (int k = 0; k < 3; k++) {
            btdf_full_free(own[i][k]);
            own[i][k] = NULL;
        }
}

