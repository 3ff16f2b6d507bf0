/* SPDX-License-Identifier: MIT */
/* cli.h: what the commands of btdftab share: the parsed command line (struct cli),
   its parsing (cli.c) and the checks and helpers of several commands. */
#ifndef BTDFTAB_CLI_H
#define BTDFTAB_CLI_H

#include <stddef.h>

#include <btdf/btdf.h>

#include "options.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* Exit statuses (README "Exit status"). */
enum { EXIT_USAGE = 2, EXIT_BUDGET = 3 };

/* The program's name in messages. */
extern const char *prog;

#define MAX_PREVIEWS 4

typedef struct preview_req {
    btdf_preview_kind kind;
    int analytic;
    int named; /* KIND= was given */
    const char *path;
} preview_req;

/* ------------------------------------------------------------------------- */
/* The options of every command, parsed once                                 */
/* ------------------------------------------------------------------------- */

typedef struct cli {
    unsigned char given[OPT_COUNT]; /* how often each option was given */
    btdf_params p;
    int threads, quiet, force, best_effort, sides, reflection, dry_run, shard_k, shard_n;
    btdf_rad_basis basis;
    btdf_part part; /* --part: a table's lobes (default transmission); a .bsdf's blocks
                       (default both when not given) */
    const char *table, *out, *report;
    btdf_table_opts o; /* tolerance, metric, grid, max_samples */
    size_t mib;
    double ti0, ti1, to0, to1, ph0, ph1;
    double log_decades; /* render previews: 0 linear */
    double zoom;        /* render previews: 0 the whole face */
    int digits;         /* albedo: significant digits (default 7) */
    preview_req previews[MAX_PREVIEWS + 1]; /* + 1: -o F.png */
    int npreview, pic_w, pic_h;
    double mat_n[BTDF_PREVIEW_MAX_CURVES], mat_s[BTDF_PREVIEW_MAX_CURVES];
    double angles[BTDF_PREVIEW_MAX_CURVES];
    size_t nm, na;
    int back_smooth;      /* --back smooth */
    double back_s, thickness, absorption; /* --back S, --thickness, --absorption */
    const char *light;    /* --light of eval --back (checked in cmd_pane.c) */
    const char *pos[512]; /* positional arguments */
    int npos;
} cli;

#define GIVEN(c, id) ((c)->given[(id)-OPT_HELP])

/* Below this R + T the model has lost more light than a user would guess: its single
   scattering and the shadowing term V(ti) V(to) drop what real rough surfaces scatter
   again (docs/model.md, "Where the model holds"). */
#define ALBEDO_WARN 0.9

/* cli.c: messages, option values, argument checks */
int fail(int code, const char *fmt, ...);
int ends_with(const char *s, const char *suffix);
int parse_double(const char *flag, const char *s, double *out);
int parse_size(const char *flag, const char *s, size_t lo, size_t hi, size_t *out);
int parse_ior(const char *val, btdf_params *p);
int parse_range(const char *flag, const char *s, double lo, double hi, int strict,
                double *a, double *b);
int parse_preview(const char *s, preview_req *r);
int parse_picture_size(const char *s, int *w, int *h);
void cli_defaults(cli *c);
int apply(cli *c, const opt_hit *h);
int parse_command(const cmd_def *cmd, int argc, char **argv, cli *c);
int check_params(const btdf_params *p);
int folder_writable(const char *path);
int check_angles(double ti, double to, double phi, long line);
int check_angles_r(double ti, double tr, double phi, long line);
int read_row(const char *line, double *v, int want);
int stdout_done(int code);
void table_ti_range(const btdf_table *t, double *range);
const char *num(double x);
void print_values(const double *v, int n);

/* cmd_model.c: eval, albedo, polar */
int cmd_eval(const cli *c);
void warn_albedo(const btdf_params *p, double ti_deg, double rt, const char *what);
double albedo_min(const btdf_params *p, double ti);
int cmd_albedo(const cli *c);
int cmd_polar(const cli *c);
/* polar_file.c: the polar picture png of a written file read back (.csv, .exr, .bsdf,
   .xml), one curve per channel and angle (degrees); 0 or the exit status after the
   message. */
int polar_of_file(const char *file, const char *png, btdf_part part, const double *angles,
                  size_t na, int width, int height);
/* The factors (n_c / n_G)^2 that undo a colour .bsdf's stored transmission scaling
   (btdf_scatfun.h), from its metadata; 1 each for one channel. 0 when a colour file's
   metadata lacks its three indices (fold stays all 1). */
int scatfun_fold(const btdf_scatfun *f, double fold[BTDF_MAX_CHANNELS]);

/* cmd_pane.c: a pane's system (--back): its options, tabulate to .xml, albedo */
int apply_pane(cli *c, int id, const char *v);
int cmd_pane(const cli *c, unsigned cmd, const char *prov);

/* cmd_tabulate.c: tabulate (tables, .bsdf, .xml), inspect */
int cmd_tabulate(cli *c, const char *prov);
int cmd_inspect(const cli *c);

#endif
