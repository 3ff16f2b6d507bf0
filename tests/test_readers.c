/* SPDX-License-Identifier: MIT */
/* test_readers.c: damaged table files are refused: every cut of a CSV table, rows lost
   or added, and EXR headers declaring more than the file holds. */
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "btdf_config.h"
#include "btdf_test.h"

static char dir[256];

static int setup(void **state)
{
    (void)state;
    return btdf_test_mkdtemp(dir, sizeof dir, "readers");
}

static int teardown(void **state)
{
    (void)state;
    return btdf_test_rmtree(dir);
}

static btdf_table *small_grid(int channels)
{
    btdf_table_opts o;
    btdf_table_opts_default(&o);
    o.kind = BTDF_TABLE_GRID;
    o.grid_ti = 3;
    o.grid_to = 5;
    o.grid_phi = 4;
    o.params.channels = channels;
    o.params.ior[0] = o.params.ior[1] = o.params.ior[2] = 1.5;
    btdf_table *t = NULL;
    assert_status(BTDF_OK, btdf_table_build(&o, &t, NULL, 0));
    return t;
}

static unsigned char *slurp(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *b = malloc((size_t)n + 1);
    assert_non_null(b);
    assert_int_equal(fread(b, 1, (size_t)n, f), (size_t)n);
    fclose(f);
    *len = (size_t)n;
    return b;
}

static void spill(const char *path, const void *b, size_t n)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(b, 1, n, f), n);
    assert_int_equal(fclose(f), 0);
}

/* Reading path fails with EFORMAT; returns the message. */
static const char *refused(const char *path)
{
    static char msg[512];
    btdf_table *t = NULL;
    msg[0] = 0;
    btdf_status st = btdf_table_read(path, &t, msg, sizeof msg);
    if (st != BTDF_EFORMAT) {
        print_error("%s: status '%s', expected a refusal\n", path, btdf_strerror(st));
        btdf_table_free(t);
        fail();
    }
    assert_null(t);
    return msg;
}

/* Every proper prefix of a CSV table is refused: each line cut and each byte cut. */
static void csv_cuts(void **state)
{
    (void)state;
    char path[512], cut[512];
    snprintf(path, sizeof path, "%s/t.csv", dir);
    snprintf(cut, sizeof cut, "%s/cut.csv", dir);
    btdf_table *t = small_grid(3);
    assert_status(BTDF_OK, btdf_table_write(t, path, NULL, NULL, 0));
    size_t n;
    unsigned char *b = slurp(path, &n);
    btdf_table *back = NULL;
    assert_status(BTDF_OK, btdf_table_read(path, &back, NULL, 0));
    assert_int_equal(btdf_table_node_count(back), 3 * 5 * 4);
    btdf_table_free(back);
    size_t tried = 0;
    for (size_t k = 0; k < n; k++) {
        spill(cut, b, k);
        refused(cut);
        tried++;
    }
    assert_int_equal(tried, n);
    /* the message of a cut between rows says so */
    size_t at = n - 2;
    while (b[at - 1] != '\n')
        at--;
    at--;
    while (b[at - 1] != '\n')
        at--; /* drop the end line and the last node row */
    spill(cut, b, at);
    assert_non_null(strstr(refused(cut), "cut short"));
    free(b);
    btdf_table_free(t);
}

/* A node row lost in the middle, one repeated, or text after the end line. */
static void csv_rows_lost_or_added(void **state)
{
    (void)state;
    char path[512], bad[512];
    snprintf(path, sizeof path, "%s/t.csv", dir);
    snprintf(bad, sizeof bad, "%s/bad.csv", dir);
    btdf_table *t = small_grid(1);
    assert_status(BTDF_OK, btdf_table_write(t, path, NULL, NULL, 0));
    size_t n;
    unsigned char *b = slurp(path, &n);
    char *hdr = strstr((char *)b, "\n# rows:"); /* the last line before the nodes */
    assert_non_null(hdr);
    char *row = strchr(hdr + 1, '\n') + 1; /* the first node row */
    char *row2 = strchr(row, '\n') + 1;
    size_t head = (size_t)(row - (char *)b), rl = (size_t)(row2 - row);
    /* lost: the file without its first node row */
    unsigned char *c = malloc(n + rl + 64);
    memcpy(c, b, head);
    memcpy(c + head, row2, n - head - rl);
    spill(bad, c, n - rl);
    refused(bad);
    /* added: the first node row twice */
    memcpy(c, b, head + rl);
    memcpy(c + head + rl, row, n - head);
    spill(bad, c, n + rl);
    refused(bad);
    /* text after the end line */
    memcpy(c, b, n);
    memcpy(c + n, "0,0,0,1,0,0,0\n", 14);
    spill(bad, c, n + 14);
    assert_non_null(strstr(refused(bad), "after the '# end' line"));
    /* no row count: a table of a writer that did not declare it */
    char *rows = strstr((char *)b, "# rows:");
    assert_non_null(rows);
    size_t ro = (size_t)(rows - (char *)b), rlen = (size_t)(strchr(rows, '\n') + 1 - rows);
    memcpy(c, b, ro);
    memcpy(c + ro, b + ro + rlen, n - ro - rlen);
    spill(bad, c, n - rlen);
    assert_non_null(strstr(refused(bad), "# rows"));
    free(c);
    free(b);
    btdf_table_free(t);
}

