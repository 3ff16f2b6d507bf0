/* SPDX-License-Identifier: MIT */
/* pane.c: a path through a pane of two faces (rough or flat) with Beer-Lambert
   absorption between them.

   Geometry. The faces are periodic tiles a few correlation lengths wide, and a pane is
   millimetres thick: a ray crossing it lands on the far face a distance d tan(theta)
   away, which is a lateral position unrelated to where it left, modulo the tile. Since
   the two faces are independent random surfaces, the position it meets on the far face
   is taken uniform over that face's tile (and its azimuth relative to the tile's grid
   uniform), drawn afresh at every visit of a face; in law this is the same as tracing
   the exact offset modulo the tile. The relief (heights of order sigma) is negligible
   against the thickness, so the inside path between the faces' slabs is d / |cos
   theta|, which is exact for a laterally infinite pane with flat mean planes. */
#include "sim/pane.h"

#include <math.h>

#include "core/core.h"
#include "sim/rng.h"

btdf_status sim_pane_check(const btdf_sim_opts *o, char *msg, size_t msglen)
{
    if (o->pane == 0)
        return BTDF_OK;
    if (o->pane != 1)
        return core_say(BTDF_EINVAL, msg, msglen, "pane %d: must be 0 (an interface) or 1",
                        o->pane);
    if (o->profile)
        return core_say(BTDF_EINVAL, msg, msglen,
                        "a pane of 1D profiles is not simulated: use the 2D surface");
    if (o->front_flat != 0 && o->front_flat != 1)
        return core_say(BTDF_EINVAL, msg, msglen, "front_flat %d: must be 0 or 1", o->front_flat);
    if (o->from_back != 0 && o->from_back != 1)
        return core_say(BTDF_EINVAL, msg, msglen, "from_back %d: must be 0 or 1", o->from_back);
    double b = o->back_smoothness;
    if (!(b == 0.0 || (b >= BTDF_S_MIN && b <= BTDF_S_MAX)))
        return core_say(BTDF_EINVAL, msg, msglen,
                        "back face smoothness %g: 0 (flat) or in [%g, %g]", b, BTDF_S_MIN,
                        BTDF_S_MAX);
    if (!(o->thickness_mm > 0.0 && o->thickness_mm <= 1e4))
        return core_say(BTDF_EINVAL, msg, msglen, "thickness %g mm: must lie in (0, 10000]",
                        o->thickness_mm);
    if (!(o->absorption_per_mm >= 0.0 && o->absorption_per_mm <= 1e3))
        return core_say(BTDF_EINVAL, msg, msglen, "absorption %g per mm: must lie in [0, 1000]",
                        o->absorption_per_mm);
    return BTDF_OK;
}

/* One visit of a face, in its frame (outside above): from outside (from_out, f
   pointing down) or from inside (f pointing up). Returns SIM_END_R when the light
   leaves to the outside, SIM_END_T into the pane, SIM_END_LOST; *hits the hits. */
static int visit(const sim_surface *s, double n, int from_out, int accel, uint64_t *rng,
                 double f[3], int *hits)
{
    if (!s) {
        /* the flat face: one hit at the normal on the light's side */
        double nf[3] = {0.0, 0.0, from_out ? 1.0 : -1.0};
        sim_turn(f, nf, from_out ? n : 1.0 / n, rng);
        *hits = 1;
        return f[2] > 0.0 ? SIM_END_R : SIM_END_T;
    }
    double a = 6.283185307179586 * sim_uniform(rng), c = cos(a), sn = sin(a);
    double g[3] = {c * f[0] + sn * f[1], -sn * f[0] + c * f[1], f[2]};
    int end = sim_walk(s, n, from_out, accel, rng, g, hits);
    f[0] = c * g[0] - sn * g[1];
    f[1] = sn * g[0] + c * g[1];
    f[2] = g[2];
    return end;
}

void sim_pane_path(const sim_pane *p, double ti, int accel, uint64_t *rng, sim_path *out)
{
    double dp[3] = {-sin(ti), 0.0, -cos(ti)};
    int at = 0, from_out = 1, hits = 0, end = SIM_END_LOST;
    while (hits <= SIM_MAX_HITS) {
        /* into the frame of face `at`: face 1 mirrored, so its outside is above */
        double f[3] = {dp[0], dp[1], at ? -dp[2] : dp[2]};
        int h = 0;
        int e = visit(p->face[at], p->n, from_out, accel, rng, f, &h);
        hits += h;
        dp[0] = f[0];
        dp[1] = f[1];
        dp[2] = at ? -f[2] : f[2];
        if (e == SIM_END_LOST)
            break;
        if (e == SIM_END_R) { /* out of the pane: on the lit side from face 0 */
            end = at ? SIM_END_T : SIM_END_R;
            break;
        }
        if (p->absorption > 0.0) {
            /* |cos| of a ray that left a face's slab inwards is > 0; a zero would be an
               infinite path, which exp(-inf) = 0 absorbs */
            double az = fabs(dp[2]);
            double len = az > 0.0 ? p->thickness / az : INFINITY;
            if (sim_uniform(rng) >= exp(-p->absorption * len)) {
                end = SIM_END_ABSORBED;
                break;
            }
        }
        at = !at;
        from_out = 0;
    }
    out->end = end;
    out->hits = hits;
    out->dir[0] = dp[0];
    out->dir[1] = dp[1];
    out->dir[2] = dp[2];
}
