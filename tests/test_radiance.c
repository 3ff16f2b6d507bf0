/* SPDX-License-Identifier: MIT */
/* test_radiance.c: the Radiance BSDF builder and writer (Radiance itself: tests/radiance.sh). */
#include <stdlib.h>
#include <string.h>

#include "btdf_test.h"
#include "radiance/radiance_impl.h"

/* The concentric map and its inverse agree (Radiance's two functions are inverses). */
static void test_square_disk_round_trip(void **state)
{
    (void)state;
    for (int i = 1; i < 64; i++) {
        for (int j = 1; j < 64; j++) {
            double a = i / 64.0 + 0.003, b = j / 64.0 - 0.002, x, y, a2, b2;
            rad_square_to_disk(a, b, &x, &y);
            assert_true(x * x + y * y <= 1.0 + 1e-12);
            rad_disk_to_square(x, y, &a2, &b2);
            assert_close(a2, a, 0.0, 1e-12);
            assert_close(b2, b, 0.0, 1e-12);
        }
    }
}

/* One Klems-quarter file of the default material (n = 1.5, s = 3), all four blocks,
   built once for the Klems tests (the group's setup). */
static btdf_rad *klems_q;

static int klems_setup(void **state)
{
    (void)state;
    btdf_params p;
    btdf_params_default(&p);
    return btdf_rad_build(&p, BTDF_RAD_KLEMS_QUARTER, 0.0, 0, &klems_q, NULL, 0) == BTDF_OK
               ? 0
               : -1;
}

static int klems_teardown(void **state)
{
    (void)state;
    btdf_rad_free(klems_q);
    return 0;
}

/* Patch o of a Klems basis: its band, its index in the band, and its projected solid
   angle Lambda = pi (cos^2 lo - cos^2 hi) / nphi. */
static double klems_lambda(const rad_klems_basis *kb, int o, int *band, int *j)
{
    int b = 0, q = o;
    while (q >= kb->nphi[b])
        q -= kb->nphi[b++];
    *band = b;
    *j = q;
    double t0 = kb->theta[b] * M_PI / 180, t1 = kb->theta[b + 1] * M_PI / 180;
    return M_PI * (cos(t0) * cos(t0) - cos(t1) * cos(t1)) / kb->nphi[b];
}

/* The patch a Klems patch turns into by 180 deg about the normal (every band but the
   cap has an even count). */
static int klems_turn(const rad_klems_basis *kb, int o)
{
    int band, j;
    klems_lambda(kb, o, &band, &j);
    return o - j + (j + kb->nphi[band] / 2) % kb->nphi[band];
}

/* Klems: every column's hemispherical sum is the transmittance a render sees, scaled
   as the block says (n^2 rho(1/n) seen from +Z, rho(n)/n^2 from -Z), averaged over the
   incident patch; here at normal incidence (patch 0, a 9 deg cap for the quarter basis),
   against btdf_transmittance at the cap's centre within the variation of T over the cap. */
static void test_klems_columns(void **state)
{
    (void)state;
    btdf_rad *r = klems_q;
    assert_int_equal(btdf_rad_block_count(r), 4);
    const rad_klems_basis *kb = r->kb;
    for (int k = 0; k < 2; k++) {
        double sum = 0.0, lam_total = 0.0;
        for (int o = 0; o < kb->npatch; o++) {
            int band, j;
            double lam = klems_lambda(kb, o, &band, &j);
            sum += r->b[k].klems[(size_t)o * kb->npatch] * lam;
            lam_total += lam;
            assert_true(r->b[k].klems[(size_t)o * kb->npatch] >= 0.0f);
        }
        assert_close(lam_total, M_PI, 1e-12, 0.0);
        btdf_params q = r->p;
        q.ior[0] = r->b[k].n;
        double T0, T9;
        btdf_transmittance(&q, 0.0, &T0);
        btdf_transmittance(&q, 9.0 * M_PI / 180, &T9);
        double want = r->b[k].scale * T0;
        assert_close(sum, want, 0.0, r->b[k].scale * fabs(T9 - T0) + 1e-4);
    }
}

/* The 4-point Gauss-Legendre nodes and weights on [-1, 1] (the builder's rule). */
static const double gx[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563,
                             0.8611363115940526};
static const double gw[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461,
                             0.3478548451374538};

/* The projected-solid-angle average of R(ti) over w = sin^2 ti in [w0, w1] by `panels`
   panels of the 4-point rule in w, or (u_var) in u = cos ti with dw = 2u du. The
   builder's incident rule: 1 panel in w, and in the grazing band 8 panels in u. */
static double r_average(const btdf_params *q, double w0, double w1, int panels, int u_var)
{
    double sum = 0.0, u0 = sqrt(1.0 - w1), u1 = sqrt(1.0 - w0);
    double h = u_var ? (u1 - u0) / panels : (w1 - w0) / panels;
    for (int m = 0; m < panels; m++)
        for (int a = 0; a < 4; a++) {
            double x = (u_var ? u0 : w0) + h * (m + 0.5 * (1.0 + gx[a])), R;
            assert_status(BTDF_OK, btdf_reflectance(q, u_var ? acos(x) : asin(sqrt(x)), &R));
            sum += 0.5 * gw[a] * h * R * (u_var ? 2.0 * x : 1.0);
        }
    return sum / (w1 - w0);
}

