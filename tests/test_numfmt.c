/* SPDX-License-Identifier: MIT */
/* test_numfmt.c: btdf_format_double, the shortest decimal that reads back exactly. */
#include <float.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "btdf.h"

static const char *fmt(double x)
{
    static char b[64];
    btdf_format_double(x, b, sizeof b);
    return b;
}

static void test_known(void **state)
{
    (void)state;
    assert_string_equal(fmt(0.7), "0.7");
    assert_string_equal(fmt(1.5), "1.5");
    assert_string_equal(fmt(1e-3), "0.001");
    assert_string_equal(fmt(0.0), "0");
    assert_string_equal(fmt(-0.0), "-0");
    assert_string_equal(fmt(3.0), "3");
    assert_string_equal(fmt(0.1 + 0.2), "0.30000000000000004"); /* needs all 17 */
    assert_string_equal(fmt(0.1 + 0.7), "0.7999999999999999");  /* 16 suffice */
    assert_string_equal(fmt(1.0 / 3.0), "0.3333333333333333");
    assert_string_equal(fmt(DBL_MAX), "1.7976931348623157e+308"); /* 16 overflow */
    assert_string_equal(fmt(1.2345678901234567e16), "12345678901234568"); /* fewer chars */
    assert_string_equal(fmt(5e-324), "4.94065645841247e-324"); /* the smallest subnormal */
}

/* xorshift64: many doubles of every magnitude read back bit for bit, and never
   longer than %.17g. */
static void test_round_trip(void **state)
{
    (void)state;
    uint64_t s = 88172645463325252ull;
    for (int k = 0; k < 200000; k++) {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        double x;
        uint64_t bits = s;
        memcpy(&x, &bits, sizeof x);
        if (!isfinite(x))
            continue;
        char b[64], l[64];
        int n = btdf_format_double(x, b, sizeof b);
        snprintf(l, sizeof l, "%.17g", x);
        assert_true(n > 0 && (size_t)n < 32);
        double y = strtod(b, NULL);
        assert_memory_equal(&x, &y, sizeof x);
        assert_true(strlen(b) <= strlen(l));
    }
}

/* A short buffer truncates like snprintf and says how much was needed. */
static void test_short_buffer(void **state)
{
    (void)state;
    char b[4];
    assert_int_equal(btdf_format_double(0.30000000000000004, b, sizeof b), 19);
    assert_string_equal(b, "0.3");
    assert_int_equal(btdf_format_double(1.0, NULL, 0), -1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_known),
        cmocka_unit_test(test_round_trip),
        cmocka_unit_test(test_short_buffer),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
