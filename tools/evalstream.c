/* SPDX-License-Identifier: MIT */
/* evalstream.c: see evalstream.h. */
#include "evalstream.h"

#include <errno.h>
#include <float.h>
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "fastnum.h"

enum { BLOCK = 1 << 20, CHUNKS = 16 };

typedef struct chunk {
    const char *begin, *end; /* whole lines */
    long first_line;         /* number of its first line */
    char *out;
    size_t len, cap;
    long bad_line;           /* 0, or the line that stopped this chunk */
    char msg[160];
    int oom;
} chunk;

typedef struct job {
    const btdf_params *p;
    int reflection;
    chunk c[CHUNKS];
} job;

/* Up to `want` numbers separated by blanks or commas; how many, -1 on junk, -2 on a
   number out of range (a subnormal, as numparse refuses it). The rules of the tool's
   other row readers. */
static int row(const char *s, const char *end, double *v, int want)
{
    int n = 0;
    for (;;) {
        while (s < end && (*s == ' ' || *s == '\t' || *s == ',' || *s == '\r'))
            s++;
        if (s == end || *s == '#')
            return n;
        if (n == want)
            return -1;
        /* Plain decimals only, as tools/numparse reads every other number: no hex,
           no inf or nan, nothing glued to the number. */
        const char *t = s;
        while (t < end && strchr("0123456789+-.eE", *t) != NULL)
            t++;
        char *e;
        double x = fastnum_strtod(s, &e);
        if (e == s || e != t || !isfinite(x))
            return -1;
        if (x != 0.0 && fabs(x) < DBL_MIN)
            return -2;
        v[n++] = x;
        s = e;
    }
}

static const char *angle_error(int reflection, const double *v, char *msg, size_t len)
{
    if (!(v[0] >= 0.0 && v[0] <= 90.0))
        snprintf(msg, len, "theta-i %g: must lie in [0, 90] degrees", v[0]);
    else if (reflection && !(v[1] >= 0.0 && v[1] <= 90.0))
        snprintf(msg, len, "theta-r %g: must lie in [0, 90] degrees (the reflected hemisphere)",
                 v[1]);
    else if (!reflection && !(v[1] >= 90.0 && v[1] <= 180.0))
        snprintf(msg, len,
                 "theta-o %g: must lie in [90, 180] degrees (the transmitted hemisphere)", v[1]);
    else if (!isfinite(v[2]))
        snprintf(msg, len, "phi %g: must be finite", v[2]);
    else
        return NULL;
    return msg;
}

static void run_chunk(job *j, size_t i)
{
    chunk *c = &j->c[i];
    const btdf_params *p = j->p;
    long ln = c->first_line;
    for (const char *s = c->begin; s < c->end; ln++) {
        const char *nl = memchr(s, '\n', (size_t)(c->end - s));
        const char *e = nl ? nl : c->end;
        double v[3];
        int k = row(s, e, v, 3);
        s = nl ? nl + 1 : c->end;
        if (k == 0)
            continue; /* blank or comment line */
        if (k == -2) {
            c->bad_line = ln;
            snprintf(c->msg, sizeof c->msg, "a number is out of range (its magnitude is below "
                                            "2.2e-308, the smallest normal double)");
            return;
        }
        if (k != 3) {
            c->bad_line = ln;
            snprintf(c->msg, sizeof c->msg, "expected three angles 'TI %s PHI'",
                     j->reflection ? "TR" : "TO");
            return;
        }
        if (angle_error(j->reflection, v, c->msg, sizeof c->msg)) {
            c->bad_line = ln;
            return;
        }
        if (c->cap - c->len < BTDF_MAX_CHANNELS * 32 + 2) {
            size_t cap = c->cap ? 2 * c->cap : 1 << 16;
            char *o = realloc(c->out, cap);
            if (!o) {
                c->oom = 1;
                return;
            }
            c->out = o;
            c->cap = cap;
        }
        for (int ch = 0; ch < p->channels; ch++) {
            double r = j->reflection
                           ? btdf_rho_r_model_deg(p->model, p->ior[ch], p->smoothness, p->k0,
                                                  v[0], v[1], v[2])
                           : btdf_rho_model_deg(p->model, p->ior[ch], p->smoothness, p->k0,
                                                v[0], v[1], v[2]);
            if (ch)
                c->out[c->len++] = ' ';
            c->len += (size_t)fastnum_g17(r, c->out + c->len);
        }
        c->out[c->len++] = '\n';
    }
}