/* Klems reflection blocks: for every incident patch the column summed with the outgoing
   patches' projected solid angles is R averaged over the incident patch (R of the
   block's own index: n outside, 1/n inside, whose edge of total internal reflection lies
   at 41.8 deg, inside the quarter basis' 27-45 deg band).
   (a) Against R at the builder's own incident nodes the difference is the outgoing
   integration's alone: its rule stops when its error estimates sum to 1e-7 per outgoing
   patch and incident node (KL_EPS), 41e-7 for 41 patches. An estimate (the difference
   of two rules), not a bound: allowed twice that, plus the file's 6 significant digits
   (5e-7 of the sum) and btdf_reflectance's 1e-9; measured at most 4.4e-7 (front) and
   5.1e-6 (back).
   (b) Against the exact average (256 panels in w) the builder's incident rule adds its
   own error: 4 nodes in w, and in the grazing band 8 panels in cos ti, within 1e-6 of R
   (klems.c); allowed 1e-5 more. A patch's share in the wrong direction (the lobe
   mirrored the wrong way) would move no sum: test_klems_reflection_lookup looks at
   where the lobe is. */
static void test_klems_reflection_energy(void **state)
{
    (void)state;
    btdf_rad *r = klems_q;
    const rad_klems_basis *kb = r->kb;
    for (int k = 2; k < 4; k++) {
        const rad_block *b = &r->b[k];
        assert_true(b->reflect && b->scale == 1.0);
        btdf_params q = r->p;
        q.ior[0] = b->n;
        double worst_a = 0.0, worst_b = 0.0;
        /* The averages depend on the band alone: each is computed once per band. */
        double ra_band[64], rb_band[64];
        int have_band[64] = {0};
        assert_true(kb->nbands <= 64);
        for (int i = 0; i < kb->npatch; i++) {
            int band, j;
            klems_lambda(kb, i, &band, &j);
            double sum = 0.0;
            for (int o = 0; o < kb->npatch; o++) {
                int bo, jo;
                double v = b->klems[(size_t)o * kb->npatch + (size_t)i];
                assert_true(v >= 0.0f && isfinite(v));
                sum += v * klems_lambda(kb, o, &bo, &jo);
            }
            double s0 = sin(kb->theta[band] * M_PI / 180), s1 = sin(kb->theta[band + 1] * M_PI / 180);
            int graze = band == kb->nbands - 1;
            if (!have_band[band]) {
                ra_band[band] = r_average(&q, s0 * s0, s1 * s1, graze ? 8 : 1, graze);
                rb_band[band] = r_average(&q, s0 * s0, s1 * s1, 256, 0);
                have_band[band] = 1;
            }
            double ra = ra_band[band], rb = rb_band[band];
            assert_close(sum, ra, 0.0, 2 * kb->npatch * 1e-7 + 5e-7 * ra + 1e-9);
            assert_close(sum, rb, 0.0, 2 * kb->npatch * 1e-7 + 5e-7 * rb + 1e-5);
            worst_a = fmax(worst_a, fabs(sum - ra));
            worst_b = fmax(worst_b, fabs(sum - rb));
        }
        if (getenv("BTDF_TEST_VERBOSE"))
            fprintf(stderr, "%s: column sums vs R at the rule's nodes %.3g, vs the average %.3g\n",
                    b->label, worst_a, worst_b);
    }
}

/* rho_r is reciprocal and isotropic, so swapping the light and the view maps entry
   (o, i) to (turn(i), turn(o)): the view's patch as the light's travel direction is
   turned by 180 deg, and so is the light's. Both read in one medium (the block's side).
   The builder treats the two roles differently (fixed nodes over the incident patch,
   adaptive over the outgoing one), so the two entries differ by the two rules' errors:
   the outgoing rule's 1e-7 per patch and node over the patch's Lambda (>= 0.0375 sr
   here: 2.7e-6 in the entry) twice, the file's 6 digits (5e-7 relative) twice, and the
   incident rule's error, which this test measures. Outside (n = 1.5) it is smooth:
   measured at most 1.0e-4 relative for entries above 0.01, allowed 1e-3 plus 1e-5.
   Inside (1/n) the entries of directions about 84 deg apart carry the edge of total
   internal reflection, which the incident rule's 4 x 4 nodes do not resolve: measured
   at most 2.6e-2 relative (a 9-27 deg patch with a 45-63 deg one; 1.06e-2 with the
   quarter basis' former bands, 46-66 deg), allowed 4e-2 plus 1e-5 (docs/radiance.md).
   A block with the roles mixed up (the outgoing patch read with the incident rule's
   reversal) puts the lobe at the back-scatter and fails by orders of magnitude. */
static void test_klems_reflection_reciprocity(void **state)
{
    (void)state;
    btdf_rad *r = klems_q;
    const rad_klems_basis *kb = r->kb;
    size_t np = (size_t)kb->npatch;
    for (int k = 2; k < 4; k++) {
        const float *m = r->b[k].klems;
        double worst = 0.0;
        for (int o = 0; o < kb->npatch; o++)
            for (int i = 0; i < kb->npatch; i++) {
                double a = m[(size_t)o * np + (size_t)i];
                double b = m[(size_t)klems_turn(kb, i) * np + (size_t)klems_turn(kb, o)];
                assert_close(a, b, k == 2 ? 1e-3 : 4e-2, 1e-5);
                if (a > 0.01)
                    worst = fmax(worst, fabs(a - b) / a);
            }
        if (getenv("BTDF_TEST_VERBOSE"))
            fprintf(stderr, "%s: reciprocity worst relative %.3g\n", r->b[k].label, worst);
    }
}

