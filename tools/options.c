/* SPDX-License-Identifier: MIT */
/* options.c: the table of btdftab's commands and options, and what is made from it:
   getopt_long's arguments, every --help, and the manual page. */
#include <errno.h>
#include <getopt.h>
#include <stdlib.h>
#include <string.h>

#include "options.h"

#define MAT (CMD_EVAL | CMD_TABULATE | CMD_ALBEDO | CMD_POLAR)
#define ALL (CMD_EVAL | CMD_TABULATE | CMD_ALBEDO | CMD_POLAR | CMD_BUILD | CMD_INSPECT | \
             CMD_SIMULATE)
#define SIM CMD_SIMULATE

const opt_def opt_table[] = {
    {OPT_IOR, "ior", 'n', "N|R,G,B", 0, MAT,
     "relative index n = n_lower / n_upper (default 1.5); n != 1"},
    {OPT_SMOOTHNESS, "smoothness", 's', "S", 0, MAT,
     "s = correlation length / RMS height (default 3)"},
    {OPT_K0, "k0", 0, "K", 0, MAT, "shadowing constant (default 0.7)"},
    {OPT_MODEL, "model", 0, "M", 0, MAT,
     "the facets' shadowing-masking: xu-sun (default: Eq. 25, V(ti) V(to) with k0) or\n"
     "smith (the height-correlated Smith term of the same Gaussian surface; k0 unused;\n"
     "tabulate writes it to .csv, .exr, .xml and .bsdf, the files record it) or full\n"
     "(smith plus the light scattered two or more times, tallied once per material by a\n"
     "random walk: R + T = 1; eval, albedo, polar and tabulate to .csv, .exr, .xml and\n"
     ".bsdf (one index), which keep the tally or its sum)"},
    {OPT_BACK, "back", 0, "smooth|S", 0, CMD_TABULATE | CMD_ALBEDO | CMD_EVAL | CMD_POLAR,
     "a pane, not an interface: its back face is flat (smooth) or rough with\n"
     "smoothness S; the front face is --ior, --smoothness, --model; tabulate writes the\n"
     "system (air to air, light from either side) to .xml, .csv, .exr or, with a rough\n"
     "back, .bsdf (front face up); albedo prints its T and R,\n"
     "eval its BSDF and polar its lobes, light on the face --light names (docs/pane.md)"},
    {OPT_THICKNESS, "thickness", 0, "MM", 0, CMD_TABULATE | CMD_ALBEDO | CMD_EVAL | CMD_POLAR,
     "with --back: the pane's thickness in mm (default 4)"},
    {OPT_LIGHT, "light", 0, "front|back", 0, CMD_EVAL | CMD_POLAR,
     "with --back: the face of the pane the light falls on (default front)"},
    {OPT_ABSORPTION, "absorption", 0, "PER_MM", 0,
     CMD_TABULATE | CMD_ALBEDO | CMD_EVAL | CMD_POLAR,
     "with --back: the glass's absorption coefficient per mm (default 0): light is\n"
     "attenuated by exp(-a d / cos theta) on each crossing"},
    {OPT_TABLE, "table", 0, "FILE", 0, CMD_EVAL,
     "evaluate a written table (.csv, .exr, .bsdf) instead of Eq. 25; the file gives\n"
     "the material, so --ior, --smoothness and --k0 do not apply"},
    {OPT_TABLE, "table", 0, "FILE", 0, CMD_POLAR,
     "draw the lobes of a written file (.csv, .exr, .bsdf, .xml) read back, as eval\n"
     "--table reads it, instead of Eq. 25; the file gives the material"},
    {OPT_PART, "part", 0, "P", 0, CMD_EVAL,
     "transmission (default), or reflection: rows TI TR PHI with theta_r in [0, 90],\n"
     "phi = 180 the specular plane; of the model, or of a --table that holds it"},
    {OPT_PART, "part", 0, "P", 0, CMD_POLAR,
     "transmission (default: the lobe below the surface), reflection (rho_r |cos\n"
     "theta_r| above it) or both, like the paper's figures of both halves"},
    {OPT_PART, "part", 0, "P", 0, CMD_TABULATE,
     "the lobes a .csv/.exr table holds: transmission (default), reflection (theta_r in\n"
     "[0, 90], nodes around the mirror direction) or both (one file, each part meeting\n"
     "the tolerance with the whole budget); a .bsdf's blocks: both (default: four\n"
     "blocks), transmission (the two transmission blocks) or reflection; not for .xml\n"
     "(it holds both parts)"},
    {OPT_OUTPUT, "output", 'o', "FILE", 0, CMD_TABULATE,
     ".csv, .exr, .png (a montage), .bsdf (pbrt-v3/Mitsuba tabulated) or .xml\n"
     "(Radiance/WINDOW BSDF); the last two are built from Eq. 25 directly; '-' writes\n"
     "CSV to standard output"},
    {OPT_OUTPUT, "output", 'o', "FILE.png", 0, CMD_POLAR, "the picture"},
    {OPT_TOLERANCE, "tolerance", 0, "E", 0, CMD_TABULATE,
     "target error of the adaptive table (default 1e-3), of a .bsdf (default 1e-2\n"
     "with reflection blocks, 1e-3 with --part transmission) or of a tree3 .xml\n"
     "(default 0.2)"},
    {OPT_METRIC, "metric", 0, "l1|max", 0, CMD_TABULATE,
     "which error must meet E (default l1)"},
    {OPT_GRID, "grid", 0, "NI,NO,NPHI", 0, CMD_TABULATE,
     "a plain regular grid in (theta_i, theta_o, phi) instead: N points spaced\n"
     "evenly over each range, both ends included (91,91,181: 1-degree steps)"},
    {OPT_SIDE, "side", 0, "S", 0, CMD_TABULATE,
     "enter (index n, default), leave (index 1/n); for .bsdf also both (the\n"
     "default there)"},
    {OPT_BASIS, "basis", 0, "B", 0, CMD_TABULATE,
     ".xml: tree3 (TensorTree3, default), klems-full, klems-half or klems-quarter\n"
     "(three --ior values: colour, a tree's Y, u', v' or Klems' X, Y, Z)"},
    {OPT_THETA_I, "theta-i", 0, "A:B", 0, CMD_TABULATE,
     "incidence range in degrees (default 0:90)"},
    {OPT_THETA_O, "theta-o", 0, "A:B", 0, CMD_TABULATE,
     "--grid only: outgoing range, within 90:180 (default)"},
    {OPT_PHI, "phi", 0, "A:B", 0, CMD_TABULATE,
     "--grid only: azimuth range, within 0:180 (default; rho depends on cos phi, so\n"
     "0:180 holds every azimuth)"},
    {OPT_MAX_SAMPLES, "max-samples", 0, "N", 0, CMD_TABULATE,
     "node budget (default 8000000); for .bsdf, when given, the stored coefficients"},
    {OPT_MAX_MEMORY, "max-memory", 0, "MIB", 0, CMD_TABULATE,
     "memory cap for the nodes (default 256); for .bsdf, when given, the builder's\n"
     "series"},
    {OPT_THREADS, "threads", 0, "N", 0, CMD_EVAL | CMD_TABULATE | CMD_BUILD,
     "worker threads, 0 = all cores (default 0)"},
    {OPT_REPORT, "report", 0, "FILE.json", 0, CMD_TABULATE, "write the error report as JSON"},
    {OPT_BEST_EFFORT, "best-effort", 0, NULL, 0, CMD_TABULATE | CMD_BUILD,
     "write the output even if the budget stopped refinement"},
    {OPT_ESTIMATE, "estimate", 0, "full|fast|none", 0, CMD_TABULATE,
     "full (default): check the table against Eq. 25 at every slice interval and\n"
     "where the error changes fast; fast: fewer points; none: one unchecked pass,\n"
     "the file says \"error not estimated\""},
    {OPT_PREVIEW, "preview", 0, "[KIND=]F.png", 1, CMD_TABULATE,
     "a picture of the table; KIND is montage (default), render (the paper's\n"
     "Figs. 10-11) or render-analytic (with Eq. 25 and the difference beside it);\n"
     "repeatable; -o F.png is the same as --preview F.png. Of a .bsdf or .xml: its\n"
     "lobes at theta_i = 30 read back from the file (KIND polar, the default there)"},
    {OPT_LOG_DECADES, "log-decades", 0, "D", 0, CMD_TABULATE,
     "render previews on a log scale over D decades below each row's maximum\n"
     "(1 to 12; default linear, as in the paper)"},
    {OPT_ZOOM, "zoom", 0, "Z", 0, CMD_TABULATE,
     "render previews show the central 1/Z of the face (1 to 1000; default: from\n"
     "the lobe, so that a narrow one fills the picture; 1, the whole face as in the\n"
     "paper, when the lobe fills it already)"},
    {OPT_SIZE, "size", 0, "WxH", 0, CMD_TABULATE | CMD_POLAR,
     "picture size in pixels (default: per kind)"},
    {OPT_MATERIAL, "material", 0, "N:S", 1, CMD_POLAR,
     "one material (repeatable, at most 8 curves in all); default: --ior and\n"
     "--smoothness"},
    {OPT_ANGLES, "angles", 0, "A,B,...", 0, CMD_POLAR,
     "incident angles in degrees (default 30)"},
    {OPT_FORCE, "force", 0, NULL, 0, CMD_BUILD, "redo outputs that are up to date"},
    {OPT_DRY_RUN, "dry-run", 0, NULL, 0, CMD_BUILD,
     "list every output with what would be done and why (missing, stamp changed,\n"
     "--force, up to date) on standard output; build nothing"},
    {OPT_SHARD, "shard", 0, "K/N", 0, CMD_BUILD,
     "build only the K-th of N deterministic shares of the jobs (1 <= K <= N), e.g.\n"
     "one per task of a Slurm job array; shards write disjoint files"},
    {OPT_DIGITS, "digits", 0, "D", 0, CMD_ALBEDO,
     "significant digits of T, Ft, R and R + T, 1 to 17 (default 7: T and R are\n"
     "accurate to 1e-7; 17 gives the double itself; a pane's, --back: default 6)"},
    {OPT_QUIET, "quiet", 'q', NULL, 0, CMD_TABULATE | CMD_POLAR | CMD_BUILD | CMD_ALBEDO,
     "no report lines or warnings on standard error"},
    {OPT_IOR, "ior", 'n', "N|R,G,B", 0, SIM,
     "relative index n = n_lower / n_upper (default 1.5); n < 1 is light from the dense\n"
     "side; n != 1"},
    {OPT_SMOOTHNESS, "smoothness", 's', "S", 0, SIM,
     "s = correlation length / RMS height of the generated surface (default 3)"},
    {OPT_THETA_I, "theta-i", 0, "A|A,B,..|A:B:STEP", 0, SIM,
     "incident angles in degrees, in [0, 90) (default 30)"},
    {OPT_PROFILE, "profile", 0, "2d|1d", 0, SIM,
     "2d (default): the surface; 1d: the paper's setting, a profile z = h(x) and\n"
     "rays in its plane of incidence (distribution per radian of theta_o, no\n"
     "comparison with Eq. 25's 2D BTDF)"},
    {OPT_BACK, "back", 0, "smooth|S", 0, SIM,
     "simulate a pane instead of one interface: the surface above is its front face,\n"
     "this its back face, flat (smooth) or rough with smoothness S (an independent\n"
     "surface); R is on the lit side, T through, A absorbed (docs/simulation.md)"},
    {OPT_THICKNESS, "thickness", 0, "MM", 0, SIM, "the pane's thickness in mm (default 4)"},
    {OPT_ABSORPTION, "absorption", 0, "PER_MM", 0, SIM,
     "the pane's absorption coefficient per mm, Beer-Lambert along each path inside\n"
     "(default 0)"},
    {OPT_LIGHT, "light", 0, "front|back", 0, SIM,
     "the face of the pane the light arrives on (default front)"},
    {OPT_RAYS, "rays", 0, "K", 0, SIM, "rays per angle and channel (default 1000000)"},
    {OPT_SEED, "seed", 0, "X", 0, SIM, "seed of the surfaces and rays (default 1)"},
    {OPT_CELLS, "cells-per-tau", 0, "C", 0, SIM,
     "grid points per correlation length (default 16)"},
    {OPT_TILE, "tile", 0, "L", 0, SIM, "tile side in correlation lengths (default 16)"},
    {OPT_THREADS, "threads", 0, "N", 0, SIM,
     "worker threads, 0 = all cores (default 0); results do not depend on it"},
    {OPT_MAX_MEMORY, "max-memory", 0, "MIB", 0, SIM,
     "memory cap for the surfaces and tallies (default 1024)"},
    {OPT_REPORT, "report", 0, "FILE.json", 0, SIM,
     "write R, T, their orders and errors, Eq. 25 beside them, and the surface's\n"
     "realised statistics as JSON"},
    {OPT_OUTPUT, "output", 'o', "F.csv|F.exr", 0, SIM,
     "the outgoing distribution: rho and its error per bin, all orders and one hit\n"
     "(CSV: both parts; EXR: the transmission as a grid table with error, one_hit\n"
     "and one_hit_error layers; docs/simulation.md)"},
    {OPT_PREVIEW, "preview", 0, "F.png", 0, SIM,
     "a picture: each case's transmitted lobe in the plane of incidence with error\n"
     "bars, beside Eq. 25 and Smith over the same bins (at most 16 cases)"},
    {OPT_BINS, "bins", 0, "T[,P]", 0, SIM,
     "histogram bins in theta_o per hemisphere and in |phi| (default 45,18)"},
    {OPT_SHARD, "shard", 0, "K/N", 0, SIM,
     "trace only the K-th of N ranges of batches (needs --report)"},
    {OPT_MERGE, "merge", 0, NULL, 0, SIM,
     "the arguments are shards' reports (same options): sum them into one run's\n"
     "numbers, e.g. --merge a.json b.json --report all.json"},
    {OPT_QUIET, "quiet", 'q', NULL, 0, SIM, "no progress bar and no summary"},
    {OPT_HELP, "help", 'h', NULL, 0, ALL, "this help"},
    {OPT_END, NULL, 0, NULL, 0, 0, NULL},
};

