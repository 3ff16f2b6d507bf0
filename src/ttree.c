/* SPDX-License-Identifier: MIT */
/* ttree.c: the TensorTree3 of one transmission block, built for Radiance's lookup rule.
 *
 * How Radiance reads a TensorTree3 (its BSDF library, bsdf_t.c, read for behaviour):
 *  - the incident direction s (pointing to the light) gives the first coordinate
 *    u0 = (0.5 - FTINY) - 0.5 sin(theta_s), FTINY = 1e-6: uniform in sin(theta), so
 *    the cells of one level are narrow in theta near normal incidence and wide near
 *    grazing; only u0 < 0.5 is ever used;
 *  - the outgoing direction is turned about z so that the light's horizontal direction
 *    of travel (-s_x, -s_y) lies along +x, and its (x, y) goes through the concentric
 *    square map: coordinates 1 and 2, in which area times pi is projected solid angle;
 *  - the tree is descended by halving every coordinate at each node (child bit d = upper
 *    half of coordinate d) down to a leaf, whose value is returned as it is: nearest
 *    cell, no interpolation (Radiance then perturbs it by at most 1.5e-4 relative).
 * So the best a leaf can hold is the average of the BTDF over its cell, and a cell must
 * be small where the BTDF changes within it, in u0 as in the outgoing square.
 *
 * The builder: every cell is sampled at 4 x 4 x 4 midpoints and holds their mean. Its
 * share of the e_L1 (MODEL.md 6) of an incident slice it covers is
 *   pi * area(a, b) * (mean |rho - value| at that slice) / max(T(ti), 0.01),
 * pi * area being projected solid angle; the largest over its 4 slices is compared with
 * a threshold eps and the cell is split into 8 while above it. Equal shares (rather than
 * equal error densities) give the fewest cells for a given sum in every slice: cells
 * stay large where little energy moves, small where the lobe is steep, and near grazing
 * incidence, where the BTDF changes fast in u0 but carries little energy, the octree's
 * splitting of all three coordinates at once stays affordable. The caller chooses eps
 * so that an independent estimate of e_L1 meets the tolerance.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "radiance_impl.h"

#define RAD_FTINY 1e-6 /* Radiance's FTINY in double builds, in u0 */
#define NS 4           /* samples per cell and dimension */
#define NT_GRID 1025   /* nodes of the floor max(T, 0.01) over u0 in [0, 0.5] */

void rad_square_to_disk(double a, double b, double *x, double *y)
{
    /* Shirley and Chiu's concentric map: four wedges, r = the larger |coordinate|. */
    double p = 2.0 * a - 1.0, q = 2.0 * b - 1.0, r, phi;
    if (p == 0.0 && q == 0.0) {
        *x = *y = 0.0;
        return;
    }
    if (p > -q) {
        if (p > q) {
            r = p;
            phi = (M_PI / 4.0) * (q / p); /* p > |q| >= 0: no 1/0 */
        } else {
            r = q;
            phi = (M_PI / 4.0) * (2.0 - p / q); /* q >= |p|, q > 0 */
        }
    } else if (p < q) {
        r = -p;
        phi = (M_PI / 4.0) * (4.0 + q / p); /* -p > |q|, p < 0 */
    } else {
        r = -q;
        phi = q != 0.0 ? (M_PI / 4.0) * (6.0 - p / q) : 0.0; /* q = 0 only at the centre */
    }
    *x = r * cos(phi);
    *y = r * sin(phi);
}

void rad_disk_to_square(double x, double y, double *a, double *b)
{
    double r = sqrt(x * x + y * y), phi = atan2(y, x), p, q;
    if (phi < -M_PI / 4.0)
        phi += 2.0 * M_PI; /* [-pi/4, 7pi/4) */
    if (phi < M_PI / 4.0) {
        p = r;
        q = phi * r / (M_PI / 4.0);
    } else if (phi < 3.0 * M_PI / 4.0) {
        q = r;
        p = -(phi - M_PI / 2.0) * r / (M_PI / 4.0);
    } else if (phi < 5.0 * M_PI / 4.0) {
        p = -r;
        q = -(phi - M_PI) * r / (M_PI / 4.0);
    } else {
        q = -r;
        p = (phi - 3.0 * M_PI / 2.0) * r / (M_PI / 4.0);
    }
    *a = 0.5 * (p + 1.0);
    *b = 0.5 * (q + 1.0);
}

