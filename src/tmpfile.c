/* SPDX-License-Identifier: MIT */
/* tmpfile.c: names for files being written, so that a signal handler can remove them. */
#include <errno.h>
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "tmpfile.h"

/*
 * Every writer of the library writes `path` under a temporary name beside it and
 * renames at the end. The names of the files being written are kept here, so that a
 * program (the btdftab tool does) can remove them from a SIGINT or SIGTERM handler
 * with btdf_tmp_remove_all, which only reads flags and calls unlink: both are
 * async-signal-safe. The library itself installs no signal handler.
 */
#define SLOTS 32
#define NAME 4096

static char names[SLOTS][NAME];
static volatile sig_atomic_t used[SLOTS];
static pthread_mutex_t lock = PTHREAD_MUTEX_INITIALIZER;
static unsigned long counter;

int btdf_tmp_begin(const char *path, const char *ext, char *tmp, size_t tmplen)
{
    const char *base = strrchr(path, '/');
    base = base ? base + 1 : path;
    pthread_mutex_lock(&lock);
    unsigned long k = counter++;
    int slot = -1;
    for (int i = 0; i < SLOTS && slot < 0; i++)
        if (!used[i])
            slot = i;
    /* the name keeps the extension (some writers choose the format by it) and is
       unique in this process (counter) and among processes (pid) */
    int n = snprintf(tmp, tmplen, "%.*s.%s.tmp%ld-%lu%s", (int)(base - path), path, base,
                     (long)getpid(), k, ext ? ext : "");
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

btdf_status btdf_write_file_atomic(const char *path, const char *ext, btdf_file_writer writer,
                                   void *ctx, char *msg, size_t msglen)
{
    char tmp[NAME];
    int slot = btdf_tmp_begin(path, ext, tmp, sizeof tmp);
    if (slot == -2) {
        if (msg && msglen)
            snprintf(msg, msglen, "path is longer than %d bytes", NAME - 64);
        return BTDF_EINVAL;
    }
    btdf_status st = writer(ctx, tmp, msg, msglen);
    if (st == BTDF_OK && rename(tmp, path) != 0) {
        if (msg && msglen)
            snprintf(msg, msglen, "cannot rename the finished file into place: %s",
                     strerror(errno));
        st = BTDF_EIO;
    }
    if (st != BTDF_OK)
        unlink(tmp); /* no partial file: the output either appears whole or not at all */
    btdf_tmp_end(slot);
    return st;
}

btdf_status btdf_write_bytes(void *ctx, const char *tmp, char *msg, size_t msglen)
{
    const btdf_bytes *b = ctx;
    FILE *f = fopen(tmp, "wb");
    if (!f) {
        if (msg && msglen)
            snprintf(msg, msglen, "cannot create %s: %s", tmp, strerror(errno));
        return BTDF_EIO;
    }
    int bad = fwrite(b->data, 1, b->len, f) != b->len;
    bad |= fflush(f) != 0;
    bad |= fclose(f) != 0;
    if (bad) {
        if (msg && msglen)
            snprintf(msg, msglen, "writing %s failed: %s", tmp, strerror(errno));
        return BTDF_EIO;
    }
    return BTDF_OK;
}
