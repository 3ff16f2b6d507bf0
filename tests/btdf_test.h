/* SPDX-License-Identifier: MIT */
/* btdf_test.h: assertions for doubles and statuses on top of cmocka 1.1.5. */
#ifndef BTDF_TEST_H
#define BTDF_TEST_H

#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include <cmocka.h>

#include "btdf.h"

#ifndef M_PI /* C99 does not define it; POSIX math.h does */
#define M_PI 3.14159265358979323846
#endif

/* |a - b| <= atol + rtol |b|, and neither is NaN (cmocka has no assert_double_equal). */
static inline void assert_close_(double a, double b, double rtol, double atol, const char *file,
                                 int line)
{
    if (!(fabs(a - b) <= atol + rtol * fabs(b))) {
        char buf[256];
        snprintf(buf, sizeof buf, "%.17g != %.17g (rtol %g, atol %g)", a, b, rtol, atol);
        print_error("%s\n", buf);
        _fail(file, line);
    }
}
#define assert_close(a, b, rtol, atol) assert_close_((a), (b), (rtol), (atol), __FILE__, __LINE__)

static inline void assert_status_(btdf_status want, btdf_status got, const char *file, int line)
{
    if (want != got) {
        print_error("status '%s', expected '%s'\n", btdf_strerror(got), btdf_strerror(want));
        _fail(file, line);
    }
}
#define assert_status(want, expr) assert_status_((want), (expr), __FILE__, __LINE__)

/* A fresh folder btdf-TAG-XXXXXX under $TMPDIR (or /tmp) for a suite's files: 0 on success. */
static inline int btdf_test_mkdtemp(char *dir, size_t len, const char *tag)
{
    const char *t = getenv("TMPDIR");
    snprintf(dir, len, "%s/btdf-%s-XXXXXX", t && *t ? t : "/tmp", tag);
    return mkdtemp(dir) ? 0 : -1;
}

/* Removes that folder and everything in it: 0 on success. */
static inline int btdf_test_rmtree(const char *dir)
{
    char cmd[512];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    return system(cmd) == 0 ? 0 : -1;
}

static inline double rad(double d) { return d * M_PI / 180.0; }

/* Builds the table of o, asserts the status want (printing the builder's message when it
   is not that) and a table of o's model, and returns it. */
static inline btdf_table *btdf_test_build(const btdf_table_opts *o, btdf_status want)
{
    btdf_table *t = NULL;
    char msg[512] = "";
    btdf_status st = btdf_table_build(o, &t, msg, sizeof msg);
    if (st != want)
        print_message("build: %s\n", msg);
    assert_status(want, st);
    assert_non_null(t);
    assert_int_equal(btdf_table_get_params(t)->model, o->params.model);
    return t;
}

/* A table of one channel (n, s) over ti0..ti1 degrees at tolerance tol holding part,
   built with threads workers (0 = all); asserts the status want and a table. */
static inline btdf_table *btdf_test_table(double n, double s, double ti0, double ti1, double tol,
                                          int threads, btdf_part part, btdf_status want)
{
    btdf_table_opts o;
    btdf_table_opts_default(&o);
    o.params.ior[0] = n;
    o.params.smoothness = s;
    o.ti_min = rad(ti0);
    o.ti_max = rad(ti1);
    o.tolerance = tol;
    o.threads = threads;
    o.part = part;
    return btdf_test_build(&o, want);
}

#endif
