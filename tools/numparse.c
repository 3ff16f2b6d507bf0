/* SPDX-License-Identifier: MIT */
/* numparse.c: the one reader of numbers for command-line options and manifest values. */
#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "numparse.h"

static const char *digits(const char *p, int *n)
{
    *n = 0;
    while (*p >= '0' && *p <= '9') {
        p++;
        ++*n;
    }
    return p;
}

/* The end of a decimal number starting at s, or NULL if s does not start with one. */
static const char *scan_decimal(const char *s)
{
    const char *p = s;
    int a, b;
    if (*p == '+' || *p == '-')
        p++;
    p = digits(p, &a);
    b = 0;
    if (*p == '.')
        p = digits(p + 1, &b);
    if (a + b == 0)
        return NULL;
    if (*p == 'e' || *p == 'E') {
        const char *q = p + 1;
        if (*q == '+' || *q == '-')
            q++;
        int c;
        q = digits(q, &c);
        if (c == 0)
            return NULL;
        p = q;
    }
    return p;
}

const char *num_double(const char *s, double *out)
{
    if (!s || !*s)
        return "is empty: expected a number";
    const char *end = scan_decimal(s);
    if (!end || *end)
        return "is not a number (expected decimal digits, e.g. 1.5 or 2e-3)";
    char *e;
    errno = 0;
    double v = strtod(s, &e);
    if (e != end)
        return "is not a number (expected decimal digits, e.g. 1.5 or 2e-3)";
    if (errno == ERANGE || !isfinite(v) || (v != 0.0 && fabs(v) < DBL_MIN)) {
        /* strtod reports both overflow and underflow with ERANGE */
        return fabs(v) >= 1.0 || !isfinite(v)
                   ? "is out of range (above 1.8e308, the largest double)"
                   : "is out of range (its magnitude is below 2.2e-308, the smallest normal "
                     "double; write 0 for zero)";
    }
    *out = v;
    return NULL;
}

const char *num_size(const char *s, size_t lo, size_t hi, size_t *out)
{
    static char why[96];
    snprintf(why, sizeof why, "must be a whole number in [%zu, %zu]", lo, hi);
    if (!s || !*s)
        return why;
    const char *p = s + (*s == '+');
    int n;
    const char *end = digits(p, &n);
    if (n == 0 || *end)
        return why;
    errno = 0;
    unsigned long long v = strtoull(p, NULL, 10);
    if (errno == ERANGE || v < lo || v > hi)
        return why;
    *out = (size_t)v;
    return NULL;
}

/* Splits s at commas into at most max items in buf; each item non-empty. */
static int split(const char *s, char *buf, size_t buflen, char **items, int max)
{
    if (strlen(s) >= buflen)
        return -1;
    strcpy(buf, s);
    int n = 0;
    char *p = buf;
    for (;;) {
        if (n == max)
            return -1;
        items[n++] = p;
        char *c = strchr(p, ',');
        if (!c)
            break;
        *c = 0;
        p = c + 1;
    }
    return n;
}

const char *num_double_list(const char *s, double *out, int min_n, int max_n, int *n)
{
    static char why[128];
    char buf[512], *items[16];
    if (max_n > 16)
        max_n = 16;
    int k = s ? split(s, buf, sizeof buf, items, max_n) : -1;
    if (k < min_n) {
        snprintf(why, sizeof why, "expected %d to %d numbers separated by commas", min_n, max_n);
        if (min_n == max_n)
            snprintf(why, sizeof why, "expected %d numbers separated by commas", min_n);
        return why;
    }
    for (int i = 0; i < k; i++) {
        const char *r = num_double(items[i], &out[i]);
        if (r) {
            snprintf(why, sizeof why, "item %d ('%.40s') %s", i + 1, items[i], r);
            return why;
        }
    }
    *n = k;
    return NULL;
}

const char *num_size_list(const char *s, size_t lo, size_t hi, size_t *out, int want)
{
    static char why[160];
    char buf[512], *items[16];
    int k = s && want <= 16 ? split(s, buf, sizeof buf, items, want) : -1;
    if (k != want) {
        snprintf(why, sizeof why, "expected %d whole numbers separated by commas", want);
        return why;
    }
    for (int i = 0; i < k; i++) {
        const char *r = num_size(items[i], lo, hi, &out[i]);
        if (r) {
            snprintf(why, sizeof why, "item %d ('%.40s') %s", i + 1, items[i], r);
            return why;
        }
    }
    return NULL;
}

const char *num_double_list_blanks(const char *s, double *out, int min_n, int max_n, int *n)
{
    /* blanks around the commas go, as around every value; the numbers themselves follow
       the tool's one rule */
    char list[256];
    size_t o = 0;
    if (strlen(s) >= sizeof list)
        return "is too long";
    for (const char *c = s; *c && o + 1 < sizeof list;) {
        const char *end = strchr(c, ',');
        size_t k = end ? (size_t)(end - c) : strlen(c);
        while (k > 0 && (*c == ' ' || *c == '\t'))
            c++, k--;
        while (k > 0 && (c[k - 1] == ' ' || c[k - 1] == '\t'))
            k--;
        if (o + k + 2 >= sizeof list)
            break;
        memcpy(list + o, c, k);
        o += k;
        if (end)
            list[o++] = ',';
        c = end ? end + 1 : c + k;
        if (!end)
            break;
    }
    list[o] = 0;
    return num_double_list(list, out, min_n, max_n, n);
}
