/* SPDX-License-Identifier: MIT */
/* exr_write.c: a table as a multi-part OpenEXR file (the layout in exr_impl.h). */
#include <ctype.h>
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
#include <pthread.h>

#include "formats/exr_impl.h"

/* Writing contexts: OpenEXR reports a write error while it holds the context's lock,
   and exr_get_user_data takes that same lock (a write context locks it on every call),
   so asking for the user data from the handler would wait forever. Writers register
   their record here instead, under a lock of our own that is never held while calling
   into OpenEXR. A context not (yet) registered keeps OpenEXR's default message. */
#define WRITE_SLOTS 64
static pthread_mutex_t write_slots_lock = PTHREAD_MUTEX_INITIALIZER;
static struct {
    exr_const_context_t ctx;
    exr_err *err;
} write_slots[WRITE_SLOTS];

/* Registers err for ctx (err != NULL), or frees err's slot (ctx == NULL). */
static void write_slot_set(exr_const_context_t ctx, exr_err *err, const exr_err *old)
{
    pthread_mutex_lock(&write_slots_lock);
    for (size_t i = 0; i < WRITE_SLOTS; i++)
        if (write_slots[i].err == old) {
            write_slots[i].ctx = ctx;
            write_slots[i].err = err;
            break;
        }
    pthread_mutex_unlock(&write_slots_lock);
}

static void on_exr_write_error(exr_const_context_t ctx, exr_result_t code, const char *text)
{
    pthread_mutex_lock(&write_slots_lock);
    for (size_t i = 0; i < WRITE_SLOTS; i++)
        if (write_slots[i].ctx == ctx && write_slots[i].err) {
            bexr_note_error(write_slots[i].err, code, text);
            break;
        }
    pthread_mutex_unlock(&write_slots_lock);
}

/* Space-separated %.17g list: every double comes back bit for bit through strtod. */
static char *format_list(const double *x, size_t n)
{
    /* 25 bytes hold "%.17g " of any double; n is bounded by int32 by the caller. */
    size_t cap = n * 25 + 1;
    char *s = malloc(cap);
    if (!s)
        return NULL;
    size_t used = 0;
    s[0] = '\0';
    for (size_t i = 0; i < n; i++) {
        int w = snprintf(s + used, cap - used, i ? " %.17g" : "%.17g", x[i]);
        if (w < 0 || (size_t)w >= cap - used) {
            free(s);
            return NULL;
        }
        used += (size_t)w;
    }
    return s;
}

/* ------------------------------------------------------------------------- */
/* Writing                                                                   */
/* ------------------------------------------------------------------------- */

/* pre: "btdf.report." for the table's own part, "btdf.reflection.report." for the
   reflection of a file holding both. */
static exr_result_t set_report(exr_context_t ctx, const btdf_report *r, const char *pre)
{
    exr_result_t rc = EXR_ERR_SUCCESS;
    char an[96];
    /* No times or memory here: files must be the same bytes for the same inputs; the
       tool prints those on standard error and in --report. */
#define SETD(name, v)                                                                    \
    snprintf(an, sizeof an, "%s%s", pre, name);                                          \
    if (rc == EXR_ERR_SUCCESS)                                                           \
    rc = exr_attr_set_double(ctx, 0, an, (double)(v))
    SETD("slices", r->slices);
    SETD("samples", r->samples);
    SETD("testAngles", r->test_angles);
    SETD("testPoints", r->test_points);
    SETD("eL1Max", r->e_l1_max);
    SETD("eL1Mean", r->e_l1_mean);
    SETD("eTMax", r->e_t_max);
    SETD("eTMean", r->e_t_mean);
    SETD("eMaxMax", r->e_max_max);
    SETD("eMaxMean", r->e_max_mean);
    SETD("tolerance", r->tolerance);
#undef SETD
    snprintf(an, sizeof an, "%smetric", pre);
    if (rc == EXR_ERR_SUCCESS)
        rc = exr_attr_set_string(ctx, 0, an, r->metric == BTDF_METRIC_MAX ? "max" : "l1");
    snprintf(an, sizeof an, "%smet", pre);
    if (rc == EXR_ERR_SUCCESS)
        rc = exr_attr_set_int(ctx, 0, an, r->met ? 1 : 0);
    if (rc != EXR_ERR_SUCCESS || r->test_angles == 0 || r->per_ti == NULL)
        return rc;
    /* One line per test angle; 6 numbers of at most 17 characters each. */
    size_t cap = 64 + r->test_angles * 6 * 18;
    char *s = malloc(cap);
    if (!s)
        return EXR_ERR_OUT_OF_MEMORY;
    size_t used = (size_t)snprintf(s, cap, "ti_deg T T_table e_l1 e_t e_max");
    for (size_t i = 0; i < r->test_angles && used < cap; i++) {
        const btdf_ti_error *e = &r->per_ti[i];
        int w = snprintf(s + used, cap - used, "\n%.9g %.9g %.9g %.3g %.3g %.3g",
                         e->ti * (180.0 / 3.14159265358979323846), e->T, e->T_table,
                         e->e_l1, e->e_t, e->e_max);
        if (w < 0)
            break;
        used += (size_t)w;
    }
    snprintf(an, sizeof an, "%sperTi", pre);
    rc = exr_attr_set_string(ctx, 0, an, s);
    free(s);
    return rc;
}