double rad_u0_of_sin(double sin_ti) { return (0.5 - RAD_FTINY) - 0.5 * sin_ti; }

double rad_tree_lookup(const rad_node *nodes, double u0, double a, double b)
{
    double pos[3] = {u0, a, b};
    size_t k = 0;
    while (nodes[k].child >= 0) {
        int n = 0;
        for (int d = 2; d >= 0; d--) {
            double sp = 2.0 * pos[d];
            int t = sp >= 1.0;
            n |= t << d;
            pos[d] = sp - (double)t;
        }
        k = (size_t)nodes[k].child + (size_t)n;
    }
    return nodes[k].v;
}

/* ---------------------------------------------------------------- builder */

typedef struct tt_ctx {
    double n, s, k0, scale;
    double eps;                /* largest share of a slice's e_L1 one cell may hold */
    double tfloor[NT_GRID];    /* max(T, 0.01) at u0 = 0.5 k / (NT_GRID - 1) */
    int min_level, max_level;
    size_t max_nodes;          /* per task */
} tt_ctx;

typedef struct tt_buf {
    rad_node *v;
    size_t n, cap;
    int depth;
    int budget_hit, nomem;
} tt_buf;

static int32_t buf_alloc(tt_buf *b, size_t count)
{
    if (b->n + count > b->cap) {
        size_t cap = b->cap ? 2 * b->cap : 64;
        while (cap < b->n + count)
            cap *= 2;
        rad_node *v = realloc(b->v, cap * sizeof *v);
        if (!v) {
            b->nomem = 1;
            return -1;
        }
        b->v = v;
        b->cap = cap;
    }
    if (b->n + count > (size_t)INT32_MAX) {
        b->budget_hit = 1;
        return -1;
    }
    int32_t first = (int32_t)b->n;
    for (size_t i = 0; i < count; i++) {
        b->v[b->n + i].child = -1;
        b->v[b->n + i].v = 0.0f;
    }
    b->n += count;
    return first;
}

/* The smallest floor max(T, 0.01) over u0 in [lo, hi]. */
static double floor_min(const tt_ctx *c, double lo, double hi)
{
    double scale = (double)(NT_GRID - 1) / 0.5;
    long i0 = (long)floor(lo * scale), i1 = (long)ceil(hi * scale);
    if (i0 < 0)
        i0 = 0;
    if (i1 > NT_GRID - 1)
        i1 = NT_GRID - 1;
    double m = 1e300;
    for (long i = i0; i <= i1; i++)
        m = fmin(m, c->tfloor[i]);
    return m < 1e300 ? m : 0.01;
}

/* Leaf values are stored as the file writes them (6 significant digits, FLT_DIG, so the
   text reads back to this very float in Radiance), so the object and the file agree. */
static float file_value(double v)
{
    char t[32];
    snprintf(t, sizeof t, "%.6g", v);
    return (float)strtod(t, NULL);
}

