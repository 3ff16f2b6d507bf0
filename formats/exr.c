/* SPDX-License-Identifier: MIT */
/* exr.c: tables as multi-part OpenEXR files (one 32-bit float part per ti slice). */
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

#include "formats/formats.h"
#include "model/kernel.h"
#include "table/table.h"

/* Layout (docs/formats.md is the reference):
 *   part k = slice k, scanline storage, ZIP, FLOAT channels "Y" or "B","G","R";
 *   pixel (x = col, y = row), data window (0, 0) - (ncols - 1, nrows - 1);
 *   per part:  btdf.ti (double, radians), btdf.rows / btdf.cols (string, %.17g
 *              radians separated by spaces), btdf.rowAxis / btdf.colAxis (string);
 *   part 0:    the table (kind, channels, n per channel, s, k0, units, report);
 *   a file holding both parts: the reflection's slices after the transmission's, each
 *   with btdf.part "reflection", and btdf.refl.* on part 0 (docs/formats.md). */

#define ATTR_PREFIX "btdf."

/* The first OpenEXR error message of a context, for our own messages. */
typedef struct exr_err {
    int have;
    char text[256];
} exr_err;

static void note_error(exr_err *e, exr_result_t code, const char *text)
{
    if (e->have)
        return; /* keep the first: later ones are usually consequences */
    e->have = 1;
    snprintf(e->text, sizeof e->text, "%s", text ? text : exr_get_default_error_message(code));
}

/* Reading contexts: the record is the context's user data. */
static void on_exr_error(exr_const_context_t ctx, exr_result_t code, const char *text)
{
    void *ud = NULL;
    if (exr_get_user_data(ctx, &ud) != EXR_ERR_SUCCESS || ud == NULL)
        return;
    note_error(ud, code, text);
}

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
            note_error(write_slots[i].err, code, text);
            break;
        }
    pthread_mutex_unlock(&write_slots_lock);
}

#define say core_say /* core/core.h */

/* The OpenEXR message for a failed call rc, or its default text. */
static const char *exr_text(const exr_err *e, exr_result_t rc)
{
    return e->have ? e->text : exr_get_default_error_message(rc);
}

static const char *const chan_rgb[3] = {"R", "G", "B"};
static const char *const chan_y[1] = {"Y"};