/* Read back by Radiance's rule (btdf_rad_lookup), a Klems reflection block puts the
   lobe of a view at 37 deg, azimuth 20 deg, around the mirror azimuth 200 deg on the
   view's side: the largest value over the hemisphere lies within a grazing-band patch
   (45 deg) of it (s = 3: the rough lobe peaks towards grazing, measured at 66.5 deg,
   204 deg), the mirror direction itself reads the matrix' diagonal entry of its patch,
   more than the back-scatter direction (37 deg, 20 deg), and the other side reads 0. */
static void test_klems_reflection_lookup(void **state)
{
    (void)state;
    btdf_rad *r = klems_q;
    const rad_klems_basis *kb = r->kb;
    for (int k = 2; k < 4; k++) {
        double sg = r->b[k].side == BTDF_SIDE_ENTER ? -1.0 : 1.0;
        double tv = 37.0 * M_PI / 180, pv = 20.0 * M_PI / 180;
        double p[3] = {sin(tv) * cos(pv), sin(tv) * sin(pv), sg * cos(tv)};
        double best = -1.0, bt = 0.0, bp = 0.0;
        for (int a = 0; a < 89; a++)
            for (int c = 0; c < 360; c += 2) {
                double t = (a + 0.5) * M_PI / 180, ph = c * M_PI / 180;
                double q[3] = {sin(t) * cos(ph), sin(t) * sin(ph), sg * cos(t)};
                double v = btdf_rad_lookup(r, k, p, q);
                if (v > best) {
                    best = v;
                    bt = a + 0.5;
                    bp = c;
                }
            }
        if (getenv("BTDF_TEST_VERBOSE"))
            fprintf(stderr, "%s: peak %.6g at %.1f %.1f\n", r->b[k].label, best, bt, bp);
        assert_true(fabs(bp - 200.0) <= 45.0);
        double mirror[3] = {-p[0], -p[1], p[2]}, back[3] = {p[0], p[1], p[2]};
        int i = rad_klems_patch(kb, 37.0, 200.0);
        double vm = btdf_rad_lookup(r, k, p, mirror), vb = btdf_rad_lookup(r, k, p, back);
        assert_true(vm == r->b[k].klems[(size_t)i * kb->npatch + (size_t)i]);
        if (getenv("BTDF_TEST_VERBOSE"))
            fprintf(stderr, "%s: mirror %.6g back-scatter %.6g\n", r->b[k].label, vm, vb);
        assert_true(vm > vb);
        double q_other[3] = {-p[0], -p[1], -p[2]};
        assert_true(btdf_rad_lookup(r, k, p, q_other) == 0.0);
    }
}

/* A tree3 file of n = 1.5, s = 2 (coarse: loose tolerance) holding the blocks first..last
   of transmission front and back, reflection front and back (slots 0 to 3, the
   writer's), each grown once at the threshold 3e-4 within max_nodes: no calibration,
   to keep the tests short. */
/* The file btdf_write makes of r, read back whole (*len bytes, malloc'd). */
static char *xml_bytes(const btdf_rad *r, size_t *len)
{
    char path[] = "test_radiance_rt.xml";
    btdf_output what = {NULL, NULL, NULL, NULL, NULL, r};
    assert_status(BTDF_OK, btdf_write(&what, path, NULL, 0));
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    assert_true(n > 0);
    fseek(f, 0, SEEK_SET);
    char *buf = malloc((size_t)n);
    assert_non_null(buf);
    assert_int_equal(fread(buf, 1, (size_t)n, f), (size_t)n);
    fclose(f);
    remove(path);
    *len = (size_t)n;
    return buf;
}

/* What btdf_rad_read_mem reads of our own file is what was written, node for node and
   entry for entry (the file's values are the in-memory floats: 4 digits for tree
   leaves, 6 for Klems entries, 9 for u', v', each reading back to the same float);
   every prefix of it is refused, and so is a leaf made negative. */