static void tt_cell(const tt_ctx *c, tt_buf *b, int32_t node, int level, uint32_t i0,
                    uint32_t i1, uint32_t i2)
{
    double h = ldexp(1.0, -level), f[NS][NS * NS];
    rho_out ro[NS * NS];
    double cph[NS * NS], sph[NS * NS];
    for (int j = 0; j < NS; j++) {
        for (int k = 0; k < NS; k++) {
            double a = ((double)i1 + (j + 0.5) / NS) * h, bb = ((double)i2 + (k + 0.5) / NS) * h;
            double x, y;
            rad_square_to_disk(a, bb, &x, &y);
            double r2 = fmin(1.0, x * x + y * y), r = sqrt(r2);
            int m = j * NS + k;
            rho_out_init(&ro[m], r, -sqrt(1.0 - r2), c->s, c->k0);
            /* phi = psi + pi, psi the azimuth of (x, y); any phi at the centre r = 0 */
            cph[m] = r > 0.0 ? -x / r : 1.0;
            sph[m] = r > 0.0 ? -y / r : 0.0;
        }
    }
    double sum = 0.0;
    for (int i = 0; i < NS; i++) {
        double u0 = ((double)i0 + (i + 0.5) / NS) * h;
        double st = fmin(1.0, fmax(0.0, 1.0 - 2.0 * (u0 + RAD_FTINY)));
        rho_in ri;
        rho_in_init(&ri, st, sqrt(1.0 - st * st), c->s, c->k0);
        for (int m = 0; m < NS * NS; m++) {
            f[i][m] = c->scale * rho_kernel(c->n, c->s, &ri, &ro[m], cph[m], sph[m]);
            sum += f[i][m];
        }
    }
    double v = sum / (NS * NS * NS);
    b->v[node].v = file_value(v);
    if (level > b->depth)
        b->depth = level;
    int split = level < c->min_level;
    if (!split && level < c->max_level) {
        double fl = floor_min(c, (double)i0 * h, ((double)i0 + 1.0) * h), dmax = 0.0;
        for (int i = 0; i < NS; i++) {
            double dev = 0.0;
            for (int m = 0; m < NS * NS; m++)
                dev += fabs(f[i][m] - v);
            dmax = fmax(dmax, dev / (NS * NS));
        }
        /* The cell's share of the e_L1 of the slices it covers (pi * area = projected
           solid angle); split while it is above the threshold. */
        split = M_PI * h * h * dmax / fl > c->eps;
    }
    if (!split)
        return;
    if (b->n + 8 > c->max_nodes) {
        b->budget_hit = 1;
        return;
    }
    int32_t ch = buf_alloc(b, 8);
    if (ch < 0)
        return;
    b->v[node].child = ch;
    for (int n = 0; n < 8; n++)
        tt_cell(c, b, ch + n, level + 1, 2 * i0 + (n & 1), 2 * i1 + ((n >> 1) & 1),
                2 * i2 + ((n >> 2) & 1));
}

typedef struct tt_job {
    const tt_ctx *c;
    int level;           /* level of the task cells */
    uint32_t n0, n1, n2; /* task cells per dimension (u0 < 0.5, b < 0.5 only) */
    tt_buf *bufs;
} tt_job;

static void tt_task(void *arg, size_t t)
{
    tt_job *j = arg;
    uint32_t i2 = (uint32_t)(t % j->n2), i1 = (uint32_t)((t / j->n2) % j->n1);
    uint32_t i0 = (uint32_t)(t / ((size_t)j->n2 * j->n1));
    tt_buf *b = &j->bufs[t];
    if (buf_alloc(b, 1) < 0)
        return;
    tt_cell(j->c, b, 0, j->level, i0, i1, i2);
}

typedef struct tt_out {
    tt_buf dst;
    const tt_job *j;
} tt_out;

static void copy_sub(tt_out *o, const tt_buf *src, int32_t si, int mirror, int32_t di)
{
    o->dst.v[di].v = src->v[si].v;
    if (src->v[si].child < 0)
        return;
    int32_t ch = buf_alloc(&o->dst, 8);
    if (ch < 0)
        return;
    o->dst.v[di].child = ch;
    for (int n = 0; n < 8; n++)
        copy_sub(o, src, src->v[si].child + (mirror ? (n ^ 4) : n), mirror, ch + n);
}

/* Lays the tree out from the root: full levels above the task cells, placeholders for
   u0 >= 0.5, the task subtrees below, mirrored (b -> 1 - b) for b >= 0.5. */
static void assemble(tt_out *o, int32_t di, int level, uint32_t i0, uint32_t i1, uint32_t i2)
{
    const tt_job *j = o->j;
    if (level == j->level) {
        int mirror = i2 >= j->n2;
        uint32_t m2 = mirror ? 2 * j->n2 - 1 - i2 : i2;
        size_t t = ((size_t)i0 * j->n1 + i1) * j->n2 + m2;
        copy_sub(o, &j->bufs[t], 0, mirror, di);
        return;
    }
    int32_t ch = buf_alloc(&o->dst, 8);
    if (ch < 0)
        return;
    o->dst.v[di].child = ch;
    for (int n = 0; n < 8; n++) {
        uint32_t c0 = 2 * i0 + (n & 1), c1 = 2 * i1 + ((n >> 1) & 1), c2 = 2 * i2 + ((n >> 2) & 1);
        if (level == 0 && (n & 1))
            continue; /* u0 >= 0.5 is never looked up: a { 0 } placeholder */
        assemble(o, ch + n, level + 1, c0, c1, c2);
    }
}