/* Worker t of nt runs chunks t, t + nt, ...: a fixed share, so no locking. */
typedef struct worker {
    job *j;
    int t, nt;
} worker;

static void *run_worker(void *arg)
{
    worker *w = arg;
    for (int k = w->t; k < CHUNKS; k += w->nt)
        run_chunk(w->j, (size_t)k);
    return NULL;
}

/* The chunks of one block on nt threads (the calling one included); a thread that
   cannot be started leaves its chunks to the calling thread. */
static void run_block(job *j, int nt)
{
    pthread_t tid[CHUNKS];
    worker w[CHUNKS];
    int started[CHUNKS] = {0};
    for (int t = 1; t < nt; t++) {
        w[t].j = j;
        w[t].t = t;
        w[t].nt = nt;
        started[t] = pthread_create(&tid[t], NULL, run_worker, &w[t]) == 0;
    }
    w[0].j = j;
    w[0].t = 0;
    w[0].nt = nt;
    run_worker(&w[0]);
    for (int t = 1; t < nt; t++) {
        if (started[t])
            pthread_join(tid[t], NULL);
        else
            for (int k = t; k < CHUNKS; k += nt)
                run_chunk(j, (size_t)k);
    }
}

int eval_stream(FILE *in, FILE *out, const btdf_params *p, int reflection, int threads,
                char *err, size_t errlen)
{
    char *buf = malloc(BLOCK + 1);
    job *j = calloc(1, sizeof *j);
    int code = 0;
    if (!buf || !j) {
        snprintf(err, errlen, "out of memory");
        free(buf);
        free(j);
        return 1;
    }
    j->p = p;
    j->reflection = reflection;
    long cores = sysconf(_SC_NPROCESSORS_ONLN);
    int nt = threads > 0 ? threads : cores > 0 ? (int)cores : 1;
    if (nt > CHUNKS)
        nt = CHUNKS;
    size_t have = 0;
    long line = 1;
    int eof = 0;
    while (!eof && code == 0) {
        size_t got = fread(buf + have, 1, BLOCK - have, in);
        have += got;
        if (got == 0) {
            if (ferror(in)) {
                snprintf(err, errlen, "standard input: %s", strerror(errno));
                code = 1;
                break;
            }
            eof = 1;
        }
        /* whole lines only, unless the input has ended (a last line without '\n') */
        size_t use = have;
        if (!eof) {
            while (use > 0 && buf[use - 1] != '\n')
                use--;
            if (use == 0) {
                if (have < BLOCK)
                    continue; /* read more of this line */
                snprintf(err, errlen, "line %ld: longer than %d bytes", line, BLOCK);
                code = 2;
                break;
            }
        }
        if (use == 0)
            break;
        buf[have] = 0; /* a number at the very end stops here, whatever reads it */
        /* CHUNKS pieces of about equal size, cut at line ends */
        const char *s = buf, *end = buf + use;
        for (int k = 0; k < CHUNKS; k++) {
            chunk *c = &j->c[k];
            c->len = 0;
            c->bad_line = 0;
            c->oom = 0;
            c->first_line = line;
            c->begin = s;
            const char *e = k == CHUNKS - 1 ? end : buf + use * (size_t)(k + 1) / CHUNKS;
            if (e < s)
                e = s;
            const char *nl = e < end ? memchr(e, '\n', (size_t)(end - e)) : NULL;
            e = nl ? nl + 1 : end;
            c->end = e;
            for (const char *q = s; q < e; q++) /* numbering of the next chunk */
                line += *q == '\n';
            s = e;
        }
        run_block(j, nt);
        for (int k = 0; k < CHUNKS && code == 0; k++) {
            chunk *c = &j->c[k];
            if (c->len && fwrite(c->out, 1, c->len, out) != c->len) {
                snprintf(err, errlen, "standard output: %s", strerror(errno));
                code = 1;
            } else if (c->oom) {
                snprintf(err, errlen, "out of memory");
                code = 1;
            } else if (c->bad_line) {
                snprintf(err, errlen, "line %ld: %s", c->bad_line, c->msg);
                code = 2;
            }
        }
        memmove(buf, buf + use, have - use);
        have -= use;
    }
    for (int k = 0; k < CHUNKS; k++)
        free(j->c[k].out);
    free(j);
    free(buf);
    return code;
}
