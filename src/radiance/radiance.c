/* SPDX-License-Identifier: MIT */
/* radiance.c: builds the blocks of a WINDOW/Radiance BSDF and reads them back by
   Radiance's rules (tree: ttree.c; Klems: klems.c). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "radiance/radiance_impl.h"

static const char *const basis_names[] = {"tree3", "klems-full", "klems-half", "klems-quarter"};

BTDF_API int btdf_rad_basis_parse(const char *s, btdf_rad_basis *b)
{
    for (int k = 0; k < 4; k++)
        if (s && !strcmp(s, basis_names[k])) {
            *b = (rad_basis)k;
            return 1;
        }
    return 0;
}

const char *rad_basis_name(rad_basis b)
{
    return (unsigned)b < 4 ? basis_names[b] : "unknown";
}

BTDF_API const char *btdf_rad_basis_name(btdf_rad_basis b) { return rad_basis_name(b); }

BTDF_API int btdf_rad_block_count(const btdf_rad *r) { return r ? r->nblocks : 0; }

BTDF_API int btdf_rad_channels(const btdf_rad *r) { return r ? (r->channels == 3 ? 3 : 1) : 0; }

/* ------------------------------------------------------------------ colour */

/* Radiance renders in its own RGB: the primaries of its color.h when built without
   NTSC_RGB or SHARP_RGB ("nominal CRT primaries"), with an equal-energy white:
   chromaticities (x, y) R (0.640, 0.330), G (0.290, 0.600), B (0.150, 0.060), white
   (1/3, 1/3). A three-channel file's R, G, B are in that space, so that rtrace's R, G, B
   are the three channels and equal channels are white (docs/radiance.md "Colour"). */
static const double rad_prim[4][2] = {{0.640, 0.330}, {0.290, 0.600}, {0.150, 0.060},
                                      {1.0 / 3.0, 1.0 / 3.0}};

static void inv3(double a[3][3], double o[3][3])
{
    double c00 = a[1][1] * a[2][2] - a[1][2] * a[2][1];
    double c01 = a[1][2] * a[2][0] - a[1][0] * a[2][2];
    double c02 = a[1][0] * a[2][1] - a[1][1] * a[2][0];
    /* only for the primaries' matrices: three chromaticities not on one line, so
       det != 0 (a triangle of area 0.1 or so in (x, y)) */
    double d = a[0][0] * c00 + a[0][1] * c01 + a[0][2] * c02;
    o[0][0] = c00 / d;
    o[1][0] = c01 / d;
    o[2][0] = c02 / d;
    o[0][1] = (a[0][2] * a[2][1] - a[0][1] * a[2][2]) / d;
    o[1][1] = (a[0][0] * a[2][2] - a[0][2] * a[2][0]) / d;
    o[2][1] = (a[0][1] * a[2][0] - a[0][0] * a[2][1]) / d;
    o[0][2] = (a[0][1] * a[1][2] - a[0][2] * a[1][1]) / d;
    o[1][2] = (a[0][2] * a[1][0] - a[0][0] * a[1][2]) / d;
    o[2][2] = (a[0][0] * a[1][1] - a[0][1] * a[1][0]) / d;
}

/* Column j of the matrix is primary j's XYZ at luminance S_j: (x/y, 1, z/y) S_j, the
   S_j chosen so that R = G = B = 1 gives the white's XYZ at Y = 1, here (1, 1, 1). */
void rad_rgb_to_xyz(double m[3][3])
{
    double p[3][3], ip[3][3], w[3];
    for (int j = 0; j < 3; j++) {
        double x = rad_prim[j][0], y = rad_prim[j][1];
        p[0][j] = x / y; /* y > 0 for every primary */
        p[1][j] = 1.0;
        p[2][j] = (1.0 - x - y) / y;
    }
    double xw = rad_prim[3][0], yw = rad_prim[3][1];
    w[0] = xw / yw;
    w[1] = 1.0;
    w[2] = (1.0 - xw - yw) / yw;
    inv3(p, ip);
    for (int j = 0; j < 3; j++) {
        double sj = ip[j][0] * w[0] + ip[j][1] * w[1] + ip[j][2] * w[2];
        for (int i = 0; i < 3; i++)
            m[i][j] = p[i][j] * sj;
    }
}

void rad_xyz_to_rgb(double m[3][3])
{
    double a[3][3];
    rad_rgb_to_xyz(a);
    inv3(a, m);
}

