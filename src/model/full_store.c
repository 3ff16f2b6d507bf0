/* SPDX-License-Identifier: MIT */
/* full_store.c: the model full's tally as tables keep it: its multiply scattered part
   alone, its energies and noise, a copy, and the text of its ladder nodes (full.h). */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "btdf.h"
#include "core/core.h"
#include "model/full.h"
#include "model/kernel.h" /* M_PI */

double full_ms_energy(const btdf_full *f, int h, double ti, double *se)
{
    double w;
    int k = full_locate(f, ti * (180.0 / M_PI), &w);
    if (se)
        *se = fmax(f->ems_se[k][h], f->ems_se[k + 1][h]);
    return (1.0 - w) * f->ems[k][h] + w * f->ems[k + 1][h];
}

double full_ms_noise(const btdf_full *f, int h, double ti0, double ti1)
{
    double a = ti0 * (180.0 / M_PI), b = ti1 * (180.0 / M_PI), worst = 0.0;
    for (int k = 0; k + 1 < f->nodes; k++) {
        if (f->node_deg[k + 1] < a || f->node_deg[k] > b)
            continue; /* this interval does not meet the range */
        worst = fmax(worst, fmax(f->ems_se[k][h], f->ems_se[k + 1][h]));
    }
    return worst;
}

btdf_full *full_clone(const btdf_full *f)
{
    btdf_full *c = malloc(sizeof *c);
    if (c)
        memcpy(c, f, sizeof *c);
    return c;
}

int full_node_text(const btdf_full *f, int node, char *buf, size_t len)
{
    size_t at = 0;
    int w = snprintf(buf, len, "%.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g",
                     f->node_deg[node], f->e1[node][0], f->ems[node][0], f->ems_se[node][0],
                     f->e1[node][1], f->ems[node][1], f->ems_se[node][1], f->lost[node]);
    if (w < 0)
        return w;
    at = (size_t)w;
    for (int h = 0; h < 2; h++)
        for (int k = 0; k < FULL_K; k++)
            for (int m = 0; m < FULL_M; m++) {
                w = snprintf(at < len ? buf + at : NULL, at < len ? len - at : 0, " %.17g",
                             f->coef[node][h][k][m]);
                if (w < 0)
                    return w;
                at += (size_t)w;
            }
    return (int)at;
}

/* Reads the next number of *p into *v; 0 when there is none or it is not finite. */
static int next_num(const char **p, double *v)
{
    char *end;
    errno = 0;
    double x = strtod(*p, &end);
    if (end == *p || errno == ERANGE || !isfinite(x))
        return 0;
    *p = end;
    *v = x;
    return 1;
}

btdf_status full_from_text(double n, double s, uint64_t paths, uint64_t seed,
                           const char *const *lines, int nodes, btdf_full **out, char *msg,
                           size_t msglen)
{
    if (nodes < 2 || nodes > FULL_NODES_MAX)
        return core_say(BTDF_EFORMAT, msg, msglen,
                        "multiple scattering: %d ladder nodes, must be 2 to %d", nodes,
                        FULL_NODES_MAX);
    btdf_full *f = calloc(1, sizeof *f);
    if (!f)
        return core_say(BTDF_ENOMEM, msg, msglen, "out of memory");
    f->n = n;
    f->s = s;
    f->alpha = 2.0 / s; /* as btdf_full_new: s > 0 checked by the reader */
    f->paths = paths;
    f->seed = seed;
    f->nodes = nodes;
    full_make_poly(f->poly);
    for (int k = 0; k < nodes; k++) {
        const char *p = lines[k];
        double head[8];
        int ok = 1;
        for (int i = 0; i < 8 && ok; i++)
            ok = next_num(&p, &head[i]);
        for (int h = 0; h < 2 && ok; h++)
            for (int a = 0; a < FULL_K && ok; a++)
                for (int m = 0; m < FULL_M && ok; m++)
                    ok = next_num(&p, &f->coef[k][h][a][m]);
        while (ok && (*p == ' ' || *p == '\t' || *p == '\r' || *p == '\n'))
            p++;
        const char *why = !ok  ? "a number is missing or not finite (8 + 80 numbers per node)"
                          : *p ? "text after the node's 88 numbers"
                          : !(head[0] >= 0.0 && head[0] <= 90.0)
                              ? "its angle is not in [0, 90] degrees"
                          : k > 0 && !(head[0] > f->node_deg[k - 1])
                              ? "its angle does not increase"
                              : NULL;
        for (int i = 1; !why && i < 8; i++)
            if (!(head[i] >= 0.0 && head[i] <= 1.0))
                why = "an energy, error or lost fraction outside [0, 1]";
        if (why) {
            free(f);
            return core_say(BTDF_EFORMAT, msg, msglen, "multiple scattering node %d: %s", k,
                            why);
        }
        f->node_deg[k] = head[0];
        f->e1[k][0] = head[1];
        f->ems[k][0] = head[2];
        f->ems_se[k][0] = head[3];
        f->e1[k][1] = head[4];
        f->ems[k][1] = head[5];
        f->ems_se[k][1] = head[6];
        f->lost[k] = head[7];
    }
    if (!full_set_clip_scale(f)) {
        free(f);
        return core_say(BTDF_ENOMEM, msg, msglen, "out of memory");
    }
    *out = f;
    return BTDF_OK;
}