const cmd_def cmd_table[] = {
    {"eval", CMD_EVAL, "[options] [TI TO PHI]",
     "rho at angles (degrees), or rows on stdin",
     "Prints rho (1/sr, one value per channel) at the incident angle TI, outgoing angle TO\n"
     "and azimuth PHI in degrees; without angles, one line per input row 'TI TO PHI'\n"
     "(blanks or commas; '#' starts a comment). With --part reflection, rho_r of the\n"
     "same surface at rows 'TI TR PHI'."},
    {"tabulate", CMD_TABULATE, "[options] -o FILE", "write a table, a .bsdf or a picture",
     "Builds an adaptive table (or a --grid) of Eq. 25 and writes it in the format its\n"
     "extension names; prints one report line on standard error (slices, samples, times\n"
     "and the errors e_L1, e_max, e_T estimated at points the table was not built on)."},
    {"albedo", CMD_ALBEDO, "[options] [TI ...]", "T(ti), the flat Ft(ti), R(ti), R + T",
     "Prints, as CSV, the directional transmittance T of Eq. 25, the Fresnel\n"
     "transmittance Ft of a flat interface, the reflectance R of the same surface and\n"
     "R + T at each incident angle TI in degrees (default 0, 10, ..., 80)."},
    {"polar", CMD_POLAR, "[options] -o FILE.png", "lobes in the plane of incidence",
     "Draws rho |cos to| in the plane of incidence, one curve per material and angle,\n"
     "like Figs. 5 and 6 of Xu & Sun (2008); with --table, of a written file."},
    {"build", CMD_BUILD, "[options] SCENE.ini", "the outputs a scene manifest lists",
     "Builds every output of a scene manifest (docs/pipelines.md) that is missing or\n"
     "out of date; each table is built once and shared by its outputs. Output paths\n"
     "are relative to the manifest's folder; missing folders are created."},
    {"inspect", CMD_INSPECT, "FILE", "header and statistics of a file",
     "Prints the header and statistics of a table (.csv, .exr) or a .bsdf."},
    {"simulate", CMD_SIMULATE, "[options] [--report F.json] [--merge SHARD.json ...]",
     "Monte Carlo rays on generated rough surfaces",
     "Traces rays through periodic Gaussian random surfaces of smoothness S (exact\n"
     "intersections, Fresnel at every hit, every order) and prints R and T with their\n"
     "standard errors, split by order (1, 2, 3+), beside Eq. 25 (docs/simulation.md)."},
    {NULL, 0, NULL, NULL, NULL},
};