/* Table-wide attributes, all on part 0. */
static exr_result_t set_table_attrs(exr_context_t ctx, const btdf_table *t,
                                    const btdf_write_opts *w, size_t nslices,
                                    const char *value)
{
    const btdf_params *p = btdf_table_get_params(t);
    const char *const *names = bexr_chan_names(p->channels);
    exr_result_t rc =
        exr_attr_set_string(ctx, 0, ATTR_PREFIX "kind", table_kind_name(btdf_table_get_kind(t)));
    /* The interpolation rule of facet tables (btdf.h); absent: plain, as every file
       written before it had a name. */
    if (rc == EXR_ERR_SUCCESS && btdf_table_get_kind(t) != BTDF_TABLE_GRID)
        rc = exr_attr_set_string(ctx, 0, ATTR_PREFIX "rule",
                                 btdf_table_rule_name(btdf_table_get_rule(t)));
    if (rc == EXR_ERR_SUCCESS)
        rc = exr_attr_set_int(ctx, 0, ATTR_PREFIX "channels", p->channels);
    if (rc == EXR_ERR_SUCCESS)
        rc = exr_attr_set_int(ctx, 0, ATTR_PREFIX "slices", (int32_t)nslices);
    for (int ch = 0; ch < p->channels && rc == EXR_ERR_SUCCESS; ch++) {
        char name[32];
        snprintf(name, sizeof name, ATTR_PREFIX "n.%s", names[ch]);
        rc = exr_attr_set_double(ctx, 0, name, p->ior[ch]);
    }
    if (rc == EXR_ERR_SUCCESS)
        rc = exr_attr_set_double(ctx, 0, ATTR_PREFIX "s", p->smoothness);
    if (rc == EXR_ERR_SUCCESS)
        rc = exr_attr_set_double(ctx, 0, ATTR_PREFIX "k0", p->k0);
    /* absent (every file before it, and every xu-sun file, which keeps its bytes):
       xu-sun */
    if (rc == EXR_ERR_SUCCESS && p->model != BTDF_MODEL_XU_SUN)
        rc = exr_attr_set_string(ctx, 0, ATTR_PREFIX "model", btdf_model_name(p->model));
    if (rc == EXR_ERR_SUCCESS)
        rc = exr_attr_set_string(ctx, 0, ATTR_PREFIX "units", "1/sr");
    int refl = kind_is_reflection(btdf_table_get_kind(t));
    if (rc == EXR_ERR_SUCCESS)
        rc = exr_attr_set_string(ctx, 0, ATTR_PREFIX "value",
                                 value  ? value
                                 : refl ? "rho_r, the reflection of the same facets (BRDF), no "
                                        "cosine factor"
                                      : p->model == BTDF_MODEL_SMITH
                                      ? "rho, the BTDF of the facets of Xu & Sun 2008 with the "
                                        "height-correlated Smith term, no cosine factor"
                                      : p->model == BTDF_MODEL_FULL
                                      ? "rho of the model full: the slices' value (the smith "
                                        "model's single scattering) plus the multiply scattered "
                                        "part of the tally in " ATTR_PREFIX "ms.*, no cosine "
                                        "factor"
                                      : "rho, the BTDF of Xu & Sun 2008 Eq. 25, no cosine factor");
    const btdf_table *tr = t->refl;
    if (rc == EXR_ERR_SUCCESS && tr)
        rc = exr_attr_set_string(ctx, 0, ATTR_PREFIX "refl.kind", table_kind_name(tr->kind));
    if (rc == EXR_ERR_SUCCESS && tr)
        rc = exr_attr_set_int(ctx, 0, ATTR_PREFIX "refl.slices", (int32_t)tr->ns);
    if (rc == EXR_ERR_SUCCESS && tr)
        rc = exr_attr_set_string(ctx, 0, ATTR_PREFIX "refl.rule", btdf_table_rule_name(tr->rule));
    if (rc == EXR_ERR_SUCCESS && tr)
        rc = exr_attr_set_string(ctx, 0, ATTR_PREFIX "refl.value",
                                 "rho_r, the reflection of the same facets (BRDF), no cosine "
                                 "factor; parts after the transmission's");
    if (rc == EXR_ERR_SUCCESS)
        rc = exr_attr_set_string(ctx, 0, ATTR_PREFIX "version", BTDF_VERSION_STRING);
    if (rc == EXR_ERR_SUCCESS && w->provenance)
        rc = exr_attr_set_string(ctx, 0, ATTR_PREFIX "provenance", w->provenance);
    if (rc == EXR_ERR_SUCCESS && w->report)
        rc = set_report(ctx, w->report, ATTR_PREFIX "report.");
    if (rc == EXR_ERR_SUCCESS && tr && w->report_reflection)
        rc = set_report(ctx, w->report_reflection, ATTR_PREFIX "refl.report.");
    /* model full: what the errors are measured against, and each channel's tally */
    if (rc == EXR_ERR_SUCCESS && p->model == BTDF_MODEL_FULL && w->report)
        rc = exr_attr_set_double(ctx, 0, ATTR_PREFIX "report.msNoise", w->report->ms_noise);
    for (int ch = 0; ch < p->channels && rc == EXR_ERR_SUCCESS && p->model == BTDF_MODEL_FULL;
         ch++) {
        char name[32], *txt = table_ms_write(t, ch);
        snprintf(name, sizeof name, ATTR_PREFIX "ms.%s", names[ch]);
        rc = txt ? exr_attr_set_string(ctx, 0, name, txt) : EXR_ERR_OUT_OF_MEMORY;
        free(txt);
    }
    return rc;
}