static void read_back(const btdf_rad *r)
{
    size_t len;
    char *buf = xml_bytes(r, &len);
    btdf_rad *q = NULL;
    char msg[256];
    assert_status(BTDF_OK, btdf_rad_read_mem(buf, len, &q, msg, sizeof msg));
    assert_int_equal(q->basis, r->basis);
    assert_int_equal(q->channels, r->channels == 3 ? 3 : 1);
    assert_int_equal(q->nblocks, r->nblocks);
    assert_string_equal(q->name, r->name[0] ? r->name : "rough_interface"); /* the writer's default */
    for (int c = 0; c < r->channels; c++)
        assert_true(q->p.ior[c] == r->p.ior[c]);
    assert_true(q->p.smoothness == r->p.smoothness && q->p.k0 == r->p.k0);
    for (int k = 0; k < r->nblocks; k++) {
        const rad_block *a = &r->b[k], *b = &q->b[k];
        assert_string_equal(a->label, b->label);
        if (r->basis == BTDF_RAD_TREE3) {
            assert_int_equal(a->leaves, b->leaves);
            assert_int_equal(a->depth, b->depth);
            /* the layouts may differ: compare by lookups on a grid of directions */
            for (int i = 0; i < 17; i++)
                for (int j = 0; j < 17; j++) {
                    double ti = 0.09 * i, to = 0.09 * j, ph = 0.37 * (i + j);
                    double pv[3] = {sin(ti), 0.0, (a->side == BTDF_SIDE_ENTER ? -1 : 1) * cos(ti)};
                    double sq = a->reflect ? 1.0 : -1.0;
                    double qv[3] = {sin(to) * cos(ph), sin(to) * sin(ph), sq * pv[2] / fmax(1e-300, fabs(pv[2])) * cos(to)};
                    double xa[3], xb[3];
                    btdf_rad_lookup_xyz(r, k, pv, qv, xa);
                    btdf_rad_lookup_xyz(q, k, pv, qv, xb);
                    for (int c = 0; c < 3; c++)
                        assert_true(xa[c] == xb[c]);
                }
        } else {
            size_t np = (size_t)r->kb->npatch;
            for (size_t e = 0; e < np * np; e++) {
                assert_true(a->klems[e] == b->klems[e]);
                if (a->klems_x)
                    assert_true(a->klems_x[e] == b->klems_x[e] && a->klems_z[e] == b->klems_z[e]);
            }
        }
    }
    btdf_rad_free(q);
    /* every cut is found (the stride keeps the test short; the fuzzer tries the rest) */
    size_t tail = strlen("</WindowElement>\n");
    for (size_t cut = 0; cut + tail < len; cut += 1 + len / 397) {
        q = NULL;
        assert_int_equal(btdf_rad_read_mem(buf, cut, &q, msg, sizeof msg), BTDF_EFORMAT);
        assert_null(q);
    }
    char *v = strstr(buf, "<ScatteringData>");
    assert_non_null(v);
    v = strpbrk(v + 16, "0123456789.");
    assert_non_null(v);
    memmove(v + 2, v, (size_t)(buf + len - v) - 2); /* drops the final newline */
    v[0] = '-';
    v[1] = '1';
    assert_int_equal(btdf_rad_read_mem(buf, len, &q, msg, sizeof msg), BTDF_EFORMAT);
    assert_non_null(strstr(msg, "not a btdftab Radiance BSDF"));
    free(buf);
}

static btdf_rad *coarse_tree(int first, int last, size_t max_nodes)
{
    btdf_params p;
    btdf_params_default(&p);
    p.smoothness = 2.0;
    btdf_rad *r = calloc(1, sizeof *r);
    assert_non_null(r);
    r->basis = BTDF_RAD_TREE3;
    r->p = p;
    r->tolerance = 0.5;
    r->nblocks = last + 1;
    double n = p.ior[0];
    const rad_block all[4] = {
        {BTDF_SIDE_ENTER, "Transmission Front", n, 1 / (n * n), 0, BTDF_SIDE_LEAVE, 1 / n, NULL,
         0, 0, 0, NULL, NULL, NULL, NULL},
        {BTDF_SIDE_LEAVE, "Transmission Back", 1 / n, n * n, 0, BTDF_SIDE_ENTER, n, NULL, 0, 0,
         0, NULL, NULL, NULL, NULL},
        {BTDF_SIDE_ENTER, "Reflection Front", n, 1.0, 1, BTDF_SIDE_ENTER, n, NULL, 0, 0, 0, NULL,
         NULL, NULL, NULL},
        {BTDF_SIDE_LEAVE, "Reflection Back", 1 / n, 1.0, 1, BTDF_SIDE_LEAVE, 1 / n, NULL, 0, 0, 0,
         NULL, NULL, NULL, NULL}};
    for (int k = first; k <= last; k++) {
        r->b[k] = all[k];
        assert_status(BTDF_OK, rad_tree_build(&p, 3e-4, 0, max_nodes, &r->b[k], NULL, 0));
    }
    return r;
}

/* A coarse tree: both blocks, the report through Radiance's rule, and a file with
   balanced braces. */
static void test_tree_file(void **state)
{
    (void)state;
    btdf_rad *r = coarse_tree(0, 1, (size_t)1 << 24);
    assert_int_equal(btdf_rad_block_count(r), 2);
    for (int k = 0; k < 2; k++) {
        btdf_report rep;
        memset(&rep, 0, sizeof rep);
        assert_status(BTDF_OK, btdf_rad_report(r, k, 16, 2048, 7, 0, &rep));
        /* up to 80 deg this tree measured e_L1 max 0.23 (block 0); a block read the wrong
           way round (n for 1/n) or mirrored would be off by 1.25 or more */
        assert_true(btdf_rad_e_l1_checked(&rep) < 0.5);
        btdf_report_clear(&rep);
    }
    btdf_rad_set_name(r, "glass & co");
    char path[] = "test_radiance_out.xml";
    btdf_output what = {NULL, NULL, NULL, NULL, NULL, r};
    assert_status(BTDF_OK, btdf_write(&what, path, NULL, 0));
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    long depth = 0, maxd = 0, opens = 0;
    int c, bad = 0;
    char head[64] = "";
    size_t nh = fread(head, 1, sizeof head - 1, f);
    head[nh] = 0;
    fseek(f, 0, SEEK_SET);
    while ((c = fgetc(f)) != EOF) {
        if (c == '{') {
            depth++;
            opens++;
        } else if (c == '}') {
            bad |= --depth < 0;
        }
        maxd = depth > maxd ? depth : maxd;
    }
    fclose(f);
    remove(path);
    assert_true(strncmp(head, "<?xml", 5) == 0);
    assert_int_equal(depth, 0);
    assert_false(bad);
    assert_true(opens > 1000 && maxd > 4);
    read_back(r); /* a name with '&' too */
    btdf_rad_free(r);
}

/* The tree for a threshold eps is the tree grown to a smaller one cut at eps (the
   split rule looks at one cell alone), node for node: what lets the builder search eps
   without evaluating cells again. */