const cmd_def *cmd_find(const char *name)
{
    for (const cmd_def *c = cmd_table; c->name; c++)
        if (!strcmp(c->name, name))
            return c;
    return NULL;
}

const opt_def *opt_find(opt_id id)
{
    for (const opt_def *o = opt_table; o->name; o++)
        if (o->id == id)
            return o; /* the first: entries of one id share their name */
    return NULL;
}

/* ------------------------------------------------------------------------- */
/* Parsing                                                                   */
/* ------------------------------------------------------------------------- */

/* Edit distance between a and b (each at most 63 characters), for suggestions. */
static size_t distance(const char *a, const char *b)
{
    size_t la = strlen(a), lb = strlen(b), row[64];
    if (la > 63 || lb > 63)
        return (size_t)-1;
    for (size_t j = 0; j <= lb; j++)
        row[j] = j;
    for (size_t i = 1; i <= la; i++) {
        size_t diag = row[0];
        row[0] = i;
        for (size_t j = 1; j <= lb; j++) {
            size_t up = row[j];
            size_t best = diag + (a[i - 1] != b[j - 1]);
            if (up + 1 < best)
                best = up + 1;
            if (row[j - 1] + 1 < best)
                best = row[j - 1] + 1;
            row[j] = best;
            diag = up;
        }
    }
    return row[lb];
}

