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
#include "formats/formats.h"

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
    btdf_write_opts none = {NULL, NULL, NULL};
    fmt_output_ctx c = {.table = t, .opts = w ? w : &none};
    FILE *f = fopen(path, "wb");
    if (!f)
        return BTDF_EIO;
    btdf_status st = fmt_exr.write_path(&c, f, path, msg, msglen);
    if (fclose(f) != 0 && st == BTDF_OK)
        st = BTDF_EIO;
    return st;
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
    btdf_status st = fmt_exr.read_path(f->path, &back, msg, sizeof msg);
    if (st != BTDF_OK)
        fail_msg("read: %s", msg);
    const btdf_params *a = btdf_table_get_params(f->table), *b = btdf_table_get_params(back);
    assert_int_equal(btdf_table_get_kind(back), btdf_table_get_kind(f->table));
    assert_int_equal(btdf_table_get_rule(back), btdf_table_get_rule(f->table));
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
    btdf_write_opts w = {&rep, "btdftab -o x.exr --s 3.3", NULL};
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
    btdf_status st = fmt_exr.read_path(path, &t, msg, sizeof msg);
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

/* ------------------------------------------------------------------------- */
/* Sweep: every size, 1 and 3 channels, compressible and incompressible data  */
/* ------------------------------------------------------------------------- */

