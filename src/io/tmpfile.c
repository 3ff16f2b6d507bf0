/* SPDX-License-Identifier: MIT */
/* tmpfile.c: files written under safe temporary names, alone or in groups; a signal handler
   can remove them. */
#define _XOPEN_SOURCE 700 /* realpath */
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <time.h>
#include <unistd.h>

#include "btdf_io.h"
#include "io/tmpfile.h"
#include "core/core.h"

/*
 * Every writer of the library writes `path` under a temporary name beside it and
 * renames at the end. The names of the files being written are kept here, so that a
 * program (the btdftab tool does) can remove them from a SIGINT or SIGTERM handler
 * with tmp_remove_all, which only reads flags and calls unlink and rename: all
 * are async-signal-safe. The library itself installs no signal handler.
 *
 * The temporary name is `.NAME.btdftmpR.EXT` beside the output: NAME is the output's
 * own name, cut short where needed so that the whole name stays within the 255 bytes a
 * directory entry may have (so any legal output name works), R sixteen hexadecimal
 * digits from /dev/urandom, EXT the output's extension. The file is created with
 * O_CREAT|O_EXCL|O_NOFOLLOW: a name planted in advance (a symbolic link to someone's
 * file, or anything else) is never opened, only stepped over by drawing another name.
 * Its mode is 0666 less the umask, as fopen would give.
 *
 * While a file is being written, and until its group is committed, the writer holds an
 * flock on it. A process killed outright (SIGKILL, a power cut) leaves such a file with
 * no lock; the next write into the same folder removes it (tmp_sweep), and nothing
 * else: not a name of another shape, not a file of another user, not a locked one.
 */
#define SLOTS 32
#define NAME 4096
#define NAME_MAX_BYTES 255 /* one directory entry; POSIX NAME_MAX on Linux file systems */
#define MARK ".btdftmp"    /* temporaries; what the sweep may remove */
#define BAK_MARK ".btdfbak" /* copies kept during a commit; never swept */
#define RAND_DIGITS 16

#ifdef BTDF_TMP_SEAM
/* A test build replaces these to inject faults (tests/test_tmpfaults.c). */
int tmp_seam_link(const char *from, const char *to);
int tmp_seam_rename(const char *from, const char *to);
#define LINK tmp_seam_link
#define RENAME tmp_seam_rename
#else
#define LINK link
#define RENAME rename
#endif

static char names[SLOTS][NAME];
static volatile sig_atomic_t used[SLOTS];
static pthread_mutex_t lock = PTHREAD_MUTEX_INITIALIZER;
static unsigned long counter;

/* The one message helper (core/core.h), in this file's argument order. */
#define say(msg, msglen, ...) ((void)core_say(BTDF_OK, msg, msglen, __VA_ARGS__))

/* Sixteen hexadecimal digits, from /dev/urandom. Without it (a chroot without /dev) the
   digits come from the clock, the pid and a counter: guessable, yet still safe, since the
   file is created with O_EXCL and a planted name is only skipped. */
static void random_digits(char out[RAND_DIGITS + 1])
{
    unsigned char b[RAND_DIGITS / 2];
    int ok = 0;
    int fd = open("/dev/urandom", O_RDONLY | O_CLOEXEC);
    if (fd >= 0) {
        ok = read(fd, b, sizeof b) == (ssize_t)sizeof b;
        close(fd);
    }
    if (!ok) {
        pthread_mutex_lock(&lock);
        unsigned long k = counter++;
        pthread_mutex_unlock(&lock);
        unsigned long long x = (unsigned long long)time(NULL) * 6364136223846793005ULL ^
                               (unsigned long long)getpid() << 20 ^ k;
        for (size_t i = 0; i < sizeof b; i++, x >>= 8)
            b[i] = (unsigned char)x;
    }
    static const char hex[] = "0123456789abcdef";
    for (size_t i = 0; i < sizeof b; i++) {
        out[2 * i] = hex[b[i] >> 4];
        out[2 * i + 1] = hex[b[i] & 15];
    }
    out[RAND_DIGITS] = 0;
}

/* A fresh name beside path: `.NAME` mark, random digits, ext. 0, or -1 if too long. */
static int make_name(const char *path, const char *mark, const char *ext, char *tmp,
                     size_t tmplen)
{
    const char *base = strrchr(path, '/');
    base = base ? base + 1 : path;
    if (!ext)
        ext = "";
    char digits[RAND_DIGITS + 1];
    random_digits(digits);
    /* the fixed part: ".", the mark, the digits and the extension */
    char tail[96];
    int tl = snprintf(tail, sizeof tail, "%s%s%s", mark, digits, ext);
    size_t keep = strlen(base);
    if (tl < 0 || (size_t)tl >= sizeof tail || (size_t)tl + 1 >= NAME_MAX_BYTES)
        return -1;
    if (1 + keep + (size_t)tl > NAME_MAX_BYTES)
        keep = NAME_MAX_BYTES - 1 - (size_t)tl; /* the name is cut, the digits keep it apart */
    int n = snprintf(tmp, tmplen, "%.*s.%.*s%s", (int)(base - path), path, (int)keep, base, tail);
    if (n < 0 || (size_t)n >= tmplen || (size_t)n >= NAME)
        return -1;
    return 0;
}

