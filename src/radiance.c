/* SPDX-License-Identifier: MIT */
/* radiance.c: builds the blocks of a WINDOW/Radiance BSDF and reads them back by
   Radiance's rules (tree: ttree.c; Klems: klems.c). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "radiance_impl.h"

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
        free(r->b[k].klems);
    }
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

/* The tree's node budget: about 1 GB of nodes, far beyond any useful file. */
#define RAD_MAX_NODES ((size_t)1 << 26)
/* Internal check: its own seed and 4 times the reported estimate's angles, since e_L1
   jumps at the tree's cell edges in theta_i and a max over few angles is noisy. */
#define RAD_CHECK_SEED 0x5ad1a7e5u

BTDF_API btdf_status btdf_rad_build(const btdf_params *p, btdf_rad_basis basis,
                                    double tolerance, int threads, btdf_rad **out, char *msg,
                                    size_t msglen)
{
    return btdf_rad_build_progress(p, basis, tolerance, threads, NULL, NULL, out, msg, msglen);
}

/* Passes of a tensor-tree block, at most (the rounds of the eps search below). */
#define RAD_TREE_PASSES 6

BTDF_API btdf_status btdf_rad_build_progress(const btdf_params *p, btdf_rad_basis basis,
                                             double tolerance, int threads,
                                             btdf_progress_fn progress, void *user,
                                             btdf_rad **out, char *msg, size_t msglen)
{
    btdf_status st = btdf_params_check(p, msg, msglen);
    if (st != BTDF_OK)
        return st;
    if (p->channels != 1) {
        if (msg && msglen)
            snprintf(msg, msglen, "a Radiance BSDF file holds one channel (Visible): give one "
                                  "--ior value, not %d", p->channels);
        return BTDF_EINVAL;
    }
    if ((unsigned)basis > RAD_BASIS_KLEMS_QUARTER)
        return BTDF_EINVAL;
    if (basis == RAD_BASIS_TREE3 && !(tolerance >= 1e-4 && tolerance <= 0.5)) {
        if (msg && msglen)
            snprintf(msg, msglen, "tolerance %g: a tensor tree takes [1e-4, 0.5]", tolerance);
        return BTDF_EINVAL;
    }
    btdf_rad *r = calloc(1, sizeof *r);
    if (!r)
        return BTDF_ENOMEM;
    double t0 = btdf_now();
    r->basis = basis;
    r->p = *p;
    r->tolerance = basis == RAD_BASIS_TREE3 ? tolerance : 0.0;
    r->kb = rad_klems(basis);
    r->nblocks = 2;
    double n = p->ior[0];
    r->b[0].side = BTDF_SIDE_ENTER; /* radiance.h: what each block holds and why */
    r->b[0].label = "Transmission Front";
    r->b[0].n = n;
    r->b[0].scale = 1.0 / (n * n);
    r->b[0].light = BTDF_SIDE_LEAVE;
    r->b[0].n_light = 1.0 / n;
    r->b[1].side = BTDF_SIDE_LEAVE;
    r->b[1].label = "Transmission Back";
    r->b[1].n = 1.0 / n;
    r->b[1].scale = n * n;
    r->b[1].light = BTDF_SIDE_ENTER;
    r->b[1].n_light = n;
    for (int k = 0; k < r->nblocks && st == BTDF_OK; k++) {
        rad_block *b = &r->b[k];
        if (basis != RAD_BASIS_TREE3) {
            if (progress)
                progress(user, "Klems patch averages, block", (size_t)k,
                         (size_t)(r->nblocks - k));
            st = rad_klems_build(p, b->n, b->scale, r->kb, threads, b, msg, msglen);
            continue;
        }
        /* The cell threshold eps sets the error: e_L1 grows about as eps^(1/3) (a cell
           of side h on a smooth lobe holds a share ~ h^3, a slice ~ h^-2 cells). Start
           from eps = 1e-4 (10 tolerance)^3 (measured: eps = 1e-4 gives e_L1 about 0.07 at
           n = 1.5, s = 3), then move eps (damped) towards 0.6 * tolerance on an independent
           estimate, at most 6 builds; keep the last build that met the tolerance. */
        double eps = 1e-4 * pow(10.0 * tolerance, 3.0), good_eps = 0.0;
        for (int round = 0; round < RAD_TREE_PASSES; round++) {
            if (progress) /* a block may stop early: its passes left count as done then */
                progress(user, k == 0 ? "tensor tree, front block, pass" : "tensor tree, back block, pass",
                         (size_t)(k * RAD_TREE_PASSES + round),
                         (size_t)((r->nblocks - k) * RAD_TREE_PASSES - round));
            free(b->nodes);
            b->nodes = NULL;
            st = rad_tree_build(p, b->n, b->scale, eps, threads, RAD_MAX_NODES, b, msg,
                                msglen);
            if (st != BTDF_OK)
                break;
            btdf_report rep;
            memset(&rep, 0, sizeof rep);
            st = btdf_rad_report(r, k, 192, 4096, RAD_CHECK_SEED, threads, &rep);
            double e = btdf_rad_e_l1_checked(&rep);
            btdf_report_clear(&rep);
            if (st != BTDF_OK)
                break;
            /* aim below the tolerance: the reported estimate has another seed */
            if (e <= 0.85 * tolerance)
                good_eps = eps;
            if (e <= 0.85 * tolerance && e >= 0.4 * tolerance)
                break; /* close enough: a smaller file would risk the tolerance */
            double g = 0.6 * tolerance / fmax(e, 1e-12);
            g = g * g; /* damped: the slope is near 1/3 but the estimate is noisy */
            eps *= g < 1.0 / 64 ? 1.0 / 64 : (g > 64.0 ? 64.0 : g);
            if (round == RAD_TREE_PASSES - 1) {
                if (good_eps > 0.0) { /* the last build missed: go back to the good one */
                    free(b->nodes);
                    b->nodes = NULL;
                    st = rad_tree_build(p, b->n, b->scale, good_eps, threads, RAD_MAX_NODES,
                                        b, msg, msglen);
                } else {
                    if (msg && msglen)
                        snprintf(msg, msglen, "%s: e_L1 %.3g above the tolerance %g after 6 "
                                              "builds", b->label, e, tolerance);
                    st = BTDF_EBUDGET;
                }
            }
        }
    }
    r->seconds_build = btdf_now() - t0;
    if (st != BTDF_OK && st != BTDF_EBUDGET) {
        btdf_rad_free(r);
        return st;
    }
    *out = r;
    return st;
}