BTDF_API void btdf_rad_rgb_to_xyz(double m[3][3]) { rad_rgb_to_xyz(m); }

/* Block k's geometry for the index nc (radiance.h: what each block holds and why). */
void rad_block_of(int k, double nc, rad_block *b)
{
    static const char *const labels[4] = {"Transmission Front", "Transmission Back",
                                          "Reflection Front", "Reflection Back"};
    b->label = labels[k];
    b->reflect = k >= 2;
    b->side = k % 2 == 0 ? BTDF_SIDE_ENTER : BTDF_SIDE_LEAVE;
    b->n = k % 2 == 0 ? nc : 1.0 / nc;
    /* transmission: p as incident, rho(n; p -> q) scaled to rho(n_light; q -> p) */
    b->scale = k == 0 ? 1.0 / (nc * nc) : (k == 1 ? nc * nc : 1.0);
    /* Reflection: p and q on one side, rho_r reciprocal: no swap, no scale. */
    b->light = k == 0 || k == 3 ? BTDF_SIDE_LEAVE : BTDF_SIDE_ENTER;
    b->n_light = b->light == BTDF_SIDE_ENTER ? nc : 1.0 / nc;
}

/* The index of the light block k serves, in channel c. */
double rad_n_light(const btdf_rad *r, int k, int c)
{
    rad_block b;
    rad_block_of(k, r->p.ior[r->channels == 3 && c > 0 ? c : 0], &b);
    return b.n_light;
}


/* Channel c (-1: Y) of leaf i of tree block b: chosen = 1, in a colour tree, the value
   the builder chose (cv), else as Radiance reads the file back (Y and u', v' to X, Y, Z,
   then to R, G, B through the inverse of rad_rgb_to_xyz). */
double rad_tree_value(const btdf_rad *r, const rad_block *b, size_t i, int c, int chosen)
{
    if (!b->cv || c < 0)
        return b->nodes[i].v;
    const float *cv = b->cv + i * RAD_CV;
    if (chosen)
        return cv[c];
    double xyz[3];
    rad_colour_xyz(b->nodes[i].v, cv[3], cv[4], xyz);
    return r->to_rgb[c][0] * xyz[0] + r->to_rgb[c][1] * xyz[1] + r->to_rgb[c][2] * xyz[2];
}

BTDF_API btdf_status btdf_rad_block(const btdf_rad *r, int k, btdf_rad_block_info *info)
{
    if (!r || !info || k < 0 || k >= r->nblocks)
        return BTDF_EINVAL;
    const rad_block *b = &r->b[k];
    info->label = b->label;
    info->light = b->light;
    info->n_light = b->n_light;
    info->values = r->basis == RAD_BASIS_TREE3 ? b->leaves
                                               : (size_t)r->kb->npatch * (size_t)r->kb->npatch;
    info->depth = r->basis == RAD_BASIS_TREE3 ? b->depth : 0;
    return BTDF_OK;
}

BTDF_API btdf_rad_basis btdf_rad_get_basis(const btdf_rad *r) { return r->basis; }

BTDF_API const btdf_params *btdf_rad_get_params(const btdf_rad *r) { return r ? &r->p : NULL; }

BTDF_API double btdf_rad_seconds_build(const btdf_rad *r) { return r ? r->seconds_build : 0.0; }

BTDF_API void btdf_rad_set_name(btdf_rad *r, const char *name)
{
    if (r && name)
        snprintf(r->name, sizeof r->name, "%s", name);
}

BTDF_API void btdf_rad_set_errors(btdf_rad *r, int k, double e_l1, double e_t)
{
    if (!r || k < 0 || k >= r->nblocks)
        return;
    r->e_l1[k] = e_l1;
    r->e_t[k] = e_t;
    r->reported = 1;
}

BTDF_API void btdf_rad_free(btdf_rad *r)
{
    if (!r)
        return;
    for (int k = 0; k < RAD_MAX_BLOCKS; k++) {
        free(r->b[k].nodes);
        free(r->b[k].cv);
        free(r->b[k].klems);
        free(r->b[k].klems_x);
        free(r->b[k].klems_z);
    }
    for (int c = 0; c < BTDF_MAX_CHANNELS; c++)
        for (int h = 0; h < 2; h++)
            btdf_full_free(r->ms[c][h]);
    free(r);
}

