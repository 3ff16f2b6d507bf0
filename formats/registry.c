/* SPDX-License-Identifier: MIT */
/* registry.c: the one list of formats, and the one write, read and inspect path. */
#include <ctype.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "btdf_radiance.h"
#include "formats/formats.h"
#include "core/core.h"
#include "io/tmpfile.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static const fmt_ops *const all_formats[] = {&fmt_csv, &fmt_exr,
                                                     &fmt_bsdf, &fmt_png,
                                                     &fmt_xml};
#define NFORMATS (sizeof all_formats / sizeof all_formats[0])

static int ext_is(const char *path, const char *ext)
{
    size_t lp = strlen(path), le = strlen(ext);
    if (lp < le)
        return 0;
    for (size_t i = 0; i < le; i++)
        if (tolower((unsigned char)path[lp - le + i]) != tolower((unsigned char)ext[i]))
            return 0;
    return 1;
}

const fmt_ops *fmt_for_path(const char *path)
{
    if (!path)
        return NULL;
    for (size_t i = 0; i < NFORMATS; i++)
        if (ext_is(path, all_formats[i]->ext))
            return all_formats[i];
    return NULL;
}

BTDF_API int btdf_format_find(const char *path, btdf_format_info *info)
{
    const fmt_ops *f = fmt_for_path(path);
    if (!f)
        return 0;
    if (info) {
        info->name = f->name;
        info->ext = f->ext;
        info->feature = f->feature;
        info->available = f->available;
        info->needs = f->needs;
        info->can_stream = f->write_stream != NULL;
        info->can_read = f->read_path != NULL || f->read_series != NULL || f->read_rad != NULL;
    }
    return 1;
}

BTDF_API const char *btdf_format_list(void)
{
    return ".csv .exr .bsdf .png .xml"; /* the order of all_formats */
}

BTDF_API int btdf_format_available(const char *ext)
{
    if (!ext)
        return 0;
    char buf[32];
    snprintf(buf, sizeof buf, "%s%s", ext[0] == '.' ? "" : ".", ext);
    const fmt_ops *f = fmt_for_path(buf);
    return f && f->available;
}

static btdf_status switched_off(const fmt_ops *f, char *msg, size_t msglen)
{
    return core_say(BTDF_ENOTSUP, msg, msglen,
               "%s support was switched off at build time (-D%s=disabled)", f->name,
               f->feature ? f->feature : f->name);
}

/* ------------------------------------------------------------------------- */
/* Writing                                                                   */
/* ------------------------------------------------------------------------- */

typedef struct reg_ctx {
    const fmt_ops *f;
    const fmt_output_ctx *c;
} reg_ctx;

static btdf_status reg_write(void *ctx, FILE *fp, const char *tmp, char *msg, size_t msglen)
{
    const reg_ctx *r = ctx;
    if (r->f->write_path)
        return r->f->write_path(r->c, fp, tmp, msg, msglen);
    return r->f->write_stream(r->c, fp, msg, msglen);
}

btdf_status fmt_write_atomic(const fmt_ops *f, const fmt_output_ctx *c,
                              const char *path, char *msg, size_t msglen)
{
    if (!f->available)
        return switched_off(f, msg, msglen);
    reg_ctx r = {f, c};
    return io_write_file_atomic(path, f->ext, reg_write, &r, msg, msglen);
}

/* The text each picture kind stores in its PNG (indexed by btdf_preview_kind). */
static const char *picture_description(btdf_preview_kind kind)
{
    static const char *const what[3] = {"btdftab polar plot of rho |cos to|",
                                        "btdftab montage of table slices",
                                        "btdftab render of a rough face"};
    return kind >= 0 && kind < 3 ? what[kind] : NULL;
}

/* Draws the picture, then writes it like any other output. */
static btdf_status write_picture(const fmt_ops *f, fmt_output_ctx *c,
                                 const btdf_preview_opts *po, const char *path, char *msg,
                                 size_t msglen)
{
    unsigned char *rgb = NULL;
    btdf_status st = btdf_preview_render(po, &rgb, &c->width, &c->height, msg, msglen);
    if (st != BTDF_OK)
        return st;
    c->rgb = rgb;
    c->description = picture_description(po->kind);
    st = fmt_write_atomic(f, c, path, msg, msglen);
    btdf_preview_free(rgb);
    return st;
}

