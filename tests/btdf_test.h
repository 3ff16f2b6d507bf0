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

#endif