static exr_result_t set_slice_attrs(exr_context_t ctx, int part, btdf_table_kind kind,
                                    const btdf_slice *sl)
{
    char *rows = format_list(sl->rows, sl->nrows);
    char *cols = format_list(sl->cols, sl->ncols);
    exr_result_t rc = (rows && cols) ? EXR_ERR_SUCCESS : EXR_ERR_OUT_OF_MEMORY;
    if (rc == EXR_ERR_SUCCESS)
        rc = exr_attr_set_double(ctx, part, ATTR_PREFIX "ti", sl->ti);
    if (rc == EXR_ERR_SUCCESS)
        rc = exr_attr_set_string(ctx, part, ATTR_PREFIX "rows", rows);
    if (rc == EXR_ERR_SUCCESS)
        rc = exr_attr_set_string(ctx, part, ATTR_PREFIX "cols", cols);
    if (rc == EXR_ERR_SUCCESS)
        rc = exr_attr_set_string(ctx, part, ATTR_PREFIX "rowAxis",
                                 kind == BTDF_TABLE_GRID ? "to" : "tn");
    if (rc == EXR_ERR_SUCCESS)
        rc = exr_attr_set_string(ctx, part, ATTR_PREFIX "colAxis",
                                 kind == BTDF_TABLE_GRID ? "phi" : "psi");
    if (rc == EXR_ERR_SUCCESS && kind_is_reflection(kind)) /* only the reflection says */
        rc = exr_attr_set_string(ctx, part, ATTR_PREFIX "part", "reflection");
    free(rows);
    free(cols);
    return rc;
}