BTDF_API double btdf_rad_e_l1_checked(const btdf_report *rep)
{
    double e = 0.0;
    for (size_t a = 0; a < rep->test_angles; a++)
        if (rep->per_ti[a].ti <= RAD_TI_CHECKED + 1e-12)
            e = fmax(e, rep->per_ti[a].e_l1);
    return e;
}

/* The tree's node budget: 2^25 nodes (384 MB while building), far beyond any useful file. */
#define RAD_MAX_NODES ((size_t)1 << 23)
/* The builder's own error estimate: its own seed, 192 light angles up to RAD_TI_CHECKED
   (stratified) and 32 x 64 views each, stratified in projected solid angle. */
#define RAD_CHECK_SEED 0x5ad1a7e5u
#define RAD_CHECK_ANGLES 192
#define RAD_CHECK_S 32
#define RAD_CHECK_PHI 64
/* Aim below the tolerance: the report is another, independent estimate. */
#define RAD_AIM 0.85
#define RAD_EDGE_DIV 64 /* ring radii j / 64: the r edges of level-7 cells */
/* The final check of a cut tree, by the report's estimator with the builder's seed. */
#define RAD_AIM_CHECK 0.92

BTDF_API btdf_status btdf_rad_build(const btdf_params *p, btdf_rad_basis basis,
                                    double tolerance, int threads, btdf_rad **out, char *msg,
                                    size_t msglen)
{
    return btdf_rad_build_progress(p, basis, tolerance, threads, NULL, NULL, out, msg, msglen);
}

/* ------------------------------------------------------------ probe estimate */


void rad_probes_free(rad_probes *pr)
{
    free(pr->ti);
    free(pr->u0);
    memset(pr, 0, sizeof *pr);
}

/* The view p and light q of block k (Radiance's frame) for the light at ti in its own
   MODEL.md frame and a view at (to, phi) in it (to in [pi/2, pi] for a transmission
   block, [0, pi/2] for a reflection block). */
void rad_render_dirs(const btdf_rad *r, int k, double ti, double to, double phi, double p[3],
                        double q[3])
{
    const rad_block *b = &r->b[k];
    if (b->reflect) {
        /* rho_r: the light at azimuth 0, phi = pi the specular plane (MODEL.md 8) */
        double sg = b->side == BTDF_SIDE_ENTER ? -1.0 : 1.0;
        q[0] = sin(ti);
        q[1] = 0.0;
        q[2] = sg * cos(ti);
        p[0] = sin(to) * cos(phi);
        p[1] = sin(to) * sin(phi);
        p[2] = sg * cos(to);
        return;
    }
    /* the light's MODEL.md frame: source at azimuth pi, so it travels towards +x */
    q[0] = -sin(ti);
    q[1] = 0.0;
    q[2] = cos(ti);
    p[0] = sin(to) * cos(phi - M_PI);
    p[1] = sin(to) * sin(phi - M_PI);
    p[2] = cos(to);
    if (b->light == BTDF_SIDE_ENTER) {
        /* light from -Z: its frame seen from Radiance's is turned by pi about x */
        q[2] = -q[2];
        p[1] = -p[1];
        p[2] = -p[2];
    }
}

static void probe_angle(void *arg, size_t i)
{
    rad_probes *pr = arg;
    const btdf_rad *r = pr->r;
    const rad_block *b = &r->b[pr->k];
    uint64_t z = RAD_CHECK_SEED ^ (0x51ed2701u * (uint64_t)(i + 1)) ^ ((uint64_t)pr->k << 40);
    double ti = pr->ti[i];
    for (size_t s = 0; s < pr->ns; s++) {
        for (size_t ph = 0; ph < pr->nphi; ph++) {
            size_t j = i * pr->kv + s * pr->nphi + ph;
            double u1 = ((double)s + core_unif(&z)) / (double)pr->ns;
            double phi = 2.0 * M_PI * ((double)ph + core_unif(&z)) / (double)pr->nphi;
            double st = sqrt(u1), to = asin(st), f;
            if (b->reflect) {
                f = pr->ms ? btdf_full_rho_r(pr->ms, ti, to, phi)
                           : btdf_rho_r_model(r->p.model, pr->n_light, r->p.smoothness,
                                              r->p.k0, ti, to, phi);
            } else {
                to = M_PI - to;
                f = pr->ms ? btdf_full_rho(pr->ms, ti, to, phi)
                           : btdf_rho_model(r->p.model, pr->n_light, r->p.smoothness, r->p.k0,
                                            ti, to, phi);
            }
            double pv[3], qv[3];
            rad_render_dirs(r, pr->k, ti, to, phi, pv, qv);
            if (r->basis == RAD_BASIS_TREE3) {
                rad_tree_coords(pv, qv, &pr->u0[j], &pr->a[j], &pr->b[j]);
            } else {
                pr->u0[j] = rad_lookup_ch(r, pr->k, pr->c, 0, pv, qv);
                pr->a[j] = pr->b[j] = 0.0;
            }
            pr->f[j] = f;
        }
    }
}