/* Tree coordinates of the incident direction p and the outgoing q (Radiance frame). */
static void tree_coords(const double p[3], const double q[3], double *u0, double *a, double *b)
{
    *u0 = rad_u0_of_sin(sqrt(p[0] * p[0] + p[1] * p[1]));
    /* Turn q about z by -atan2(-p_y, -p_x): p's direction of travel to +x. */
    double ang = -atan2(-p[1], -p[0]);
    double c = cos(ang), s = sin(ang);
    double x = q[0] * c - q[1] * s, y = q[0] * s + q[1] * c;
    rad_disk_to_square(x, y, a, b);
}

static double deg(double r) { return r * (180.0 / M_PI); }

BTDF_API double btdf_rad_lookup(const btdf_rad *r, int k, const double p[3],
                                const double q[3])
{
    if (!r || k < 0 || k >= r->nblocks)
        return 0.0;
    const rad_block *b = &r->b[k];
    /* block 0 (Transmission Front): p on -Z; block 1: p on +Z */
    double sg = b->side == BTDF_SIDE_ENTER ? -1.0 : 1.0;
    if (!(sg * p[2] > 0.0 && sg * q[2] < 0.0))
        return 0.0;
    if (r->basis == RAD_BASIS_TREE3) {
        double u0, a, bb;
        tree_coords(p, q, &u0, &a, &bb);
        return rad_tree_lookup(b->nodes, u0, a, bb);
    }
    /* Klems: incident patch of p's direction of travel (-p), outgoing patch of q, both by
       the polar angle from their own side's normal. */
    int i = rad_klems_patch(r->kb, deg(acos(fmin(1.0, fabs(p[2])))), deg(atan2(-p[1], -p[0])));
    int o = rad_klems_patch(r->kb, deg(acos(fmin(1.0, fabs(q[2])))), deg(atan2(q[1], q[0])));
    if (i < 0 || o < 0)
        return 0.0;
    return b->klems[(size_t)o * (size_t)r->kb->npatch + (size_t)i];
}

double btdf_rad_render(const btdf_rad *r, btdf_side light, double ti, double to, double phi)
{
    /* the light's MODEL.md frame: source at azimuth pi, so it travels towards +x */
    double src[3] = {-sin(ti), 0.0, cos(ti)};
    double view[3] = {sin(to) * cos(phi - M_PI), sin(to) * sin(phi - M_PI), cos(to)};
    int k = light == BTDF_SIDE_LEAVE ? 0 : 1; /* the block of the view's side */
    if (light == BTDF_SIDE_ENTER) {
        /* light from -Z: its frame seen from Radiance's is turned by pi about x */
        src[2] = -src[2];
        view[1] = -view[1];
        view[2] = -view[2];
    }
    return btdf_rad_lookup(r, k, view, src);
}

typedef struct rad_est {
    const btdf_rad *r;
    btdf_side light;
} rad_est;

static void rad_est_fn(const void *obj, double ti, const double *q, double *out)
{
    const rad_est *e = obj;
    /* q = {sin ti, cos ti, sin to, cos to, cos phi, sin phi, |phi|, to} */
    out[0] = btdf_rad_render(e->r, e->light, ti, q[7], atan2(q[5], q[4]));
}

BTDF_API btdf_status btdf_rad_report(const btdf_rad *r, int k, size_t test_angles,
                                     size_t points_per_angle, uint64_t seed, int threads,
                                     btdf_report *rep)
{
    if (!r || !rep || k < 0 || k >= r->nblocks)
        return BTDF_EINVAL;
    btdf_params q = r->p;
    q.channels = 1;
    q.ior[0] = r->b[k].n_light;
    rad_est e = {r, r->b[k].light};
    btdf_status st = btdf_estimate_fn(&q, 0.0, M_PI / 2, test_angles, points_per_angle, seed,
                                      threads, rad_est_fn, &e, rep);
    if (st == BTDF_OK) {
        rep->seconds_build = r->seconds_build;
        rep->tolerance = r->tolerance;
        rep->metric = BTDF_METRIC_L1;
        rep->met = r->basis != RAD_BASIS_TREE3 || btdf_rad_e_l1_checked(rep) <= r->tolerance;
        if (r->basis == RAD_BASIS_TREE3) {
            rep->slices = (size_t)r->b[k].depth;
            rep->samples = r->b[k].leaves;
        } else {
            rep->slices = (size_t)r->kb->npatch;
            rep->samples = (size_t)r->kb->npatch * (size_t)r->kb->npatch;
        }
    }
    return st;
}
