/* SPDX-License-Identifier: MIT */
/* test_fastnum.c: the tool's row parser and printer give strtod's values and
   printf("%.17g")'s bytes, on random bit patterns, decimals and odd inputs. */
#include <stdlib.h>
#include <string.h>

#include "btdf_test.h"
#include "fastnum.h"

static uint64_t next(uint64_t *s)
{
    *s ^= *s << 13;
    *s ^= *s >> 7;
    *s ^= *s << 17;
    return *s;
}

static void same_as_libc(void **state)
{
    (void)state;
    uint64_t st = 88172645463325252u;
    long checked = 0;
    for (long i = 0; i < 1000000; i++) {
        uint64_t r = next(&st);
        double x;
        if (i % 3 == 0) /* any bit pattern: every exponent, subnormals */
            memcpy(&x, &r, sizeof x);
        else if (i % 3 == 1) /* 17 digits over 40 decades */
            x = (double)(r >> 11) / 9007199254740992.0 * pow(10.0, (double)(int)(r % 40) - 20);
        else /* short decimals such as a tool's rows hold */
            x = (double)(r % 100000) / (double)(1 + r % 1000);
        if (!isfinite(x))
            continue;
        char a[64], b[64];
        snprintf(a, sizeof a, "%.17g", x);
        assert_int_equal(fastnum_g17(x, b), (int)strlen(a));
        assert_string_equal(a, b);
        for (int prec = 0; prec < 2; prec++) {
            if (prec)
                snprintf(a, sizeof a, "%.6g", x);
            char *e1, *e2;
            double p = strtod(a, &e1), q = fastnum_strtod(a, &e2);
            assert_memory_equal(&p, &q, sizeof p);
            assert_ptr_equal(e1, e2);
        }
        checked++;
    }
    assert_true(checked > 900000);
    const char *odd[] = {"30",   "150.0", "-0",  "0.000", "1e5",   "1e",    "1e+", "+.5",
                         "-.5e-3", ".",   "-",   "abc",   "inf",   "nan",   "0x1p3", "1.5x",
                         "12345678901234567890", "007", "1,2", "  3", "1e400", "1e-400",
                         "0.0000000000000000000000001", "9007199254740993"};
    for (size_t i = 0; i < sizeof odd / sizeof odd[0]; i++) {
        char *e1, *e2;
        double p = strtod(odd[i], &e1), q = fastnum_strtod(odd[i], &e2);
        assert_memory_equal(&p, &q, sizeof p);
        assert_ptr_equal(e1, e2);
    }
    char b[64];
    fastnum_g17(0.0, b);
    assert_string_equal(b, "0");
    fastnum_g17(-0.0, b);
    assert_string_equal(b, "-0");
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(same_as_libc)};
    return cmocka_run_group_tests_name("fastnum", tests, NULL, NULL);
}