const cmd_def *cmd_nearest(const char *name)
{
    const cmd_def *best = NULL;
    size_t bestd = (size_t)-1, len = strlen(name);
    for (const cmd_def *c = cmd_table; c->name; c++) {
        size_t d = len && !strncmp(c->name, name, len) ? 1 : distance(name, c->name);
        if (d < bestd) {
            bestd = d;
            best = c;
        }
    }
    /* the thresholds of the options' suggestions: a slip, not another word */
    return len && bestd <= (len > 5 ? 3 : len > 2 ? 2 : len - 1) ? best : NULL;
}

/* Says an option is unknown, with the nearest of this command's options, or the
   commands that take it when it belongs to another. */
static void unknown_option(const char *prog, const cmd_def *cmd, const char *arg)
{
    char name[64];
    const char *s = arg;
    while (*s == '-')
        s++;
    snprintf(name, sizeof name, "%.*s", (int)strcspn(s, "="), s);
    fprintf(stderr, "%s: %s: unknown option '%s'", prog, cmd->name, arg);
    const opt_def *best = NULL, *elsewhere = NULL;
    size_t bestd = (size_t)-1, len = strlen(name);
    for (const opt_def *o = opt_table; o->name; o++) {
        if (!(o->cmds & cmd->bit)) {
            if (!strcmp(o->name, name) || (len == 1 && o->letter == name[0]))
                elsewhere = o;
            continue;
        }
        size_t d = distance(name, o->name);
        if (len > 1 && !strncmp(o->name, name, len))
            d = 1; /* an ambiguous abbreviation reads as its first match */
        if (d < bestd) {
            bestd = d;
            best = o;
        }
    }
    if (elsewhere && best && !strcmp(best->name, elsewhere->name))
        elsewhere = NULL; /* a name this command has too, spelled wrong ("-ior") */
    if (elsewhere) {
        fprintf(stderr, ": --%s is an option of", elsewhere->name);
        const char *sep = " ";
        for (const cmd_def *c = cmd_table; c->name; c++)
            if (elsewhere->cmds & c->bit) {
                fprintf(stderr, "%s%s", sep, c->name);
                sep = ", ";
            }
    } else if (best && bestd <= (len > 5 ? 3 : len > 2 ? 2 : len - 1)) {
        fprintf(stderr, "; did you mean '--%s'?", best->name);
    }
    fprintf(stderr, "\nTry '%s help %s' for its options.\n", prog, cmd->name);
}