btdf_status rad_probes_make(const btdf_rad *r, int k, int c, double ti_max, size_t m,
                                   size_t ns, size_t nphi, uint64_t seed, int threads,
                                   rad_probes *pr)
{
    memset(pr, 0, sizeof *pr);
    pr->c = c;
    pr->n_light = rad_n_light(r, k, c);
    pr->ms = rad_ms(r, c, pr->n_light);
    pr->ti_max = ti_max;
    /* e_L1 jumps where a light's ring passes from one cell to the next in r, at
       r = j / 2^(L-1) for a cell of level L; a stratified set misses narrow peaks
       there, so the builder's set (ti_max < pi/2) adds both sides of every level-7
       edge up to ti_max. */
    size_t extra = 0;
    if (ti_max < M_PI / 2)
        for (int j = 1; j < RAD_EDGE_DIV && asin((j + 1e-6) / RAD_EDGE_DIV) <= ti_max; j++)
            extra += 2;
    m += extra;
    pr->m = m;
    pr->ns = ns;
    pr->nphi = nphi;
    pr->kv = ns * nphi;
    pr->r = r;
    pr->k = k;
    size_t n = m * pr->kv;
    pr->ti = malloc(3 * m * sizeof *pr->ti);
    pr->u0 = malloc(4 * n * sizeof *pr->u0);
    if (!pr->ti || !pr->u0) {
        rad_probes_free(pr);
        return BTDF_ENOMEM;
    }
    pr->T = pr->ti + m;
    pr->fl = pr->T + m;
    pr->a = pr->u0 + n;
    pr->b = pr->a + n;
    pr->f = pr->b + n;
    btdf_params q = rad_single(&r->p);
    q.channels = 1;
    q.ior[0] = pr->n_light;
    uint64_t z = seed;
    for (size_t i = 0; i < m; i++) {
        if (i < m - extra) {
            pr->ti[i] = pr->ti_max * ((double)i + core_unif(&z)) / (double)(m - extra);
        } else {
            size_t e = i - (m - extra);
            pr->ti[i] = asin(((double)(e / 2 + 1) + (e % 2 ? 1e-6 : -1e-6)) / RAD_EDGE_DIV);
        }
        double v = 0.0;
        btdf_status st = r->b[k].reflect ? btdf_reflectance(&q, pr->ti[i], &v)
                                         : btdf_transmittance(&q, pr->ti[i], &v);
        if (st != BTDF_OK) {
            rad_probes_free(pr);
            return st;
        }
        if (pr->ms) /* full's norm: smith's quadrature plus the tallied orders 2+ */
            v += full_ms_energy(pr->ms, r->b[k].reflect, pr->ti[i], NULL);
        pr->T[i] = v;
        pr->fl[i] = fmax(v, 0.01); /* MODEL.md section 6 floor */
    }
    core_parallel_for(threads, m, probe_angle, pr);
    return BTDF_OK;
}

static void probe_error(void *arg, size_t i)
{
    rad_probes *pr = arg;
    double l1 = 0.0, dmax = 0.0, fmaxv = 0.0, tf = 0.0;
    for (size_t j = i * pr->kv; j < (i + 1) * pr->kv; j++) {
        double v = pr->tree ? rad_tree_value(pr->r, pr->tree,
                                          rad_tree_leaf(pr->tree->nodes, pr->u0[j], pr->a[j],
                                                        pr->b[j]),
                                          pr->r->channels == 3 ? pr->c : -1, pr->chosen)
                            : pr->u0[j];
        double d = fabs(v - pr->f[j]);
        l1 += d;
        tf += v;
        dmax = fmax(dmax, d);
        fmaxv = fmax(fmaxv, pr->f[j]);
    }
    double w = M_PI / (double)pr->kv; /* projected solid angle of one stratum */
    btdf_ti_error *e = &pr->res[i];
    e->ti = pr->ti[i];
    e->T = pr->T[i];
    e->T_table = w * tf;
    e->e_l1 = w * l1 / pr->fl[i];
    e->e_t = fabs(w * tf - pr->T[i]) / pr->fl[i];
    /* e_max is defined where T >= 0.01 (MODEL.md 6); fmaxv > 0 there */
    e->e_max = pr->T[i] >= 0.01 && fmaxv > 0.0 ? dmax / fmaxv : 0.0;
}

