/* SPDX-License-Identifier: MIT */
/* inifile.c: a reader of INI files with lines of any length and the line of every entry. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "inifile.h"

static int blank(char c)
{
    return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v';
}

static char *trim(char *s)
{
    while (blank(*s))
        s++;
    size_t n = strlen(s);
    while (n > 0 && blank(s[n - 1]))
        s[--n] = 0;
    return s;
}

/* Cuts an inline comment: ';' or '#' at the start or after a blank. */
static void cut_comment(char *s)
{
    for (char *p = s; *p; p++)
        if ((*p == ';' || *p == '#') && (p == s || blank(p[-1]))) {
            *p = 0;
            return;
        }
}

int ini_read(const char *path, ini_handler fn, void *user, char *why, size_t whylen)
{
    struct stat st;
    if (stat(path, &st) != 0) {
        snprintf(why, whylen, "cannot read: %s", strerror(errno));
        return -1;
    }
    if (S_ISDIR(st.st_mode)) {
        snprintf(why, whylen, "is a directory, not a manifest");
        return -1;
    }
    FILE *f = fopen(path, "r");
    if (!f) {
        snprintf(why, whylen, "cannot read: %s", strerror(errno));
        return -1;
    }
    char *line = NULL, *section = NULL;
    size_t cap = 0;
    ssize_t len;
    int ln = 0, err = 0;
    while (!err && (len = getline(&line, &cap, f)) >= 0) {
        ln++;
        if (memchr(line, 0, (size_t)len)) {
            snprintf(why, whylen, "the line holds a NUL byte: not a text file");
            err = ln;
            break;
        }
        char *s = trim(line);
        if (!*s || *s == ';' || *s == '#')
            continue;
        if (*s == '[') {
            char *close = strchr(s, ']');
            if (!close) {
                snprintf(why, whylen, "a section header needs its closing ']'");
                err = ln;
                break;
            }
            char *rest = close + 1;
            *close = 0;
            cut_comment(rest);
            char *name = trim(s + 1);
            if (*trim(rest) || !*name) {
                snprintf(why, whylen, "expected [name] alone on the line");
                err = ln;
                break;
            }
            free(section);
            section = strdup(name);
            if (!section) {
                snprintf(why, whylen, "out of memory");
                err = ln;
                break;
            }
            if (!fn(user, section, NULL, NULL, ln)) {
                why[0] = 0;
                err = ln;
            }
            continue;
        }
        char *eq = strchr(s, '=');
        if (!eq) {
            snprintf(why, whylen, "syntax error (expected [section], key = value or ; comment)");
            err = ln;
            break;
        }
        *eq = 0;
        char *key = trim(s), *value = eq + 1;
        cut_comment(value);
        value = trim(value);
        if (!*key) {
            snprintf(why, whylen, "a key is missing before '='");
            err = ln;
            break;
        }
        if (!fn(user, section ? section : "", key, value, ln)) {
            why[0] = 0;
            err = ln;
        }
    }
    if (!err && ferror(f)) {
        snprintf(why, whylen, "read error: %s", strerror(errno));
        err = -1;
    }
    free(line);
    free(section);
    fclose(f);
    return err;
}
