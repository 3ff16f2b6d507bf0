/* SPDX-License-Identifier: MIT */
/* test_budget.c: --max-samples and --max-memory are bounds on the nodes, never hints. */
#include <string.h>

#include "btdf_test.h"

/* Builds with a budget; returns the status, the table (or NULL) in *t. */
static btdf_status build(int channels, double tol, size_t samples, size_t bytes, int threads,
                         btdf_table **t, char *msg, size_t msglen)
{
    btdf_table_opts o;
    btdf_table_opts_default(&o);
    o.params.channels = channels;
    o.params.ior[0] = 1.5;
    o.params.ior[1] = 1.45;
    o.params.ior[2] = 1.4;
    o.tolerance = tol;
    o.max_samples = samples;
    o.max_bytes = bytes;
    o.threads = threads;
    *t = NULL;
    return btdf_table_build(&o, t, msg, msglen);
}

/* The first pass holds 19 slices (0 to 90 degrees, 5 apart) of at least 17 x 13 nodes:
   4199 nodes; a smaller budget builds nothing and says so. */
static void below_the_coarsest_table(void **state)
{
    (void)state;
    btdf_table *t;
    char msg[256] = "";
    assert_status(BTDF_EBUDGET, build(1, 1e-3, 1000, 0, 1, &t, msg, sizeof msg));
    assert_null(t);
    assert_non_null(strstr(msg, "4199 nodes"));
    assert_status(BTDF_EBUDGET, build(1, 1e-3, 4198, 0, 1, &t, msg, sizeof msg));
    assert_null(t);
}

/* The cases: 1000 and 20000 samples with a tolerance they cannot meet. */
static void samples_are_a_bound(void **state)
{
    (void)state;
    static const size_t budgets[] = {4199, 5000, 12000, 20000, 31000};
    for (size_t b = 0; b < sizeof budgets / sizeof budgets[0]; b++) {
        for (int threads = 1; threads <= 2; threads++) {
            btdf_table *t;
            char msg[256] = "";
            btdf_status st = build(1, 1e-5, budgets[b], 0, threads, &t, msg, sizeof msg);
            assert_status(BTDF_EBUDGET, st);
            assert_non_null(t);
            if (btdf_table_node_count(t) > budgets[b]) {
                print_error("budget %zu, %d threads: %zu nodes\n", budgets[b], threads,
                            btdf_table_node_count(t));
                fail();
            }
            btdf_table_free(t);
        }
    }
}

/* 3 channels at 1 MiB: nodes x (3 values + 1 weight) x 8 bytes stay within it. */
static void memory_is_a_bound(void **state)
{
    (void)state;
    static const size_t mib[] = {1, 2};
    for (int ch = 1; ch <= 3; ch += 2) {
        for (size_t k = 0; k < 2; k++) {
            btdf_table *t;
            size_t cap = mib[k] << 20;
            char msg[256] = "";
            btdf_status st = build(ch, 1e-5, 0, cap, 2, &t, msg, sizeof msg);
            assert_true(st == BTDF_EBUDGET || st == BTDF_OK);
            assert_non_null(t);
            size_t held = btdf_table_node_count(t) * ((size_t)ch + 1) * sizeof(double);
            if (held > cap) {
                print_error("%d channels, %zu MiB: %zu bytes\n", ch, mib[k], held);
                fail();
            }
            btdf_table_free(t);
        }
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(below_the_coarsest_table),
        cmocka_unit_test(samples_are_a_bound),
        cmocka_unit_test(memory_is_a_bound),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