BTDF_API btdf_status btdf_write(const btdf_output *what, const char *path, char *msg,
                                size_t msglen)
{
    if (!what || !path || !*path)
        return core_say(BTDF_EINVAL, msg, msglen, "no object or no file name%s%s", "", "");
    int to_stdout = !strcmp(path, "-");
    const fmt_ops *f = to_stdout ? &fmt_csv : fmt_for_path(path);
    if (!f)
        return core_say(BTDF_EINVAL, msg, msglen, "unknown format of '%s': use %s", path,
                   btdf_format_list());
    if (!f->available)
        return switched_off(f, msg, msglen);
    btdf_write_opts none = {NULL, NULL, NULL};
    fmt_output_ctx c;
    memset(&c, 0, sizeof c);
    c.opts = what->opts ? what->opts : &none;
    switch (f->needs) {
    case BTDF_NEEDS_TABLE: c.table = what->table; break;
    case BTDF_NEEDS_SERIES:
        c.scatfun = what->scatfun;
        c.metadata_json = what->metadata_json;
        break;
    case BTDF_NEEDS_PICTURE:
        if (!what->picture)
            break;
        return write_picture(f, &c, what->picture, path, msg, msglen);
    case BTDF_NEEDS_RADIANCE: c.rad = what->radiance; break;
    default: break;
    }
    if (!c.table && !c.scatfun && !c.rad)
        return core_say(BTDF_EINVAL, msg, msglen, "%s: nothing to write as %s", path, f->name);
    if (to_stdout) {
        btdf_status st = f->write_stream(&c, stdout, msg, msglen);
        if (st == BTDF_OK && fflush(stdout) != 0)
            st = core_say(BTDF_EIO, msg, msglen, "standard output: %s%s", strerror(errno), "");
        return st;
    }
    return fmt_write_atomic(f, &c, path, msg, msglen);
}

BTDF_API btdf_status btdf_write_table_layers(const btdf_table *t, const btdf_layer *layers,
                                             size_t nlayers, const char *value,
                                             const btdf_write_opts *w, const char *path,
                                             char *msg, size_t msglen)
{
    if (!t || !path)
        return core_say(BTDF_EINVAL, msg, msglen, "no table or no path");
    const fmt_ops *f = fmt_for_path(path);
    if (!f || f->needs != BTDF_NEEDS_TABLE)
        return core_say(BTDF_EINVAL, msg, msglen, "'%s': a table with layers is written as .exr",
                        path);
    if (!f->available)
        return switched_off(f, msg, msglen);
    if (nlayers && f != &fmt_exr)
        return core_say(BTDF_EINVAL, msg, msglen, "'%s': only .exr holds more layers", path);
    btdf_write_opts none = {NULL, NULL, NULL};
    fmt_output_ctx c;
    memset(&c, 0, sizeof c);
    c.opts = w ? w : &none;
    c.table = t;
    c.layers = layers;
    c.nlayers = layers ? nlayers : 0;
    c.value = value;
    return fmt_write_atomic(f, &c, path, msg, msglen);
}

BTDF_API btdf_status btdf_table_write(const btdf_table *t, const char *path,
                                      const btdf_write_opts *w, char *msg, size_t msglen)
{
    if (!t || !path)
        return BTDF_EINVAL;
    const fmt_ops *f = fmt_for_path(path);
    if (!f || f->needs != BTDF_NEEDS_TABLE)
        return core_say(BTDF_EINVAL, msg, msglen, "unknown table format of '%s': use .csv or .exr%s",
                   path, "");
    btdf_output what = {t, NULL, NULL, w, NULL, NULL};
    return btdf_write(&what, path, msg, msglen);
}

BTDF_API btdf_status btdf_preview_write(const btdf_preview_opts *o, const char *path,
                                        char *msg, size_t msglen)
{
    if (!path || !*path)
        return core_say(BTDF_EINVAL, msg, msglen, "no file name%s%s", "", "");
    if (!fmt_png.available)
        return switched_off(&fmt_png, msg, msglen);
    fmt_output_ctx c;
    memset(&c, 0, sizeof c);
    btdf_write_opts none = {NULL, NULL, NULL};
    c.opts = &none;
    return write_picture(&fmt_png, &c, o, path, msg, msglen);
}

