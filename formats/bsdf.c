/* SPDX-License-Identifier: MIT */
/* bsdf.c: the SCATFUN v1 (.bsdf) entry of the format registry; the byte layout is scatfun.c's. */
#include <stdlib.h>

#include "formats.h"
#include "tmpfile.h"

static btdf_status bsdf_write(const btdf_output_ctx *c, FILE *f, const char *path, char *msg,
                              size_t msglen)
{
    unsigned char *b = NULL;
    size_t len = 0;
    btdf_status st = btdf_scatfun_to_mem(c->scatfun, c->metadata_json, &b, &len, msg, msglen);
    if (st != BTDF_OK)
        return st;
    btdf_bytes bytes = {b, len};
    st = btdf_write_bytes(&bytes, f, path, msg, msglen);
    free(b);
    return st;
}

static btdf_status bsdf_inspect(const btdf_input *in, FILE *out)
{
    return btdf_scatfun_info(in->scatfun, out);
}

const btdf_format_ops btdf_format_bsdf = {
    .name = "SCATFUN",
    .ext = ".bsdf",
    .available = 1,
    .needs = BTDF_NEEDS_SERIES,
    .write_path = bsdf_write,
    .read_series = btdf_scatfun_read,
    .inspect = bsdf_inspect,
};
