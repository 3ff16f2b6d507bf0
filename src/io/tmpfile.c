/* SPDX-License-Identifier: MIT */
/* tmpfile.c: names for files being written, so that a signal handler can remove them. */
#define _XOPEN_SOURCE 700 /* realpath */
#include <dirent.h>
#include <errno.h>
#include <limits.h>
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

#include "btdf_io.h"
#include "io/tmpfile.h"
#include "core/core.h"

/*
 * Every writer of the library writes `path` under a temporary name beside it and
 * renames at the end. The names of the files being written are kept here, so that a
 * program (the btdftab tool does) can remove them from a SIGINT or SIGTERM handler
 * with btdf_tmp_remove_all, which only reads flags and calls unlink: both are
 * async-signal-safe. The library itself installs no signal handler.
 *
 * The temporary name is `.NAME.tmpPID-K.EXT` beside the output: NAME is the output's
 * own name, cut short where needed so that the whole name stays within the 255 bytes a
 * directory entry may have (so any legal output name works), PID the writing process,
 * K a counter within it, EXT the output's extension (some writers choose the format by
 * it). A process killed outright (SIGKILL, a power cut) leaves such a file; the next
 * write into the same folder removes those whose process no longer exists.
 */
#define SLOTS 32
#define NAME 4096
#define NAME_MAX_BYTES 255 /* one directory entry; POSIX NAME_MAX on Linux file systems */

static char names[SLOTS][NAME];
static volatile sig_atomic_t used[SLOTS];
static pthread_mutex_t lock = PTHREAD_MUTEX_INITIALIZER;
static unsigned long counter;

/* The one message helper (core/core.h), in this file's argument order. */
#define say(msg, msglen, ...) ((void)core_say(BTDF_OK, msg, msglen, __VA_ARGS__))

int btdf_tmp_begin(const char *path, const char *ext, char *tmp, size_t tmplen)
{
    const char *base = strrchr(path, '/');
    base = base ? base + 1 : path;
    if (!ext)
        ext = "";
    pthread_mutex_lock(&lock);
    unsigned long k = counter++;
    int slot = -1;
    for (int i = 0; i < SLOTS && slot < 0; i++)
        if (!used[i])
            slot = i;
    /* the fixed part: ".", ".tmp", the pid, "-", the counter and the extension */
    char tail[96];
    int tl = snprintf(tail, sizeof tail, ".tmp%ld-%lu%s", (long)getpid(), k, ext);
    size_t keep = strlen(base);
    if (tl < 0 || (size_t)tl >= sizeof tail || (size_t)tl + 1 >= NAME_MAX_BYTES) {
        pthread_mutex_unlock(&lock);
        return -2;
    }
    if (1 + keep + (size_t)tl > NAME_MAX_BYTES)
        keep = NAME_MAX_BYTES - 1 - (size_t)tl; /* the name is cut, the counter keeps it unique */
    int n = snprintf(tmp, tmplen, "%.*s.%.*s%s", (int)(base - path), path, (int)keep, base, tail);
    if (n < 0 || (size_t)n >= tmplen || (size_t)n >= NAME) {
        pthread_mutex_unlock(&lock);
        return -2;
    }
    if (slot >= 0) {
        memcpy(names[slot], tmp, (size_t)n + 1);
        used[slot] = 1;
    }
    pthread_mutex_unlock(&lock);
    return slot; /* -1 when all slots are taken: the file is still written, untracked */
}

void btdf_tmp_end(int slot)
{
    if (slot < 0 || slot >= SLOTS)
        return;
    pthread_mutex_lock(&lock);
    used[slot] = 0;
    pthread_mutex_unlock(&lock);
}

void btdf_tmp_remove_all(void)
{
    for (int i = 0; i < SLOTS; i++)
        if (used[i])
            unlink(names[i]);
}

/* ------------------------------------------------------------------------- */
/* Stale temporaries                                                         */
/* ------------------------------------------------------------------------- */

static int all_digits(const char *s, const char *end)
{
    if (s == end)
        return 0;
    for (; s < end; s++)
        if (*s < '0' || *s > '9')
            return 0;
    return 1;
}