/* 1 if s reads entirely as a negative number ("-30", "-.5", "-1e-3"). */
static int negative_number(const char *s)
{
    if (s[0] != '-' || !(s[1] == '.' || (s[1] >= '0' && s[1] <= '9')))
        return 0;
    char *e;
    errno = 0;
    (void)strtod(s, &e);
    return *e == '\0';
}

/* The option of this command spelled by letter c, or NULL. */
static const opt_def *by_letter(const cmd_def *cmd, int c)
{
    for (const opt_def *o = opt_table; o->name; o++)
        if (o->letter == c && (o->cmds & cmd->bit))
            return o;
    return NULL;
}

/* The option of this command whose long name is spelled by "--name[=v]", or NULL. */
static const opt_def *by_long(const cmd_def *cmd, const char *arg)
{
    size_t l = strcspn(arg + 2, "=");
    const opt_def *hit = NULL;
    for (const opt_def *o = opt_table; o->name; o++) {
        if (!(o->cmds & cmd->bit) || strncmp(o->name, arg + 2, l))
            continue;
        if (o->name[l] == '\0')
            return o; /* exact */
        hit = hit ? NULL : o; /* a unique abbreviation, as getopt_long takes it */
    }
    return hit;
}

int opt_parse(const char *prog, const cmd_def *cmd, int argc, char **argv, opt_hit *hits,
              int maxhits, const char **positional, int *npositional)
{
    struct option longs[OPT_COUNT + 1];
    char shorts[2 * OPT_COUNT + 2];
    size_t nl = 0, ns = 0;
    shorts[ns++] = ':'; /* a missing value returns ':' */
    for (const opt_def *o = opt_table; o->name; o++) {
        if (!(o->cmds & cmd->bit))
            continue;
        longs[nl].name = o->name;
        longs[nl].has_arg = o->value ? required_argument : no_argument;
        longs[nl].flag = NULL;
        longs[nl].val = (int)o->id;
        nl++;
        if (o->letter) {
            shorts[ns++] = o->letter;
            if (o->value)
                shorts[ns++] = ':';
        }
    }
    memset(&longs[nl], 0, sizeof longs[nl]);
    shorts[ns] = '\0';

    /* Options first, then "--", then the positional arguments in their order: a
       negative number ("-30") is an angle, not an option, and stays in place among
       the angles. An option's separate value is kept with its option. */
    char **args = malloc(((size_t)argc + 2) * sizeof *args);
    const char **pos = positional;
    int na = 0, np = 0;
    if (!args) {
        fprintf(stderr, "%s: out of memory\n", prog);
        return -1;
    }
    args[na++] = argv[0];
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "--")) {
            while (++i < argc)
                pos[np++] = argv[i];
            break;
        }
        if (a[0] != '-' || a[1] == '\0' || negative_number(a)) {
            pos[np++] = a;
            continue;
        }
        args[na++] = argv[i];
        if (a[1] == '-') {
            const opt_def *o = by_long(cmd, a);
            if (o && o->value && !strchr(a, '=') && i + 1 < argc)
                args[na++] = argv[++i];
            continue;
        }
        if (!by_letter(cmd, a[1])) { /* "-ior" for "--ior", or a letter not ours */
            unknown_option(prog, cmd, a);
            free(args);
            return -1;
        }
        for (const char *s = a + 1; *s; s++) { /* a cluster of short options */
            const opt_def *o = by_letter(cmd, *s);
            if (o && o->value) {
                if (s[1] == '\0' && i + 1 < argc)
                    args[na++] = argv[++i];
                break;
            }
        }
    }
    args[na] = NULL;

    int nh = 0, bad = 0;
    unsigned char seen[OPT_COUNT];
    memset(seen, 0, sizeof seen);
    opterr = 0;
    optind = 0; /* 0: a full reset of getopt's state (glibc) */
    for (;;) {
        int c = getopt_long(na, args, shorts, longs, NULL);
        if (c == -1)
            break;
        if (c == '?') {
            const char *a = args[optind - 1];
            const opt_def *o = a[0] == '-' && a[1] == '-' && strchr(a, '=') ? by_long(cmd, a)
                                                                             : NULL;
            if (o && !o->value) { /* "--help=yes": a known option that takes no value */
                fprintf(stderr, "%s: --%s takes no value, not '%s'\n", prog, o->name, a);
            } else if (optopt) {
                char s[3] = {'-', (char)optopt, '\0'};
                unknown_option(prog, cmd, s);
            } else {
                unknown_option(prog, cmd, args[optind - 1]);
            }
            bad = 1;
            break;
        }
        if (c == ':') {
            fprintf(stderr, "%s: %s: missing value\n", prog, args[optind - 1]);
            bad = 1;
            break;
        }
        const opt_def *o = by_letter(cmd, c);
        for (const opt_def *d = opt_table; !o && d->name; d++)
            if ((int)d->id == c && (d->cmds & cmd->bit))
                o = d;
        if (!o)
            continue; /* not reached: getopt_long returns only what it was given */
        if (seen[o->id - OPT_HELP]++ && !o->repeatable) {
            fprintf(stderr, "%s: --%s given twice: give it once\n", prog, o->name);
            bad = 1;
            break;
        }
        if (nh == maxhits) {
            fprintf(stderr, "%s: too many options\n", prog);
            bad = 1;
            break;
        }
        hits[nh].id = o->id;
        hits[nh].value = o->value ? optarg : NULL;
        nh++;
    }
    for (int i = optind; !bad && i < na; i++) /* arguments getopt_long left over */
        pos[np++] = args[i];
    /* pos may hold arguments before and after the options: order them as given. */
    if (!bad) {
        int k = 0;
        for (int i = 1; i < argc; i++)
            for (int j = k; j < np; j++)
                if (pos[j] == argv[i]) {
                    const char *t = pos[j];
                    memmove(&pos[k + 1], &pos[k], (size_t)(j - k) * sizeof *pos);
                    pos[k++] = t;
                    break;
                }
    }
    free(args);
    *npositional = np;
    return bad ? -1 : nh;
}

