/* SPDX-License-Identifier: MIT */
/* exr_read.c: a table from a multi-part OpenEXR file, its sizes checked before any
   allocation (the layout in exr_impl.h). */
#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

#include <openexr.h>

#include "formats/exr_impl.h"

/* ------------------------------------------------------------------------- */
/* Reading                                                                   */
/* ------------------------------------------------------------------------- */

typedef struct reader {
    exr_context_t ctx;
    exr_err err;
    const char *path;
    char *msg;
    size_t msglen;
    uint64_t file_size; /* bytes, for checking declared sizes before allocating */
} reader;

/* A string attribute as a NUL-terminated copy (caller frees), or NULL with a message. */
static char *get_string(reader *r, int part, const char *name, btdf_status *st)
{
    int32_t len = 0;
    const char *s = NULL;
    exr_result_t rc = exr_attr_get_string(r->ctx, part, name, &len, &s);
    if (rc != EXR_ERR_SUCCESS || len < 0 || (len > 0 && s == NULL)) {
        *st = say(BTDF_EFORMAT, r->msg, r->msglen,
                  "not a btdftab table: part %d has no string attribute %s", part, name);
        return NULL;
    }
    char *out = malloc((size_t)len + 1);
    if (!out) {
        *st = say(BTDF_ENOMEM, r->msg, r->msglen, "out of memory");
        return NULL;
    }
    if (len > 0)
        memcpy(out, s, (size_t)len);
    out[len] = '\0';
    return out;
}

static btdf_status get_double(reader *r, int part, const char *name, double *out)
{
    exr_result_t rc = exr_attr_get_double(r->ctx, part, name, out);
    if (rc != EXR_ERR_SUCCESS)
        return say(BTDF_EFORMAT, r->msg, r->msglen,
                   "not a btdftab table: part %d has no double attribute %s", part, name);
    if (!isfinite(*out))
        return say(BTDF_EFORMAT, r->msg, r->msglen, "attribute %s is not finite", name);
    return BTDF_OK;
}

/* Parses exactly n finite numbers from a space-separated list. */
static btdf_status parse_list(reader *r, int part, const char *name, size_t n, double *out)
{
    btdf_status st = BTDF_OK;
    char *s = get_string(r, part, name, &st);
    if (!s)
        return st;
    const char *p = s;
    size_t i = 0;
    for (;;) {
        while (*p == ' ')
            p++;
        if (*p == '\0')
            break;
        char *end = NULL;
        errno = 0;
        double v = strtod(p, &end);
        if (end == p || !isfinite(v) || i >= n) {
            st = say(BTDF_EFORMAT, r->msg, r->msglen,
                     "part %d: %s is not a list of %zu numbers", part, name, n);
            break;
        }
        out[i++] = v;
        p = end;
    }
    if (st == BTDF_OK && i != n)
        st = say(BTDF_EFORMAT, r->msg, r->msglen,
                 "part %d: %s holds %zu numbers, the image %zu", part, name, i, n);
    free(s);
    return st;
}

