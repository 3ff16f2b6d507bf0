/* SPDX-License-Identifier: MIT */
/* build_nodes.c: the node-set state: allocation, carry-over of series to a new node set, the
   nodes set, and the file assembled from the pairs. */
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "btdf.h"
#include "btdf_scatfun.h"
#include "core/core.h"
#include "model/kernel.h"
#include "model/facet.h"
#include "estimate/estimate.h"
#include "scatfun/scatfun.h"
#include "scatfun/build.h"
#include "scatfun/spline.h"

static void free_pair_array(pair **pp, size_t count)
{
    if (!*pp)
        return;
    for (size_t i = 0; i < count; i++)
        free((*pp)[i].a);
    free(*pp);
    *pp = NULL;
}

/* Frees everything that belongs to one node set (sizes follow c->K). */
void sf_free_state(build_ctx *c)
{
    size_t KK = c->K * c->K;
    for (int s = 0; s < NBLK; s++) {
        free_pair_array(&c->pairs[s], KK);
        free_pair_array(&c->pcol[s], KK);
        free_pair_array(&c->prow[s], KK);
        free(c->errc[s]);
        free(c->errr[s]);
        free(c->gapr[s]);
        free(c->okc[s]);
        free(c->okr[s]);
        c->errc[s] = c->errr[s] = c->gapr[s] = NULL;
        c->okc[s] = c->okr[s] = NULL;
    }
    free(c->Tn);
    free(c->Tm);
    free(c->hasTn);
    free(c->hasTm);
    free(c->mid);
    c->Tn = c->Tm = NULL;
    c->hasTn = c->hasTm = NULL;
    c->mid = NULL;
}

/* Allocates what is missing for the current node set; 0 on success. */
int sf_ensure_state(build_ctx *c)
{
    size_t K = c->K, KK = K * K;
    for (int s = 0; s < NBLK; s++) {
        if (!c->pairs[s])
            c->pairs[s] = calloc(KK, sizeof(pair));
        if (!c->pcol[s])
            c->pcol[s] = calloc(KK, sizeof(pair));
        if (!c->prow[s])
            c->prow[s] = calloc(KK, sizeof(pair));
        if (!c->errc[s])
            c->errc[s] = calloc(KK, sizeof(double));
        if (!c->gapr[s])
            c->gapr[s] = calloc(KK, sizeof(double));
        if (!c->okc[s])
            c->okc[s] = calloc(KK, 1);
        if (!c->okr[s])
            c->okr[s] = calloc(KK, 1);
        free(c->errr[s]);
        c->errr[s] = calloc(K, sizeof(double));
        if (!c->pairs[s] || !c->pcol[s] || !c->prow[s] || !c->errc[s] || !c->gapr[s] ||
            !c->okc[s] || !c->okr[s] || !c->errr[s])
            return -1;
    }
    if (!c->Tn)
        c->Tn = calloc(K, sizeof *c->Tn);
    if (!c->Tm)
        c->Tm = calloc(K, sizeof *c->Tm);
    if (!c->hasTn)
        c->hasTn = calloc(K, 1);
    if (!c->hasTm)
        c->hasTm = calloc(K, 1);
    free(c->mid);
    c->mid = malloc(K * sizeof *c->mid);
    return c->Tn && c->Tm && c->hasTn && c->hasTm && c->mid ? 0 : -1;
}


/* sf_carry_over's work for one block: the block's pairs, check series and carried check
   results moved to their places in the new grid. Every loop walks its source row by
   row (the arrays are row-major: a column walk strides K records, and this runs on
   every pass). */
typedef struct carry_job {
    build_ctx *c;
    size_t KQ;
    const unsigned char *ins, *same, *sten;
    const size_t *map, *qn;
    pair *(*np)[3];
    double **ne, **ng;
    unsigned char **noc, **nor;
} carry_job;

static void carry_block(void *arg, size_t s)
{
    const carry_job *J = arg;
    build_ctx *c = J->c;
    size_t K = c->K, KQ = J->KQ;
    const size_t *map = J->map, *qn = J->qn;
    const unsigned char *ins = J->ins, *same = J->same, *sten = J->sten;
    pair *pp = c->pairs[s], *pc = c->pcol[s], *pr = c->prow[s];
    pair *n0 = J->np[s][0], *n1 = J->np[s][1], *n2 = J->np[s][2];
    for (size_t r = 0; r < K; r++) {
        pair *dst = n0 + map[r] * KQ;
        for (size_t col = 0; col < K; col++) {
            dst[map[col]] = pp[r * K + col];
            pp[r * K + col].a = NULL;
        }
    }
    /* column checks: pcol[r * K + j] is the series at (P[r], mid[j]) */
    for (size_t r = 0; r < K; r++) {
        for (size_t j = 0; j < K; j++) {
            pair *src = &pc[r * K + j];
            if (ins[j] == 1)
                n0[map[r] * KQ + qn[j]] = *src; /* (P[r], new node) */
            else if (same[j])
                n1[map[r] * KQ + map[j]] = *src;
            else
                free(src->a);
            src->a = NULL;
            if (sten[j]) {
                J->ne[s][map[r] * KQ + map[j]] = c->errc[s][r * K + j];
                J->noc[s][map[r] * KQ + map[j]] = 1;
            }
        }
    }
    /* row checks: prow[j * K + col] is the series at (mid[j], P[col]) */
    for (size_t j = 0; j < K; j++) {
        for (size_t col = 0; col < K; col++) {
            pair *src = &pr[j * K + col];
            if (ins[j] == 1)
                n0[qn[j] * KQ + map[col]] = *src; /* (new node, P[col]) */
            else if (same[j])
                n2[map[j] * KQ + map[col]] = *src;
            else
                free(src->a);
            src->a = NULL;
            if (sten[j]) {
                J->ng[s][map[j] * KQ + map[col]] = c->gapr[s][j * K + col];
                J->nor[s][map[j] * KQ + map[col]] = 1;
            }
        }
    }
}