/* The file with its lines "# rows: N" and "# end: N rows" removed and its comment block
   moved before the header row: the layout btdftab 0.3.0 wrote before row counts. */
static size_t legacy_layout(const unsigned char *b, size_t n, unsigned char *c)
{
    const char *s = (const char *)b, *hdr_end = strchr(s, '\n') + 1;
    const char *rows = strstr(s, "# rows:"), *rows_end = strchr(rows, '\n') + 1;
    const char *end = strstr(s, "# end:");
    size_t k = 0, hl = (size_t)(hdr_end - s);
    memcpy(c + k, hdr_end, (size_t)(rows - hdr_end)); /* the comments */
    k += (size_t)(rows - hdr_end);
    memcpy(c + k, s, hl); /* the header row */
    k += hl;
    memcpy(c + k, rows_end, (size_t)(end - rows_end)); /* the node rows */
    k += (size_t)(end - rows_end);
    (void)n;
    return k;
}

/* Tables of the format before row counts are read, to the same table; a file lacking
   a key names exactly that key and the version that wrote it. */
static void csv_previous_format(void **state)
{
    (void)state;
    char path[512], old[512], again[512];
    snprintf(path, sizeof path, "%s/t.csv", dir);
    snprintf(old, sizeof old, "%s/old.csv", dir);
    snprintf(again, sizeof again, "%s/again.csv", dir);
    btdf_table *t = small_grid(3);
    assert_status(BTDF_OK, btdf_table_write(t, path, NULL, NULL, 0));
    size_t n, m;
    unsigned char *b = slurp(path, &n);
    unsigned char *c = malloc(n + 1);
    assert_non_null(c);
    size_t k = legacy_layout(b, n, c);
    spill(old, c, k);
    btdf_table *back = NULL;
    char msg[512] = "";
    assert_status(BTDF_OK, btdf_table_read(old, &back, msg, sizeof msg));
    /* the same nodes and values: written again it is the original file, byte for byte */
    assert_status(BTDF_OK, btdf_table_write(back, again, NULL, NULL, 0));
    unsigned char *b2 = slurp(again, &m);
    assert_int_equal(m, n);
    assert_memory_equal(b2, b, n);
    free(b2);
    btdf_table_free(back);
    /* its last row cut inside a number: refused (no line end) */
    spill(old, c, k - 3);
    assert_non_null(strstr(refused(old), "cut short"));
    /* without '# smoothness': that key alone is named, and the writer */
    char *sm = strstr((char *)c, "# smoothness:");
    assert_non_null(sm);
    size_t so = (size_t)(sm - (char *)c), sl = (size_t)(strchr(sm, '\n') + 1 - sm);
    memmove(c + so, c + so + sl, k - so - sl);
    spill(old, c, k - sl);
    const char *why = refused(old);
    assert_non_null(strstr(why, "missing '# smoothness' comment"));
    assert_null(strstr(why, "'# k0'"));
    assert_null(strstr(why, "'# rows'"));
    assert_non_null(strstr(why, "written by btdftab " BTDF_VERSION_STRING));
    free(c);
    free(b);
    btdf_table_free(t);
}

/* Header and row numbers are plain decimals, as the tool reads every number: hex, a
   blank before or after, inf or a stray channel count are refused, each naming its key. */
