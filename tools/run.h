/* SPDX-License-Identifier: MIT */
/* run.h: work shared by the commands of btdftab (tabulate and build). */
#ifndef BTDFTAB_RUN_H
#define BTDFTAB_RUN_H

#include <pthread.h>
#include <stddef.h>
#include <stdio.h>

#include <btdf/btdf.h>

/* Seed of the reported error estimates; the builders check themselves with others. */
#define REPORT_SEED 20081231u

/* Seconds on a monotonic clock. */
double run_now(void);

/* Opens a JSON report: '{', the program, its version and the command prov (escaped),
   each on its own line, the last followed by ',' and a newline. */
void run_json_open(FILE *f, const char *prov);

/* s as the inside of a JSON string into out (room for 6 strlen(s) + 1): quote and
   backslash escaped, control characters and bytes outside UTF-8 sequences (Latin-1)
   as \u00XX, UTF-8 sequences kept; returns the length written. */
size_t run_json_escape(const char *s, char *out);

/* The words the command line and the manifest share: "enter", "leave", "both" as a
   btdf_side (0 for any other word); "l1", "max" as a metric (0 for any other). */
int run_parse_side(const char *word);
int run_parse_metric(const char *word, btdf_metric *metric);

/* A progress line on standard error for a person watching: what is known (the stage,
   its counts, the time elapsed), a bar only while the stage's total stays fixed and its
   fraction never falls, and a time left only where that is honest (below). Drawn only when `on` (stderr is a terminal and
   not --quiet) and once the run has lasted a second; a ticker thread, started at the
   first update, redraws it 4 times a second (the elapsed time moves even while one
   unit of work runs long); run_progress_end stops the ticker and erases the line, and
   must be called before the run_progress goes out of scope. */
typedef struct run_progress {
    int on, drawn, running, stop;
    char label[96], stage[96];
    double t0, last, frac;
    /* the builder's stage as last reported: its name, total and fraction; a stage whose
       total grew or whose fraction fell is shown as counts only, no bar and no ETA */
    char cb_stage[64];
    size_t cb_total;
    double cb_frac, cb_t0, cb_end, cb_end_prev; /* cb_end: the stage's end as the last two updates
                                      predicted it, when they agreed (else 0) */
    int cb_unsure;
    char cb_grew[4][64]; /* stages whose work grew in this run: counts only from then on */
    pthread_t tid;
    pthread_mutex_t lock;
} run_progress;

void run_progress_start(run_progress *pr, int on, const char *label);
/* A btdf_progress_fn: user is a run_progress. */
void run_progress_cb(void *user, const char *stage, size_t done, size_t todo);
/* A stage of the tool's own (the error estimate, the write), without a fraction. */
void run_progress_stage(run_progress *pr, const char *stage);
void run_progress_end(run_progress *pr);

/* A .bsdf request as the command line and the manifest state it: the light's sides
   (btdf_side, 0: both) and the parts (btdf_part, 0: not given, both) give its blocks
   (btdf_scatfun_block: light from above has T_ENTER and R_TOP, from below T_LEAVE and
   R_BOTTOM). The tolerance: tol when given, else tol (the tables' default) for
   transmission blocks alone and 1e-2 once the file holds reflection. */
int run_series_blocks(int sides, int part);
double run_series_tolerance(int part, int given, double tol);

/* Builds a .bsdf from Eq. 25, reports its error per side on standard error (unless
   quiet) and writes it at path unless the tolerance was missed without best_effort.
   Returns an exit status: 0, 1 failed run, 2 bad parameters, 3 tolerance not met. */
int run_series(const char *prog, const char *path, const btdf_params *p, double tol, int sides,
               int threads, int quiet, int best_effort, const char *prov, run_progress *pr);

/* run_series with a JSON report written at report (NULL: none) and the builder's
   budgets (btdf_scatfun_build_limits: 0 = the format's own). A run that missed its
   tolerance returns 3 also when best_effort wrote the file; a request refused
   before any work (a lobe too narrow for the node budget) returns 3 with no file. */
int run_series_ex(const char *prog, const char *path, const btdf_params *p, double tol,
                  int sides, int threads, int quiet, int best_effort, const char *prov,
                  const char *report, size_t max_coeffs, size_t max_bytes, run_progress *pr);

/* Builds a Radiance BSDF (.xml) from Eq. 25 in the given basis, reports each block's
   error as Radiance reads it on standard error (unless quiet), and writes it (and the
   JSON report with probes, if report is not NULL) together, unless a tree missed its
   tolerance without best_effort. Exit status as run_series. */
int run_radiance(const char *prog, const char *path, const char *report, const btdf_params *p,
                 btdf_rad_basis basis, double tol, int threads, int quiet, int best_effort,
                 const char *prov, run_progress *pr);

/* Peak resident memory of this process so far, in bytes. */
size_t run_peak_rss(void);

/* One output of a table run: the table in a format picked by extension (path "-":
   CSV on standard output), or a picture of it when preview is not NULL (the run fills
   in its table). with_table: also hand the table to the writer, as a manifest's .png
   montage wants. */
typedef struct run_table_out {
    const char *path;
    const btdf_preview_opts *preview;
    int with_table;
} run_table_out;

/* A table run: build, estimate each part, the verdict, and the outputs and report
   written together or not at all. Both `tabulate` and a manifest's tables take it. */
typedef struct run_table_req {
    const char *prog;  /* the messages' prefix: "btdftab", or "btdftab: window (enter)" */
    const char *name;  /* the table's name in the verdict: its file (NULL: "table") */
    btdf_table_opts o; /* the request, with its progress callback (run_progress_cb) */
    int name_parts;    /* the report lines name the part (a request beyond transmission) */
    const run_table_out *outs;
    int nouts;
    const char *report; /* the JSON report's path, or NULL */
    const char *prov;   /* the provenance written into the outputs */
    int quiet, best_effort;
    run_progress *pr;
    int *missed; /* set to 1 when best_effort wrote a table above its tolerance (or NULL) */
} run_table_req;

/* Exit status: 0 (also a missed tolerance written with best_effort), 1 failed run, 2 bad
   parameters, 3 tolerance not met or budget too small, nothing written. */
int run_table(const run_table_req *rq);

#endif
