/* SPDX-License-Identifier: MIT */
/* stamp.c: a manifest output's stamp (a hidden file beside it: what the output was made
   from, its size and hash), whether the output is up to date, and its missing folders. */
#include "stamp.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <btdf/btdf.h>

/* .NAME.btdftab-stamp beside the output; for a name too long for that to fit in 255
   bytes, the name is cut and a hash of the whole name keeps it unique. */
static void stamp_path(char *buf, size_t len, const char *out)
{
    const char *base = strrchr(out, '/');
    base = base ? base + 1 : out;
    size_t bl = strlen(base);
    if (1 + bl + 15 <= 255) {
        snprintf(buf, len, "%.*s.%s.btdftab-stamp", (int)(base - out), out, base);
        return;
    }
    unsigned long long h = 14695981039346656037ull;
    for (const char *c = base; *c; c++)
        h = (h ^ (unsigned char)*c) * 1099511628211ull;
    /* 1 + 200 + 1 + 16 + 15 = 233 bytes */
    snprintf(buf, len, "%.*s.%.200s-%016llx.btdftab-stamp", (int)(base - out), out, base, h);
}

/* What identifies an output's content: its size and the 64-bit FNV-1a hash of its
   bytes, as stamp text; 0 if it is not a readable regular file. */
static int content_id(const char *path, char *buf, size_t len)
{
    struct stat st;
    if (lstat(path, &st) != 0 || !S_ISREG(st.st_mode))
        return 0;
    FILE *f = fopen(path, "rb");
    if (!f)
        return 0;
    unsigned long long h = 14695981039346656037ull, size = 0;
    unsigned char chunk[65536];
    size_t n;
    while ((n = fread(chunk, 1, sizeof chunk, f)) > 0) {
        for (size_t i = 0; i < n; i++)
            h = (h ^ chunk[i]) * 1099511628211ull;
        size += n;
    }
    int bad = ferror(f);
    fclose(f);
    if (bad || size != (unsigned long long)st.st_size)
        return 0;
    snprintf(buf, len, "size %llu\nfnv1a64 %016llx\n", size, h);
    return 1;
}

/* Why out must be (re)built, or NULL when it is up to date: the stamp records the
   same parameters, and the size and hash of the file as it is now (a file cut short,
   emptied or replaced is rebuilt). */
const char *why_stale(const char *out, const char *stamp, int force)
{
    char sp[4200], have[8192], id[128];
    if (access(out, F_OK) != 0)
        return "missing";
    if (force)
        return "--force";
    if (!content_id(out, id, sizeof id))
        return "not a readable regular file";
    stamp_path(sp, sizeof sp, out);
    FILE *f = fopen(sp, "r");
    if (!f)
        return "no stamp beside it";
    size_t n = fread(have, 1, sizeof have - 1, f);
    fclose(f);
    have[n] = 0;
    size_t ls = strlen(stamp);
    if (!(n > ls && strncmp(have, stamp, ls) == 0))
        return "parameters or program version changed";
    return strcmp(have + ls, id) == 0 ? NULL : "content changed since it was built";
}

int up_to_date(const char *out, const char *stamp)
{
    return why_stale(out, stamp, 0) == NULL;
}

/* Creates the folders of path that are missing (mkdir -p of its dirname). */
int make_parents(const char *path)
{
    char d[4096];
    snprintf(d, sizeof d, "%s", path);
    char *slash = strrchr(d, '/');
    if (!slash || slash == d)
        return 1;
    *slash = 0;
    for (char *q = d + 1; *q; q++) {
        if (*q != '/')
            continue;
        *q = 0;
        if (mkdir(d, 0777) != 0 && errno != EEXIST)
            return 0;
        *q = '/';
    }
    return mkdir(d, 0777) == 0 || errno == EEXIST;
}

/* Whether the folder of path exists; if not, whether the nearest folder above it that
   does exist can take the new ones (0 and why set when it cannot). */
int parents_creatable(const char *path, int *exists, char *why, size_t whylen)
{
    char d[4096];
    snprintf(d, sizeof d, "%s", path);
    char *slash = strrchr(d, '/');
    *exists = 1;
    if (!slash || slash == d)
        return 1;
    *slash = 0;
    struct stat st;
    if (stat(d, &st) == 0)
        return 1;
    *exists = 0;
    while ((slash = strrchr(d, '/')) != NULL && slash != d) {
        *slash = 0;
        if (stat(d, &st) == 0)
            break;
    }
    if (slash == d)
        snprintf(d, sizeof d, "/");
    else if (!slash)
        snprintf(d, sizeof d, ".");
    int err = 0;
    if (stat(d, &st) != 0)
        err = errno;
    else if (!S_ISDIR(st.st_mode))
        err = ENOTDIR;
    else if (access(d, W_OK | X_OK) != 0)
        err = errno;
    if (err) {
        snprintf(why, whylen, "cannot create its folder in '%.300s': %s", d, strerror(err));
        return 0;
    }
    return 1;
}

static int write_stamp(const char *out, const char *stamp)
{
    char sp[4200];
    stamp_path(sp, sizeof sp, out);
    return btdf_write_buffer(sp, NULL, stamp, strlen(stamp), NULL, 0) == BTDF_OK;
}

/* The stamp of a file just written: its parameters, then what identifies its content. */
int write_stamp_for(const char *out, const char *stamp)
{
    char id[128], full[4096 + 128];
    if (!content_id(out, id, sizeof id))
        return 0;
    snprintf(full, sizeof full, "%s%s", stamp, id);
    return write_stamp(out, full);
}