/* Moves everything still valid to the refined node set Q (KQ nodes, a superset of
   c->P). ins[j] = 1 when old interval j got the node mid[j], whose check series
   become pairs; 2 when it got another node. Series at unchanged nodes, checks
   whose stencil is unchanged and norms are kept, so a pass only computes what the
   new nodes touch. Returns 0 on success; on failure the old state is intact. */
int sf_carry_over(build_ctx *c, const double *Q, size_t KQ, const unsigned char *ins,
                      int threads)
{
    size_t K = c->K, KK2 = KQ * KQ;
    size_t *map = malloc(K * sizeof *map), *qn = malloc(K * sizeof *qn);
    unsigned char *same = malloc(K), *sten = malloc(K);
    pair *np[NBLK][3] = {{NULL}};
    double *ne[NBLK] = {NULL}, *ng[NBLK] = {NULL};
    unsigned char *noc[NBLK] = {NULL}, *nor[NBLK] = {NULL};
    double(*tn)[NBLK][8] = calloc(KQ, sizeof *tn), (*tm)[NBLK][8] = calloc(KQ, sizeof *tm);
    unsigned char *htn = calloc(KQ, 1), *htm = calloc(KQ, 1);
    int ok = map && qn && same && sten && tn && tm && htn && htm;
    for (int s = 0; s < NBLK && ok; s++) {
        for (int k = 0; k < 3; k++)
            ok &= (np[s][k] = calloc(KK2, sizeof(pair))) != NULL;
        ok &= (ne[s] = calloc(KK2, sizeof(double))) != NULL;
        ok &= (ng[s] = calloc(KK2, sizeof(double))) != NULL;
        ok &= (noc[s] = calloc(KK2, 1)) != NULL;
        ok &= (nor[s] = calloc(KK2, 1)) != NULL;
    }
    if (!ok) {
        for (int s = 0; s < NBLK; s++) {
            for (int k = 0; k < 3; k++)
                free(np[s][k]);
            free(ne[s]);
            free(ng[s]);
            free(noc[s]);
            free(nor[s]);
        }
        free(map); free(qn); free(same); free(sten); free(tn); free(tm); free(htn); free(htm);
        return -1;
    }
    for (size_t r = 0, q = 0; r < K; r++) {
        while (Q[q] != c->P[r])
            q++; /* every old node is in the new list, in order */
        map[r] = q;
    }
    for (size_t j = 0; j < K; j++) {
        same[j] = !ins[j];
        qn[j] = ins[j] ? map[j] - 1 : (size_t)-1; /* the new node sits just before P[j] */
    }
    for (size_t j = 0; j < K; j++)
        sten[j] = same[j] && (j == 0 || same[j - 1]) && (j + 1 >= K || same[j + 1]);
    carry_job cj = {c, KQ, ins, same, sten, map, qn, np, ne, ng, noc, nor};
    core_parallel_for(threads, NBLK, carry_block, &cj); /* the blocks share nothing */
    for (size_t r = 0; r < K; r++) {
        memcpy(tn[map[r]], c->Tn[r], sizeof tn[0]);
        htn[map[r]] = c->hasTn[r];
    }
    for (size_t j = 0; j < K; j++) {
        if (ins[j] == 1) {
            memcpy(tn[qn[j]], c->Tm[j], sizeof tn[0]);
            htn[qn[j]] = c->hasTm[j];
        }
        if (same[j]) {
            memcpy(tm[map[j]], c->Tm[j], sizeof tm[0]);
            htm[map[j]] = c->hasTm[j];
        }
    }
    sf_free_state(c); /* the moved series were detached above */
    for (int s = 0; s < NBLK; s++) {
        c->pairs[s] = np[s][0];
        c->pcol[s] = np[s][1];
        c->prow[s] = np[s][2];
        c->errc[s] = ne[s];
        c->gapr[s] = ng[s];
        c->okc[s] = noc[s];
        c->okr[s] = nor[s];
    }
    c->Tn = tn;
    c->Tm = tm;
    c->hasTn = htn;
    c->hasTm = htm;
    free(map); free(qn); free(same); free(sten);
    return sf_set_nodes(c, Q, KQ); /* sets K first, so sizes stay consistent on failure */
}


