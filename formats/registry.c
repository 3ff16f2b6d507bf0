/* SPDX-License-Identifier: MIT */
/* registry.c: finds a format by extension and writes files atomically. */
#include <ctype.h>
#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "formats.h"

static const btdf_format_ops *const all_formats[] = {&btdf_format_csv, &btdf_format_exr};

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

/* The temporary file being written, removed if a signal ends the process. */
static char pending_tmp[4096];
static volatile sig_atomic_t pending_set;

static void on_signal(int sig)
{
    if (pending_set)
        unlink(pending_tmp); /* async-signal-safe */
    signal(sig, SIG_DFL);
    raise(sig);
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
    if (strlen(path) + 16 >= sizeof pending_tmp) {
        if (msg && msglen)
            snprintf(msg, msglen, "path is longer than %zu bytes", sizeof pending_tmp - 16);
        return BTDF_EINVAL;
    }
    /* The temporary name keeps the extension: some writers choose by it. */
    const char *base = strrchr(path, '/');
    base = base ? base + 1 : path;
    char tmp[sizeof pending_tmp];
    snprintf(tmp, sizeof tmp, "%.*s.%s.tmp%ld%s", (int)(base - path), path, base,
             (long)getpid(), f->ext);
    struct sigaction sa, old_int, old_term;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    memcpy(pending_tmp, tmp, sizeof tmp);
    pending_set = 1;
    sigaction(SIGINT, &sa, &old_int);
    sigaction(SIGTERM, &sa, &old_term);
    btdf_status st;
    if (f->write_path) {
        st = f->write_path(c, tmp, msg, msglen);
    } else {
        FILE *fp = fopen(tmp, "wb");
        if (!fp) {
            if (msg && msglen)
                snprintf(msg, msglen, "cannot create %s: %s", tmp, strerror(errno));
            st = BTDF_EIO;
        } else {
            st = f->write_stream(c, fp, msg, msglen);
            if (fflush(fp) != 0 || ferror(fp)) {
                if (st == BTDF_OK && msg && msglen)
                    snprintf(msg, msglen, "writing %s failed: %s", tmp, strerror(errno));
                if (st == BTDF_OK)
                    st = BTDF_EIO;
            }
            if (fclose(fp) != 0 && st == BTDF_OK) {
                if (msg && msglen)
                    snprintf(msg, msglen, "closing %s failed: %s", tmp, strerror(errno));
                st = BTDF_EIO;
            }
        }
    }
    if (st == BTDF_OK && rename(tmp, path) != 0) {
        if (msg && msglen)
            snprintf(msg, msglen, "cannot rename to %s: %s", path, strerror(errno));
        st = BTDF_EIO;
    }
    if (st != BTDF_OK)
        unlink(tmp);
    pending_set = 0;
    sigaction(SIGINT, &old_int, NULL);
    sigaction(SIGTERM, &old_term, NULL);
    return st;
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
    btdf_output_ctx c = {t, w ? w : &none};
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