long btdf_tmp_name_pid(const char *name)
{
    if (!name || name[0] != '.')
        return 0;
    for (const char *p = strstr(name + 1, ".tmp"); p; p = strstr(p + 1, ".tmp")) {
        const char *d = p + 4, *dash = strchr(d, '-');
        if (!dash || !all_digits(d, dash) || dash - d > 18)
            continue;
        const char *k = dash + 1, *e = k;
        while (*e >= '0' && *e <= '9')
            e++;
        if (e == k)
            continue;
        if (*e == '.') { /* an extension: letters and digits only */
            const char *x = e + 1;
            while ((*x >= 'a' && *x <= 'z') || (*x >= 'A' && *x <= 'Z') ||
                   (*x >= '0' && *x <= '9'))
                x++;
            if (x == e + 1 || *x)
                continue;
        } else if (*e) {
            continue;
        }
        long pid = strtol(d, NULL, 10);
        return pid > 0 ? pid : 0;
    }
    return 0;
}

size_t btdf_tmp_sweep(const char *path)
{
    const char *slash = strrchr(path, '/');
    char dir[NAME];
    if (!slash)
        snprintf(dir, sizeof dir, ".");
    else if (slash == path)
        snprintf(dir, sizeof dir, "/");
    else if ((size_t)(slash - path) < sizeof dir)
        snprintf(dir, sizeof dir, "%.*s", (int)(slash - path), path);
    else
        return 0;
    DIR *d = opendir(dir);
    if (!d)
        return 0;
    size_t removed = 0;
    long self = (long)getpid();
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
        long pid = btdf_tmp_name_pid(e->d_name);
        if (pid <= 0 || pid == self || (long)(pid_t)pid != pid)
            continue;
        /* only a process that is gone: EPERM means it exists under another user */
        if (kill((pid_t)pid, 0) == 0 || errno != ESRCH)
            continue;
        char full[NAME + NAME_MAX_BYTES + 2];
        snprintf(full, sizeof full, "%s/%s", dir, e->d_name);
        struct stat st;
        if (lstat(full, &st) == 0 && S_ISREG(st.st_mode) && unlink(full) == 0)
            removed++;
    }
    closedir(d);
    return removed;
}

/* ------------------------------------------------------------------------- */
/* What may be written                                                       */
/* ------------------------------------------------------------------------- */

BTDF_API btdf_status btdf_output_check(const char *path, char *msg, size_t msglen)
{
    if (!path || !path[0]) {
        say(msg, msglen, "%s%san empty file name", "", "");
        return BTDF_EINVAL;
    }
    const char *slash = strrchr(path, '/');
    const char *base = slash ? slash + 1 : path;
    if (!base[0] || !strcmp(base, ".") || !strcmp(base, "..")) {
        say(msg, msglen, "%s%sis a folder, not a file name", "", "");
        return BTDF_EINVAL;
    }
    if (strlen(base) > NAME_MAX_BYTES) {
        say(msg, msglen, "the file name is longer than %s bytes%s", "255", "");
        return BTDF_EINVAL;
    }
    if (strlen(path) >= NAME - 64) {
        say(msg, msglen, "the path is longer than %s bytes%s", "4032", "");
        return BTDF_EINVAL;
    }
    struct stat st;
    if (lstat(path, &st) == 0) {
        if (S_ISDIR(st.st_mode)) {
            say(msg, msglen, "is a folder%s%s", "", "");
            return BTDF_EINVAL;
        }
        if (!S_ISREG(st.st_mode)) {
            say(msg, msglen,
                "is not a regular file (a device, pipe, socket or symbolic link): refusing to "
                "replace it%s%s", "", "");
            return BTDF_EINVAL;
        }
    } else if (errno != ENOENT) {
        say(msg, msglen, "cannot look at it: %s%s", strerror(errno), "");
        return BTDF_EIO;
    }
    char dir[NAME];
    if (!slash)
        snprintf(dir, sizeof dir, ".");
    else if (slash == path)
        snprintf(dir, sizeof dir, "/");
    else
        snprintf(dir, sizeof dir, "%.*s", (int)(slash - path), path);
    if (stat(dir, &st) != 0) {
        say(msg, msglen, "cannot write in the folder '%s': %s", dir, strerror(errno));
        return BTDF_EIO;
    }
    if (!S_ISDIR(st.st_mode)) {
        say(msg, msglen, "cannot write in the folder '%s': %s", dir, strerror(ENOTDIR));
        return BTDF_EIO;
    }
    if (access(dir, W_OK | X_OK) != 0) {
        say(msg, msglen, "cannot write in the folder '%s': %s", dir, strerror(errno));
        return BTDF_EIO;
    }
    return BTDF_OK;
}