static void test_tree_cut(void **state)
{
    (void)state;
    btdf_params p;
    btdf_params_default(&p);
    p.smoothness = 2.0;
    double n = p.ior[0];
    rad_block direct = {BTDF_SIDE_LEAVE, "Transmission Back", 1 / n, n * n, 0, BTDF_SIDE_ENTER,
                        n, NULL, 0, 0, 0, NULL, NULL, NULL, NULL};
    rad_block cut = direct;
    const double eps = 2e-3;
    assert_status(BTDF_OK, rad_tree_build(&p, eps, 0, (size_t)1 << 22, &direct, NULL, 0));
    rad_tb *t = rad_tb_new(&p, &cut, NULL, NULL, 0);
    assert_non_null(t);
    assert_status(BTDF_OK, rad_tb_grow(t, eps / 4, (size_t)1 << 22));
    assert_status(BTDF_OK, rad_tb_extract(t, eps / 4, &cut));
    size_t finer = cut.nnodes;
    assert_status(BTDF_OK, rad_tb_extract(t, eps, &cut));
    rad_tb_free(t);
    assert_true(finer > cut.nnodes); /* the finer tree is larger: the cut did cut */
    assert_int_equal(direct.nnodes, cut.nnodes);
    assert_int_equal(direct.leaves, cut.leaves);
    for (size_t i = 0; i < direct.nnodes; i++) {
        assert_int_equal(direct.nodes[i].child, cut.nodes[i].child);
        assert_true(direct.nodes[i].v == cut.nodes[i].v);
    }
    free(direct.nodes);
    free(cut.nodes);
}

/* A reflection block (MODEL.md 8) read back by Radiance's rule: a coarse tree's e_L1
   up to 80 deg, and the reflectance it holds against btdf_reflectance. */
static void test_reflection_block(void **state)
{
    (void)state;
    btdf_rad *r = coarse_tree(2, 3, (size_t)1 << 22);
    for (int k = 2; k < 4; k++) {
        btdf_report rep;
        memset(&rep, 0, sizeof rep);
        assert_status(BTDF_OK, btdf_rad_report(r, k, 16, 2048, 7, 0, &rep));
        /* measured: e_L1 up to 80 deg 0.27 (front) and 0.31 (back) for this coarse
           tree, largest near 78 deg; rho (transmission) in place of rho_r reads 0 here,
           and the wrong index (n for 1/n: R differs by 1.5x to 10x) is off by more
           than 0.5 */
        assert_true(btdf_rad_e_l1_checked(&rep) < 0.5);
        for (size_t a = 0; a < rep.test_angles; a++)
            if (rep.per_ti[a].ti < 1.2) /* measured within 3 % up to 69 deg */
                assert_close(rep.per_ti[a].T_table, rep.per_ti[a].T, 0.0,
                             0.1 * fmax(rep.per_ti[a].T, 0.01));
        btdf_report_clear(&rep);
    }
    btdf_rad_free(r);
}

/* Radiance's RGB to XYZ (radiance.c) is fixed by its primaries and white: R = G = B = 1
   is the equal-energy white (X = Y = Z = 1), and each column (one primary alone) has
   that primary's chromaticity; the Y row is then what Radiance's color.h macros give
   (CIE_rf, CIE_gf, CIE_bf). Exact up to rounding: 1e-12. */
static void test_rgb_to_xyz(void **state)
{
    (void)state;
    static const double prim[3][2] = {{0.640, 0.330}, {0.290, 0.600}, {0.150, 0.060}};
    double m[3][3], mi[3][3];
    btdf_rad_rgb_to_xyz(m);
    rad_xyz_to_rgb(mi);
    for (int i = 0; i < 3; i++) {
        assert_close(m[i][0] + m[i][1] + m[i][2], 1.0, 0.0, 1e-12);
        double s = m[0][i] + m[1][i] + m[2][i];
        assert_close(m[0][i] / s, prim[i][0], 0.0, 1e-12);
        assert_close(m[1][i] / s, prim[i][1], 0.0, 1e-12);
        for (int j = 0; j < 3; j++) {
            double e = mi[i][0] * m[0][j] + mi[i][1] * m[1][j] + mi[i][2] * m[2][j];
            assert_close(e, i == j ? 1.0 : 0.0, 0.0, 1e-12);
        }
    }
    /* Radiance's macros (color.h) with these primaries and white, worked by hand */
    assert_close(m[1][0], 0.2651058201, 0.0, 1e-9);
    assert_close(m[1][1], 0.6701058201, 0.0, 1e-9);
    assert_close(m[1][2], 0.0647883598, 0.0, 1e-9);
}

/* ------------------------------------------------------------ colour trees */

/* Blocks 0 and 1 (both transmissions) of a tree3 file, s = 2, each grown once at the
   threshold 3e-4 in every channel (as coarse_tree: no calibration, to keep the tests
   short): one channel (n[0]) or three (R, G, B at n[0..2]: Y, u', v'). */
static btdf_rad *tree_rad(int channels, const double n[3], int threads)
{
    btdf_rad *r = calloc(1, sizeof *r);
    assert_non_null(r);
    btdf_params_default(&r->p);
    r->p.smoothness = 2.0;
    r->p.channels = channels;
    for (int c = 0; c < channels; c++)
        r->p.ior[c] = n[c];
    r->basis = BTDF_RAD_TREE3;
    r->channels = channels;
    r->tolerance = 0.5;
    r->nblocks = 2;
    rad_xyz_to_rgb(r->to_rgb);
    for (int k = 0; k < 2; k++) {
        rad_block_of(k, n[0], &r->b[k]);
        assert_status(BTDF_OK, rad_tree_build(&r->p, 3e-4, threads, (size_t)1 << 24, &r->b[k],
                                              NULL, 0));
    }
    return r;
}