static btdf_status read_params(reader *r, btdf_table_kind *kind, btdf_params *p)
{
    btdf_status st = BTDF_OK;
    char *k = get_string(r, 0, ATTR_PREFIX "kind", &st);
    if (!k)
        return st;
    if (!table_kind_parse(k, kind))
        st = say(BTDF_EFORMAT, r->msg, r->msglen, "unknown table kind \"%s\"", k);
    free(k);
    if (st != BTDF_OK)
        return st;
    int32_t channels = 0;
    if (exr_attr_get_int(r->ctx, 0, ATTR_PREFIX "channels", &channels) != EXR_ERR_SUCCESS ||
        (channels != 1 && channels != 3))
        return say(BTDF_EFORMAT, r->msg, r->msglen,
                   "attribute " ATTR_PREFIX "channels missing or not 1 or 3");
    btdf_params_default(p);
    p->channels = channels;
    const char *const *names = bexr_chan_names(channels);
    for (int ch = 0; ch < channels && st == BTDF_OK; ch++) {
        char name[32];
        snprintf(name, sizeof name, ATTR_PREFIX "n.%s", names[ch]);
        st = get_double(r, 0, name, &p->ior[ch]);
    }
    if (st == BTDF_OK)
        st = get_double(r, 0, ATTR_PREFIX "s", &p->smoothness);
    if (st == BTDF_OK)
        st = get_double(r, 0, ATTR_PREFIX "k0", &p->k0);
    const char *ms = NULL;
    int32_t len = 0;
    if (st == BTDF_OK &&
        exr_attr_get_string(r->ctx, 0, ATTR_PREFIX "model", &len, &ms) == EXR_ERR_SUCCESS) {
        char word[32] = ""; /* EXR strings carry a length and need not end in NUL */
        if (ms && len > 0 && (size_t)len < sizeof word)
            memcpy(word, ms, (size_t)len);
        if (!btdf_model_parse(word, &p->model))
            st = say(BTDF_EFORMAT, r->msg, r->msglen,
                     "attribute " ATTR_PREFIX "model \"%s\": must be xu-sun, smith or full",
                     word);
    }
    return st;
}

/* Checks part's storage, channels and size; gives the data window. */
static btdf_status check_part(reader *r, int part, int channels, exr_attr_box2i_t *dw)
{
    exr_storage_t stor;
    if (exr_get_storage(r->ctx, part, &stor) != EXR_ERR_SUCCESS || stor != EXR_STORAGE_SCANLINE)
        return say(BTDF_EFORMAT, r->msg, r->msglen, "part %d is not a scanline image",
                   part);
    const exr_attr_chlist_t *cl = NULL;
    /* the table's channels, and any number of extra layers (names with a '.', such as
       a simulation's error.Y), which the reader leaves aside */
    int plain = 0;
    if (exr_get_channels(r->ctx, part, &cl) == EXR_ERR_SUCCESS && cl)
        for (int i = 0; i < cl->num_channels; i++) {
            const exr_attr_chlist_entry_t *e = &cl->entries[i];
            plain += strchr(e->name.str, '.') == NULL;
            if (strchr(e->name.str, '.') && (e->pixel_type != EXR_PIXEL_FLOAT ||
                                             e->x_sampling != 1 || e->y_sampling != 1))
                return say(BTDF_EFORMAT, r->msg, r->msglen,
                           "part %d: layer channel %s is not a full-size 32-bit float", part,
                           e->name.str);
        }
    if (!cl || plain != channels)
        return say(BTDF_EFORMAT, r->msg, r->msglen, "part %d does not have %d channel%s",
                   part, channels, channels == 1 ? "" : "s");
    const char *const *names = bexr_chan_names(channels);
    for (int ch = 0; ch < channels; ch++) {
        int found = 0;
        for (int i = 0; i < cl->num_channels; i++) {
            const exr_attr_chlist_entry_t *e = &cl->entries[i];
            if (strcmp(e->name.str, names[ch]) == 0 && e->pixel_type == EXR_PIXEL_FLOAT &&
                e->x_sampling == 1 && e->y_sampling == 1)
                found = 1;
        }
        if (!found)
            return say(BTDF_EFORMAT, r->msg, r->msglen,
                       "part %d lacks the 32-bit float channel %s", part,
                       names[ch]);
    }
    if (exr_get_data_window(r->ctx, part, dw) != EXR_ERR_SUCCESS ||
        dw->max.x < dw->min.x || dw->max.y < dw->min.y)
        return say(BTDF_EFORMAT, r->msg, r->msglen, "part %d has no data window",
                   part);
    return BTDF_OK;
}