/* ------------------------------------------------------------------------- */
/* Help and the manual page                                                  */
/* ------------------------------------------------------------------------- */

static const char *model_text =
    "Model: Xu & Sun (2008), Eq. 25, the single-scattering BTDF of a Gaussian rough\n"
    "interface; rho in 1/sr without a cosine factor. Angles in degrees: theta_i in\n"
    "[0, 90], theta_o in [90, 180] (transmitted side), phi = 180 the forward plane.\n";

static const char *exit_text =
    "Exit status: 0 success, 1 failed run, 2 usage error, 3 tolerance not met.\n";

/* "-n, --ior N|R,G,B" */
static void opt_label(char *buf, size_t len, const opt_def *o)
{
    char shortpart[8] = "    ";
    if (o->letter)
        snprintf(shortpart, sizeof shortpart, "-%c, ", o->letter);
    snprintf(buf, len, "%s--%s%s%s", shortpart, o->name, o->value ? " " : "",
             o->value ? o->value : "");
}

/* The option's label, then its help filled to HELP_WIDTH columns beside it. */
#define HELP_WIDTH 52
static void print_option(FILE *f, const opt_def *o)
{
    char label[64];
    opt_label(label, sizeof label, o);
    if (strlen(label) > 22)
        fprintf(f, "  %s\n", label);
    const char *h = o->help;
    size_t col = 0;
    int line = strlen(label) > 22;
    while (*h) {
        while (*h == ' ' || *h == '\n')
            h++;
        size_t l = strcspn(h, " \n");
        if (l == 0)
            break;
        if (col > 0 && col + 1 + l > HELP_WIDTH) {
            fputc('\n', f);
            col = 0;
            line++;
        }
        if (col == 0)
            fprintf(f, "  %-22s  ", line ? "" : label);
        else
            fputc(' ', f);
        fprintf(f, "%.*s", (int)l, h);
        col += (col ? 1 : 0) + l;
        h += l;
    }
    fputc('\n', f);
}

void opt_help(FILE *f, const cmd_def *cmd)
{
    if (cmd) {
        fprintf(f, "usage: btdftab %s %s\n%s.\n", cmd->name, cmd->synopsis, cmd->summary);
        if (cmd->details)
            fprintf(f, "\n%s\n", cmd->details);
        fprintf(f, "\nOptions (--opt=value and --opt value both work; '--' ends them):\n");
        for (const opt_def *o = opt_table; o->name; o++)
            if (o->cmds & cmd->bit)
                print_option(f, o);
        fprintf(f, "\n%s", exit_text);
        return;
    }
    for (const cmd_def *c = cmd_table; c->name; c++) {
        char head[64];
        snprintf(head, sizeof head, "btdftab %s %s", c->name, c->synopsis);
        fprintf(f, "%s%-42s %s\n", c == cmd_table ? "usage: " : "       ", head, c->summary);
    }
    fprintf(f, "       %-42s %s\n", "btdftab help [COMMAND]", "this help, or a command's");
    fprintf(f, "       %-42s %s\n", "btdftab -V | --version", "version and build features");
    fprintf(f, "\n%s\n", model_text);
    fprintf(f, "'btdftab help COMMAND' or 'btdftab COMMAND --help' lists a command's "
               "options;\n'man btdftab' has them all.\n\n%s",
            exit_text);
}