BTDF_API btdf_status btdf_scatfun_write(const btdf_scatfun *f, const char *path,
                                        const char *metadata_json, char *msg, size_t msglen)
{
    if (!f || !path || !*path)
        return core_say(BTDF_EINVAL, msg, msglen, "file or path missing%s%s", "", "");
    fmt_output_ctx c;
    memset(&c, 0, sizeof c);
    btdf_write_opts none = {NULL, NULL, NULL};
    c.opts = &none;
    c.scatfun = f;
    c.metadata_json = metadata_json;
    char why[256] = "";
    btdf_status st = fmt_write_atomic(&fmt_bsdf, &c, path, why, sizeof why);
    if (st != BTDF_OK)
        core_say(st, msg, msglen, "%s: %s", path, why);
    return st;
}

static btdf_status buffer_writer(void *ctx, FILE *f, const char *tmp, char *msg, size_t msglen)
{
    return io_write_bytes(ctx, f, tmp, msg, msglen);
}

BTDF_API btdf_status btdf_write_buffer(const char *path, const char *ext, const void *data,
                                       size_t len, char *msg, size_t msglen)
{
    if (!path || !*path || (!data && len))
        return core_say(BTDF_EINVAL, msg, msglen, "no file name or no data%s%s", "", "");
    io_bytes b = {data, len};
    return io_write_file_atomic(path, ext, buffer_writer, &b, msg, msglen);
}

BTDF_API void btdf_remove_partial_files(void)
{
    tmp_remove_all();
}

/* ------------------------------------------------------------------------- */
/* Reading                                                                   */
/* ------------------------------------------------------------------------- */

BTDF_API btdf_status btdf_read(const char *path, btdf_input *in, char *msg, size_t msglen)
{
    if (!path || !in)
        return BTDF_EINVAL;
    memset(in, 0, sizeof *in);
    const fmt_ops *f = fmt_for_path(path);
    if (!f || (!f->read_path && !f->read_series && !f->read_rad))
        return core_say(BTDF_EINVAL, msg, msglen, "not a file format btdf reads: use .csv, .exr, "
                   ".bsdf or .xml%s%s", "", "");
    if (!f->available)
        return switched_off(f, msg, msglen);
    /* A FIFO would block the open and a device (/dev/zero) never end: only regular
       files are read (stat first, so that nothing is opened that could hang). */
    struct stat rs;
    if (stat(path, &rs) == 0 && !S_ISREG(rs.st_mode))
        return core_say(BTDF_EINVAL, msg, msglen, "not a regular file (%s): btdftab reads "
                        "tables, .bsdf and .xml from files%s",
                        S_ISFIFO(rs.st_mode) ? "a pipe" : S_ISDIR(rs.st_mode) ? "a folder"
                                                                            : "a device", "");
    /* One wording for a file that cannot be opened, whatever its format. */
    FILE *probe = fopen(path, "rb");
    if (!probe)
        return core_say(BTDF_EIO, msg, msglen, "cannot open: %s%s", strerror(errno), "");
    fclose(probe);
    if (f->read_series)
        return f->read_series(path, &in->scatfun, msg, msglen);
    if (f->read_rad)
        return f->read_rad(path, &in->radiance, msg, msglen);
    return f->read_path(path, &in->table, msg, msglen);
}

BTDF_API btdf_status btdf_table_read(const char *path, btdf_table **out, char *msg,
                                     size_t msglen)
{
    if (!path || !out)
        return BTDF_EINVAL;
    const fmt_ops *f = fmt_for_path(path);
    if (!f || !f->read_path)
        return core_say(BTDF_EINVAL, msg, msglen, "unknown table format of '%s': use .csv or .exr%s",
                   path, "");
    btdf_input in;
    btdf_status st = btdf_read(path, &in, msg, msglen);
    if (st == BTDF_OK)
        *out = in.table;
    return st;
}

/* The ranges, sizes and slices of one part; label prefixes its lines ("" for a table
   of one part, so that those print as they always have). */
