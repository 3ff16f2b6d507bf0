/* SPDX-License-Identifier: MIT */
/* object.c: the in-memory SCATFUN file: allocation, the node index, the getters and the
   blocks present. The builder (build*.c) and the reader (formats/bsdf.c) fill it. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>

#include "btdf.h"
#include "btdf_scatfun.h"
#include "scatfun/scatfun.h"

btdf_scatfun *sf_alloc(uint32_t n, uint32_t ncoeffs, uint32_t mmax, uint32_t channels,
                       int with_meta, size_t metalen)
{
    btdf_scatfun *f = calloc(1, sizeof *f);
    if (!f)
        return NULL;
    f->memo = albedo_memo_new(); /* NULL is fine: the reports then compute every T */
    size_t nn = (size_t)n * n;
    f->n = n;
    f->ncoeffs = ncoeffs;
    f->mmax = mmax;
    f->channels = channels;
    f->nodes = malloc(n * sizeof(float));
    f->cdf = malloc(nn * sizeof(float));
    f->offsets = malloc(2 * nn * sizeof(uint32_t));
    f->coeffs = malloc((ncoeffs ? ncoeffs : 1) * sizeof(float));
    if (with_meta) {
        f->metalen = metalen;
        f->meta = malloc(metalen + 1);
    }
    if (!f->nodes || !f->cdf || !f->offsets || !f->coeffs || (with_meta && !f->meta)) {
        btdf_scatfun_free(f);
        return NULL;
    }
    return f;
}

int sf_index(btdf_scatfun *f)
{
    f->xd = malloc(f->n * sizeof *f->xd);
    if (!f->xd)
        return -1;
    for (uint32_t i = 0; i < f->n; i++)
        f->xd[i] = (double)f->nodes[i];
    free(f->xcell);
    f->xcell = NULL;
    f->nxcell = 0;
    if (f->n < 2)
        return 0;
    double lo = f->xd[0], span = f->xd[f->n - 1] - lo;
    for (uint32_t i = 1; i < f->n; i++)
        if (!(f->xd[i] >= f->xd[i - 1]))
            return 0; /* unsorted: cr_weights' binary search as it stands */
    if (!(span > 0.0) || f->n > UINT32_MAX / 4)
        return 0; /* no width: the scale would divide by 0 */
    /* four cells per node: this library's nodes crowd towards grazing, where a
       cell then holds a node or two */
    uint32_t cells = 4 * f->n;
    f->xcell = malloc(((size_t)cells + 1) * sizeof *f->xcell);
    if (!f->xcell)
        return -1;
    f->nxcell = cells;
    f->xcell_scale = (double)cells / span; /* span > 0 (above) */
    uint32_t i = 0;
    for (uint32_t c = 0; c <= cells; c++) {
        double edge = lo + (double)c / f->xcell_scale;
        while (i + 1 < f->n && f->xd[i + 1] <= edge)
            i++;
        f->xcell[c] = i;
    }
    return 0;
}

BTDF_API int btdf_scatfun_channels(const btdf_scatfun *f) { return f ? (int)f->channels : 0; }
BTDF_API size_t btdf_scatfun_node_count(const btdf_scatfun *f) { return f ? f->n : 0; }
BTDF_API size_t btdf_scatfun_coeff_count(const btdf_scatfun *f) { return f ? f->ncoeffs : 0; }
BTDF_API size_t btdf_scatfun_max_order(const btdf_scatfun *f) { return f ? f->mmax : 0; }
BTDF_API double btdf_scatfun_eta(const btdf_scatfun *f) { return f ? (double)f->eta : 0.0; }
BTDF_API const char *btdf_scatfun_metadata(const btdf_scatfun *f) { return f ? f->meta : NULL; }
BTDF_API const float *btdf_scatfun_nodes(const btdf_scatfun *f) { return f ? f->nodes : NULL; }
BTDF_API const float *btdf_scatfun_cdf(const btdf_scatfun *f) { return f ? f->cdf : NULL; }
BTDF_API const float *btdf_scatfun_coeffs(const btdf_scatfun *f) { return f ? f->coeffs : NULL; }

BTDF_API btdf_status btdf_scatfun_pair(const btdf_scatfun *f, size_t i, size_t o,
                                       size_t *offset, size_t *length)
{
    if (!f || i >= f->n || o >= f->n || !offset || !length)
        return BTDF_EINVAL;
    size_t e = 2 * (i * f->n + o);
    *offset = f->offsets[e];
    *length = f->offsets[e + 1];
    return BTDF_OK;
}

BTDF_API int btdf_scatfun_sides(const btdf_scatfun *f)
{
    if (!f)
        return 0;
    int sides = 0;
    for (uint32_t i = 0; i < f->n; i++)
        for (uint32_t o = 0; o < f->n; o++) {
            if (f->offsets[2 * ((size_t)i * f->n + o) + 1] == 0)
                continue;
            if (f->nodes[i] > 0.0f && f->nodes[o] > 0.0f)
                sides |= BTDF_SCATFUN_T_ENTER;
            else if (f->nodes[i] < 0.0f && f->nodes[o] < 0.0f)
                sides |= BTDF_SCATFUN_T_LEAVE;
            else if (f->nodes[i] > 0.0f && f->nodes[o] < 0.0f)
                sides |= BTDF_SCATFUN_R_TOP;
            else if (f->nodes[i] < 0.0f && f->nodes[o] > 0.0f)
                sides |= BTDF_SCATFUN_R_BOTTOM;
        }
    return sides;
}

BTDF_API double btdf_scatfun_a0_peak(const btdf_scatfun *f)
{
    double peak = 0.0;
    if (!f)
        return 0.0;
    for (size_t e = 0; e < (size_t)f->n * f->n; e++)
        if (f->offsets[2 * e + 1] > 0)
            peak = fmax(peak, fabs((double)f->coeffs[f->offsets[2 * e]]));
    return peak;
}

BTDF_API void btdf_scatfun_free(btdf_scatfun *f)
{
    if (!f)
        return;
    free(f->nodes);
    free(f->xd);
    free(f->xcell);
    free(f->cdf);
    free(f->offsets);
    free(f->coeffs);
    free(f->meta);
    albedo_memo_free(f->memo);
    for (int i = 0; i < 2; i++)
        for (int k = 0; k < 3; k++)
            btdf_full_free(f->ms[i][k]);
    free(f);
}