/* Slice k of the file: the transmission's slices first, then those of an attached
   reflection (a file holding both parts). Sets *own to the table it belongs to. */
static void file_slice(const btdf_table *t, size_t k, btdf_slice *sl, const btdf_table **own)
{
    size_t nt = btdf_table_slice_count(t);
    *own = k < nt ? t : t->refl;
    btdf_table_slice(*own, k < nt ? k : k - nt, sl);
}

/* Slice k as planar float channels, planes[ch][r * ncols + c]. */
static btdf_status slice_to_float(const btdf_slice *sl, int channels, float *planes,
                                  char *msg, size_t msglen)
{
    size_t npix = sl->nrows * sl->ncols;
    for (size_t i = 0; i < npix; i++) {
        for (int ch = 0; ch < channels; ch++) {
            double v = sl->values[i * (size_t)channels + (size_t)ch];
            /* EXR FLOAT is binary32: larger values would become inf in the file. */
            if (!(v >= 0.0 && v <= FLT_MAX))
                return say(BTDF_EDOMAIN, msg, msglen,
                           "value %g at ti = %g rad, node %zu does not fit a 32-bit float",
                           v, sl->ti, i);
            planes[(size_t)ch * npix + i] = (float)v;
        }
    }
    return BTDF_OK;
}

/* OpenEXR's rule for a chunk: stored size equal to the raw size means raw bytes, any
   smaller size means compressed. The ZIP encoder of the OpenEXR C core (3.1.5 in
   Debian 12; fixed upstream in 2026 by OpenEXR pull request #2307) falls back to raw
   bytes only when the zlib stream is strictly longer than the raw data; a stream of exactly the raw length is
   stored as it is, and every reader then takes the zlib bytes for pixels. This wraps
   the library's compressor and applies the rule itself, so any library version writes
   files that read back. The original compressor travels in encoding_user_data, which
   the library leaves to the caller. */
typedef exr_result_t (*compress_fn_t)(exr_encode_pipeline_t *);

typedef struct compress_guard {
    compress_fn_t inner;
} compress_guard;

static exr_result_t compress_or_store_raw(exr_encode_pipeline_t *enc)
{
    const compress_guard *g = enc->encoding_user_data;
    exr_result_t rc = g->inner(enc);
    if (rc != EXR_ERR_SUCCESS || enc->compressed_bytes < enc->packed_bytes)
        return rc;
    /* Not smaller: store the raw bytes. The compressed buffer is at least as large as
       what the compressor wrote, so it holds packed_bytes; check rather than trust. */
    if (enc->compressed_buffer == NULL || enc->packed_buffer == NULL ||
        enc->compressed_alloc_size < enc->packed_bytes)
        return EXR_ERR_OUT_OF_MEMORY;
    if (enc->compressed_buffer != enc->packed_buffer)
        memcpy(enc->compressed_buffer, enc->packed_buffer, enc->packed_bytes);
    enc->compressed_bytes = enc->packed_bytes;
    return EXR_ERR_SUCCESS;
}