/* Writes s with troff's special characters escaped (backslash, leading dot, dash). */
static void roff(FILE *f, const char *s, size_t len)
{
    int bol = 1;
    for (size_t i = 0; i < len && s[i]; i++) {
        char c = s[i];
        if (bol && (c == '.' || c == '\''))
            fputs("\\&", f);
        if (c == '\\')
            fputs("\\e", f);
        else if (c == '-')
            fputs("\\-", f);
        else
            fputc(c, f);
        bol = c == '\n';
    }
}

static void roff_text(FILE *f, const char *s)
{
    roff(f, s, strlen(s));
}

void opt_man(FILE *f, const char *version)
{
    fprintf(f, ".\\\" SPDX-License-Identifier: MIT\n"
               ".\\\" Generated by 'btdftab --man' from the option table in tools/options.c.\n");
    fprintf(f, ".TH BTDFTAB 1 \"\" \"btdftab %s\" \"User Commands\"\n", version);
    fprintf(f, ".SH NAME\nbtdftab \\- tabulate the rough-interface BTDF of Xu & Sun (2008)\n");
    fprintf(f, ".SH SYNOPSIS\n");
    for (const cmd_def *c = cmd_table; c->name; c++) {
        fprintf(f, ".B btdftab %s\n", c->name);
        roff_text(f, c->synopsis);
        fprintf(f, "\n.br\n");
    }
    fprintf(f, ".B btdftab help\n[COMMAND]\n.br\n.B btdftab \\-\\-version\n");
    fprintf(f, ".SH DESCRIPTION\n");
    roff_text(f, model_text);
    fprintf(f, ".PP\nOptions take their value as the next argument or after '=' "
               "(\\fB\\-\\-ior=1.5\\fR); '\\-\\-' ends the options.\n");
    fprintf(f, ".SH COMMANDS\n");
    for (const cmd_def *c = cmd_table; c->name; c++) {
        fprintf(f, ".SS %s\n", c->name);
        roff_text(f, c->summary);
        fprintf(f, ".\n");
        if (c->details) {
            fprintf(f, ".PP\n");
            roff_text(f, c->details);
            fprintf(f, "\n");
        }
        for (const opt_def *o = opt_table; o->name; o++) {
            if (!(o->cmds & c->bit))
                continue;
            char label[64];
            opt_label(label, sizeof label, o);
            const char *l = label;
            while (*l == ' ')
                l++;
            fprintf(f, ".TP\n.B ");
            roff_text(f, l);
            fprintf(f, "\n");
            roff_text(f, o->help);
            fprintf(f, "\n");
        }
    }
    fprintf(f, ".SH EXIT STATUS\n0 success, 1 a failed run (I/O, unreadable table), 2 a usage "
               "error (named in the message), 3 the tolerance was not met within the budget "
               "(nothing is written unless \\fB\\-\\-best\\-effort\\fR).\n");
    /* the keys manifest.c reads (KEYS there), as docs/pipelines.md states them */
    static const char *const mkeys[][2] = {
        {"ior", "n = n_lower / n_upper, or R,G,B (three values)"},
        {"smoothness", "s, as \\fB\\-\\-smoothness\\fR"},
        {"k0", "optional, as \\fB\\-\\-k0\\fR"},
        {"theta_i", "optional, degrees A:B (default 0:90)"},
        {"tolerance", "optional, as \\fB\\-\\-tolerance\\fR"},
        {"metric", "optional, l1 or max"},
        {"part", "optional, transmission, reflection or both, as \\fB\\-\\-part\\fR"},
        {"model", "optional, xu-sun (default), smith or full, as \\fB\\-\\-model\\fR"},
        {"enter", "outputs for light entering (index n): .csv .exr .png"},
        {"leave", "outputs for light leaving (index 1/n)"},
        {"bsdf", "a .bsdf output, as \\fBtabulate \\-o F.bsdf\\fR"},
        {"sides", "the sides the .bsdf holds: enter, leave or both"},
        {"xml", "a Radiance BSDF XML output, as \\fBtabulate \\-o F.xml\\fR"},
        {"basis", "the .xml's basis, as \\fB\\-\\-basis\\fR: tree3 (default), klems-full, "
                  "klems-half or klems-quarter"},
        {"back", "a pane (its system, to the xml, grid and bsdf outputs; bsdf with a rough back): the back face, "
                 "smooth or a smoothness, as \\fB\\-\\-back\\fR"},
        {"thickness", "the pane's thickness in mm (default 4), as \\fB\\-\\-thickness\\fR"},
        {"absorption", "the pane's absorption per mm (default 0), as "
                       "\\fB\\-\\-absorption\\fR"},
        {"grid", "a pane's system on a grid, .csv or .exr, as \\fBtabulate \\-\\-back \\-o "
                 "F.csv\\fR"},
        {"grid_size", "optional, the grid's nodes NI,NO,NPHI (default 46,46,37), as "
                      "\\fB\\-\\-grid\\fR"}};
    fprintf(f, ".SH MANIFEST\nA scene manifest (\\fBbtdftab build\\fR) is an INI file, one "
               "[section] per material, with the keys:\n");
    for (size_t k = 0; k < sizeof mkeys / sizeof mkeys[0]; k++)
        fprintf(f, ".TP\n.B %s\n%s\n", mkeys[k][0], mkeys[k][1]);
    fprintf(f, ".SH FILES\nOutputs are written under a temporary name beside them and renamed "
               "at the end; an interrupted run leaves no output.\n");
    fprintf(f, ".SH SEE ALSO\nREADME.md and the docs/ folder of the source distribution "
               "(tables, formats, scatfun, radiance, pipelines; not installed).\n");
}