/* The canonical name of path: the real path of its folder, then its own name. */
static int canonical(const char *path, char *out, size_t outlen)
{
    const char *slash = strrchr(path, '/');
    char dir[NAME];
    if (!slash)
        snprintf(dir, sizeof dir, ".");
    else if (slash == path)
        snprintf(dir, sizeof dir, "/");
    else
        snprintf(dir, sizeof dir, "%.*s", (int)(slash - path), path);
    char *real = realpath(dir, NULL);
    if (!real)
        return 0;
    int n = snprintf(out, outlen, "%s/%s", real, slash ? slash + 1 : path);
    free(real);
    return n > 0 && (size_t)n < outlen;
}

BTDF_API int btdf_same_file(const char *a, const char *b)
{
    if (!a || !b)
        return 0;
    if (!strcmp(a, b))
        return 1;
    struct stat sa, sb;
    if (stat(a, &sa) == 0 && stat(b, &sb) == 0)
        return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
    char ca[NAME + NAME_MAX_BYTES + 2], cb[NAME + NAME_MAX_BYTES + 2];
    return canonical(a, ca, sizeof ca) && canonical(b, cb, sizeof cb) && !strcmp(ca, cb);
}

/* Nothing that is not a regular file is ever replaced: a device, a pipe, a folder. */
static btdf_status replaceable(const char *path, char *msg, size_t msglen)
{
    struct stat st;
    if (lstat(path, &st) == 0 && !S_ISREG(st.st_mode)) {
        say(msg, msglen, "%s is not a regular file (a %s): refusing to replace it", path,
            S_ISDIR(st.st_mode) ? "folder" : "device, pipe, socket or symbolic link");
        return BTDF_EINVAL;
    }
    return BTDF_OK;
}

/* ------------------------------------------------------------------------- */
/* Writing, alone or as a group                                              */
/* ------------------------------------------------------------------------- */

typedef struct pending {
    char tmp[NAME];
    char path[NAME];
    int slot;
} pending;

static struct group {
    int open;
    int failed;
    size_t n;
    pending p[SLOTS];
} grp;

void btdf_tmp_group_begin(void)
{
    btdf_tmp_group_abort();
    grp.open = 1;
}

void btdf_tmp_group_abort(void)
{
    for (size_t i = 0; i < grp.n; i++) {
        unlink(grp.p[i].tmp);
        btdf_tmp_end(grp.p[i].slot);
    }
    grp.n = 0;
    grp.open = 0;
    grp.failed = 0;
}