static btdf_status read_part_pixels(reader *r, int part, const exr_attr_box2i_t *dw,
                                    int channels, float *planes)
{
    size_t width = (size_t)((int64_t)dw->max.x - dw->min.x + 1);
    size_t height = (size_t)((int64_t)dw->max.y - dw->min.y + 1);
    size_t npix = width * height;
    const char *const *names = bexr_chan_names(channels);
    int32_t lpc = 1;
    exr_result_t rc = exr_get_scanlines_per_chunk(r->ctx, part, &lpc);
    if (rc != EXR_ERR_SUCCESS || lpc < 1)
        return say(BTDF_EFORMAT, r->msg, r->msglen, "part %d: %s", part,
                   bexr_text(&r->err, rc));
    exr_decode_pipeline_t dec = EXR_DECODE_PIPELINE_INITIALIZER;
    int started = 0;
    for (int64_t y = dw->min.y; y <= dw->max.y && rc == EXR_ERR_SUCCESS; y += lpc) {
        exr_chunk_info_t ci;
        rc = exr_read_scanline_chunk_info(r->ctx, part, (int)y, &ci);
        if (rc != EXR_ERR_SUCCESS)
            break;
        rc = started ? exr_decoding_update(r->ctx, part, &ci, &dec)
                     : exr_decoding_initialize(r->ctx, part, &ci, &dec);
        if (rc != EXR_ERR_SUCCESS)
            break;
        /* The chunk's first line, relative to the window; check_part bounded it. */
        int64_t row0 = (int64_t)ci.start_y - dw->min.y;
        if (row0 < 0 || row0 + ci.height > (int64_t)height) {
            rc = EXR_ERR_CORRUPT_CHUNK;
            break;
        }
        for (int16_t i = 0; i < dec.channel_count; i++) {
            exr_coding_channel_info_t *c = &dec.channels[i];
            c->decode_to_ptr = NULL;
            for (int ch = 0; ch < channels; ch++) {
                if (strcmp(c->channel_name, names[ch]) != 0)
                    continue;
                c->user_pixel_stride = (int32_t)sizeof(float);
                c->user_line_stride = (int32_t)(width * sizeof(float));
                c->user_bytes_per_element = (int16_t)sizeof(float);
                c->user_data_type = EXR_PIXEL_FLOAT;
                c->decode_to_ptr =
                    (uint8_t *)(planes + (size_t)ch * npix + (size_t)row0 * width);
            }
        }
        if (!started)
            rc = exr_decoding_choose_default_routines(r->ctx, part, &dec);
        started = 1;
        if (rc == EXR_ERR_SUCCESS)
            rc = exr_decoding_run(r->ctx, part, &dec);
    }
    if (started)
        exr_decoding_destroy(r->ctx, &dec);
    if (rc != EXR_ERR_SUCCESS)
        return say(BTDF_EFORMAT, r->msg, r->msglen, "part %d pixels unreadable (%s): %s",
                   part, exr_get_error_code_as_string(rc), bexr_text(&r->err, rc));
    return BTDF_OK;
}

/* The largest ratio of decoded to stored bytes a compression can reach: deflate's
   limit is 1032:1 (ZIP, ZIPS; PXR24 stores 3 of a float's 4 bytes, so 4/3 of it); an
   OpenEXR RLE pair of 2 bytes gives at most 128 bytes; PIZ's Huffman run codes stay
   below deflate's; B44 and B44A store 32-bit float channels as they are. DWA and
   anything newer: an RLE pass under deflate, 64 x 1032. */
static uint64_t max_ratio(exr_compression_t c)
{
    switch (c) {
    case EXR_COMPRESSION_NONE:
    case EXR_COMPRESSION_B44:
    case EXR_COMPRESSION_B44A:
        return 1;
    case EXR_COMPRESSION_RLE:
        return 64;
    case EXR_COMPRESSION_ZIPS:
    case EXR_COMPRESSION_ZIP:
    case EXR_COMPRESSION_PIZ:
        return 1032;
    case EXR_COMPRESSION_PXR24:
        return 1376;
    default:
        return 64 * 1032;
    }
}

/* Before anything is allocated for a part: its declared sizes must fit in the file.
   Each of the width numbers of btdf.cols (and height of btdf.rows) takes at least a
   digit and a separator; each chunk has an 8-byte entry in the offset table; the
   chunks lie inside the file without overlapping, and none decodes to more than its
   compression allows. */