/* The errors of tree block `tree` (NULL: a Klems block) at every probe angle into res[m]. */
void rad_probes_eval(rad_probes *pr, const rad_block *tree, int threads,
                            btdf_ti_error *res)
{
    pr->tree = tree;
    pr->res = res;
    core_parallel_for(threads, pr->m, probe_error, pr);
}

static double res_max_l1(const btdf_ti_error *res, size_t m)
{
    double e = 0.0;
    for (size_t i = 0; i < m; i++)
        e = fmax(e, res[i].e_l1);
    return e;
}

/* Passes of a tensor-tree block, for the progress bar (growth steps). */
#define RAD_TREE_PASSES 8


/* The channels a colour tree's builder checks: one per distinct index (equal indices
   give equal channels), into ch[]; their count. One channel: channel 0. */
static int tree_channels(const btdf_rad *r, int ch[3])
{
    int n = 0;
    for (int c = 0; c < (r->channels == 3 ? 3 : 1); c++) {
        int seen = 0;
        for (int d = 0; d < c; d++)
            seen |= r->p.ior[d] == r->p.ior[c];
        if (!seen)
            ch[n++] = c;
    }
    return n;
}

/* The largest probe e_L1 of tree block b per checked channel (into e[], the probe sets'
   order) and the worst of them (res: the last channel's per-angle errors). */
static double tree_probe_err(rad_probes *pr, int npr, const rad_block *b, int threads,
                             btdf_ti_error *res, double *e)
{
    double w = 0.0;
    for (int i = 0; i < npr; i++) {
        rad_probes_eval(&pr[i], b, threads, res);
        e[i] = res_max_l1(res, pr[i].m);
        w = fmax(w, e[i]);
    }
    return w;
}

/* Thresholds per channel from those of the checked channels (chs[i]: eps[i]); a channel
   of an index met before shares its threshold. */
static void tree_eps3(const btdf_rad *r, const int *chs, int npr, const double *eps,
                      double out[3])
{
    for (int c = 0; c < 3; c++) {
        out[c] = eps[0]; /* one channel: eps[0] alone is used */
        for (int i = 0; i < npr && r->channels == 3; i++)
            if (r->p.ior[chs[i]] == r->p.ior[c])
                out[c] = eps[i];
    }
}

/* Multiplies by f the threshold lo[c] of every channel whose e_L1 ech[c] is above aim;
   where one falls below what the tree was grown to (grown[c]), grows the tree further;
   then cuts it at lo into b. */
static btdf_status recut_missing(const btdf_rad *r, rad_tb *t, rad_block *b, const int *chs,
                                 int npr, const double *ech, double aim, double f, double *lo,
                                 double *grown)
{
    double e3[3];
    int regrow = 0;
    for (int c = 0; c < npr; c++) {
        if (!(ech[c] > aim))
            continue;
        lo[c] *= f;
        if (lo[c] < grown[c]) {
            grown[c] = lo[c];
            regrow = 1;
        }
    }
    if (regrow) {
        tree_eps3(r, chs, npr, grown, e3);
        btdf_status st = rad_tb_grow3(t, e3, RAD_MAX_NODES);
        if (st != BTDF_OK)
            return st;
    }
    tree_eps3(r, chs, npr, lo, e3);
    return rad_tb_extract3(t, e3, b);
}

/* Grows the tree of block k until the probe estimate's largest e_L1 is below
   RAD_AIM * tolerance, then cuts it at the largest eps that still holds that. A colour
   tree has one eps per channel (index): grown with one eps until every channel meets the
   aim (each channel's probes against its own leaf values, as the builder chose them; the
   file carries them to the rounding of Y, 5e-4), then each channel's eps raised in turn
   while every channel still meets it (a channel's splits help the others, so all are
   checked). With one index this is the one-channel search, step for step. */