/* Three equal indices: the colour tree is the one-index tree, node for node (the split
   rule sees three equal shares, each channel's leaf value is the one index's, and Y of
   three equal channels is that value: the Y row of the matrix sums to 1), and every
   leaf has the white point's chromaticity u' = 4/19, v' = 9/19 as the file holds them
   (where there is light: grey; where there is none: the white written for no light). */
static void test_tree_colour_neutral(void **state)
{
    (void)state;
    const double n[3] = {1.5, 1.5, 1.5};
    btdf_rad *r3 = tree_rad(3, n, 0), *r1 = tree_rad(1, n, 0);
    read_back(r3); /* a colour tree: Y, u', v' of one structure */
    const float wu = (float)(4.0 / 19.0), wv = (float)(9.0 / 19.0);
    size_t lit = 0;
    for (int k = 0; k < 2; k++) {
        const rad_block *a = &r3->b[k], *b = &r1->b[k];
        assert_non_null(a->cv);
        assert_null(b->cv);
        assert_int_equal(a->nnodes, b->nnodes);
        assert_int_equal(a->leaves, b->leaves);
        for (size_t i = 0; i < a->nnodes; i++) {
            assert_int_equal(a->nodes[i].child, b->nodes[i].child);
            assert_true(a->nodes[i].v == b->nodes[i].v);
            if (a->nodes[i].child >= 0)
                continue;
            const float *cv = a->cv + i * RAD_CV;
            for (int c = 0; c < 3; c++)
                assert_true(cv[c] == b->nodes[i].v);
            assert_true(cv[3] == wu && cv[4] == wv);
            lit += b->nodes[i].v > 0.0f;
        }
    }
    assert_true(lit > 1000);
    /* and Radiance's reading of it: X = Y = Z to the white's floats (X / Y = 9 u' / (4 v')
       is 1 within 2e-7, Z / Y within 4e-7) */
    double p[3] = {0.3, 0.1, -sqrt(0.9)}, q[3] = {-0.2, -0.05, sqrt(1.0 - 0.0425)}, xyz[3];
    btdf_rad_lookup_xyz(r3, 0, p, q, xyz);
    assert_true(xyz[1] > 0.0 && xyz[1] == btdf_rad_lookup(r1, 0, p, q));
    assert_close(xyz[0], xyz[1], 2e-7, 0.0);
    assert_close(xyz[2], xyz[1], 4e-7, 0.0);
    btdf_rad_free(r3);
    btdf_rad_free(r1);
}

/* Walks tree a (colour) and b (one channel, index n[c]) side by side: where both have a
   leaf for the same cell, a's channel c is b's value exactly (the builder gives each
   channel its own value on each cell); counts those leaves into *same. */
static void walk_same(const rad_block *a, size_t ia, const rad_block *b, size_t ib, int c,
                      size_t *same)
{
    int la = a->nodes[ia].child < 0, lb = b->nodes[ib].child < 0;
    if (la && lb) {
        assert_true(a->cv[ia * RAD_CV + (size_t)c] == b->nodes[ib].v);
        ++*same;
        return;
    }
    if (la || lb)
        return; /* one finer than the other there (a splits for any channel) */
    for (int k = 0; k < 8; k++)
        walk_same(a, (size_t)a->nodes[ia].child + (size_t)k, b,
                  (size_t)b->nodes[ib].child + (size_t)k, c, same);
}

/* Three distinct indices (1.2, 1.5, 2.2: saturated, far from white). Each channel's
   leaf value is that index's own (exactly the one-index tree's where the two trees have
   the same cell), and reading the file back as Radiance does (Y and u', v' to X, Y, Z,
   then the inverse matrix) gives each channel within the file's roundings: Y to 4
   significant digits (half a unit of its 4th digit, relative to Y, scales all three
   channels alike) and u', v' to floats (6e-8 relative each, through the derivatives of
   channel c in u' and v' at Y), plus float rounding (6e-8 relative of the channels,
   1e-12 of the tolerance). A channel read with another's index (B for R)
   is tens of per cent off somewhere. No NaN or inf, u', v' > 0 everywhere. */