static uint64_t sweep_rng(uint64_t *x)
{
    uint64_t z = (*x += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

/* Compares the file at path with t rounded to binary32, node for node and bit for bit;
   returns the number of chunks the file stores raw (stored size = raw size). */
static size_t check_file_equals_float(const btdf_table *t, const char *path)
{
    char msg[300] = "";
    btdf_table *back = NULL;
    btdf_status st = fmt_exr.read_path(path, &back, msg, sizeof msg);
    if (st != BTDF_OK)
        fail_msg("read back %s: %s", path, msg);
    int nch = btdf_table_get_params(t)->channels;
    assert_int_equal(btdf_table_slice_count(back), btdf_table_slice_count(t));
    for (size_t k = 0; k < btdf_table_slice_count(t); k++) {
        btdf_slice a, b;
        assert_int_equal(btdf_table_slice(t, k, &a), BTDF_OK);
        assert_int_equal(btdf_table_slice(back, k, &b), BTDF_OK);
        assert_int_equal(a.nrows, b.nrows);
        assert_int_equal(a.ncols, b.ncols);
        for (size_t i = 0; i < a.nrows * a.ncols * (size_t)nch; i++)
            if (!(b.values[i] == (double)(float)a.values[i]))
                fail_msg("%s: slice %zu (%zu x %zu) value %zu is %.9g, the table's %.9g", path,
                         k, a.nrows, a.ncols, i, b.values[i], (double)(float)a.values[i]);
    }
    btdf_table_free(back);
    /* How the chunks were stored, through the library's chunk table. */
    exr_context_t ctx = NULL;
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    assert_int_equal(exr_start_read(&ctx, path, &init), EXR_ERR_SUCCESS);
    int parts = 0;
    size_t raw = 0;
    assert_int_equal(exr_get_count(ctx, &parts), EXR_ERR_SUCCESS);
    for (int part = 0; part < parts; part++) {
        exr_attr_box2i_t dw;
        int32_t lpc = 0;
        assert_int_equal(exr_get_data_window(ctx, part, &dw), EXR_ERR_SUCCESS);
        assert_int_equal(exr_get_scanlines_per_chunk(ctx, part, &lpc), EXR_ERR_SUCCESS);
        for (int y = dw.min.y; y <= dw.max.y; y += lpc) {
            exr_chunk_info_t ci;
            assert_int_equal(exr_read_scanline_chunk_info(ctx, part, y, &ci), EXR_ERR_SUCCESS);
            raw += ci.packed_size == ci.unpacked_size;
        }
    }
    exr_finish(&ctx);
    return raw;
}

/* Slices of every height and width around the 16-line ZIP chunk (1, 2, 15, 16, 17, 31,
   33, 50 rows; 1 to 64 columns), values whose low mantissa bits are random, with a
   number of random bits that varies from slice to slice: chunks zlib shrinks a lot, a
   little, or not at all (stored raw). Every file must read back as the table rounded
   to binary32, and the sweep must contain raw chunks (else it did not test that path).
   The case of a zlib stream exactly as long as the raw chunk did not occur with this
   data; the builder's tables below hit it (the writer bug that test_built_sweep
   caught stored such streams as if they were pixels). */
static void test_size_sweep(void **state)
{
    (void)state;
    static const size_t heights[] = {1, 2, 15, 16, 17, 31, 33, 50};
    static const size_t widths[] = {1, 2, 3, 5, 7, 13, 16, 17, 29, 33, 64};
    const size_t nh = sizeof heights / sizeof heights[0], nw = sizeof widths / sizeof widths[0];
    uint64_t rng = 12345;
    size_t raw_chunks = 0;
    for (int nch = 1; nch <= 3; nch += 2) {
        btdf_params p;
        btdf_params_default(&p);
        p.channels = nch;
        btdf_table *t = NULL;
        char msg[300] = "";
        assert_int_equal(btdf_table_new(BTDF_TABLE_FACET, &p, &t, msg, sizeof msg), BTDF_OK);
        size_t k = 0;
        for (size_t ih = 0; ih < nh; ih++)
            for (size_t iw = 0; iw < nw * 6; iw++, k++) {
                size_t nr = heights[ih], nc = widths[iw % nw];
                double rows[64], cols[64], *vals = malloc(nr * nc * 3 * sizeof *vals);
                assert_non_null(vals);
                for (size_t r = 0; r < nr; r++)
                    rows[r] = 0.02 * (double)r;
                for (size_t c = 0; c < nc; c++)
                    cols[c] = 0.04 * (double)c;
                /* 0 to 23 random low bits of a smooth value, six counts per size */
                unsigned bits = (unsigned)((k * 7 + iw / nw * 4) % 24);
                for (size_t i = 0; i < nr * nc * (size_t)nch; i++) {
                    float v = (float)(0.01 + exp(-0.001 * (double)i));
                    uint32_t u;
                    memcpy(&u, &v, sizeof u);
                    if (bits)
                        u ^= (uint32_t)(sweep_rng(&rng) & ((1u << bits) - 1u));
                    memcpy(&v, &u, sizeof v);
                    /* a double below float precision too, to test the rounding */
                    vals[i] = (double)v * (1.0 + 1e-12);
                }
                assert_int_equal(btdf_table_add_slice(t, 0.001 * (double)k, nr, rows, nc, cols,
                                                      vals, msg, sizeof msg),
                                 BTDF_OK);
                free(vals);
            }
        char path[256];
        temp_path(path, sizeof path, nch == 1 ? "sweep-y" : "sweep-rgb");
        assert_int_equal(write_exr(t, path, NULL, msg, sizeof msg), BTDF_OK);
        raw_chunks += check_file_equals_float(t, path);
        remove(path);
        btdf_table_free(t);
    }
    print_message("size sweep: %zu chunks stored raw\n", raw_chunks);
    assert_true(raw_chunks > 0);
}

/* Tables the builder makes, at tolerances 1e-1 to 1e-3 (1e-4 is in the CLI suite, for
   time), 1 and 3 channels, a glass-like and an ice-like material. */
static void test_built_sweep(void **state)
{
    (void)state;
    static const double tols[] = {1e-1, 3e-2, 1e-2, 3e-3, 1e-3};
    static const double mats[][2] = {{1.5, 3.0}, {1.31, 20.0}};
    size_t raw_chunks = 0, files = 0;
    for (size_t m = 0; m < sizeof mats / sizeof mats[0]; m++)
        for (size_t it = 0; it < sizeof tols / sizeof tols[0]; it++)
            for (int nch = 1; nch <= 3; nch += 2) {
                if (nch == 3 && tols[it] < 1e-2)
                    continue; /* time: three channels at the loose end suffice */
                btdf_table_opts o;
                btdf_table_opts_default(&o);
                o.params.ior[0] = mats[m][0];
                o.params.ior[1] = mats[m][0] + 0.01;
                o.params.ior[2] = mats[m][0] + 0.02;
                o.params.channels = nch;
                o.params.smoothness = mats[m][1];
                o.tolerance = tols[it];
                o.estimate = BTDF_ESTIMATE_NONE; /* the file is under test, not the error */
                btdf_table *t = NULL;
                char msg[300] = "";
                btdf_status st = btdf_table_build(&o, &t, msg, sizeof msg);
                if (st != BTDF_OK && st != BTDF_EBUDGET)
                    fail_msg("build: %s", msg);
                char path[256];
                temp_path(path, sizeof path, "built");
                assert_int_equal(write_exr(t, path, NULL, msg, sizeof msg), BTDF_OK);
                raw_chunks += check_file_equals_float(t, path);
                btdf_table *back = NULL; /* the builder's rule comes back with the file */
                assert_int_equal(fmt_exr.read_path(path, &back, msg, sizeof msg), BTDF_OK);
                assert_int_equal(btdf_table_get_rule(back), BTDF_RULE_CHI);
                btdf_table_free(back);
                files++;
                remove(path);
                btdf_table_free(t);
            }
    print_message("built sweep: %zu files, %zu chunks stored raw\n", files, raw_chunks);
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
        cmocka_unit_test(test_size_sweep),
        cmocka_unit_test(test_built_sweep),
    };
    return cmocka_run_group_tests_name("exr", tests, NULL, NULL);
}