static btdf_status rad_tree_block(btdf_rad *r, int k, int threads, btdf_progress_fn progress,
                                  void *user, char *msg, size_t msglen)
{
    rad_block *b = &r->b[k];
    rad_probes pr[3];
    int chs[3], npr = tree_channels(r, chs);
    btdf_status st = BTDF_OK;
    memset(pr, 0, sizeof pr);
    for (int i = 0; i < npr && st == BTDF_OK; i++) {
        st = rad_probes_make(r, k, chs[i], RAD_TI_CHECKED, RAD_CHECK_ANGLES, RAD_CHECK_S,
                             RAD_CHECK_PHI, RAD_CHECK_SEED, threads, &pr[i]);
        pr[i].chosen = 1;
    }
    if (st != BTDF_OK) {
        for (int i = 0; i < npr; i++)
            rad_probes_free(&pr[i]);
        return st;
    }
    btdf_ti_error *res = malloc(pr[0].m * sizeof *res);
    btdf_full *ms[3], *msl[3];
    int full = rad_block_ms(r, k, ms, msl);
    rad_tb *t = res ? rad_tb_new(&r->p, b, full ? ms : NULL, full ? msl : NULL, threads) : NULL;
    if (!t) {
        free(res);
        for (int i = 0; i < npr; i++)
            rad_probes_free(&pr[i]);
        return core_say(BTDF_ENOMEM, msg, msglen, "out of memory building the tensor tree");
    }
    double aim = RAD_AIM * r->tolerance, ech[3], e3[3];
    /* per checked channel: its cut (lo) and what the tree is grown to (grown; 1e300: not
       yet, no split for that channel) */
    double lo[3] = {0.0, 0.0, 0.0}, grown[3] = {1e300, 1e300, 1e300}, e = 0.0;
    int pass = 0;
    for (int c = 0; c < npr && st == BTDF_OK; c++) {
        /* Channel c alone (the others' thresholds at infinity): its one-channel tree.
           A cell's share is about eps and a light's ring crosses some 10^2 to 10^4 cells:
           start from eps = tolerance / 100 and refine as e_L1 ~ eps^(1/3) suggests. */
        double eps = r->tolerance * 1e-2, one[3] = {1e300, 1e300, 1e300};
        for (;;) {
            if (progress)
                progress(user, "tensor tree, block", (size_t)(k * RAD_TREE_PASSES + pass),
                         (size_t)((r->nblocks - k) * RAD_TREE_PASSES - pass));
            grown[c] = fmin(grown[c], eps);
            tree_eps3(r, chs, npr, grown, e3);
            st = rad_tb_grow3(t, e3, RAD_MAX_NODES);
            if (st == BTDF_ENOMEM)
                break;
            one[c] = eps;
            tree_eps3(r, chs, npr, one, e3);
            btdf_status se = rad_tb_extract3(t, e3, b);
            if (se != BTDF_OK) {
                st = se;
                break;
            }
            rad_probes_eval(&pr[c], b, threads, res);
            e = res_max_l1(res, pr[c].m);
            if (getenv("BTDF_RAD_DEBUG")) {
                fprintf(stderr, "grow %s channel %d eps %.3g: %zu leaves, e_L1 max %.4g:",
                        b->label, chs[c], eps, b->leaves, e);
                for (size_t i = 0; i < pr[c].m; i += 6)
                    fprintf(stderr, " %.0f:%.3g", res[i].ti * 180 / M_PI, res[i].e_l1);
                fprintf(stderr, " %.1f:%.3g\n", res[pr[c].m - 1].ti * 180 / M_PI,
                        res[pr[c].m - 1].e_l1);
            }
            if (e <= aim || st == BTDF_EBUDGET)
                break;
            double g = aim / e;
            g = g * g * g;
            eps *= g < 1.0 / 64 ? 1.0 / 64 : (g > 0.5 ? 0.5 : g);
            if (pass < RAD_TREE_PASSES - 1)
                pass++;
        }
        if (st != BTDF_OK)
            break;
        /* Cut: the largest eps (a factor 2^(1/8) apart) whose tree still meets the aim. */
        double hi = 0.0;
        lo[c] = eps;
        for (int i = 0; i < 24; i++) {
            double x = hi > 0.0 ? sqrt(lo[c] * hi) : 2.0 * lo[c];
            if (hi > 0.0 && hi / lo[c] < 1.09)
                break;
            one[c] = x;
            tree_eps3(r, chs, npr, one, e3);
            if (rad_tb_extract3(t, e3, b) != BTDF_OK)
                break;
            rad_probes_eval(&pr[c], b, threads, res);
            double ex = res_max_l1(res, pr[c].m);
            if (getenv("BTDF_RAD_DEBUG"))
                fprintf(stderr, "cut %s channel %d eps %.3g: %zu leaves, e_L1 max %.4g\n",
                        b->label, chs[c], x, b->leaves, ex);
            if (ex <= aim)
                lo[c] = x;
            else
                hi = x;
        }
    }
    if (st == BTDF_OK) {
        /* The colour tree splits where any channel's does: check each channel on it and
           cut finer (2^(-1/8)) for a channel that misses (its leaves are its own tree's
           or finer, which usually lowers its e_L1 but need not: the leaf values minimise
           a cell's own share, not a light's sum); with one channel this never runs, its
           cut met the aim. */
        tree_eps3(r, chs, npr, lo, e3);
        st = rad_tb_extract3(t, e3, b);
        for (int i = 0; i < 16 && st == BTDF_OK && npr > 1; i++) {
            if (tree_probe_err(pr, npr, b, threads, res, ech) <= aim)
                break;
            st = recut_missing(r, t, b, chs, npr, ech, aim, 0.917 /* 2^(-1/8) */, lo, grown);
        }
        /* The probes see e_L1 at fixed angles; it jumps where a light's ring enters the
           next cell, and the report's estimate refines there. So check the cut tree
           with that estimator too (its own seed) and cut finer while it misses: the
           channels that miss. */
        for (int i = 0; i < 6 && st == BTDF_OK; i++) {
            double ec = 0.0;
            for (int c = 0; c < npr && st == BTDF_OK; c++) {
                btdf_report rep;
                memset(&rep, 0, sizeof rep);
                st = rad_report_ch(r, k, chs[c], 1, 48, 4096, RAD_CHECK_SEED, threads, &rep);
                ech[c] = btdf_rad_e_l1_checked(&rep);
                ec = fmax(ec, ech[c]);
                btdf_report_clear(&rep);
            }
            if (getenv("BTDF_RAD_DEBUG"))
                fprintf(stderr, "check %s eps %.3g: %zu leaves, e_L1 max %.4g\n", b->label,
                        lo[0], b->leaves, ec);
            if (st != BTDF_OK || ec <= RAD_AIM_CHECK * r->tolerance)
                break;
            st = recut_missing(r, t, b, chs, npr, ech, RAD_AIM_CHECK * r->tolerance, 0.6, lo,
                               grown);
        }
    }
    if (st == BTDF_EBUDGET) { /* the best tree it has: grown as far as it went */
        tree_eps3(r, chs, npr, grown, e3);
        if (rad_tb_extract3(t, e3, b) != BTDF_OK)
            st = BTDF_ENOMEM;
    }
    if (st == BTDF_EBUDGET) {
        snprintf(msg, msglen, "%s: e_L1 %.3g above the tolerance %g with the node budget "
                              "(%zu nodes)", b->label, e, r->tolerance, (size_t)RAD_MAX_NODES);
    } else if (st != BTDF_OK) {
        core_say(st, msg, msglen, "out of memory building the tensor tree");
    }
    rad_tb_free(t);
    free(res);
    for (int i = 0; i < npr; i++)
        rad_probes_free(&pr[i]);
    return st;
}