static btdf_status check_sizes(reader *r, int part, const exr_attr_box2i_t *dw, int channels)
{
    uint64_t width = (uint64_t)((int64_t)dw->max.x - dw->min.x + 1);
    uint64_t height = (uint64_t)((int64_t)dw->max.y - dw->min.y + 1);
    uint64_t fs = r->file_size;
    if (width > fs / 2 + 1 || height > fs / 2 + 1)
        return say(BTDF_EFORMAT, r->msg, r->msglen,
                   "part %d declares %llu x %llu pixels, more than a %llu-byte file can hold",
                   part, (unsigned long long)height, (unsigned long long)width,
                   (unsigned long long)fs);
    int32_t lpc = 1;
    exr_compression_t comp = EXR_COMPRESSION_LAST_TYPE;
    if (exr_get_scanlines_per_chunk(r->ctx, part, &lpc) != EXR_ERR_SUCCESS || lpc < 1 ||
        exr_get_compression(r->ctx, part, &comp) != EXR_ERR_SUCCESS)
        return say(BTDF_EFORMAT, r->msg, r->msglen, "part %d: no chunk layout", part);
    uint64_t chunks = (height + (uint64_t)lpc - 1) / (uint64_t)lpc;
    if (chunks > fs / 8)
        return say(BTDF_EFORMAT, r->msg, r->msglen,
                   "part %d declares %llu chunks, more than a %llu-byte file can index", part,
                   (unsigned long long)chunks, (unsigned long long)fs);
    uint64_t packed = 0, unpacked = 0;
    for (int64_t y = dw->min.y; y <= dw->max.y; y += lpc) {
        exr_chunk_info_t ci;
        exr_result_t rc = exr_read_scanline_chunk_info(r->ctx, part, (int)y, &ci);
        if (rc != EXR_ERR_SUCCESS)
            return say(BTDF_EFORMAT, r->msg, r->msglen, "part %d: chunk table unreadable: %s",
                       part, bexr_text(&r->err, rc));
        if (ci.data_offset > fs || ci.packed_size > fs - ci.data_offset ||
            (ci.unpacked_size - 1) / max_ratio(comp) >= ci.packed_size)
            return say(BTDF_EFORMAT, r->msg, r->msglen,
                       "part %d: chunk at line %lld declares %llu bytes stored and %llu "
                       "decoded, beyond a %llu-byte file",
                       part, (long long)y, (unsigned long long)ci.packed_size,
                       (unsigned long long)ci.unpacked_size, (unsigned long long)fs);
        packed += ci.packed_size; /* checked at each step: the sums cannot overflow */
        unpacked += ci.unpacked_size;
        if (packed > fs)
            break;
    }
    /* bytes per pixel, all channels: the table's and any extra layers' (check_part
       saw that each is a float, the table's by name, the layers' counted here) */
    const exr_attr_chlist_t *cl = NULL;
    int all = channels;
    if (exr_get_channels(r->ctx, part, &cl) == EXR_ERR_SUCCESS && cl && cl->num_channels > all)
        all = cl->num_channels;
    uint64_t px = (uint64_t)all * sizeof(float);
    if (packed > fs || unpacked % px != 0 || unpacked / px != width * height)
        return say(BTDF_EFORMAT, r->msg, r->msglen,
                   "part %d: its chunks hold %llu bytes stored and %llu decoded, not a "
                   "%llu x %llu image in a %llu-byte file",
                   part, (unsigned long long)packed, (unsigned long long)unpacked,
                   (unsigned long long)height, (unsigned long long)width,
                   (unsigned long long)fs);
    return BTDF_OK;
}