int sf_set_nodes(build_ctx *c, const double *P, size_t K)
{
    c->K = K; /* first: the per-node-set arrays already have this size */
    double *np = realloc(c->P, K * sizeof *np);
    if (!np)
        return -1;
    c->P = np;
    memcpy(c->P, P, K * sizeof *P);
    double *full = realloc(c->full, (2 * K + 2) * sizeof *full);
    if (!full)
        return -1;
    c->full = full;
    for (size_t r = 0; r < K; r++) {
        full[K + 2 + r] = P[r];
        full[K - 1 - r] = -P[r];
    }
    full[K] = full[K + 1] = 0.0;
    return 0;
}


/* Fills a btdf_scatfun from the pairs of the current pass. */
btdf_status sf_assemble(build_ctx *c, btdf_scatfun **out, char *msg, size_t msglen)
{
    size_t K = c->K, n = 2 * K + 2;
    size_t total = 0, mmax = 0;
    for (int s = 0; s < NBLK; s++) {
        if (!c->want[s])
            continue;
        for (size_t i = 0; i < K * K; i++) {
            total += (size_t)c->pairs[s][i].m * (size_t)c->nst;
            if (c->pairs[s][i].m > mmax)
                mmax = c->pairs[s][i].m;
        }
    }
    if (total > UINT32_MAX)
        return core_say(BTDF_EOVERFLOW, msg, msglen, "%zu coefficients exceed the format's 32-bit count",
                   total);
    btdf_scatfun *f = sf_alloc((uint32_t)n, (uint32_t)total, (uint32_t)mmax, (uint32_t)c->nst,
                               0, 0);
    if (!f)
        return BTDF_ENOMEM;
    f->eta = (float)(c->nc == 3 ? c->p->ior[1] : c->p->ior[0]);
    /* Beckmann alpha of Eq. 25's facet distribution: RMS slope 2/s (MODEL.md 2);
       s >= BTDF_S_MIN > 0 was checked */
    f->alpha[0] = f->alpha[1] = (float)(2.0 / c->p->smoothness);
    double *v = malloc(n * sizeof(double)), *cd = malloc(n * sizeof(double));
    if (!v || !cd) {
        free(v);
        free(cd);
        btdf_scatfun_free(f);
        return BTDF_ENOMEM;
    }
    for (size_t i = 0; i < n; i++)
        f->nodes[i] = (float)c->full[i];
    if (sf_index(f)) {
        free(v);
        free(cd);
        btdf_scatfun_free(f);
        return BTDF_ENOMEM;
    }
    size_t pos = 0;
    for (size_t i = 0; i < n; i++) {
        for (size_t o = 0; o < n; o++) {
            const pair *pr = NULL;
            int ni, no;
            long hi = half_any(c, (long)i, &ni), ho = half_any(c, (long)o, &no);
            for (int s = 0; s < NBLK && !pr && hi >= 0 && ho >= 0; s++)
                if (c->want[s] && blk_slow_neg[s] == ni && blk_fast_neg[s] == no)
                    pr = &c->pairs[s][(size_t)hi * K + (size_t)ho];
            size_t m = pr ? pr->m : 0;
            f->offsets[2 * (i * n + o)] = (uint32_t)pos;
            f->offsets[2 * (i * n + o) + 1] = (uint32_t)m;
            for (size_t q = 0; q < m * (size_t)c->nst; q++)
                f->coeffs[pos + q] = (float)pr->a[q];
            pos += m * (size_t)c->nst;
        }
    }
    /* cdf rows from the stored (float) a_0 of Y, as a reader recomputes them */
    for (size_t i = 0; i < n; i++) {
        for (size_t o = 0; o < n; o++) {
            uint32_t m = f->offsets[2 * (i * n + o) + 1];
            v[o] = m ? (double)f->coeffs[f->offsets[2 * (i * n + o)]] : 0.0;
            cd[o] = (double)f->nodes[o];
        }
        double *row = malloc(n * sizeof(double));
        if (!row) {
            free(v);
            free(cd);
            btdf_scatfun_free(f);
            return BTDF_ENOMEM;
        }
        spline_cdf(cd, v, n, row);
        for (size_t o = 0; o < n; o++)
            f->cdf[i * n + o] = (float)row[o];
        free(row);
    }
    free(v);
    free(cd);
    f->built = 1;
    f->params = *c->p;
    f->sides = 0;
    for (int s = 0; s < NBLK; s++)
        f->sides |= c->want[s] ? blk_mask[s] : 0;
    /* full: copies of the tallies of the blocks' two indices, for the file's reports */
    for (int i = 0; i < 2; i++)
        for (int k = 0; k < c->nc; k++) {
            const btdf_full *src = c->ms[blk_of_index[i][0]][k] ? c->ms[blk_of_index[i][0]][k]
                                                               : c->ms[blk_of_index[i][1]][k];
            if (src && !(f->ms[i][k] = full_clone(src))) {
                btdf_scatfun_free(f);
                return BTDF_ENOMEM;
            }
        }
    *out = f;
    return BTDF_OK;
}
