/* SPDX-License-Identifier: MIT */
/* pathnorm.c: output paths compared before their folders exist (nd/x.csv and nd//x.csv,
   o/./x.bsdf, d/../d/x.csv are one file whether or not nd, o and d exist yet). */
#define _XOPEN_SOURCE 700 /* realpath */
#include <errno.h>
#include <limits.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "btdf_io.h"
#include "pathnorm.h"

#ifndef PATH_MAX
#define PATH_MAX 4096
#endif

/* Appends "/" and the len bytes of comp to cur (of capacity cap); 0 if it does not fit. */
static int append(char *cur, size_t cap, const char *comp, size_t len)
{
    size_t n = strlen(cur);
    int root = n == 1 && cur[0] == '/';
    if (n + !root + len + 1 > cap)
        return 0;
    if (!root)
        cur[n++] = '/';
    memcpy(cur + n, comp, len);
    cur[n + len] = 0;
    return 1;
}

int path_normalise(const char *path, char *out, size_t outlen)
{
    if (!path || !out || outlen < 2)
        return 0;
    char cur[PATH_MAX];
    if (path[0] == '/') {
        strcpy(cur, "/");
    } else if (!getcwd(cur, sizeof cur)) {
        return 0;
    } else {
        char *real = realpath(cur, NULL); /* getcwd is canonical already; to be sure */
        if (real) {
            size_t n = strlen(real);
            if (n < sizeof cur)
                memcpy(cur, real, n + 1);
            free(real);
        }
    }
    /* cur stays canonical: every link among the components that exist is followed, so
       ".." may be taken as the text's parent */
    int exists = 1;
    for (const char *p = path; *p;) {
        while (*p == '/')
            p++;
        const char *e = p;
        while (*e && *e != '/')
            e++;
        size_t len = (size_t)(e - p);
        if (len == 0 || (len == 1 && p[0] == '.')) {
            /* nothing */
        } else if (len == 2 && p[0] == '.' && p[1] == '.') {
            char *slash = strrchr(cur, '/');
            if (slash == cur)
                cur[1] = 0; /* the parent of / is / */
            else if (slash)
                *slash = 0;
        } else {
            if (!append(cur, sizeof cur, p, len))
                return 0;
            struct stat st;
            if (exists && lstat(cur, &st) != 0)
                exists = 0; /* from here on nothing exists: no link to follow */
            if (exists && S_ISLNK(st.st_mode)) {
                char *real = realpath(cur, NULL);
                if (real) { /* a dangling link stays as its own name */
                    size_t n = strlen(real);
                    if (n >= sizeof cur) {
                        free(real);
                        return 0;
                    }
                    memcpy(cur, real, n + 1);
                    free(real);
                }
            }
        }
        p = e;
    }
    size_t n = strlen(cur);
    if (n + 1 > outlen)
        return 0;
    memcpy(out, cur, n + 1);
    return 1;
}

int path_same(const char *a, const char *b)
{
    if (btdf_same_file(a, b))
        return 1;
    char na[PATH_MAX], nb[PATH_MAX];
    return path_normalise(a, na, sizeof na) && path_normalise(b, nb, sizeof nb) &&
           !strcmp(na, nb);
}