static btdf_status read_slice(reader *r, btdf_table *t, int part, int channels)
{
    exr_attr_box2i_t dw;
    btdf_status st = check_part(r, part, channels, &dw);
    if (st == BTDF_OK)
        st = check_sizes(r, part, &dw, channels);
    if (st != BTDF_OK)
        return st;
    size_t width = (size_t)((int64_t)dw.max.x - dw.min.x + 1);
    size_t height = (size_t)((int64_t)dw.max.y - dw.min.y + 1);
    if (width > SIZE_MAX / height || width * height > SIZE_MAX / sizeof(double) / 3)
        return say(BTDF_EOVERFLOW, r->msg, r->msglen, "part %d is too large", part);
    size_t npix = width * height;
    double ti = 0.0;
    st = get_double(r, part, ATTR_PREFIX "ti", &ti);
    if (st != BTDF_OK)
        return st;
    double *rows = malloc(height * sizeof *rows);
    double *cols = malloc(width * sizeof *cols);
    float *planes = malloc(npix * (size_t)channels * sizeof *planes);
    double *vals = malloc(npix * (size_t)channels * sizeof *vals);
    if (!rows || !cols || !planes || !vals)
        st = say(BTDF_ENOMEM, r->msg, r->msglen, "out of memory for part %d", part);
    if (st == BTDF_OK)
        st = parse_list(r, part, ATTR_PREFIX "rows", height, rows);
    if (st == BTDF_OK)
        st = parse_list(r, part, ATTR_PREFIX "cols", width, cols);
    if (st == BTDF_OK)
        st = read_part_pixels(r, part, &dw, channels, planes);
    for (size_t i = 0; st == BTDF_OK && i < npix; i++) {
        for (int ch = 0; ch < channels; ch++) {
            float v = planes[(size_t)ch * npix + i];
            if (!(v >= 0.0f && v <= FLT_MAX)) { /* rejects NaN, inf and negatives */
                st = say(BTDF_EFORMAT, r->msg, r->msglen,
                         "part %d pixel %zu channel %s is %g, not a BTDF value", part, i,
                         bexr_chan_names(channels)[ch], (double)v);
                break;
            }
            vals[i * (size_t)channels + (size_t)ch] = (double)v;
        }
    }
    if (st == BTDF_OK) {
        char why[200] = "";
        st = btdf_table_add_slice(t, ti, height, rows, width, cols, vals, why, sizeof why);
        if (st == BTDF_EINVAL)
            st = say(BTDF_EFORMAT, r->msg, r->msglen, "part %d: %s", part, why);
        else if (st != BTDF_OK)
            say(st, r->msg, r->msglen, "part %d: %s", part, why);
    }
    free(rows);
    free(cols);
    free(planes);
    free(vals);
    return st;
}

/* The interpolation rule stored in attribute `name` of part 0 into t; no attribute:
   the plain rule of files written before it. */
static btdf_status read_rule(reader *r, const char *name, btdf_table *t)
{
    const char *rs = NULL;
    int32_t len = 0;
    btdf_table_rule rule = BTDF_RULE_PLAIN;
    char why[200] = "", word[16] = "";
    if (exr_attr_get_string(r->ctx, 0, name, &len, &rs) == EXR_ERR_SUCCESS) {
        /* EXR strings carry a length and need not end in NUL */
        if (rs && len > 0 && (size_t)len < sizeof word)
            memcpy(word, rs, (size_t)len);
        if (!btdf_table_rule_parse(word, &rule))
            return say(BTDF_EFORMAT, r->msg, r->msglen,
                       "attribute %s \"%s\": must be plain, chi or fresnel", name, word);
    }
    if (btdf_table_set_rule(t, rule, why, sizeof why) != BTDF_OK)
        return say(BTDF_EFORMAT, r->msg, r->msglen, "%s", why);
    return BTDF_OK;
}