static const char *const *chan_names(int channels)
{
    return channels == 3 ? chan_rgb : chan_y;
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
                                    const btdf_write_opts *w, size_t nslices)
{
    const btdf_params *p = btdf_table_get_params(t);
    const char *const *names = chan_names(p->channels);
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
                                 refl ? "rho_r, the reflection of the same facets (BRDF), no "
                                        "cosine factor"
                                      : p->model == BTDF_MODEL_SMITH
                                      ? "rho, the BTDF of the facets of Xu & Sun 2008 with the "
                                        "height-correlated Smith term, no cosine factor"
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
                                     int channels, const float *planes, const exr_err *err,
                                     char *msg, size_t msglen)
{
    int32_t lpc = 1;
    exr_result_t rc = exr_get_scanlines_per_chunk(ctx, part, &lpc);
    if (rc != EXR_ERR_SUCCESS || lpc < 1)
        return say(BTDF_EIO, msg, msglen, "OpenEXR: %s", exr_text(err, rc));
    const char *const *names = chan_names(channels);
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
        return say(BTDF_EIO, msg, msglen, "OpenEXR: %s", exr_text(err, rc));
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

static btdf_status exr_write(const btdf_output_ctx *c, FILE *f, const char *path, char *msg,
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
    if (maxpix > SIZE_MAX / sizeof(float) / (size_t)channels)
        return say(BTDF_EOVERFLOW, msg, msglen, "a slice is too large to convert");
    float *planes = malloc(maxpix * (size_t)channels * sizeof(float));
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
        return say(BTDF_EIO, msg, msglen, "%s", exr_text(&err, rc));
    }
    write_slot_set(ctx, &err, NULL); /* from here on, OpenEXR's messages reach err */
    const char *const *names = chan_names(channels);
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
        for (int ch = 0; ch < channels && rc == EXR_ERR_SUCCESS; ch++)
            rc = exr_add_channel(ctx, part, names[ch], EXR_PIXEL_FLOAT,
                                 EXR_PERCEPTUALLY_LINEAR, 1, 1);
        if (rc == EXR_ERR_SUCCESS)
            rc = set_slice_attrs(ctx, part, kind, &sl);
    }
    if (rc == EXR_ERR_SUCCESS)
        rc = set_table_attrs(ctx, t, c->opts, btdf_table_slice_count(t));
    if (rc == EXR_ERR_SUCCESS)
        rc = exr_write_header(ctx);
    if (rc != EXR_ERR_SUCCESS)
        st = say(rc == EXR_ERR_OUT_OF_MEMORY ? BTDF_ENOMEM : BTDF_EIO, msg, msglen,
                 "OpenEXR header: %s", exr_text(&err, rc));
    for (size_t k = 0; k < nslices && st == BTDF_OK; k++) {
        btdf_slice sl;
        const btdf_table *own;
        file_slice(t, k, &sl, &own);
        st = slice_to_float(&sl, channels, planes, msg, msglen);
        if (st == BTDF_OK)
            st = write_part_pixels(ctx, (int)k, &sl, channels, planes, &err, msg, msglen);
    }
    free(planes);
    rc = exr_finish(&ctx);
    write_slot_set(NULL, NULL, &err);
    if (st == BTDF_OK && rc != EXR_ERR_SUCCESS)
        st = say(BTDF_EIO, msg, msglen, "OpenEXR: %s", exr_text(&err, rc));
    return st;
}

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
    const char *const *names = chan_names(channels);
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
    if (exr_get_channels(r->ctx, part, &cl) != EXR_ERR_SUCCESS || !cl ||
        cl->num_channels != channels)
        return say(BTDF_EFORMAT, r->msg, r->msglen, "part %d does not have %d channel%s",
                   part, channels, channels == 1 ? "" : "s");
    const char *const *names = chan_names(channels);
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
    const char *const *names = chan_names(channels);
    int32_t lpc = 1;
    exr_result_t rc = exr_get_scanlines_per_chunk(r->ctx, part, &lpc);
    if (rc != EXR_ERR_SUCCESS || lpc < 1)
        return say(BTDF_EFORMAT, r->msg, r->msglen, "part %d: %s", part,
                   exr_text(&r->err, rc));
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
                   part, exr_get_error_code_as_string(rc), exr_text(&r->err, rc));
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
                       part, exr_text(&r->err, rc));
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
    uint64_t px = (uint64_t)channels * sizeof(float); /* bytes per pixel, all channels */
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
                         chan_names(channels)[ch], (double)v);
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

static btdf_status exr_read(const char *path, btdf_table **out, char *msg, size_t msglen)
{
    reader r = {NULL, {0, {0}}, path, msg, msglen, 0};
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = on_exr_error;
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
            exr_text(&r.err, rc));
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
    if (st == BTDF_OK && both) {
        char why[200] = "";
        st = btdf_table_new(BTDF_TABLE_FACET_REFLECTION, &p, &tr, why, sizeof why);
        if (st != BTDF_OK)
            st = say(st == BTDF_EINVAL ? BTDF_EFORMAT : st, msg, msglen,
                     "bad parameters in the file: %s", why);
    }
    if (st == BTDF_OK) {
        char why[200] = "";
        st = btdf_table_new(kind, &p, &t, why, sizeof why);
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
    exr_finish(&r.ctx);
    if (st == BTDF_OK && tr) {
        char why[200] = "";
        st = btdf_table_attach_reflection(t, tr, why, sizeof why);
        if (st == BTDF_OK)
            tr = NULL; /* owned by t */
        else
            st = say(BTDF_EFORMAT, msg, msglen, "%s", why);
    }
    btdf_table_free(tr);
    if (st != BTDF_OK) {
        btdf_table_free(t);
        return st;
    }
    *out = t;
    return BTDF_OK;
}

/* The error report and provenance stored in part 0's attributes (set_report). */
static btdf_status exr_stored(const char *path, FILE *out)
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
    exr_finish(&ctx);
    return ferror(out) ? BTDF_EIO : BTDF_OK;
}

const btdf_format_ops btdf_format_exr = {
    .name = "OpenEXR",
    .ext = ".exr",
    .feature = "openexr",
    .available = 1,
    .needs = BTDF_NEEDS_TABLE,
    .write_path = exr_write,
    .read_path = exr_read,
    .stored = exr_stored,
};