btdf_status rad_tree_build(const btdf_params *p, double n, double scale, double eps,
                           int threads,
                           size_t max_nodes, rad_block *blk, char *msg, size_t msglen)
{
    tt_ctx *c = calloc(1, sizeof *c);
    if (!c)
        return BTDF_ENOMEM;
    c->n = n;
    c->s = p->smoothness;
    c->k0 = p->k0;
    c->eps = eps;
    c->scale = scale;
    /* Start where a cell is no wider than the lobe (about 2/s rad in facet slope). */
    int lv = 3 + (int)ceil(log2(fmax(1.0, p->smoothness / 2.0)));
    c->min_level = lv < 3 ? 3 : (lv > 6 ? 6 : lv);
    c->max_level = 16;
    btdf_params q = *p;
    q.channels = 1;
    q.ior[0] = n;
    for (int i = 0; i < NT_GRID; i++) {
        double u0 = 0.5 * i / (NT_GRID - 1), T;
        double st = fmin(1.0, fmax(0.0, 1.0 - 2.0 * (u0 + RAD_FTINY)));
        btdf_transmittance(&q, asin(st), &T);
        c->tfloor[i] = fmax(scale * T, 0.01); /* MODEL.md section 6 floor */
    }
    tt_job j;
    j.c = c;
    j.level = c->min_level;
    j.n0 = 1u << (j.level - 1);
    j.n1 = 1u << j.level;
    j.n2 = 1u << (j.level - 1);
    size_t ntask = (size_t)j.n0 * j.n1 * j.n2;
    c->max_nodes = max_nodes; /* per task; the total is checked when assembling */
    j.bufs = calloc(ntask, sizeof *j.bufs);
    if (!j.bufs) {
        free(c);
        return BTDF_ENOMEM;
    }
    btdf_parallel_for(threads, ntask, tt_task, &j);
    int nomem = 0, hit = 0, depth = 0;
    size_t total = 1, used = 0;
    for (size_t t = 0; t < ntask; t++) {
        used += j.bufs[t].n;
        nomem |= j.bufs[t].nomem || !j.bufs[t].v;
        hit |= j.bufs[t].budget_hit;
        depth = j.bufs[t].depth > depth ? j.bufs[t].depth : depth;
        total += 2 * j.bufs[t].n + 8;
    }
    hit |= used > max_nodes;
    tt_out o;
    memset(&o, 0, sizeof o);
    o.j = &j;
    btdf_status st = BTDF_OK;
    if (nomem) {
        st = BTDF_ENOMEM;
    } else {
        o.dst.v = malloc(total * sizeof *o.dst.v);
        o.dst.cap = o.dst.v ? total : 0;
        if (!o.dst.v || buf_alloc(&o.dst, 1) < 0) {
            st = BTDF_ENOMEM;
        } else {
            assemble(&o, 0, 0, 0, 0, 0);
            if (o.dst.nomem || o.dst.budget_hit)
                st = BTDF_ENOMEM;
        }
    }
    for (size_t t = 0; t < ntask; t++)
        free(j.bufs[t].v);
    free(j.bufs);
    free(c);
    if (st != BTDF_OK) {
        free(o.dst.v);
        if (msg && msglen)
            snprintf(msg, msglen, "out of memory building the tensor tree");
        return st;
    }
    blk->nodes = o.dst.v;
    blk->nnodes = o.dst.n;
    blk->leaves = 0;
    for (size_t i = 0; i < o.dst.n; i++)
        blk->leaves += o.dst.v[i].child < 0;
    blk->depth = depth;
    if (hit) {
        if (msg && msglen)
            snprintf(msg, msglen, "tensor tree node budget (%zu) reached at depth %d",
                     max_nodes, depth);
        return BTDF_EBUDGET;
    }
    return BTDF_OK;
}