static void inspect_part(const btdf_table *t, FILE *out, const char *label)
{
    const btdf_params *p = btdf_table_get_params(t);
    btdf_table_kind kind = btdf_table_get_kind(t);
    size_t ns = btdf_table_slice_count(t), nodes = btdf_table_node_count(t);
    btdf_slice s0, s1;
    if (ns > 0 && btdf_table_slice(t, 0, &s0) == BTDF_OK &&
        btdf_table_slice(t, ns - 1, &s1) == BTDF_OK) {
        if (kind == BTDF_TABLE_FACET_RECIPROCAL) /* slices are indexed by pi - theta_o */
            fprintf(out, "%stheta_i range: 0:90 deg (slices over theta_o %.6g:%.6g deg)\n",
                    label, 180.0 - s1.ti * 180.0 / M_PI, 180.0 - s0.ti * 180.0 / M_PI);
        else
            fprintf(out, "%stheta_i range: %.6g:%.6g deg\n", label, s0.ti * 180.0 / M_PI,
                    s1.ti * 180.0 / M_PI);
    }
    /* Value range over every node of every channel. */
    double lo = 0.0, hi = 0.0;
    int first = 1;
    for (size_t k = 0; k < ns; k++) {
        btdf_slice s;
        if (btdf_table_slice(t, k, &s) != BTDF_OK)
            continue;
        size_t m = s.nrows * s.ncols * (size_t)p->channels;
        for (size_t q = 0; q < m; q++) {
            if (first || s.values[q] < lo)
                lo = s.values[q];
            if (first || s.values[q] > hi)
                hi = s.values[q];
            first = 0;
        }
    }
    fprintf(out, "%s%s range: %.6g to %.6g 1/sr\n", label,
            kind == BTDF_TABLE_FACET_REFLECTION ? "rho_r" : "rho", lo, hi);
    fprintf(out, "%sslices: %zu\n%snodes: %zu\n%svalues: %zu doubles (%.1f MiB in memory)\n",
            label, ns, label, nodes, label, nodes * (size_t)p->channels,
            (double)(nodes * (size_t)(p->channels + 2) * sizeof(double)) / 1048576.0);
    for (size_t k = 0; k < ns; k++) {
        btdf_slice s;
        btdf_table_slice(t, k, &s);
        fprintf(out, "%sslice %zu: index %.6f deg, %zu x %zu\n", label, k, s.ti * 180.0 / M_PI,
                s.nrows, s.ncols);
    }
}

/* The summary of a table file: its header, ranges and sizes, then one line per slice. */
static btdf_status table_inspect(const btdf_input *in, FILE *out)
{
    const btdf_table *t = in->table;
    const btdf_params *p = btdf_table_get_params(t);
    btdf_table_kind kind = btdf_table_get_kind(t);
    char b[40];
    fprintf(out, "kind: %s\nchannels: %d\nior:", btdf_table_kind_name(kind), p->channels);
    for (int ch = 0; ch < p->channels; ch++) {
        btdf_format_double(p->ior[ch], b, sizeof b);
        fprintf(out, " %s", b);
    }
    btdf_format_double(p->smoothness, b, sizeof b);
    fprintf(out, "\nsmoothness: %s\n", b);
    btdf_format_double(p->k0, b, sizeof b);
    fprintf(out, "k0: %s\nmodel: %s\n", b, btdf_model_name(p->model));
    if (kind != BTDF_TABLE_GRID) /* what the slices interpolate (docs/tables.md) */
        fprintf(out, "slice rule: %s\n", btdf_table_rule_name(btdf_table_get_rule(t)));
    const btdf_table *tr = btdf_table_parts(t) == BTDF_PART_BOTH
                               ? btdf_table_part(t, BTDF_PART_REFLECTION) : NULL;
    if (tr)
        fprintf(out, "parts: transmission, reflection (kind %s, slice rule %s)\n",
                btdf_table_kind_name(btdf_table_get_kind(tr)),
                btdf_table_rule_name(btdf_table_get_rule(tr)));
    inspect_part(t, out, "");
    if (tr)
        inspect_part(tr, out, "reflection ");
    return ferror(out) ? BTDF_EIO : BTDF_OK;
}

BTDF_API btdf_status btdf_inspect(const char *path, FILE *out, char *msg, size_t msglen)
{
    if (!out)
        return BTDF_EINVAL;
    btdf_input in;
    btdf_status st = btdf_read(path, &in, msg, msglen);
    if (st != BTDF_OK)
        return st;
    const fmt_ops *f = fmt_for_path(path);
    struct stat sb;
    if (stat(path, &sb) == 0)
        fprintf(out, "file: %s, %s, %lld bytes\n", path, f->name, (long long)sb.st_size);
    if (f->stored)
        st = f->stored(path, out);
    if (st == BTDF_OK)
        st = f->inspect ? f->inspect(&in, out) : table_inspect(&in, out);
    if (st == BTDF_OK && fflush(out) != 0)
        st = BTDF_EIO;
    if (st != BTDF_OK)
        core_say(st, msg, msglen, "%s: printing failed: %s", path, strerror(errno));
    btdf_table_free(in.table);
    btdf_scatfun_free(in.scatfun);
    btdf_rad_free(in.radiance);
    return st;
}