static btdf_status write_part_pixels(exr_context_t ctx, int part, const btdf_slice *sl,
                                     int channels, const char *const *names,
                                     const float *planes, const exr_err *err, char *msg,
                                     size_t msglen)
{
    int32_t lpc = 1;
    exr_result_t rc = exr_get_scanlines_per_chunk(ctx, part, &lpc);
    if (rc != EXR_ERR_SUCCESS || lpc < 1)
        return say(BTDF_EIO, msg, msglen, "OpenEXR: %s", bexr_text(err, rc));
    size_t npix = sl->nrows * sl->ncols;
    int32_t width = (int32_t)sl->ncols, height = (int32_t)sl->nrows;
    exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
    compress_guard guard = {NULL};
    int started = 0;
    for (int32_t y = 0; y < height && rc == EXR_ERR_SUCCESS; y += lpc) {
        exr_chunk_info_t ci;
        rc = exr_write_scanline_chunk_info(ctx, part, y, &ci);
        if (rc != EXR_ERR_SUCCESS)
            break;
        rc = started ? exr_encoding_update(ctx, part, &ci, &enc)
                     : exr_encoding_initialize(ctx, part, &ci, &enc);
        if (rc != EXR_ERR_SUCCESS)
            break;
        for (int16_t i = 0; i < enc.channel_count; i++) {
            exr_coding_channel_info_t *c = &enc.channels[i];
            int ch = 0;
            while (ch < channels && strcmp(c->channel_name, names[ch]) != 0)
                ch++;
            if (ch == channels) {
                rc = EXR_ERR_INVALID_ARGUMENT; /* cannot happen: we declared them */
                break;
            }
            c->user_pixel_stride = (int32_t)sizeof(float);
            c->user_line_stride = width * (int32_t)sizeof(float);
            c->user_bytes_per_element = (int16_t)sizeof(float);
            c->user_data_type = EXR_PIXEL_FLOAT;
            c->encode_from_ptr =
                (const uint8_t *)(planes + (size_t)ch * npix + (size_t)y * sl->ncols);
        }
        if (rc == EXR_ERR_SUCCESS && !started) {
            rc = exr_encoding_choose_default_routines(ctx, part, &enc);
            if (rc == EXR_ERR_SUCCESS && enc.compress_fn != NULL) {
                guard.inner = enc.compress_fn;
                enc.encoding_user_data = &guard;
                enc.compress_fn = compress_or_store_raw;
            }
        }
        started = 1;
        if (rc == EXR_ERR_SUCCESS)
            rc = exr_encoding_run(ctx, part, &enc);
    }
    if (started)
        exr_encoding_destroy(ctx, &enc);
    if (rc != EXR_ERR_SUCCESS)
        return say(BTDF_EIO, msg, msglen, "OpenEXR: %s", bexr_text(err, rc));
    return BTDF_OK;
}

/* OpenEXR's custom stream: pwrite on the descriptor of the temporary the caller created
   safely (OpenEXR never opens the file by its name). */
static int64_t exr_pwrite(exr_const_context_t ctx, void *user, const void *buf, uint64_t sz,
                          uint64_t offset, exr_stream_error_func_ptr_t error_cb)
{
    int fd = *(const int *)user;
    const char *p = buf;
    uint64_t done = 0;
    while (done < sz) {
        if (offset + done > (uint64_t)INT64_MAX) {
            error_cb(ctx, EXR_ERR_WRITE_IO, "offset beyond what a file can hold");
            return -1;
        }
        size_t chunk = sz - done > (uint64_t)(1u << 30) ? (size_t)1 << 30 : (size_t)(sz - done);
        ssize_t w = pwrite(fd, p + done, chunk, (off_t)(offset + done));
        if (w < 0 && errno == EINTR)
            continue;
        if (w <= 0) {
            error_cb(ctx, EXR_ERR_WRITE_IO, "writing failed: %s",
                     w < 0 ? strerror(errno) : "no progress");
            return -1;
        }
        done += (uint64_t)w;
    }
    return (int64_t)done;
}

