/* SPDX-License-Identifier: MIT */
/* registry.c: finds a format by extension and writes files atomically. */
#include <ctype.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "formats.h"
#include "tmpfile.h"

static const btdf_format_ops *const all_formats[] = {&btdf_format_csv, &btdf_format_exr,
                                                     &btdf_format_xml};

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

const btdf_format_ops *btdf_format_for_path(const char *path)
{
    if (!path)
        return NULL;
    for (size_t i = 0; i < sizeof all_formats / sizeof all_formats[0]; i++)
        if (ext_is(path, all_formats[i]->ext))
            return all_formats[i];
    return NULL;
}

BTDF_API int btdf_format_available(const char *ext)
{
    if (!ext)
        return 0;
    char buf[32];
    snprintf(buf, sizeof buf, "%s%s", ext[0] == '.' ? "" : ".", ext);
    const btdf_format_ops *f = btdf_format_for_path(buf);
    return f && f->available;
}

typedef struct reg_ctx {
    const btdf_format_ops *f;
    const btdf_output_ctx *c;
} reg_ctx;

static btdf_status reg_write(void *ctx, const char *tmp, char *msg, size_t msglen)
{
    const reg_ctx *r = ctx;
    if (r->f->write_path)
        return r->f->write_path(r->c, tmp, msg, msglen);
    FILE *fp = fopen(tmp, "wb");
    if (!fp) {
        if (msg && msglen)
            snprintf(msg, msglen, "cannot create %s: %s", tmp, strerror(errno));
        return BTDF_EIO;
    }
    btdf_status st = r->f->write_stream(r->c, fp, msg, msglen);
    int bad = fflush(fp) != 0 || ferror(fp);
    bad |= fclose(fp) != 0;
    if (st == BTDF_OK && bad) {
        if (msg && msglen)
            snprintf(msg, msglen, "writing %s failed: %s", tmp, strerror(errno));
        st = BTDF_EIO;
    }
    return st;
}

btdf_status btdf_write_atomic(const btdf_format_ops *f, const btdf_output_ctx *c,
                              const char *path, char *msg, size_t msglen)
{
    if (!f->available) {
        if (msg && msglen)
            snprintf(msg, msglen, "%s support was switched off at build time (-D%s=disabled)",
                     f->name, f->feature ? f->feature : f->name);
        return BTDF_ENOTSUP;
    }
    reg_ctx r = {f, c};
    return btdf_write_file_atomic(path, f->ext, reg_write, &r, msg, msglen);
}

BTDF_API btdf_status btdf_table_write(const btdf_table *t, const char *path,
                                      const btdf_write_opts *w, char *msg, size_t msglen)
{
    if (!t || !path)
        return BTDF_EINVAL;
    const btdf_format_ops *f = btdf_format_for_path(path);
    if (!f || (!f->write_path && !f->write_stream)) {
        if (msg && msglen)
            snprintf(msg, msglen, "unknown table format of '%s': use .csv or .exr", path);
        return BTDF_EINVAL;
    }
    btdf_write_opts none = {NULL, NULL};
    btdf_output_ctx c = {t, w ? w : &none, NULL};
    return btdf_write_atomic(f, &c, path, msg, msglen);
}

BTDF_API btdf_status btdf_table_read(const char *path, btdf_table **out, char *msg,
                                     size_t msglen)
{
    if (!path || !out)
        return BTDF_EINVAL;
    const btdf_format_ops *f = btdf_format_for_path(path);
    if (!f || !f->read_path) {
        if (msg && msglen)
            snprintf(msg, msglen, "unknown table format of '%s': use .csv or .exr", path);
        return BTDF_EINVAL;
    }
    if (!f->available) {
        if (msg && msglen)
            snprintf(msg, msglen, "%s support was switched off at build time (-D%s=disabled)",
                     f->name, f->feature ? f->feature : f->name);
        return BTDF_ENOTSUP;
    }
    return f->read_path(path, out, msg, msglen);
}
