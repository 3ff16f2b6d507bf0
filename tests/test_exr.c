/* SPDX-License-Identifier: MIT */
/* test_exr.c: OpenEXR tables read back exactly; truncated and foreign files refused. */
#include <float.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>
#include <openexr.h>

#include "btdf.h"
#include "formats.h"

#define NSLICES 3

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

typedef struct fixture {
    btdf_table *table;   /* the table as built, double values */
    btdf_table *rounded; /* the same with every value rounded to binary32 */
    char path[256];
} fixture;

static void temp_path(char *buf, size_t len, const char *tag)
{
    const char *dir = getenv("TMPDIR");
    snprintf(buf, len, "%s/btdf-test-%s-%ld.exr", dir && *dir ? dir : "/tmp", tag,
             (long)getpid());
}

/* Three slices of different sizes with awkward coordinates (not binary32 numbers). */
static btdf_table *make_table(int channels, btdf_table_kind kind, int round_values)
{
    btdf_params p;
    btdf_params_default(&p);
    p.channels = channels;
    p.ior[0] = 1.0 / 1.4;
    p.ior[1] = 1.0 / 1.41;
    p.ior[2] = 1.0 / 1.42;
    p.smoothness = 3.3;
    btdf_table *t = NULL;
    char msg[200];
    assert_int_equal(btdf_table_new(kind, &p, &t, msg, sizeof msg), BTDF_OK);
    for (int k = 0; k < NSLICES; k++) {
        size_t nr = 5 + 3 * (size_t)k, nc = 7 + 2 * (size_t)k;
        double ti = 0.1 + 0.3 * k + 1e-13;
        double rows[16], cols[16], vals[16 * 16 * 3];
        for (size_t r = 0; r < nr; r++)
            rows[r] = M_PI / 2 + (M_PI / 2) * sqrt((double)r / (double)(nr - 1));
        for (size_t c = 0; c < nc; c++)
            cols[c] = M_PI * (double)c / (double)(nc - 1);
        for (size_t r = 0; r < nr; r++)
            for (size_t c = 0; c < nc; c++) {
                double *v = &vals[(r * nc + c) * (size_t)channels];
                assert_int_equal(btdf_eval(&p, ti, rows[r], cols[c], v), BTDF_OK);
                for (int ch = 0; ch < channels && round_values; ch++)
                    v[ch] = (double)(float)v[ch];
            }
        assert_int_equal(
            btdf_table_add_slice(t, ti, nr, rows, nc, cols, vals, msg, sizeof msg), BTDF_OK);
    }
    return t;
}

static btdf_status write_exr(const btdf_table *t, const char *path, const btdf_write_opts *w,
                             char *msg, size_t msglen)
{
    btdf_write_opts none = {NULL, NULL};
    btdf_output_ctx c = {.table = t, .opts = w ? w : &none};
    return btdf_format_exr.write_path(&c, path, msg, msglen);
}

static int setup_rgb(void **state)
{
    fixture *f = calloc(1, sizeof *f);
    f->table = make_table(3, BTDF_TABLE_GRID, 0);
    f->rounded = make_table(3, BTDF_TABLE_GRID, 1);
    temp_path(f->path, sizeof f->path, "rgb");
    *state = f;
    return 0;
}

static int setup_y(void **state)
{
    fixture *f = calloc(1, sizeof *f);
    f->table = make_table(1, BTDF_TABLE_FACET, 0);
    f->rounded = make_table(1, BTDF_TABLE_FACET, 1);
    temp_path(f->path, sizeof f->path, "y");
    *state = f;
    return 0;
}

/* The kind the builder gives every n < 1; the file layout is the facet one. */
static int setup_recip(void **state)
{
    fixture *f = calloc(1, sizeof *f);
    f->table = make_table(1, BTDF_TABLE_FACET_RECIPROCAL, 0);
    f->rounded = make_table(1, BTDF_TABLE_FACET_RECIPROCAL, 1);
    temp_path(f->path, sizeof f->path, "recip");
    *state = f;
    return 0;
}

static int teardown(void **state)
{
    fixture *f = *state;
    remove(f->path);
    btdf_table_free(f->table);
    btdf_table_free(f->rounded);
    free(f);
    return 0;
}