btdf_status bexr_read(const char *path, btdf_table **out, char *msg, size_t msglen)
{
    reader r = {NULL, {0, {0}}, path, msg, msglen, 0};
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = bexr_on_read_error;
    init.user_data = &r.err;
    /* A truncated file must fail, not be patched up by guessing the chunk table. */
    init.flags = EXR_CONTEXT_FLAG_DISABLE_CHUNK_RECONSTRUCTION;
    struct stat fst;
    if (stat(path, &fst) != 0)
        return say(BTDF_EIO, msg, msglen, "cannot open: %s", strerror(errno));
    if (!S_ISREG(fst.st_mode)) /* its size is what every declared size is checked against */
        return say(BTDF_EFORMAT, msg, msglen, "not a regular file");
    r.file_size = (uint64_t)fst.st_size;
    exr_result_t rc = exr_start_read(&r.ctx, path, &init);
    if (rc != EXR_ERR_SUCCESS) {
        btdf_status st = rc == EXR_ERR_FILE_ACCESS ? BTDF_EIO : BTDF_EFORMAT;
        say(st, msg, msglen, st == BTDF_EIO ? "%s" : "not a readable OpenEXR file: %s",
            bexr_text(&r.err, rc));
        exr_finish(&r.ctx);
        return st;
    }
    btdf_table *t = NULL;
    btdf_table_kind kind = BTDF_TABLE_GRID;
    btdf_params p;
    int nparts = 0;
    btdf_status st = BTDF_OK;
    if (exr_get_count(r.ctx, &nparts) != EXR_ERR_SUCCESS || nparts < 1)
        st = say(BTDF_EFORMAT, msg, msglen, "no image parts");
    if (st == BTDF_OK)
        st = read_params(&r, &kind, &p);
    int32_t nslices = 0, nrefl = 0;
    /* A file holding both parts: the reflection's slices follow the transmission's. */
    int both = exr_attr_get_int(r.ctx, 0, ATTR_PREFIX "refl.slices", &nrefl) ==
               EXR_ERR_SUCCESS;
    if (st == BTDF_OK && both) {
        char *rk = get_string(&r, 0, ATTR_PREFIX "refl.kind", &st);
        btdf_table_kind k2 = BTDF_TABLE_FACET;
        if (st == BTDF_OK && (!table_kind_parse(rk, &k2) || !kind_is_reflection(k2) ||
                              kind_is_reflection(kind) || nrefl < 1))
            st = say(BTDF_EFORMAT, msg, msglen, "a file holding both parts needs a "
                     "transmission kind, " ATTR_PREFIX "refl.kind facet-reflection "
                     "and at least one reflection slice");
        free(rk);
    }
    if (st == BTDF_OK &&
        (exr_attr_get_int(r.ctx, 0, ATTR_PREFIX "slices", &nslices) != EXR_ERR_SUCCESS ||
         nslices < 1 || nrefl < 0 || (int64_t)nslices + nrefl != nparts))
        st = say(BTDF_EFORMAT, msg, msglen, ATTR_PREFIX "slices does not match the %d parts",
                 nparts);
    btdf_table *tr = NULL;
    btdf_params single = table_single_params(&p); /* full: smith's slices, then its tally */
    if (st == BTDF_OK && both) {
        char why[200] = "";
        st = btdf_table_new(BTDF_TABLE_FACET_REFLECTION, &single, &tr, why, sizeof why);
        if (st != BTDF_OK)
            st = say(st == BTDF_EINVAL ? BTDF_EFORMAT : st, msg, msglen,
                     "bad parameters in the file: %s", why);
    }
    if (st == BTDF_OK) {
        char why[200] = "";
        st = btdf_table_new(kind, &single, &t, why, sizeof why);
        if (st != BTDF_OK)
            st = say(st == BTDF_EINVAL ? BTDF_EFORMAT : st, msg, msglen,
                     "bad parameters in the file: %s", why);
    }
    if (st == BTDF_OK)
        st = read_rule(&r, ATTR_PREFIX "rule", t);
    if (st == BTDF_OK && tr)
        st = read_rule(&r, ATTR_PREFIX "refl.rule", tr);
    for (int k = 0; k < nparts && st == BTDF_OK; k++)
        st = read_slice(&r, k < nslices ? t : tr, k, p.channels);
    table_ms_text mst; /* model full: each channel's tally */
    memset(&mst, 0, sizeof mst);
    for (int ch = 0; st == BTDF_OK && ch < p.channels; ch++) {
        const char *txt = NULL, *const *names = bexr_chan_names(p.channels);
        int32_t len = 0;
        char an[32];
        snprintf(an, sizeof an, ATTR_PREFIX "ms.%s", names[ch]);
        if (exr_attr_get_string(r.ctx, 0, an, &len, &txt) != EXR_ERR_SUCCESS || !txt ||
            len <= 0)
            continue;
        mst.text[ch] = malloc((size_t)len + 1); /* EXR strings need not end in NUL */
        if (!mst.text[ch]) {
            st = say(BTDF_ENOMEM, msg, msglen, "out of memory");
            break;
        }
        memcpy(mst.text[ch], txt, (size_t)len);
        mst.text[ch][len] = '\0';
        mst.len[ch] = (size_t)len;
    }
    exr_finish(&r.ctx);
    if (st == BTDF_OK && tr) {
        char why[200] = "";
        st = btdf_table_attach_reflection(t, tr, why, sizeof why);
        if (st == BTDF_OK)
            tr = NULL; /* owned by t */
        else
            st = say(BTDF_EFORMAT, msg, msglen, "%s", why);
    }
    if (st == BTDF_OK) {
        char why[200] = "";
        if (table_full_from_text(t, p.model, &mst, why, sizeof why) != BTDF_OK)
            st = say(BTDF_EFORMAT, msg, msglen, "%s", why);
    }
    table_ms_text_free(&mst);
    btdf_table_free(tr);
    if (st != BTDF_OK) {
        btdf_table_free(t);
        return st;
    }
    *out = t;
    return BTDF_OK;
}