btdf_status btdf_tmp_group_commit(char *msg, size_t msglen)
{
    if (!grp.open)
        return BTDF_OK;
    btdf_status st = grp.failed ? BTDF_EIO : BTDF_OK;
    if (grp.failed)
        say(msg, msglen, "an earlier output of the run failed: nothing was written%s%s", "", "");
    for (size_t i = 0; i < grp.n && st == BTDF_OK; i++)
        st = replaceable(grp.p[i].path, msg, msglen);
    if (st != BTDF_OK) {
        btdf_tmp_group_abort();
        return st;
    }
    /* Keep a hard link to each file about to be replaced, so that a rename failing
       half-way can put the earlier files back. */
    char bak[SLOTS][NAME];
    int bslot[SLOTS], have_bak[SLOTS], done[SLOTS];
    for (size_t i = 0; i < grp.n; i++) {
        have_bak[i] = 0;
        done[i] = 0;
        bslot[i] = -1;
        if (access(grp.p[i].path, F_OK) != 0)
            continue;
        bslot[i] = btdf_tmp_begin(grp.p[i].path, ".bak", bak[i], sizeof bak[i]);
        if (bslot[i] != -2 && link(grp.p[i].path, bak[i]) == 0)
            have_bak[i] = 1;
    }
    size_t i = 0;
    for (; i < grp.n; i++) {
        if (rename(grp.p[i].tmp, grp.p[i].path) != 0) {
            say(msg, msglen, "%s: cannot rename the finished file into place: %s",
                grp.p[i].path, strerror(errno));
            st = BTDF_EIO;
            break;
        }
        done[i] = 1;
    }
    for (size_t k = 0; k < grp.n; k++) {
        if (st != BTDF_OK && done[k]) { /* undo: the earlier file, or none */
            if (have_bak[k])
                rename(bak[k], grp.p[k].path);
            else
                unlink(grp.p[k].path);
        }
        if (have_bak[k])
            unlink(bak[k]); /* a link: the file itself stays */
        if (bslot[k] >= 0)
            btdf_tmp_end(bslot[k]);
        if (!done[k])
            unlink(grp.p[k].tmp);
        btdf_tmp_end(grp.p[k].slot);
    }
    grp.n = 0;
    grp.open = 0;
    grp.failed = 0;
    return st;
}

BTDF_API void btdf_outputs_begin(void)
{
    btdf_tmp_group_begin();
}

BTDF_API btdf_status btdf_outputs_commit(char *msg, size_t msglen)
{
    return btdf_tmp_group_commit(msg, msglen);
}

BTDF_API void btdf_outputs_abort(void)
{
    btdf_tmp_group_abort();
}

btdf_status btdf_write_file_atomic(const char *path, const char *ext, btdf_file_writer writer,
                                   void *ctx, char *msg, size_t msglen)
{
    btdf_status st = replaceable(path, msg, msglen);
    if (st != BTDF_OK) {
        grp.failed |= grp.open;
        return st;
    }
    btdf_tmp_sweep(path);
    char tmp[NAME];
    int slot = btdf_tmp_begin(path, ext, tmp, sizeof tmp);
    if (slot == -2) {
        say(msg, msglen, "path is longer than %s bytes%s", "4032", "");
        grp.failed |= grp.open;
        return BTDF_EINVAL;
    }
    if (grp.open && grp.n == SLOTS) {
        btdf_tmp_end(slot);
        say(msg, msglen, "more than %s outputs in one group%s", "32", "");
        grp.failed = 1;
        return BTDF_EINVAL;
    }
    st = writer(ctx, tmp, msg, msglen);
    if (st == BTDF_OK && grp.open) { /* renamed with the rest of the group, or removed */
        pending *p = &grp.p[grp.n++];
        snprintf(p->tmp, sizeof p->tmp, "%s", tmp);
        snprintf(p->path, sizeof p->path, "%s", path);
        p->slot = slot;
        return BTDF_OK;
    }
    if (st == BTDF_OK)
        st = replaceable(path, msg, msglen); /* it may have appeared while writing */
    if (st == BTDF_OK && rename(tmp, path) != 0) {
        say(msg, msglen, "cannot rename the finished file into place: %s%s", strerror(errno),
            "");
        st = BTDF_EIO;
    }
    if (st != BTDF_OK) {
        unlink(tmp); /* no partial file: the output either appears whole or not at all */
        grp.failed |= grp.open;
    }
    btdf_tmp_end(slot);
    return st;
}

btdf_status btdf_write_bytes(void *ctx, const char *tmp, char *msg, size_t msglen)
{
    const btdf_bytes *b = ctx;
    FILE *f = fopen(tmp, "wb");
    if (!f) {
        say(msg, msglen, "cannot create %s: %s", tmp, strerror(errno));
        return BTDF_EIO;
    }
    int bad = fwrite(b->data, 1, b->len, f) != b->len;
    bad |= fflush(f) != 0;
    bad |= fclose(f) != 0;
    if (bad) {
        say(msg, msglen, "writing %s failed: %s", tmp, strerror(errno));
        return BTDF_EIO;
    }
    return BTDF_OK;
}
