/* SPDX-License-Identifier: MIT */
/* cmd_simulate_pane.c: btdftab simulate --back smooth|S --thickness MM --absorption
   PER_MM --light front|back: the pane of btdf_sim_opts (docs/simulation.md). */
#include "cmd_simulate_pane.h"

#include <math.h>
#include <stdarg.h>
#include <string.h>

#include <btdf/btdf.h>
#include <btdf/btdf_io.h>

#include "numparse.h"
#include "options.h"

/* Options given, to say which one needs --back. */
static int given_thickness, given_absorption, given_light;

static int fail(const char *prog, const char *fmt, ...)
{
    va_list ap;
    fprintf(stderr, "%s: simulate: ", prog);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
    return 2;
}

int simpane_option(const char *prog, int id, const char *v, btdf_sim_opts *o)
{
    double x;
    switch (id) {
    case OPT_BACK:
        o->pane = 1;
        if (o->thickness_mm == 0.0)
            o->thickness_mm = 4.0; /* the default, until --thickness says otherwise */
        if (!strcmp(v, "smooth")) {
            o->back_smoothness = 0.0;
            return -1;
        }
        if (num_double(v, &x) || !(x >= BTDF_S_MIN && x <= BTDF_S_MAX))
            return fail(prog, "--back: '%s': smooth (a flat back face) or its smoothness S in "
                              "[%g, %g]", v, BTDF_S_MIN, BTDF_S_MAX);
        o->back_smoothness = x;
        return -1;
    case OPT_THICKNESS:
        if (num_double(v, &x) || !(x > 0.0 && x <= 1e4))
            return fail(prog, "--thickness: '%s': the pane's thickness in mm, in (0, 10000]", v);
        o->thickness_mm = x;
        given_thickness = 1;
        return -1;
    case OPT_ABSORPTION:
        if (num_double(v, &x) || !(x >= 0.0 && x <= 1e3))
            return fail(prog, "--absorption: '%s': the absorption coefficient per mm, in "
                              "[0, 1000]", v);
        o->absorption_per_mm = x;
        given_absorption = 1;
        return -1;
    case OPT_LIGHT:
        if (strcmp(v, "front") && strcmp(v, "back"))
            return fail(prog, "--light: '%s': front or back (the face the light arrives on)", v);
        o->from_back = !strcmp(v, "back");
        given_light = 1;
        return -1;
    default: return -1;
    }
}

int simpane_finish(const char *prog, const btdf_sim_opts *o, const char *dist,
                   const char *preview)
{
    if (!o->pane) {
        const char *lone = given_thickness ? "--thickness" : given_absorption ? "--absorption"
                         : given_light     ? "--light" : NULL;
        if (lone)
            return fail(prog, "%s describes a pane: give its back face with --back smooth|S",
                        lone);
        return -1;
    }
    if (o->profile)
        return fail(prog, "--back with --profile 1d: a pane is simulated with the 2D surface");
    if (preview)
        return fail(prog, "--preview with --back: the picture sets an interface beside Eq. 25; "
                          "a pane has no such model");
    size_t n = dist ? strlen(dist) : 0;
    if (n >= 4 && !strcmp(dist + n - 4, ".exr"))
        return fail(prog, "-o %s with --back: a pane's distribution is written as .csv", dist);
    return -1;
}

static void num(char *b, size_t len, double x)
{
    btdf_format_double(isfinite(x) ? x : 0.0, b, len); /* never NaN in a file */
}

int simpane_fingerprint(const btdf_sim_opts *o, char *out, size_t len)
{
    if (!o->pane)
        return 0;
    char b[40], d[40], a[40];
    num(b, sizeof b, o->back_smoothness);
    num(d, sizeof d, o->thickness_mm);
    num(a, sizeof a, o->absorption_per_mm);
    return snprintf(out, len, " pane=back:%s,mm:%s,per_mm:%s,light:%s",
                    o->back_smoothness > 0.0 ? b : "smooth", d, a,
                    o->from_back ? "back" : "front");
}

static void jlist(FILE *f, const char *key, const btdf_sim_result *r, int se)
{
    char b[40];
    fprintf(f, "  \"%s\": %s", key, r->count > 1 ? "[" : "");
    for (size_t k = 0; k < r->count; k++) {
        num(b, sizeof b, se ? r->tally[k].A.se : r->tally[k].A.mean);
        fprintf(f, "%s%s", k ? ", " : "", b);
    }
    fprintf(f, "%s,\n", r->count > 1 ? "]" : "");
}

void simpane_json(FILE *f, const btdf_sim_opts *o, const btdf_sim_result *r)
{
    if (!o->pane)
        return;
    char s[40], b[40], d[40], a[40];
    num(s, sizeof s, o->smoothness);
    num(b, sizeof b, o->back_smoothness);
    num(d, sizeof d, o->thickness_mm);
    num(a, sizeof a, o->absorption_per_mm);
    fprintf(f, "  \"pane\": {\"front\": {\"smoothness\": %s}, \"back\": ", s);
    if (o->back_smoothness > 0.0)
        fprintf(f, "{\"smoothness\": %s}", b);
    else
        fputs("\"smooth\"", f);
    fprintf(f, ", \"thickness_mm\": %s, \"absorption_per_mm\": %s, \"light\": \"%s\", "
               "\"R\": \"on the lit side\", \"T\": \"through to the other side\", \"A\": "
               "\"absorbed inside\"},\n",
            d, a, o->from_back ? "back" : "front");
    jlist(f, "A", r, 0);
    jlist(f, "A_se", r, 1);
}

void simpane_csv(FILE *f, const btdf_sim_opts *o)
{
    char buf[256];
    if (simpane_fingerprint(o, buf, sizeof buf) > 0)
        fprintf(f, "\n# pane: %s (reflection on the lit side, transmission through to the "
                   "other)", buf + 6); /* past " pane=" */
}

void simpane_summary(FILE *f, const btdf_sim_opts *o, const btdf_sim_tally *t)
{
    fprintf(f, "  pane (%s back, %g mm, %g per mm, light on the %s): A %.5f +- %.5f\n",
            o->back_smoothness > 0.0 ? "rough" : "smooth", o->thickness_mm,
            o->absorption_per_mm, o->from_back ? "back" : "front", t->A.mean, t->A.se);
}