/* Block k of a three-channel Klems file: each channel's exact patch-pair averages (in
   double, before rounding), combined linearly into CIE X, Y and Z (averaging is
   linear, so each XYZ matrix is the average of the XYZ BSDF), then rounded for the file
   each on its own. Channels with equal indices are integrated once. */
btdf_status rad_klems_colour(btdf_rad *r, int k, int threads, char *msg, size_t msglen)
{
    rad_block *b = &r->b[k];
    size_t np = (size_t)r->kb->npatch, nn = np * np;
    double *acc[3] = {NULL, NULL, NULL}, m[3][3];
    btdf_status st = BTDF_OK;
    rad_rgb_to_xyz(m);
    for (int c = 0; c < 3 && st == BTDF_OK; c++) {
        int same = -1;
        for (int d = 0; d < c; d++)
            if (r->p.ior[d] == r->p.ior[c])
                same = d;
        if (same >= 0) {
            acc[c] = acc[same];
            continue;
        }
        rad_block bc;
        rad_block_of(k, r->p.ior[c], &bc);
        st = rad_klems_acc(&r->p, bc.n, bc.scale, bc.reflect, r->kb, rad_ms(r, c, bc.n),
                           threads, &acc[c], msg, msglen);
    }
    float *out[3] = {NULL, NULL, NULL};
    for (int i = 0; i < 3 && st == BTDF_OK; i++) {
        out[i] = malloc(nn * sizeof *out[i]);
        if (!out[i]) {
            st = core_say(BTDF_ENOMEM, msg, msglen, "out of memory for a Klems matrix");
            break;
        }
        for (size_t e = 0; e < nn; e++) {
            double v = m[i][0] * acc[0][e] + m[i][1] * acc[1][e] + m[i][2] * acc[2][e];
            out[i][e] = rad_klems_value(v);
        }
    }
    for (int c = 0; c < 3; c++) {
        int shared = 0;
        for (int d = 0; d < c; d++)
            shared |= acc[d] == acc[c];
        if (!shared)
            free(acc[c]);
    }
    if (st != BTDF_OK) {
        for (int i = 0; i < 3; i++)
            free(out[i]);
        return st;
    }
    b->klems_x = out[0];
    b->klems = out[1];
    b->klems_z = out[2];
    return BTDF_OK;
}