static void test_tree_colour_channels(void **state)
{
    (void)state;
    const double n[3] = {1.2, 1.5, 2.2};
    btdf_rad *r = tree_rad(3, n, 0);
    double C[3][3], used = 0.0, apart = 0.0;
    rad_xyz_to_rgb(C);
    for (int c = 0; c < 3; c++) {
        const double n1[3] = {n[c], n[c], n[c]};
        btdf_rad *one = tree_rad(1, n1, 0);
        for (int k = 0; k < 2; k++) {
            size_t same = 0;
            walk_same(&r->b[k], 0, &one->b[k], 0, c, &same);
            /* the colour tree is finer, but shares most cells with each channel's */
            assert_true(same * 2 > one->b[k].leaves);
        }
        btdf_rad_free(one);
    }
    for (int k = 0; k < 2; k++) {
        const rad_block *b = &r->b[k];
        for (size_t i = 0; i < b->nnodes; i++) {
            if (b->nodes[i].child >= 0)
                continue;
            const float *cv = b->cv + i * RAD_CV;
            double y = b->nodes[i].v, u = cv[3], v = cv[4], xyz[3];
            assert_true(isfinite(y) && isfinite(u) && isfinite(v) && u > 0.0 && v > 0.0);
            rad_colour_xyz(y, u, v, xyz);
            /* half a unit of Y's 4th digit (its float may sit just below a power of 10:
               1e-4 is 9.99999975e-05) */
            double dy = 0.5 * pow(10.0, floor(log10(fmax(y, 1e-300) * (1.0 + 1e-6))) - 3);
            for (int c = 0; c < 3; c++) {
                double got = C[c][0] * xyz[0] + C[c][1] * xyz[1] + C[c][2] * xyz[2];
                double gu = (C[c][0] * 9.0 - C[c][2] * 3.0) / (4.0 * v);
                double gv = -(C[c][0] * 9.0 * u + C[c][2] * (12.0 - 3.0 * u)) / (4.0 * v * v);
                double tol = (y > 0.0 ? fabs(got) * dy / y : 0.0) +
                             y * (fabs(gu) * 6e-8 * u + fabs(gv) * 6e-8 * v);
                tol = tol * (1.0 + 1e-12) + 6e-8 * (fabs(got) + cv[c]) + 1e-30;
                assert_close(got, cv[c], 0.0, tol);
                used = fmax(used, fabs(got - cv[c]) / tol);
            }
            if (cv[0] > 0.1)
                apart = fmax(apart, fabs(cv[2] - cv[0]) / cv[0]);
        }
    }
    assert_true(apart > 0.1);
    if (getenv("BTDF_TEST_VERBOSE"))
        fprintf(stderr, "colour tree: read back within %.2f of the rounding bound; B vs R up "
                        "to %.3g relative\n", used, apart);
    btdf_rad_free(r);
}

/* The same colour tree on 1 and 2 threads: the same nodes, values and colours, bit for
   bit, and the same file bytes; the file has the Visible, CIE-u and CIE-v trees, of one
   structure (as many braces each). */
static void test_tree_colour_threads(void **state)
{
    (void)state;
    const double n[3] = {1.2, 1.5, 2.2};
    btdf_rad *a = tree_rad(3, n, 1), *b = tree_rad(3, n, 2);
    char pa[] = "test_radiance_c1.xml", pb[] = "test_radiance_c2.xml";
    for (int k = 0; k < 2; k++) {
        assert_int_equal(a->b[k].nnodes, b->b[k].nnodes);
        assert_memory_equal(a->b[k].nodes, b->b[k].nodes, a->b[k].nnodes * sizeof(rad_node));
        assert_memory_equal(a->b[k].cv, b->b[k].cv, a->b[k].nnodes * RAD_CV * sizeof(float));
    }
    btdf_output wa = {NULL, NULL, NULL, NULL, NULL, a}, wb = {NULL, NULL, NULL, NULL, NULL, b};
    assert_status(BTDF_OK, btdf_write(&wa, pa, NULL, 0));
    assert_status(BTDF_OK, btdf_write(&wb, pb, NULL, 0));
    FILE *fa = fopen(pa, "rb"), *fb = fopen(pb, "rb");
    assert_non_null(fa);
    assert_non_null(fb);
    int ca, cb, differ = 0;
    long braces[3] = {0, 0, 0}, part = -1;
    char win[32] = "";
    do {
        ca = fgetc(fa);
        cb = fgetc(fb);
        differ |= ca != cb;
        if (ca == EOF)
            break;
        memmove(win, win + 1, sizeof win - 2);
        win[sizeof win - 2] = (char)ca;
        if (strstr(win, ">Visible<"))
            part = 0;
        else if (strstr(win, ">CIE-u<"))
            part = 1;
        else if (strstr(win, ">CIE-v<"))
            part = 2;
        if (ca == '{' && part >= 0)
            braces[part]++;
    } while (cb != EOF);
    fclose(fa);
    fclose(fb);
    remove(pa);
    remove(pb);
    assert_false(differ);
    assert_true(braces[0] > 1000 && braces[1] == braces[0] && braces[2] == braces[0]);
    btdf_rad_free(a);
    btdf_rad_free(b);
}

/* Blocks 0-2 of a three-channel Klems-quarter file (Reflection Back, the slowest block to
   build, left out: it goes through the same combination). */
static btdf_rad *colour_rad(double n0, double n1, double n2)
{
    btdf_rad *r = calloc(1, sizeof *r);
    assert_non_null(r);
    btdf_params_default(&r->p);
    r->p.channels = 3;
    r->p.ior[0] = n0;
    r->p.ior[1] = n1;
    r->p.ior[2] = n2;
    r->basis = BTDF_RAD_KLEMS_QUARTER;
    r->kb = rad_klems(r->basis);
    r->channels = 3;
    r->nblocks = 3;
    for (int k = 0; k < 3; k++) {
        rad_block_of(k, n0, &r->b[k]);
        assert_status(BTDF_OK, rad_klems_colour(r, k, 0, NULL, 0));
    }
    return r;
}

/* One unit in the 6th significant digit of v: the file's values are rounded to 6
   significant digits (rad_klems_value), so two roundings of values equal up to 1e-15
   relative agree, or differ by this where they straddle a rounding edge. */
static double digit6(double v) { return v == 0.0 ? 0.0 : pow(10.0, floor(log10(fabs(v))) - 5); }