btdf_status bexr_write(const fmt_output_ctx *c, FILE *f, const char *path, char *msg,
                             size_t msglen)
{
    int fd = fileno(f); /* nothing is buffered in f: OpenEXR writes through fd alone */
    const btdf_table *t = c->table;
    const btdf_params *p = btdf_table_get_params(t);
    size_t nslices = btdf_table_slice_count(t) + btdf_table_slice_count(t->refl);
    int channels = p->channels;
    if (nslices == 0)
        return say(BTDF_EINVAL, msg, msglen, "the table has no slices: nothing to write");
    if (nslices > INT32_MAX)
        return say(BTDF_EOVERFLOW, msg, msglen, "%zu slices exceed OpenEXR's part count",
                   nslices);
    size_t maxpix = 0, maxrows = 0, maxcols = 0;
    for (size_t k = 0; k < nslices; k++) {
        btdf_slice sl;
        const btdf_table *own;
        file_slice(t, k, &sl, &own);
        if (sl.nrows == 0 || sl.ncols == 0 || sl.nrows > INT32_MAX || sl.ncols > INT32_MAX)
            return say(BTDF_EOVERFLOW, msg, msglen,
                       "slice %zu has %zu x %zu nodes: not an OpenEXR image size", k,
                       sl.nrows, sl.ncols);
        if (sl.ncols > SIZE_MAX / sl.nrows)
            return say(BTDF_EOVERFLOW, msg, msglen, "slice %zu is too large", k);
        size_t npix = sl.nrows * sl.ncols;
        maxpix = npix > maxpix ? npix : maxpix;
        maxrows = sl.nrows > maxrows ? sl.nrows : maxrows;
        maxcols = sl.ncols > maxcols ? sl.ncols : maxcols;
    }
    /* displayWindow is shared by all parts of a multi-part file (the C++ library refuses
       files where it differs): the largest slice's; each dataWindow is its slice. */
    exr_attr_box2i_t disp;
    disp.min.x = disp.min.y = 0;
    disp.max.x = (int32_t)maxcols - 1;
    disp.max.y = (int32_t)maxrows - 1;
    exr_attr_v2f_t centre;
    centre.x = centre.y = 0.0f;
    /* the extra layers: the table's own layout, so each slice's pixels line up */
    size_t nl = c->layers ? c->nlayers : 0;
    if (nl > 8)
        return say(BTDF_EINVAL, msg, msglen, "%zu layers: at most 8", nl);
    for (size_t l = 0; l < nl; l++) {
        const btdf_table *lt = c->layers[l].table;
        const char *ln = c->layers[l].name;
        size_t len = ln ? strlen(ln) : 0;
        int ok = lt && len > 0 && len < 24 && btdf_table_get_kind(lt) == btdf_table_get_kind(t) &&
                 btdf_table_get_params(lt)->channels == channels && !lt->refl == !t->refl &&
                 btdf_table_slice_count(lt) == btdf_table_slice_count(t);
        for (size_t i = 0; ok && i < len; i++)
            ok = isalnum((unsigned char)ln[i]) || ln[i] == '_';
        for (size_t k = 0; ok && k < nslices; k++) {
            btdf_slice a, b;
            const btdf_table *oa, *ob;
            file_slice(t, k, &a, &oa);
            file_slice(lt, k, &b, &ob);
            ok = a.nrows == b.nrows && a.ncols == b.ncols;
        }
        if (!ok)
            return say(BTDF_EINVAL, msg, msglen,
                       "layer %zu ('%s'): needs a name of letters, digits and '_' (under 24) "
                       "and the table's kind, channels, slices and nodes",
                       l + 1, ln ? ln : "");
    }
    int nch = channels * (int)(1 + nl);
    char lnames[8 * 3][32];
    const char *names_all[3 * 9];
    for (int ch = 0; ch < channels; ch++)
        names_all[ch] = bexr_chan_names(channels)[ch];
    for (size_t l = 0; l < nl; l++)
        for (int ch = 0; ch < channels; ch++) {
            char *b = lnames[l * 3 + (size_t)ch];
            snprintf(b, sizeof lnames[0], "%s.%s", c->layers[l].name, bexr_chan_names(channels)[ch]);
            names_all[(size_t)channels * (l + 1) + (size_t)ch] = b;
        }
    if (maxpix > SIZE_MAX / sizeof(float) / (size_t)nch)
        return say(BTDF_EOVERFLOW, msg, msglen, "a slice is too large to convert");
    float *planes = malloc(maxpix * (size_t)nch * sizeof(float));
    if (!planes)
        return say(BTDF_ENOMEM, msg, msglen, "out of memory for a %zu-node slice", maxpix);

    exr_err err = {0, {0}};
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = on_exr_write_error;
    init.write_fn = exr_pwrite;
    init.user_data = &fd;
    exr_context_t ctx = NULL;
    btdf_status st = BTDF_OK;
    exr_result_t rc = exr_start_write(&ctx, path, EXR_WRITE_FILE_DIRECTLY, &init);
    if (rc != EXR_ERR_SUCCESS) {
        free(planes);
        return say(BTDF_EIO, msg, msglen, "%s", bexr_text(&err, rc));
    }
    write_slot_set(ctx, &err, NULL); /* from here on, OpenEXR's messages reach err */
    for (size_t k = 0; k < nslices && rc == EXR_ERR_SUCCESS; k++) {
        btdf_slice sl;
        const btdf_table *own;
        file_slice(t, k, &sl, &own);
        btdf_table_kind kind = btdf_table_get_kind(own);
        char pname[64];
        /* part names are unique in a file: a reflection's count from its own first */
        if (own != t)
            snprintf(pname, sizeof pname, "reflection%04zu ti=%.4fdeg",
                     k - btdf_table_slice_count(t), sl.ti * (180.0 / 3.14159265358979323846));
        else
            snprintf(pname, sizeof pname, "slice%04zu ti=%.4fdeg", k,
                     sl.ti * (180.0 / 3.14159265358979323846));
        int part = -1;
        rc = exr_add_part(ctx, pname, EXR_STORAGE_SCANLINE, &part);
        exr_attr_box2i_t data = disp;
        data.max.x = (int32_t)sl.ncols - 1;
        data.max.y = (int32_t)sl.nrows - 1;
        if (rc == EXR_ERR_SUCCESS)
            rc = exr_initialize_required_attr(ctx, part, &disp, &data, 1.0f, &centre, 1.0f,
                                              EXR_LINEORDER_INCREASING_Y, EXR_COMPRESSION_ZIP);
        for (int ch = 0; ch < nch && rc == EXR_ERR_SUCCESS; ch++)
            rc = exr_add_channel(ctx, part, names_all[ch], EXR_PIXEL_FLOAT,
                                 EXR_PERCEPTUALLY_LINEAR, 1, 1);
        if (rc == EXR_ERR_SUCCESS)
            rc = set_slice_attrs(ctx, part, kind, &sl);
    }
    if (rc == EXR_ERR_SUCCESS)
        rc = set_table_attrs(ctx, t, c->opts, btdf_table_slice_count(t), c->value);
    if (rc == EXR_ERR_SUCCESS)
        rc = exr_write_header(ctx);
    if (rc != EXR_ERR_SUCCESS)
        st = say(rc == EXR_ERR_OUT_OF_MEMORY ? BTDF_ENOMEM : BTDF_EIO, msg, msglen,
                 "OpenEXR header: %s", bexr_text(&err, rc));
    for (size_t k = 0; k < nslices && st == BTDF_OK; k++) {
        btdf_slice sl;
        const btdf_table *own;
        file_slice(t, k, &sl, &own);
        st = slice_to_float(&sl, channels, planes, msg, msglen);
        size_t npix = sl.nrows * sl.ncols;
        for (size_t l = 0; l < nl && st == BTDF_OK; l++) {
            btdf_slice ls;
            const btdf_table *lo;
            file_slice(c->layers[l].table, k, &ls, &lo);
            st = slice_to_float(&ls, channels, planes + (l + 1) * (size_t)channels * npix, msg,
                                msglen);
        }
        if (st == BTDF_OK)
            st = write_part_pixels(ctx, (int)k, &sl, nch, names_all, planes, &err, msg,
                                   msglen);
    }
    free(planes);
    rc = exr_finish(&ctx);
    write_slot_set(NULL, NULL, &err);
    if (st == BTDF_OK && rc != EXR_ERR_SUCCESS)
        st = say(BTDF_EIO, msg, msglen, "OpenEXR: %s", bexr_text(&err, rc));
    return st;
}