/* Coordinates and parameters come back bit for bit, values as binary32. */
static void test_round_trip(void **state)
{
    fixture *f = *state;
    char msg[300] = "";
    assert_int_equal(write_exr(f->table, f->path, NULL, msg, sizeof msg), BTDF_OK);
    btdf_table *back = NULL;
    btdf_status st = btdf_format_exr.read_path(f->path, &back, msg, sizeof msg);
    if (st != BTDF_OK)
        fail_msg("read: %s", msg);
    const btdf_params *a = btdf_table_get_params(f->table), *b = btdf_table_get_params(back);
    assert_int_equal(btdf_table_get_kind(back), btdf_table_get_kind(f->table));
    assert_int_equal(b->channels, a->channels);
    for (int ch = 0; ch < a->channels; ch++)
        assert_true(b->ior[ch] == a->ior[ch]);
    assert_true(b->smoothness == a->smoothness);
    assert_true(b->k0 == a->k0);
    assert_int_equal(btdf_table_slice_count(back), NSLICES);
    size_t nonzero = 0;
    for (size_t k = 0; k < NSLICES; k++) {
        btdf_slice s0, s1;
        assert_int_equal(btdf_table_slice(f->table, k, &s0), BTDF_OK);
        assert_int_equal(btdf_table_slice(back, k, &s1), BTDF_OK);
        assert_true(s1.ti == s0.ti);
        assert_int_equal(s1.nrows, s0.nrows);
        assert_int_equal(s1.ncols, s0.ncols);
        for (size_t r = 0; r < s0.nrows; r++)
            assert_true(s1.rows[r] == s0.rows[r]);
        for (size_t c = 0; c < s0.ncols; c++)
            assert_true(s1.cols[c] == s0.cols[c]);
        for (size_t i = 0; i < s0.nrows * s0.ncols * (size_t)a->channels; i++) {
            assert_true(s1.values[i] == (double)(float)s0.values[i]);
            nonzero += s1.values[i] > 0.0;
        }
    }
    assert_true(nonzero > 20); /* the fixture is not all zeros */
    /* Evaluating the file equals evaluating the float-rounded table, everywhere. */
    for (int i = 0; i < 200; i++) {
        double ti = 0.05 + 0.7 * i / 200.0, to = M_PI / 2 + 1.5 * ((i * 37) % 200) / 200.0;
        double phi = 3.1 * ((i * 71) % 200) / 200.0;
        double v0[3], v1[3];
        assert_int_equal(btdf_table_eval(f->rounded, ti, to, phi, v0), BTDF_OK);
        assert_int_equal(btdf_table_eval(back, ti, to, phi, v1), BTDF_OK);
        for (int ch = 0; ch < a->channels; ch++)
            assert_true(v0[ch] == v1[ch]);
    }
    btdf_table_free(back);
}