/* Three equal indices: a neutral material. X, Y, Z are the one matrix times the white's
   X/Y and Z/Y (1 and 1 for the equal-energy white), and Y is the one-channel file's
   (the fixture, n = 1.5), within one unit of the 6th digit (digit6). */
static void test_klems_colour_neutral(void **state)
{
    (void)state;
    btdf_rad *r = colour_rad(1.5, 1.5, 1.5);
    size_t nn = (size_t)r->kb->npatch * (size_t)r->kb->npatch;
    for (int k = 0; k < 3; k++) {
        const rad_block *b = &r->b[k], *g = &klems_q->b[k];
        assert_string_equal(b->label, g->label);
        for (size_t e = 0; e < nn; e++) {
            double y = b->klems[e];
            assert_close(y, g->klems[e], 0.0, digit6(g->klems[e]) * 1.0001);
            assert_close(b->klems_x[e], y, 0.0, digit6(y) * 1.0001);
            assert_close(b->klems_z[e], y, 0.0, digit6(y) * 1.0001);
        }
    }
    btdf_rad_free(r);
}

/* Three distinct indices: each channel read back from the file's X, Y, Z (the inverse
   matrix) is the one-channel matrix of its own index. Tolerance per entry, from the
   roundings alone: X, Y and Z are each within half a unit of their 6th digit (5e-6
   relative), which moves channel c by at most sum_j |inv[c][j]| 5e-6 |XYZ_j|; the
   one-channel value is rounded the same way (5e-6 of it); floats add 6e-8 relative,
   or where they are subnormal their smallest step (2^-149, a few of them).
   A channel mixed up with another (n 1.51 for 1.53) differs by about 1 % and fails. */
static void test_klems_colour_channels(void **state)
{
    (void)state;
    const double n[3] = {1.51, 1.52, 1.53};
    btdf_rad *r = colour_rad(n[0], n[1], n[2]);
    const rad_klems_basis *kb = r->kb;
    size_t nn = (size_t)kb->npatch * (size_t)kb->npatch;
    double mi[3][3];
    rad_xyz_to_rgb(mi);
    double worst = 0.0, used = 0.0, apart = 0.0;
    for (int c = 0; c < 3; c++) {
        btdf_params p = r->p;
        p.channels = 1;
        p.ior[0] = n[c];
        for (int k = 0; k < 3; k++) {
            rad_block one;
            memset(&one, 0, sizeof one);
            rad_block_of(k, n[c], &one);
            assert_status(BTDF_OK, rad_klems_build(&p, one.n, one.scale, kb, NULL, 0, &one, NULL, 0));
            const rad_block *b = &r->b[k];
            for (size_t e = 0; e < nn; e++) {
                double xyz[3] = {b->klems_x[e], b->klems[e], b->klems_z[e]};
                double v = 0.0, tol = 5e-6 * fabs(one.klems[e]);
                for (int j = 0; j < 3; j++) {
                    v += mi[c][j] * xyz[j];
                    tol += fabs(mi[c][j]) * 5e-6 * fabs(xyz[j]);
                }
                /* and a float's smallest step where values are subnormal (2^-149 = 1.4e-45) */
                tol = tol * (1.0 + 1e-6) + 6e-8 * (fabs(v) + fabs(one.klems[e]))
                      + 8 * ldexp(1.0, -149);
                assert_close(v, one.klems[e], 0.0, tol);
                worst = fmax(worst, fabs(v - one.klems[e]));
                if (tol > 0.0)
                    used = fmax(used, fabs(v - one.klems[e]) / tol);
                if (c == 0 && one.klems[e] > 0.1)
                    apart = fmax(apart, fabs(mi[2][0] * xyz[0] + mi[2][1] * xyz[1] +
                                             mi[2][2] * xyz[2] - one.klems[e]) /
                                            one.klems[e]);
            }
            free(one.klems);
        }
    }
    /* the channels do differ: B against R's matrix, somewhere */
    assert_true(apart > 1e-3);
    if (getenv("BTDF_TEST_VERBOSE"))
        fprintf(stderr, "colour channels: worst %.3g absolute, %.2f of the tolerance; B vs R "
                        "up to %.3g relative\n", worst, used, apart);
    btdf_rad_free(r);
}

/* The Klems file reads back entry for entry. */
static void test_klems_read_back(void **state)
{
    (void)state;
    btdf_rad_set_name(klems_q, "Glass \xc3\xa9");
    read_back(klems_q);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_square_disk_round_trip),
        cmocka_unit_test(test_tree_file),
        cmocka_unit_test(test_tree_cut),
        cmocka_unit_test(test_reflection_block),
        cmocka_unit_test(test_rgb_to_xyz),
        cmocka_unit_test(test_tree_colour_neutral),
        cmocka_unit_test(test_tree_colour_channels),
        cmocka_unit_test(test_tree_colour_threads),
    };
    const struct CMUnitTest klems[] = {
        cmocka_unit_test(test_klems_columns),
        cmocka_unit_test(test_klems_reflection_energy),
        cmocka_unit_test(test_klems_reflection_reciprocity),
        cmocka_unit_test(test_klems_reflection_lookup),
        cmocka_unit_test(test_klems_colour_neutral),
        cmocka_unit_test(test_klems_colour_channels),
        cmocka_unit_test(test_klems_read_back),
    };
    int fails = cmocka_run_group_tests(tests, NULL, NULL);
    return fails + cmocka_run_group_tests(klems, klems_setup, klems_teardown);
}
