/* SPDX-License-Identifier: MIT */
/* test_numparse.c: one reader of numbers: what it takes and what it refuses. */
#include <float.h>
#include <string.h>

#include "btdf_test.h"
#include "numparse.h"

static void doubles(void **state)
{
    (void)state;
    static const struct {
        const char *s;
        double v;
    } good[] = {{"1.5", 1.5}, {"-2", -2.0}, {"+3", 3.0}, {".5", 0.5}, {"5.", 5.0},
                {"1e3", 1e3}, {"2E-3", 2e-3}, {"0", 0.0}, {"-0", 0.0}, {"1e-300", 1e-300},
                {"1.7976931348623157e308", DBL_MAX}};
    for (size_t i = 0; i < sizeof good / sizeof good[0]; i++) {
        double v = -1;
        assert_null(num_double(good[i].s, &v));
        assert_true(v == good[i].v);
    }
    static const char *const not_numbers[] = {
        "", " 3", "3 ", "0x10", "0X1p3", "inf", "-inf", "nan", "NAN", "infinity", "1,5", "e3",
        ".", "-", "1e", "1e+", "1.2.3", "3abc", "\t1", "1\n", "--1", "1e3.5"};
    for (size_t i = 0; i < sizeof not_numbers / sizeof not_numbers[0]; i++) {
        double v = 7;
        const char *r = num_double(not_numbers[i], &v);
        assert_non_null(r);
        assert_true(strstr(r, "not a number") || strstr(r, "empty"));
        assert_true(v == 7);
    }
    static const char *const out_of_range[] = {"1e-320", "-4e-310", "1e309", "-1e400",
                                               "1e-400"};
    for (size_t i = 0; i < sizeof out_of_range / sizeof out_of_range[0]; i++) {
        double v = 7;
        const char *r = num_double(out_of_range[i], &v);
        assert_non_null(r);
        assert_non_null(strstr(r, "out of range"));
        assert_true(v == 7);
    }
}

static void sizes(void **state)
{
    (void)state;
    size_t v = 0;
    assert_null(num_size("42", 0, 100, &v));
    assert_int_equal(v, 42);
    assert_null(num_size("+7", 0, 100, &v));
    assert_int_equal(v, 7);
    assert_null(num_size("100", 0, 100, &v));
    static const char *const bad[] = {"", "-1", "101", "0x10", " 5", "5 ", "1e3", "4.0", "+",
                                      "99999999999999999999999"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        v = 3;
        const char *r = num_size(bad[i], 0, 100, &v);
        assert_non_null(r);
        assert_non_null(strstr(r, "[0, 100]"));
        assert_int_equal(v, 3);
    }
}

static void lists(void **state)
{
    (void)state;
    double d[3];
    int n = 0;
    assert_null(num_double_list("1.5,1.4,1.3", d, 1, 3, &n));
    assert_int_equal(n, 3);
    assert_true(d[2] == 1.3);
    assert_null(num_double_list("2", d, 1, 3, &n));
    assert_int_equal(n, 1);
    assert_non_null(num_double_list("1,2,3,4", d, 1, 3, &n));
    assert_non_null(num_double_list("1,,3", d, 1, 3, &n));
    assert_non_null(num_double_list("1,2,", d, 1, 3, &n));
    assert_non_null(num_double_list(" 1,2,3", d, 1, 3, &n));
    assert_non_null(num_double_list("0x1,2,3", d, 1, 3, &n));
    size_t z[3];
    assert_null(num_size_list("3,5,5", 2, 100, z, 3));
    assert_int_equal(z[1], 5);
    static const char *const bad[] = {" 3, 5, 5", "3,5", "3,5,5,5", "0x3,5,5", "3,-5,5",
                                      "3,5,1", "3,,5", "3,5,5,"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++)
        assert_non_null(num_size_list(bad[i], 2, 100, z, 3));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(doubles),
        cmocka_unit_test(sizes),
        cmocka_unit_test(lists),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