/* Records tmp as being written: its slot, or -1 when all are taken. */
static int record(const char *tmp)
{
    pthread_mutex_lock(&lock);
    int slot = -1;
    for (int i = 0; i < SLOTS && slot < 0; i++)
        if (!used[i])
            slot = i;
    if (slot >= 0) {
        snprintf(names[slot], sizeof names[slot], "%s", tmp);
        used[slot] = 1;
    }
    pthread_mutex_unlock(&lock);
    return slot;
}

int tmp_begin(const char *path, const char *ext, char *tmp, size_t tmplen)
{
    if (make_name(path, MARK, ext, tmp, tmplen) != 0)
        return -2;
    return record(tmp); /* -1 when all slots are taken: the file is still written, untracked */
}

/* Creates a new temporary beside path, never opening anything that was there: the open
   descriptor (locked) with its name in tmp and its slot in *slot; -1 with errno set
   (ENAMETOOLONG when the name does not fit). */
static int create_tmp(const char *path, const char *mark, const char *ext, char *tmp,
                      size_t tmplen, int *slot)
{
    for (int attempt = 0; attempt < 16; attempt++) { /* a taken name: draw another */
        if (make_name(path, mark, ext, tmp, tmplen) != 0) {
            errno = ENAMETOOLONG;
            return -1;
        }
        int s = record(tmp);
        /* 0666: the umask takes its part, as with fopen */
        int fd = open(tmp, O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
        if (fd >= 0) {
            /* the owner's mark for the sweep of other processes; a file system without
               locks (ENOLCK) leaves it unlocked, and the sweep then leaves it alone too */
            flock(fd, LOCK_EX | LOCK_NB);
            *slot = s;
            return fd;
        }
        int e = errno;
        tmp_end(s);
        if (e != EEXIST) {
            errno = e;
            return -1;
        }
    }
    errno = EEXIST;
    return -1;
}

void tmp_end(int slot)
{
    if (slot < 0 || slot >= SLOTS)
        return;
    pthread_mutex_lock(&lock);
    used[slot] = 0;
    pthread_mutex_unlock(&lock);
}

/* ------------------------------------------------------------------------- */
/* Stale temporaries                                                         */
/* ------------------------------------------------------------------------- */

int tmp_name_ours(const char *name)
{
    if (!name || name[0] != '.')
        return 0;
    size_t ml = strlen(MARK);
    for (const char *p = strstr(name + 1, MARK); p; p = strstr(p + 1, MARK)) {
        if (p == name + 1)
            continue; /* the output's own name is never empty */
        const char *d = p + ml, *e = d;
        while ((*e >= '0' && *e <= '9') || (*e >= 'a' && *e <= 'f'))
            e++;
        if (e - d != RAND_DIGITS)
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
        return 1;
    }
    return 0;
}

/* A temporary is taken for abandoned only when it is older than this: its writer
   takes the lock right after creating it, and this covers that moment many times over. */
#define STALE_SECONDS 60

size_t tmp_sweep(const char *path)
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
    int dfd = dirfd(d);
    size_t removed = 0;
    time_t now = time(NULL);
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
        if (!tmp_name_ours(e->d_name))
            continue;
        int fd = openat(dfd, e->d_name, O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
        if (fd < 0)
            continue;
        struct stat st, again;
        /* ours: a regular file of this user, old, and no writer holding its lock (a live
           writer in any process, whatever its PID namespace, holds it) */
        if (fstat(fd, &st) == 0 && S_ISREG(st.st_mode) && st.st_uid == geteuid() &&
            now - st.st_mtime > STALE_SECONDS && flock(fd, LOCK_EX | LOCK_NB) == 0 &&
            fstatat(dfd, e->d_name, &again, AT_SYMLINK_NOFOLLOW) == 0 &&
            again.st_dev == st.st_dev && again.st_ino == st.st_ino &&
            unlinkat(dfd, e->d_name, 0) == 0)
            removed++;
        close(fd);
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
    char bak[NAME];
    int slot;
    int fd; /* kept open until the rename: its lock tells other processes it is live */
    volatile sig_atomic_t done, have_bak;
} pending;

static struct group {
    int open;
    int failed;
    size_t n;
    pending p[SLOTS];
} grp;

/* Set while a group's files are renamed into place: a signal handler then completes the
   renames (rename is async-signal-safe) rather than leave half of a group new. */
static volatile sig_atomic_t committing;

void tmp_remove_all(void)
{
    if (committing) {
        for (size_t i = 0; i < grp.n; i++)
            if (!grp.p[i].done && RENAME(grp.p[i].tmp, grp.p[i].path) == 0)
                grp.p[i].done = 1;
        for (size_t i = 0; i < grp.n; i++)
            if (grp.p[i].have_bak)
                unlink(grp.p[i].bak);
    }
    for (int i = 0; i < SLOTS; i++)
        if (used[i])
            unlink(names[i]);
}

static void pending_close(pending *p)
{
    if (p->fd >= 0)
        close(p->fd);
    p->fd = -1;
    tmp_end(p->slot);
}

void tmp_group_begin(void)
{
    tmp_group_abort();
    grp.open = 1;
}

void tmp_group_abort(void)
{
    for (size_t i = 0; i < grp.n; i++) {
        unlink(grp.p[i].tmp);
        pending_close(&grp.p[i]);
    }
    grp.n = 0;
    grp.open = 0;
    grp.failed = 0;
}

/* Copies the file at from into a new file at to (created as a temporary is); 0 or -1. */
static int copy_file(const char *from, const char *to)
{
    int in = open(from, O_RDONLY | O_NOFOLLOW | O_CLOEXEC);
    if (in < 0)
        return -1;
    int out = open(to, O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
    if (out < 0) {
        close(in);
        return -1;
    }
    char buf[65536];
    int bad = 0;
    for (;;) {
        ssize_t r = read(in, buf, sizeof buf);
        if (r < 0 && errno == EINTR)
            continue;
        if (r <= 0) {
            bad = r < 0;
            break;
        }
        for (ssize_t off = 0; off < r && !bad;) {
            ssize_t w = write(out, buf + off, (size_t)(r - off));
            if (w < 0 && errno == EINTR)
                continue;
            bad = w <= 0;
            off += w > 0 ? w : 0;
        }
        if (bad)
            break;
    }
    bad |= close(out) != 0;
    close(in);
    if (bad)
        unlink(to);
    return bad ? -1 : 0;
}

/* Keeps the file at p->path (if any) under a backup name, so that a failed commit can put
   it back: a hard link, or a copy where the file system has no links (FAT, some network
   and FUSE file systems refuse link with EPERM or ENOTSUP). 0, or -1 with msg set. */
static int keep_backup(pending *p, char *msg, size_t msglen)
{
    p->have_bak = 0;
    struct stat st;
    if (lstat(p->path, &st) != 0)
        return 0; /* nothing to keep: a failed commit removes the new file */
    for (int attempt = 0; attempt < 16; attempt++) {
        if (make_name(p->path, BAK_MARK, "", p->bak, sizeof p->bak) != 0)
            break;
        if (LINK(p->path, p->bak) == 0 || copy_file(p->path, p->bak) == 0) {
            p->have_bak = 1;
            return 0;
        }
        if (errno != EEXIST)
            break;
    }
    say(msg, msglen, "%s: cannot keep a copy of the earlier file to put back if the commit "
        "failed (%s): nothing was replaced", p->path, strerror(errno));
    return -1;
}

btdf_status tmp_group_commit(char *msg, size_t msglen)
{
    if (!grp.open)
        return BTDF_OK;
    btdf_status st = grp.failed ? BTDF_EIO : BTDF_OK;
    if (grp.failed)
        say(msg, msglen, "an earlier output of the run failed: nothing was written%s%s", "", "");
    for (size_t i = 0; i < grp.n && st == BTDF_OK; i++)
        st = replaceable(grp.p[i].path, msg, msglen);
    for (size_t i = 0; i < grp.n; i++)
        grp.p[i].have_bak = grp.p[i].done = 0;
    /* Keep each file about to be replaced, so that a rename failing half-way can put the
       earlier files back; if one cannot be kept, nothing is replaced. */
    for (size_t i = 0; i < grp.n && st == BTDF_OK; i++)
        if (keep_backup(&grp.p[i], msg, msglen) != 0)
            st = BTDF_EIO;
    /* The renames are not interrupted: the signals a tool catches to clean up wait until
       the group is in place (and a handler running in another thread completes it). */
    sigset_t block, old;
    sigemptyset(&block);
    sigaddset(&block, SIGINT);
    sigaddset(&block, SIGTERM);
    sigaddset(&block, SIGHUP);
    sigaddset(&block, SIGQUIT);
    int masked = pthread_sigmask(SIG_BLOCK, &block, &old) == 0;
    if (st == BTDF_OK)
        committing = 1;
    for (size_t i = 0; i < grp.n && st == BTDF_OK; i++) {
        if (grp.p[i].done)
            continue;
        if (RENAME(grp.p[i].tmp, grp.p[i].path) != 0) {
            say(msg, msglen, "%s: cannot rename the finished file into place: %s",
                grp.p[i].path, strerror(errno));
            st = BTDF_EIO;
            break;
        }
        grp.p[i].done = 1;
    }
    committing = 0;
    for (size_t k = 0; k < grp.n; k++) {
        pending *p = &grp.p[k];
        if (st != BTDF_OK && p->done) { /* undo: the earlier file, or none */
            if (p->have_bak) {
                if (RENAME(p->bak, p->path) == 0)
                    p->have_bak = 0;
            } else {
                unlink(p->path);
            }
        }
        if (p->have_bak)
            unlink(p->bak); /* a link or a copy: the file itself is in place */
        if (!p->done || st != BTDF_OK)
            unlink(p->tmp);
        pending_close(p);
    }
    grp.n = 0;
    grp.open = 0;
    grp.failed = 0;
    if (masked)
        pthread_sigmask(SIG_SETMASK, &old, NULL); /* a signal that came in is delivered now */
    return st;
}

BTDF_API void btdf_outputs_begin(void)
{
    tmp_group_begin();
}

BTDF_API btdf_status btdf_outputs_commit(char *msg, size_t msglen)
{
    return tmp_group_commit(msg, msglen);
}

BTDF_API void btdf_outputs_abort(void)
{
    tmp_group_abort();
}

btdf_status io_write_file_atomic(const char *path, const char *ext, io_file_writer writer,
                                   void *ctx, char *msg, size_t msglen)
{
    btdf_status st = replaceable(path, msg, msglen);
    if (st != BTDF_OK) {
        grp.failed |= grp.open;
        return st;
    }
    if (grp.open && grp.n == SLOTS) {
        say(msg, msglen, "more than %s outputs in one group%s", "32", "");
        grp.failed = 1;
        return BTDF_EINVAL;
    }
    tmp_sweep(path);
    char tmp[NAME];
    int slot = -1;
    int fd = create_tmp(path, MARK, ext, tmp, sizeof tmp, &slot);
    if (fd < 0) {
        grp.failed |= grp.open;
        if (errno == ENAMETOOLONG) {
            say(msg, msglen, "path is longer than %s bytes%s", "4032", "");
            return BTDF_EINVAL;
        }
        say(msg, msglen, "cannot create a temporary file beside %s: %s", path, strerror(errno));
        return BTDF_EIO;
    }
    /* the stream gets its own descriptor; fd stays open (and locked) until the rename */
    int sfd = dup(fd);
    FILE *f = sfd >= 0 ? fdopen(sfd, "wb") : NULL;
    if (!f) {
        say(msg, msglen, "cannot open a temporary file beside %s: %s", path, strerror(errno));
        if (sfd >= 0)
            close(sfd);
        st = BTDF_EIO;
    } else {
        st = writer(ctx, f, tmp, msg, msglen);
        int bad = fflush(f) != 0 || ferror(f);
        bad |= fclose(f) != 0;
        if (st == BTDF_OK && bad) {
            say(msg, msglen, "writing %s failed: %s", tmp, strerror(errno));
            st = BTDF_EIO;
        }
    }
    if (st == BTDF_OK && grp.open) { /* renamed with the rest of the group, or removed */
        pending *p = &grp.p[grp.n++];
        snprintf(p->tmp, sizeof p->tmp, "%s", tmp);
        snprintf(p->path, sizeof p->path, "%s", path);
        p->slot = slot;
        p->fd = fd;
        return BTDF_OK;
    }
    if (st == BTDF_OK)
        st = replaceable(path, msg, msglen); /* it may have appeared while writing */
    if (st == BTDF_OK && RENAME(tmp, path) != 0) {
        say(msg, msglen, "cannot rename the finished file into place: %s%s", strerror(errno),
            "");
        st = BTDF_EIO;
    }
    if (st != BTDF_OK) {
        unlink(tmp); /* no partial file: the output either appears whole or not at all */
        grp.failed |= grp.open;
    }
    close(fd);
    tmp_end(slot);
    return st;
}

btdf_status io_write_bytes(void *ctx, FILE *f, const char *tmp, char *msg, size_t msglen)
{
    const io_bytes *b = ctx;
    if (b->len && fwrite(b->data, 1, b->len, f) != b->len) {
        say(msg, msglen, "writing %s failed: %s", tmp, strerror(errno));
        return BTDF_EIO;
    }
    return BTDF_OK;
}