/* ------------------------------------------------------------------------- */
/* Bash completion                                                           */
/* ------------------------------------------------------------------------- */

void opt_bash(FILE *f)
{
    fprintf(f, "# bash completion for btdftab, written by 'btdftab --completion bash' from its\n"
               "# option table.\n_btdftab()\n{\n"
               "    local cur=${COMP_WORDS[COMP_CWORD]} prev=${COMP_WORDS[COMP_CWORD-1]}\n"
               "    if [ \"$COMP_CWORD\" -eq 1 ]; then\n"
               "        COMPREPLY=($(compgen -W \"");
    for (const cmd_def *c = cmd_table; c->name; c++)
        fprintf(f, "%s ", c->name);
    fprintf(f, "help --help --version\" -- \"$cur\"))\n        return\n    fi\n");
    /* Options that take one of a few words complete those words (the words the
       parsers take: run.c, cli.c, btdf_rad_basis_parse, btdf_model_parse) ... */
    static const char *const words[][2] = {
        {"basis", "tree3 klems-full klems-half klems-quarter"},
        {"part", "transmission reflection both"},
        {"estimate", "full fast none"},
        {"side", "enter leave both"},
        {"metric", "l1 max"},
        {"model", "xu-sun smith full"},
        {"light", "front back"},
        {"back", "smooth"}};
    fprintf(f, "    case $prev in\n");
    for (size_t k = 0; k < sizeof words / sizeof words[0]; k++)
        fprintf(f, "        --%s) COMPREPLY=($(compgen -W \"%s\" -- \"$cur\")); return ;;\n",
                words[k][0], words[k][1]);
    fprintf(f, "    esac\n");
    /* ... and options that take a file name complete file names. */
    fprintf(f, "    case $prev in\n        ");
    int first = 1;
    for (const opt_def *o = opt_table; o->name; o++)
        if (o->value && strstr(o->value, "F") && (o == opt_table || strcmp(o[-1].name, o->name))) {
            fprintf(f, "%s--%s", first ? "" : "|", o->name);
            if (o->letter)
                fprintf(f, "|-%c", o->letter);
            first = 0;
        }
    fprintf(f, ")\n            COMPREPLY=($(compgen -f -- \"$cur\")); return ;;\n");
    /* the models this build evaluates (btdf_params_check) */
    fprintf(f, "        --model)\n            COMPREPLY=($(compgen -W \"xu-sun smith full\" -- \"$cur\")); "
               "return ;;\n    esac\n");
    fprintf(f, "    local opts\n    case ${COMP_WORDS[1]} in\n");
    for (const cmd_def *c = cmd_table; c->name; c++) {
        fprintf(f, "        %s) opts=\"", c->name);
        const char *last = "";
        for (const opt_def *o = opt_table; o->name; o++)
            if ((o->cmds & c->bit) && strcmp(o->name, last)) {
                fprintf(f, "--%s ", o->name);
                last = o->name;
            }
        fprintf(f, "\" ;;\n");
    }
    fprintf(f, "        help) COMPREPLY=($(compgen -W \"");
    for (const cmd_def *c = cmd_table; c->name; c++)
        fprintf(f, "%s ", c->name);
    fprintf(f, "\" -- \"$cur\")); return ;;\n        *) return ;;\n    esac\n"
               "    if [[ $cur == -* ]]; then\n"
               "        COMPREPLY=($(compgen -W \"$opts\" -- \"$cur\"))\n"
               "    else\n        COMPREPLY=($(compgen -f -- \"$cur\"))\n    fi\n}\n"
               "complete -F _btdftab btdftab\n");
}
