/* SPDX-License-Identifier: MIT */
/* exr_check.c: reads an EXR table, times reading and rewriting it, checks the copy is identical. */
/* Usage: exr_check table.exr copy.exr */
#include <math.h>
#include <stdio.h>
#include <time.h>

#include "btdf.h"
#include "formats.h"

#if BTDF_HAVE_OPENEXR
static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

static const char *kind_name(btdf_table_kind k)
{
    return k == BTDF_TABLE_GRID ? "grid" : (k == BTDF_TABLE_FACET ? "facet" : "facet-reciprocal");
}
#endif

int main(int argc, char **argv)
{
#if BTDF_HAVE_OPENEXR
    if (argc != 3) {
        fprintf(stderr, "usage: exr_check table.exr copy.exr\n");
        return 2;
    }
    char msg[300] = "";
    btdf_table *a = NULL, *b = NULL;
    double t0 = now();
    btdf_status st = fmt_exr.read_path(argv[1], &a, msg, sizeof msg);
    double t1 = now();
    if (st != BTDF_OK) {
        fprintf(stderr, "exr_check: %s\n", msg);
        return 1;
    }
    btdf_write_opts w = {NULL, NULL, NULL};
    fmt_output_ctx c = {.table = a, .opts = &w};
    st = fmt_exr.write_path(&c, argv[2], msg, sizeof msg);
    double t2 = now();
    if (st == BTDF_OK)
        st = fmt_exr.read_path(argv[2], &b, msg, sizeof msg);
    if (st != BTDF_OK) {
        fprintf(stderr, "exr_check: %s\n", msg);
        return 1;
    }
    size_t n = btdf_table_slice_count(a), diff = 0, vals = 0;
    int ch = btdf_table_get_params(a)->channels;
    double vmax = 0.0;
    for (size_t k = 0; k < n; k++) {
        btdf_slice x, y;
        btdf_table_slice(a, k, &x);
        btdf_table_slice(b, k, &y);
        diff += x.ti != y.ti || x.nrows != y.nrows || x.ncols != y.ncols ||
                btdf_table_get_kind(a) != btdf_table_get_kind(b);
        for (size_t i = 0; i < x.nrows && !diff; i++)
            diff += x.rows[i] != y.rows[i];
        for (size_t i = 0; i < x.ncols && !diff; i++)
            diff += x.cols[i] != y.cols[i];
        for (size_t i = 0; i < x.nrows * x.ncols * (size_t)ch && !diff; i++, vals++) {
            diff += x.values[i] != y.values[i];
            vmax = fmax(vmax, x.values[i]);
        }
    }
    printf("%s: %s table, %zu slices, %zu nodes x %d channel(s), max rho %.9g 1/sr\n", argv[1],
           kind_name(btdf_table_get_kind(a)), n,
           btdf_table_node_count(a), ch, vmax);
    printf("read %.3f s, write %.3f s; rewritten copy: %zu values compared, %zu differ\n",
           t1 - t0, t2 - t1, vals, diff);
    btdf_table_free(a);
    btdf_table_free(b);
    return diff != 0;
#else
    (void)argc;
    (void)argv;
    fprintf(stderr, "exr_check: OpenEXR support was switched off at build time\n");
    return 1;
#endif
}