static void csv_header_numbers(void **state)
{
    (void)state;
    char path[512], bad[512];
    snprintf(path, sizeof path, "%s/h.csv", dir);
    snprintf(bad, sizeof bad, "%s/bad.csv", dir);
    btdf_table *t = small_grid(3);
    assert_status(BTDF_OK, btdf_table_write(t, path, NULL, NULL, 0));
    btdf_table_free(t);
    size_t n;
    char *b = (char *)slurp(path, &n);
    b[n] = '\0';
    static const struct {
        const char *from, *to, *why;
    } cases[] = {
        {"# smoothness: 3\n", "# smoothness: 0x3\n", "'# smoothness' must be a decimal"},
        {"# smoothness: 3\n", "# smoothness:  3\n", "'# smoothness' must be a decimal"},
        {"# smoothness: 3\n", "# smoothness: 0x1.8p1\n", "'# smoothness' must be a decimal"},
        {"# k0: 0.7\n", "# k0: 0.7 \n", "'# k0' must be a decimal"},
        {"# channels: 3\n", "# channels: 0x3\n", "'# channels' must be 1 or 3"},
        {"# channels: 3\n", "# channels: 2\n", "'# channels' must be 1 or 3"},
        {"# ior: 1.5 1.5 1.5\n", "# ior: 1.5 inf 1.5\n", "'# ior' must be 1 or 3 decimal"},
        {"# ior: 1.5 1.5 1.5\n", "# ior: 1.5 1.5 0x7\n", "'# ior' must be 1 or 3 decimal"},
        {"\n0,90,0,0,", "\n0,90,0,0x0,", "malformed"}, /* rho_r of the first row */
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        char *at = strstr(b, cases[k].from);
        assert_non_null(at);
        size_t lf = strlen(cases[k].from), lt = strlen(cases[k].to), pre = (size_t)(at - b);
        char *c = malloc(n + lt + 1);
        assert_non_null(c);
        memcpy(c, b, pre);
        memcpy(c + pre, cases[k].to, lt);
        memcpy(c + pre + lt, at + lf, n - pre - lf);
        spill(bad, c, n - lf + lt);
        free(c);
        const char *why = refused(bad);
        if (!strstr(why, cases[k].why)) {
            print_error("'%s': '%s' lacks '%s'\n", cases[k].to, why, cases[k].why);
            fail();
        }
    }
    free(b);
}

#if BTDF_HAVE_OPENEXR
/* Sets the data window of the first part to (0,0)-(mx,my) in the header bytes. */
static int patch_window(unsigned char *b, size_t n, int32_t mx, int32_t my)
{
    static const char key[] = "dataWindow\0box2i\0";
    for (size_t i = 0; i + sizeof key + 20 < n; i++) {
        if (memcmp(b + i, key, sizeof key - 1) == 0) {
            unsigned char *v = b + i + sizeof key - 1 + 4; /* after the 4-byte size */
            int32_t box[4] = {0, 0, mx, my};
            for (int k = 0; k < 4; k++)
                for (int q = 0; q < 4; q++) /* little-endian, as the format says */
                    v[4 * k + q] = (unsigned char)(((uint32_t)box[k] >> (8 * q)) & 0xff);
            return 1;
        }
    }
    return 0;
}

static void exr_declared_sizes(void **state)
{
    (void)state;
    char path[512], bad[512];
    snprintf(path, sizeof path, "%s/t.exr", dir);
    snprintf(bad, sizeof bad, "%s/bad.exr", dir);
    btdf_table *t = small_grid(3);
    assert_status(BTDF_OK, btdf_table_write(t, path, NULL, NULL, 0));
    size_t n;
    unsigned char *b = slurp(path, &n);
    static const int32_t sizes[][2] = {
        {100000, 100000}, /* 120 GB asked of a few kB */
        {1000, 1000},     /* within the chunk table's reach, not the file's */
        {3, 100000},      /* tall */
        {100000, 4},      /* wide */
        {3, 40},          /* more lines than the rows list */
        {30, 4},          /* more columns than the cols list */
    };
    for (size_t k = 0; k < sizeof sizes / sizeof sizes[0]; k++) {
        unsigned char *c = malloc(n);
        memcpy(c, b, n);
        assert_true(patch_window(c, n, sizes[k][0], sizes[k][1]));
        spill(bad, c, n);
        btdf_table *r = NULL;
        char msg[512] = "";
        btdf_status st = btdf_table_read(bad, &r, msg, sizeof msg);
        assert_null(r);
        /* a refusal of a malformed file, never an allocation failure */
        if (st != BTDF_EFORMAT) {
            print_error("%dx%d: '%s' (%s)\n", sizes[k][0], sizes[k][1], msg, btdf_strerror(st));
            fail();
        }
        free(c);
    }
    unsigned char *c = malloc(n);
    memcpy(c, b, n);
    patch_window(c, n, 100000, 100000);
    spill(bad, c, n);
    assert_non_null(strstr(refused(bad), "more than a"));
    free(c);
    free(b);
    btdf_table_free(t);
}
#endif

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(csv_cuts),
        cmocka_unit_test(csv_rows_lost_or_added),
        cmocka_unit_test(csv_previous_format),
        cmocka_unit_test(csv_header_numbers),
#if BTDF_HAVE_OPENEXR
        cmocka_unit_test(exr_declared_sizes),
#endif
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
