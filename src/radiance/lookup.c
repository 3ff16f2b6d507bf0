/* SPDX-License-Identifier: MIT */
/* lookup.c: a built file's values read back by Radiance's own rules: the tree leaf or
   Klems patch pair of a (view, light) pair, in X, Y, Z and in the channels. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "radiance/radiance_impl.h"

/* Tree coordinates of the incident direction p and the outgoing q (Radiance frame). */
void rad_tree_coords(const double p[3], const double q[3], double *u0, double *a, double *b)
{
    *u0 = rad_u0_of_sin(sqrt(p[0] * p[0] + p[1] * p[1]));
    /* Turn q about z by -atan2(-p_y, -p_x): p's direction of travel to +x. */
    double ang = -atan2(-p[1], -p[0]);
    double c = cos(ang), s = sin(ang);
    double x = q[0] * c - q[1] * s, y = q[0] * s + q[1] * c;
    rad_disk_to_square(x, y, a, b);
}

static double deg(double r) { return r * (180.0 / M_PI); }

/* The file's X, Y, Z at (p, q) in block k (a one-channel file: Y in all three, the
   equal-energy white Radiance gives a grey file); 0 when off the block. */
static void rad_lookup_xyz(const btdf_rad *r, int k, const double p[3], const double q[3],
                           double xyz[3])
{
    xyz[0] = xyz[1] = xyz[2] = 0.0;
    if (!r || k < 0 || k >= r->nblocks)
        return;
    const rad_block *b = &r->b[k];
    /* Transmission Front and Reflection Front: p on -Z; the Back blocks: p on +Z; q on
       the other side (transmission) or the same (reflection) */
    double sg = b->side == BTDF_SIDE_ENTER ? -1.0 : 1.0, sq = b->reflect ? sg : -sg;
    if (!(sg * p[2] > 0.0 && sq * q[2] > 0.0))
        return;
    if (r->basis == RAD_BASIS_TREE3) {
        double u0, a, bb;
        rad_tree_coords(p, q, &u0, &a, &bb);
        size_t i = rad_tree_leaf(b->nodes, u0, a, bb);
        if (b->cv)
            rad_colour_xyz(b->nodes[i].v, b->cv[i * RAD_CV + 3], b->cv[i * RAD_CV + 4], xyz);
        else
            xyz[0] = xyz[1] = xyz[2] = b->nodes[i].v;
        return;
    }
    /* Klems: incident patch of p's direction of travel (-p), outgoing patch of q, both by
       the polar angle from their own side's normal: Radiance's bsdf_m.c rule for every
       block, transmission or reflection, front or back (its incident maps reverse x and
       y, the outgoing ones keep them; the back maps only flip z). */
    int i = rad_klems_patch(r->kb, deg(acos(fmin(1.0, fabs(p[2])))), deg(atan2(-p[1], -p[0])));
    int o = rad_klems_patch(r->kb, deg(acos(fmin(1.0, fabs(q[2])))), deg(atan2(q[1], q[0])));
    if (i < 0 || o < 0)
        return;
    size_t e = (size_t)o * (size_t)r->kb->npatch + (size_t)i;
    xyz[1] = b->klems[e];
    xyz[0] = b->klems_x ? b->klems_x[e] : xyz[1];
    xyz[2] = b->klems_z ? b->klems_z[e] : xyz[1];
}

/* Channel c (R, G, B: 0, 1, 2) of the file at (p, q), recovered from its X, Y, Z; -1:
   its Y. A one-channel file: its value for c = 0 or -1. chosen: a colour tree's channel
   as its builder chose it (rad_tree_value). */
double rad_lookup_ch(const btdf_rad *r, int k, int c, int chosen, const double p[3],
                            const double q[3])
{
    double xyz[3];
    if (chosen && c >= 0 && r && r->channels == 3 && r->basis == RAD_BASIS_TREE3 && k >= 0 &&
        k < r->nblocks) {
        const rad_block *b = &r->b[k];
        double sg = b->side == BTDF_SIDE_ENTER ? -1.0 : 1.0, sq = b->reflect ? sg : -sg;
        if (!(sg * p[2] > 0.0 && sq * q[2] > 0.0))
            return 0.0;
        double u0, a, bb;
        rad_tree_coords(p, q, &u0, &a, &bb);
        return rad_tree_value(r, b, rad_tree_leaf(b->nodes, u0, a, bb), c, 1);
    }
    rad_lookup_xyz(r, k, p, q, xyz);
    if (c < 0 || !r || r->channels != 3)
        return xyz[1];
    const double(*m)[3] = r->to_rgb;
    return m[c][0] * xyz[0] + m[c][1] * xyz[1] + m[c][2] * xyz[2];
}

BTDF_API double btdf_rad_lookup(const btdf_rad *r, int k, const double p[3],
                                const double q[3])
{
    return rad_lookup_ch(r, k, -1, 0, p, q);
}

BTDF_API void btdf_rad_lookup_xyz(const btdf_rad *r, int k, const double p[3],
                                  const double q[3], double xyz[3])
{
    rad_lookup_xyz(r, k, p, q, xyz);
}

BTDF_API double btdf_rad_lookup_channel(const btdf_rad *r, int k, int c, const double p[3],
                                        const double q[3])
{
    if (!r || c < 0 || c >= (r->channels == 3 ? 3 : 1))
        return 0.0;
    return rad_lookup_ch(r, k, c, 0, p, q);
}

double rad_render(const btdf_rad *r, btdf_side light, int c, int chosen, double ti,
                         double to, double phi)
{
    int k = light == BTDF_SIDE_LEAVE ? 0 : 1; /* the block of the view's side */
    double p[3], q[3];
    rad_render_dirs(r, k, ti, to, phi, p, q);
    return rad_lookup_ch(r, k, c, chosen, p, q);
}

BTDF_API double btdf_rad_render(const btdf_rad *r, btdf_side light, int c, double ti,
                                double to, double phi)
{
    return rad_render(r, light, c, 0, ti, to, phi);
}
