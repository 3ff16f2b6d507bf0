/* SPDX-License-Identifier: MIT */
/* options.h: btdftab's one table of commands and options, from which getopt_long's
   arguments, each command's --help and the manual page are all generated. */
#ifndef BTDFTAB_OPTIONS_H
#define BTDFTAB_OPTIONS_H

#include <stdio.h>

/* Commands, as bits: an option lists the commands that take it. */
enum {
    CMD_EVAL = 1 << 0,
    CMD_TABULATE = 1 << 1,
    CMD_ALBEDO = 1 << 2,
    CMD_POLAR = 1 << 3,
    CMD_BUILD = 1 << 4,
    CMD_INSPECT = 1 << 5,
    CMD_SIMULATE = 1 << 6
};

/* Option identities (getopt_long's return values; above every short option letter). */
typedef enum {
    OPT_HELP = 256,
    OPT_IOR,
    OPT_SMOOTHNESS,
    OPT_K0,
    OPT_TABLE,
    OPT_PART,
    OPT_OUTPUT,
    OPT_TOLERANCE,
    OPT_METRIC,
    OPT_GRID,
    OPT_SIDE,
    OPT_BASIS,
    OPT_THETA_I,
    OPT_THETA_O,
    OPT_PHI,
    OPT_MAX_SAMPLES,
    OPT_MAX_MEMORY,
    OPT_THREADS,
    OPT_REPORT,
    OPT_BEST_EFFORT,
    OPT_ESTIMATE,
    OPT_PREVIEW,
    OPT_SIZE,
    OPT_MATERIAL,
    OPT_ANGLES,
    OPT_FORCE,
    OPT_DRY_RUN,
    OPT_SHARD,
    OPT_QUIET,
    OPT_LOG_DECADES,
    OPT_ZOOM,
    OPT_DIGITS,
    OPT_RAYS,
    OPT_SEED,
    OPT_CELLS,
    OPT_TILE,
    OPT_MODEL,
    OPT_BINS,
    OPT_MERGE,
    OPT_PROFILE,
    OPT_BACK,
    OPT_THICKNESS,
    OPT_ABSORPTION,
    OPT_LIGHT,
    OPT_END
} opt_id;

#define OPT_COUNT (OPT_END - OPT_HELP)

typedef struct opt_def {
    opt_id id;
    const char *name;   /* long name, without "--" */
    char letter;        /* short option, or 0 */
    const char *value;  /* what the value looks like ("N"), or NULL for a flag */
    int repeatable;     /* 1 if it may be given more than once */
    unsigned cmds;      /* CMD_* bits of the commands that take it */
    const char *help;   /* one sentence or more; "\n" starts a new line */
} opt_def;

typedef struct cmd_def {
    const char *name;     /* "tabulate" */
    unsigned bit;         /* CMD_TABULATE */
    const char *synopsis; /* "[options] -o FILE" */
    const char *summary;  /* one line */
    const char *details;  /* a paragraph for --help and the manual, or NULL */
} cmd_def;

extern const opt_def opt_table[];
extern const cmd_def cmd_table[];

/* The command of that name, or NULL. */
const cmd_def *cmd_find(const char *name);
/* The command a mistyped name most likely meant (a prefix, or a few edits away), or NULL. */
const cmd_def *cmd_nearest(const char *name);

/* An option's definition by identity. */
const opt_def *opt_find(opt_id id);

/* One parsed option: its identity and its value (NULL for a flag). */
typedef struct opt_hit {
    opt_id id;
    const char *value;
} opt_hit;

/* Parses argv[1..argc) of one command (argv[0] is the command's name) with getopt_long
   over that command's options. Options go to hits (in order, at most maxhits), the
   other arguments to positional (in order; at most argc). An argument that reads as
   a negative number ("-30") is positional. Returns the number of hits, or -1 after
   printing a usage error (unknown option with the nearest valid one, missing value,
   an option given twice) to standard error. */
int opt_parse(const char *prog, const cmd_def *cmd, int argc, char **argv, opt_hit *hits,
              int maxhits, const char **positional, int *npositional);

/* Help of one command (its usage, details and options), or of the tool (cmd NULL). */
void opt_help(FILE *f, const cmd_def *cmd);

/* The bash completion script, from the same table. */
void opt_bash(FILE *f);

/* The manual page, btdftab.1, in troff -man. */
void opt_man(FILE *f, const char *version);

#endif