/* The error report and provenance stored in part 0's attributes (set_report). */
btdf_status bexr_stored(const char *path, FILE *out)
{
    exr_context_t ctx = NULL;
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.flags = EXR_CONTEXT_FLAG_DISABLE_CHUNK_RECONSTRUCTION;
    if (exr_start_read(&ctx, path, &init) != EXR_ERR_SUCCESS) {
        exr_finish(&ctx);
        return BTDF_EFORMAT;
    }
    const char *prov = NULL;
    if (exr_attr_get_string(ctx, 0, ATTR_PREFIX "provenance", NULL, &prov) == EXR_ERR_SUCCESS &&
        prov)
        fprintf(out, "provenance: %s\n", prov);
    static const char *const names[8] = {"eL1Max",  "eL1Mean", "eMaxMax",    "eMaxMean",
                                         "eTMax",   "eTMean",  "testAngles", "testPoints"};
    static const char *const pre[2] = {ATTR_PREFIX "report.", ATTR_PREFIX "refl.report."};
    static const char *const key[2] = {"error", "error reflection"};
    for (int q = 0; q < 2; q++) {
        double v[8];
        int have = 1;
        for (size_t k = 0; k < 8 && have; k++) {
            char attr[80];
            snprintf(attr, sizeof attr, "%s%s", pre[q], names[k]);
            have = exr_attr_get_double(ctx, 0, attr, &v[k]) == EXR_ERR_SUCCESS;
        }
        if (have) /* the wording of the CSV's "# error:" line */
            fprintf(out, "%s: e_L1 max %.4g mean %.4g; e_max max %.4g mean %.4g; e_T max %.4g "
                         "mean %.4g; %.0f test angles, %.0f test points\n",
                    key[q], v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7]);
    }
    double noise;
    if (exr_attr_get_double(ctx, 0, ATTR_PREFIX "report.msNoise", &noise) == EXR_ERR_SUCCESS)
        fprintf(out, "error against: full, whose tally has the noise floor %.4g (the largest "
                     "standard error of its multiply scattered energy over the range)\n",
                noise);
    exr_finish(&ctx);
    return ferror(out) ? BTDF_EIO : BTDF_OK;
}
