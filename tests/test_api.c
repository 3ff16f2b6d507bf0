/* SPDX-License-Identifier: MIT */
/* test_api.c: the C API refuses bad input with BTDF_EINVAL and a message (btdf.h's
   promise), one case each: NULL arguments, out-of-range enumerations, huge n. */
#include <float.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "btdf_test.h"
#include "btdf_io.h"
#include "btdf_radiance.h"

/* status EINVAL and a message written where there was none */
#define assert_refused(expr, msg)                                                             \
    do {                                                                                      \
        (msg)[0] = 0;                                                                         \
        assert_status(BTDF_EINVAL, (expr));                                                   \
        assert_true((msg)[0] != 0);                                                           \
    } while (0)

static void rad_build_out_null(void **state)
{
    (void)state;
    btdf_params p;
    btdf_params_default(&p);
    char msg[256];
    assert_refused(btdf_rad_build(&p, BTDF_RAD_KLEMS_QUARTER, 0.2, 1, NULL, msg, sizeof msg),
                   msg);
}

static void rad_build_basis_99(void **state)
{
    (void)state;
    btdf_params p;
    btdf_params_default(&p);
    btdf_rad *r = NULL;
    char msg[256];
    assert_refused(btdf_rad_build(&p, (btdf_rad_basis)99, 0.2, 1, &r, msg, sizeof msg), msg);
    assert_non_null(strstr(msg, "99"));
    assert_null(r);
}

static void rule_parse_null(void **state)
{
    (void)state;
    btdf_table_rule r = BTDF_RULE_PLAIN;
    assert_int_equal(btdf_table_rule_parse(NULL, &r), 0);
    assert_int_equal(btdf_table_rule_parse("chi", NULL), 0);
    assert_int_equal(btdf_table_rule_parse("chi", &r), 1);
}

/* Past n ~ 1e77 the kernel's form overflowed to inf / inf. R -> 1 as n grows: at normal
   incidence R = ((n - 1)/(n + 1))^2, which is 1 to double precision for n >= 1e17. */
static void fresnel_huge_n(void **state)
{
    (void)state;
    const double ns[] = {1e17, 1e77, 1e78, 1e154, 1e200, DBL_MAX};
    for (size_t i = 0; i < sizeof ns / sizeof ns[0]; i++) {
        assert_close(btdf_fresnel_r(ns[i], 0.0), 1.0, 1e-15, 0.0);
        for (double ti = 0.1; ti < 1.57; ti += 0.3) {
            double r = btdf_fresnel_r(ns[i], ti);
            assert_true(r >= 0.0 && r <= 1.0);
        }
    }
    /* the two forms meet at n = 1e4: 1e-12 relative, far above their rounding
       (a few ulps of each of a handful of operations) and far below any change of R
       over a relative step of 1e-13 in n */
    for (double ti = 0.0; ti < 1.57; ti += 0.2)
        assert_close(btdf_fresnel_r(1e4 * (1 + 1e-13), ti), btdf_fresnel_r(1e4 * (1 - 1e-13), ti),
                     1e-12, 0.0);
}

static void reflection_attached_twice(void **state)
{
    (void)state;
    btdf_params p;
    btdf_params_default(&p);
    btdf_table *t1 = NULL, *t2 = NULL, *r = NULL;
    char msg[256];
    assert_status(BTDF_OK, btdf_table_new(BTDF_TABLE_FACET, &p, &t1, msg, sizeof msg));
    assert_status(BTDF_OK, btdf_table_new(BTDF_TABLE_FACET, &p, &t2, msg, sizeof msg));
    assert_status(BTDF_OK, btdf_table_new(BTDF_TABLE_FACET_REFLECTION, &p, &r, msg, sizeof msg));
    assert_status(BTDF_OK, btdf_table_attach_reflection(t1, r, msg, sizeof msg));
    assert_refused(btdf_table_attach_reflection(t2, r, msg, sizeof msg), msg);
    assert_non_null(strstr(msg, "attached"));
    btdf_table_free(t1); /* frees r */
    btdf_table_free(t2); /* r not freed twice (AddressSanitizer would say) */
}

static void add_slice_0x0(void **state)
{
    (void)state;
    btdf_params p;
    btdf_params_default(&p);
    btdf_table *t = NULL;
    char msg[256];
    assert_status(BTDF_OK, btdf_table_new(BTDF_TABLE_GRID, &p, &t, msg, sizeof msg));
    assert_refused(btdf_table_add_slice(t, 0.1, 0, NULL, 0, NULL, NULL, msg, sizeof msg), msg);
    btdf_table_free(t);
}

static void table_new_out_null(void **state)
{
    (void)state;
    btdf_params p;
    btdf_params_default(&p);
    char msg[256];
    assert_refused(btdf_table_new(BTDF_TABLE_GRID, &p, NULL, msg, sizeof msg), msg);
}

static void table_build_out_null(void **state)
{
    (void)state;
    btdf_table_opts o;
    btdf_table_opts_default(&o);
    char msg[256];
    assert_refused(btdf_table_build(&o, NULL, msg, sizeof msg), msg);
    assert_refused(btdf_table_opts_check(NULL, msg, sizeof msg), msg);
}

static void opts_metric_99(void **state)
{
    (void)state;
    btdf_table_opts o;
    btdf_table_opts_default(&o);
    o.metric = (btdf_metric)99;
    char msg[256];
    assert_refused(btdf_table_opts_check(&o, msg, sizeof msg), msg);
    assert_non_null(strstr(msg, "metric 99"));
}

/* enumerations print as integers: %g gave "1.23457e+06" */
static void enum_messages_are_integers(void **state)
{
    (void)state;
    btdf_table_opts o;
    btdf_table_opts_default(&o);
    o.estimate = (btdf_estimate_mode)1234567;
    char msg[256];
    assert_refused(btdf_table_opts_check(&o, msg, sizeof msg), msg);
    assert_non_null(strstr(msg, "1234567"));
    btdf_table_opts_default(&o);
    o.part = (btdf_part)7654321;
    assert_refused(btdf_table_opts_check(&o, msg, sizeof msg), msg);
    assert_non_null(strstr(msg, "7654321"));
    btdf_params p;
    btdf_params_default(&p);
    p.channels = 2345678;
    assert_refused(btdf_params_check(&p, msg, sizeof msg), msg);
    assert_non_null(strstr(msg, "2345678"));
}

/* no data and no length: an empty file, with no NULL handed to fwrite */
static void write_buffer_nothing(void **state)
{
    (void)state;
    char dir[256], path[300], msg[256] = "";
    assert_int_equal(btdf_test_mkdtemp(dir, sizeof dir, "api"), 0);
    snprintf(path, sizeof path, "%s/empty.json", dir);
    assert_status(BTDF_OK, btdf_write_buffer(path, NULL, NULL, 0, msg, sizeof msg));
    struct stat st;
    assert_int_equal(stat(path, &st), 0);
    assert_int_equal(st.st_size, 0);
    assert_refused(btdf_write_buffer(path, NULL, NULL, 3, msg, sizeof msg), msg);
    btdf_test_rmtree(dir);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(rad_build_out_null),    cmocka_unit_test(rad_build_basis_99),
        cmocka_unit_test(rule_parse_null),       cmocka_unit_test(fresnel_huge_n),
        cmocka_unit_test(reflection_attached_twice), cmocka_unit_test(add_slice_0x0),
        cmocka_unit_test(table_new_out_null),    cmocka_unit_test(table_build_out_null),
        cmocka_unit_test(opts_metric_99),        cmocka_unit_test(enum_messages_are_integers),
        cmocka_unit_test(write_buffer_nothing),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