BTDF_API btdf_status btdf_rad_build_progress(const btdf_params *p, btdf_rad_basis basis,
                                             double tolerance, int threads,
                                             btdf_progress_fn progress, void *user,
                                             btdf_rad **out, char *msg, size_t msglen)
{
    if (!out) {
        if (msg && msglen)
            snprintf(msg, msglen, "no place for the file's object (out is NULL)");
        return BTDF_EINVAL;
    }
    btdf_params single = rad_single(p); /* full: smith's parameters and a tally */
    btdf_status st = btdf_params_check(&single, msg, msglen);
    if (st != BTDF_OK)
        return st;
    if ((unsigned)basis > RAD_BASIS_KLEMS_QUARTER) {
        if (msg && msglen)
            snprintf(msg, msglen, "basis %lld: must be tree3 (0), klems-full (1), klems-half "
                                  "(2) or klems-quarter (3)", (long long)basis);
        return BTDF_EINVAL;
    }
    if (p->channels != 1 && p->channels != 3) {
        if (msg && msglen)
            snprintf(msg, msglen, "a Radiance BSDF file holds one channel (Visible) or three "
                                  "(R, G, B as CIE X, Y, Z, or a tree's Y, u', v'): give one "
                                  "or three --ior values, not %d",
                     p->channels);
        return BTDF_EINVAL;
    }
    if (basis == RAD_BASIS_TREE3 && !(tolerance >= 1e-3 && tolerance <= 0.5)) {
        if (msg && msglen)
            snprintf(msg, msglen, "tolerance %g: a tensor tree takes [1e-3, 0.5]", tolerance);
        return BTDF_EINVAL;
    }
    btdf_rad *r = calloc(1, sizeof *r);
    if (!r)
        return BTDF_ENOMEM;
    double t0 = core_now();
    r->basis = basis;
    r->p = *p;
    r->tolerance = basis == RAD_BASIS_TREE3 ? tolerance : 0.0;
    r->kb = rad_klems(basis);
    r->nblocks = 4; /* both transmissions and both reflections, in every basis */
    r->channels = p->channels;
    rad_xyz_to_rgb(r->to_rgb); /* once, not per lookup */
    for (int k = 0; k < r->nblocks; k++)
        rad_block_of(k, p->ior[0], &r->b[k]);
    st = rad_make_ms(r, threads, progress, user, msg, msglen);
    if (st != BTDF_OK) {
        btdf_rad_free(r);
        return st;
    }
    for (int k = 0; k < r->nblocks && (st == BTDF_OK || st == BTDF_EBUDGET); k++) {
        rad_block *b = &r->b[k];
        if (basis != RAD_BASIS_TREE3) {
            if (progress)
                progress(user, "Klems patch averages, block", (size_t)k,
                         (size_t)(r->nblocks - k));
            st = r->channels == 3 ? rad_klems_colour(r, k, threads, msg, msglen)
                                  : rad_klems_build(p, b->n, b->scale, r->kb,
                                                    rad_ms(r, 0, b->n), threads, b, msg,
                                                    msglen);
            continue;
        }
        btdf_status sk = rad_tree_block(r, k, threads, progress, user, msg, msglen);
        st = sk != BTDF_OK ? sk : st;
    }
    r->seconds_build = core_now() - t0;
    if (st != BTDF_OK && st != BTDF_EBUDGET) {
        btdf_rad_free(r);
        return st;
    }
    *out = r;
    return st;
}
