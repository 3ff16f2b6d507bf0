/* SPDX-License-Identifier: MIT */
/* btdftab.c: the command-line tool: main, the dispatch to the commands (cmd_*.c),
   signals, version and the build command. It reads its options through the one table
   of options.c and calls libbtdf through its installed headers only. */
#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <btdf/btdf.h>

#include "cli.h"
#include "cmd_simulate.h"
#include "evalstream.h"
#include "fastnum.h"
#include "manifest.h"
#include "numparse.h"
#include "options.h"
#include "run.h"

static int cmd_build(const cli *c)
{
    if (c->npos == 0)
        return fail(EXIT_USAGE, "build: give a manifest, e.g. btdftab build scene.ini");
    if (c->npos > 1)
        return fail(EXIT_USAGE, "build: give one manifest, not '%s' and '%s'", c->pos[0],
                    c->pos[1]);
    manifest_opts mo;
    memset(&mo, 0, sizeof mo);
    mo.prog = prog;
    mo.path = c->pos[0];
    mo.force = c->force;
    mo.best_effort = c->best_effort;
    mo.quiet = c->quiet;
    mo.threads = c->threads;
    mo.progress = !c->quiet && isatty(2); /* progress bars only for a person watching */
    mo.dry_run = c->dry_run;
    mo.shard_k = c->shard_k;
    mo.shard_n = c->shard_n;
    return manifest_run(&mo);
}

/* ------------------------------------------------------------------------- */
/* main                                                                      */
/* ------------------------------------------------------------------------- */

/* SIGINT, SIGTERM, SIGHUP: remove the files being written, then die of the signal, so
   an interrupted run leaves no partial output (make and shells see the signal). */
static void on_signal(int sig)
{
    btdf_remove_partial_files(); /* async-signal-safe: flags and unlink */
    signal(sig, SIG_DFL);
    raise(sig);
}

static int print_version(void)
{
    printf("btdftab %s (OpenEXR %s, PNG %s)\n", btdf_version_string(),
           btdf_format_available("exr") ? "on" : "off",
           btdf_format_available("png") ? "on" : "off");
    return stdout_done(0);
}

static int short_usage(void)
{
    for (const cmd_def *c = cmd_table; c->name; c++)
        fprintf(stderr, "%s btdftab %s %s\n", c == cmd_table ? "usage:" : "      ", c->name,
                c->synopsis);
    fprintf(stderr, "Try 'btdftab --help' for more.\n");
    return EXIT_USAGE;
}

int main(int argc, char **argv)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    sigaction(SIGHUP, &sa, NULL);
    /* A closed pipe (btdftab eval | head -1) is a write error, exit status 1 with a
       message, as for a full disk; not a silent death by SIGPIPE. */
    signal(SIGPIPE, SIG_IGN);
    if (argc < 2)
        return short_usage();
    const char *name = argv[1];
    int alone = !strcmp(name, "--help") || !strcmp(name, "-h") || !strcmp(name, "--version") ||
                !strcmp(name, "-V") || !strcmp(name, "--man");
    if (alone && argc > 2)
        return fail(EXIT_USAGE, "%s takes nothing after it, not '%s'", name, argv[2]);
    static const char *const bare[] = {"--help=", "--version=", "--man="};
    for (size_t k = 0; k < sizeof bare / sizeof bare[0]; k++)
        if (!strncmp(name, bare[k], strlen(bare[k])))
            return fail(EXIT_USAGE, "%.*s takes no value, not '%s'", (int)strlen(bare[k]) - 1,
                        name, name);
    if (!strcmp(name, "--help") || !strcmp(name, "-h")) {
        opt_help(stdout, NULL);
        return stdout_done(0);
    }
    if (!strcmp(name, "--version") || !strcmp(name, "-V"))
        return print_version();
    if (!strcmp(name, "--completion")) {
        if (argc != 3 || strcmp(argv[2], "bash"))
            return fail(EXIT_USAGE, "--completion: give 'bash' (the only shell supported)");
        opt_bash(stdout);
        return stdout_done(0);
    }
    if (!strcmp(name, "--man")) {
        opt_man(stdout, btdf_version_string());
        return stdout_done(0);
    }
    if (!strcmp(name, "help")) {
        if (argc > 3)
            return fail(EXIT_USAGE, "help: give one command at most");
        const cmd_def *cmd = argc == 3 ? cmd_find(argv[2]) : NULL;
        if (argc == 3 && !cmd)
            return fail(EXIT_USAGE, "help: unknown command '%s'", argv[2]);
        opt_help(stdout, cmd);
        return stdout_done(0);
    }
    const cmd_def *cmd = cmd_find(name);
    if (!cmd) {
        const cmd_def *near = cmd_nearest(name);
        if (near)
            fail(EXIT_USAGE, "unknown command '%s'; did you mean '%s'?", name, near->name);
        else
            fail(EXIT_USAGE, "unknown command '%s'", name);
        return short_usage();
    }
    /* The command line, recorded in outputs as their provenance. */
    char prov[2048] = "btdftab";
    for (int i = 1; i < argc; i++) {
        size_t l = strlen(prov);
        snprintf(prov + l, sizeof prov - l, " %s", argv[i]);
    }
    if (cmd->bit == CMD_SIMULATE)
        return cmd_simulate(prog, argc - 1, argv + 1, prov);
    static cli c; /* large: off the stack */
    int code = parse_command(cmd, argc - 1, argv + 1, &c);
    if (code >= 0)
        return code;
    if (GIVEN(&c, OPT_BACK) || GIVEN(&c, OPT_THICKNESS) || GIVEN(&c, OPT_ABSORPTION) ||
        ((cmd->bit == CMD_EVAL || cmd->bit == CMD_POLAR) && GIVEN(&c, OPT_LIGHT)))
        return cmd_pane(&c, cmd->bit, prov); /* a pane's system (tools/cmd_pane.c) */
    switch (cmd->bit) {
    case CMD_EVAL: return cmd_eval(&c);
    case CMD_TABULATE: return cmd_tabulate(&c, prov);
    case CMD_ALBEDO: return cmd_albedo(&c);
    case CMD_POLAR: return cmd_polar(&c);
    case CMD_BUILD: return cmd_build(&c);
    default: return cmd_inspect(&c);
    }
}