/* The report, provenance, units and version are in part 0's header. */
static void test_attributes(void **state)
{
    fixture *f = *state;
    btdf_ti_error per[2] = {{0.1, 0.9, 0.91, 1e-3, 2e-3, 3e-3}, {0.5, 0.8, 0.79, 1e-4, 2e-4, 0}};
    btdf_report rep;
    memset(&rep, 0, sizeof rep);
    rep.slices = NSLICES;
    rep.e_l1_max = 1.25e-3;
    rep.test_angles = 2;
    rep.per_ti = per;
    rep.met = 1;
    btdf_write_opts w = {&rep, "btdftab -o x.exr --s 3.3"};
    char msg[300] = "";
    assert_int_equal(write_exr(f->table, f->path, &w, msg, sizeof msg), BTDF_OK);

    exr_context_t ctx = NULL;
    assert_int_equal(exr_start_read(&ctx, f->path, NULL), EXR_ERR_SUCCESS);
    int count = 0;
    assert_int_equal(exr_get_count(ctx, &count), EXR_ERR_SUCCESS);
    assert_int_equal(count, NSLICES);
    double d = 0;
    assert_int_equal(exr_attr_get_double(ctx, 0, "btdf.report.eL1Max", &d), EXR_ERR_SUCCESS);
    assert_true(d == 1.25e-3);
    int32_t met = 0, len = 0;
    assert_int_equal(exr_attr_get_int(ctx, 0, "btdf.report.met", &met), EXR_ERR_SUCCESS);
    assert_int_equal(met, 1);
    const char *s = NULL;
    assert_int_equal(exr_attr_get_string(ctx, 0, "btdf.provenance", &len, &s), EXR_ERR_SUCCESS);
    assert_int_equal(len, (int32_t)strlen(w.provenance));
    assert_memory_equal(s, w.provenance, (size_t)len);
    assert_int_equal(exr_attr_get_string(ctx, 0, "btdf.units", &len, &s), EXR_ERR_SUCCESS);
    assert_memory_equal(s, "1/sr", 4);
    assert_int_equal(exr_attr_get_string(ctx, 0, "btdf.version", &len, &s), EXR_ERR_SUCCESS);
    assert_memory_equal(s, BTDF_VERSION_STRING, strlen(BTDF_VERSION_STRING));
    assert_int_equal(exr_attr_get_string(ctx, 0, "btdf.report.perTi", &len, &s),
                     EXR_ERR_SUCCESS);
    assert_true(len > 40);
    /* Multi-part files share displayWindow (the C++ library refuses them otherwise);
       the slices differ in size, so their dataWindows differ. */
    exr_attr_box2i_t d0, dk, w0, wk;
    assert_int_equal(exr_get_display_window(ctx, 0, &d0), EXR_ERR_SUCCESS);
    assert_int_equal(exr_get_data_window(ctx, 0, &w0), EXR_ERR_SUCCESS);
    for (int k = 1; k < count; k++) {
        assert_int_equal(exr_get_display_window(ctx, k, &dk), EXR_ERR_SUCCESS);
        assert_memory_equal(&dk, &d0, sizeof d0);
        assert_int_equal(exr_get_data_window(ctx, k, &wk), EXR_ERR_SUCCESS);
        assert_true(wk.max.x != w0.max.x);
    }
    exr_compression_t comp;
    assert_int_equal(exr_get_compression(ctx, 2, &comp), EXR_ERR_SUCCESS);
    assert_int_equal(comp, EXR_COMPRESSION_ZIP);
    exr_finish(&ctx);
}

static long file_size(const char *path)
{
    FILE *fp = fopen(path, "rb");
    assert_non_null(fp);
    fseek(fp, 0, SEEK_END);
    long n = ftell(fp);
    fclose(fp);
    return n;
}

static void copy_prefix(const char *from, const char *to, long n)
{
    FILE *in = fopen(from, "rb"), *out = fopen(to, "wb");
    assert_non_null(in);
    assert_non_null(out);
    for (long i = 0; i < n; i++) {
        int c = getc(in);
        assert_true(c != EOF);
        putc(c, out);
    }
    fclose(in);
    assert_int_equal(fclose(out), 0);
}

static void expect_format_error(const char *path)
{
    btdf_table *t = NULL;
    char msg[300] = "";
    btdf_status st = btdf_format_exr.read_path(path, &t, msg, sizeof msg);
    if (st != BTDF_EFORMAT)
        fail_msg("%s: expected EFORMAT, got %s (%s)", path, btdf_strerror(st), msg);
    assert_null(t);
    assert_true(strlen(msg) > 10); /* a reason is given */
}

/* Every truncation of a good file is refused with BTDF_EFORMAT. */
static void test_truncated(void **state)
{
    fixture *f = *state;
    char msg[300] = "", cut[300];
    assert_int_equal(write_exr(f->table, f->path, NULL, msg, sizeof msg), BTDF_OK);
    temp_path(cut, sizeof cut, "cut");
    long n = file_size(f->path);
    long lens[] = {0, 3, 4, 8, 40, n / 3, n / 2, n - 100, n - 9, n - 1};
    for (size_t i = 0; i < sizeof lens / sizeof lens[0]; i++) {
        copy_prefix(f->path, cut, lens[i]);
        expect_format_error(cut);
    }
    remove(cut);
}

/* Text and PNG files named .exr, and a plain EXR image, are not tables. */
static void test_foreign(void **state)
{
    fixture *f = *state;
    FILE *fp = fopen(f->path, "wb");
    assert_non_null(fp);
    fputs("ti,to,phi,rho\n0,180,0,1.5\n", fp);
    fclose(fp);
    expect_format_error(f->path);

    static const unsigned char png_head[] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n',
                                             0, 0, 0, 13, 'I', 'H', 'D', 'R'};
    fp = fopen(f->path, "wb");
    assert_non_null(fp);
    fwrite(png_head, 1, sizeof png_head, fp);
    fclose(fp);
    expect_format_error(f->path);

    /* A valid one-part EXR picture without the table's attributes. */
    exr_context_t ctx = NULL;
    assert_int_equal(exr_start_write(&ctx, f->path, EXR_WRITE_FILE_DIRECTLY, NULL),
                     EXR_ERR_SUCCESS);
    int part = -1;
    assert_int_equal(exr_add_part(ctx, "picture", EXR_STORAGE_SCANLINE, &part), EXR_ERR_SUCCESS);
    assert_int_equal(exr_initialize_required_attr_simple(ctx, part, 4, 2, EXR_COMPRESSION_NONE),
                     EXR_ERR_SUCCESS);
    assert_int_equal(exr_add_channel(ctx, part, "Y", EXR_PIXEL_FLOAT, EXR_PERCEPTUALLY_LINEAR,
                                     1, 1),
                     EXR_ERR_SUCCESS);
    assert_int_equal(exr_write_header(ctx), EXR_ERR_SUCCESS);
    float px[8] = {1, 2, 3, 4, 5, 6, 7, 8};
    for (int y = 0; y < 2; y++) {
        exr_chunk_info_t ci;
        exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
        assert_int_equal(exr_write_scanline_chunk_info(ctx, part, y, &ci), EXR_ERR_SUCCESS);
        assert_int_equal(exr_encoding_initialize(ctx, part, &ci, &enc), EXR_ERR_SUCCESS);
        enc.channels[0].user_pixel_stride = 4;
        enc.channels[0].user_line_stride = 16;
        enc.channels[0].user_bytes_per_element = 4;
        enc.channels[0].user_data_type = EXR_PIXEL_FLOAT;
        enc.channels[0].encode_from_ptr = (const uint8_t *)(px + 4 * y);
        assert_int_equal(exr_encoding_choose_default_routines(ctx, part, &enc), EXR_ERR_SUCCESS);
        assert_int_equal(exr_encoding_run(ctx, part, &enc), EXR_ERR_SUCCESS);
        exr_encoding_destroy(ctx, &enc);
    }
    assert_int_equal(exr_finish(&ctx), EXR_ERR_SUCCESS);
    expect_format_error(f->path);
}

/* A value beyond binary32 is refused rather than written as inf; bad folders fail. */
static void test_write_errors(void **state)
{
    (void)state;
    btdf_params p;
    btdf_params_default(&p);
    btdf_table *t = NULL;
    char msg[300] = "";
    assert_int_equal(btdf_table_new(BTDF_TABLE_GRID, &p, &t, msg, sizeof msg), BTDF_OK);
    double rows[2] = {2.0, 3.0}, cols[2] = {0.0, 1.0}, vals[4] = {1.0, 1e39, 0.0, 2.0};
    assert_int_equal(btdf_table_add_slice(t, 0.0, 2, rows, 2, cols, vals, msg, sizeof msg),
                     BTDF_OK);
    char path[256];
    temp_path(path, sizeof path, "big");
    assert_int_equal(write_exr(t, path, NULL, msg, sizeof msg), BTDF_EDOMAIN);
    assert_non_null(strstr(msg, "32-bit"));
    remove(path);
    assert_int_equal(write_exr(t, "/nonexistent-folder/x.exr", NULL, msg, sizeof msg), BTDF_EIO);
    btdf_table_free(t);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_round_trip, setup_rgb, teardown),
        cmocka_unit_test_setup_teardown(test_round_trip, setup_y, teardown),
        cmocka_unit_test_setup_teardown(test_round_trip, setup_recip, teardown),
        cmocka_unit_test_setup_teardown(test_attributes, setup_rgb, teardown),
        cmocka_unit_test_setup_teardown(test_truncated, setup_y, teardown),
        cmocka_unit_test_setup_teardown(test_foreign, setup_y, teardown),
        cmocka_unit_test(test_write_errors),
    };
    return cmocka_run_group_tests_name("exr", tests, NULL, NULL);
}
