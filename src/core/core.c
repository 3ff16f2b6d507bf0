/* SPDX-License-Identifier: MIT */
/* core.c: messages, the clock and the thread pool. */
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include <unistd.h>

#include "core/core.h"

btdf_status core_say(btdf_status st, char *msg, size_t msglen, const char *fmt, ...)
{
    if (msg && msglen) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(msg, msglen, fmt, ap);
        va_end(ap);
    }
    return st;
}

const char *core_num(double x, char buf[32])
{
    for (int prec = 1; prec <= 17; prec++) { /* 17 digits read back for every double */
        snprintf(buf, 32, "%.*g", prec, x);
        if (strtod(buf, NULL) == x || x != x)
            break;
    }
    return buf;
}

double core_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int core_thread_count(int requested)
{
    if (requested > 0)
        return requested > 256 ? 256 : requested;
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n < 1 ? 1 : (n > 256 ? 256 : (int)n);
}

typedef struct pool {
    pthread_mutex_t lock;
    size_t next, count;
    void (*fn)(void *ctx, void *ws, size_t i);
    void *ctx;
    void *(*ws_new)(void *ctx);
    void (*ws_free)(void *ws);
    int failed; /* a worker could not allocate its workspace */
} pool;

static void *pool_worker(void *v)
{
    pool *p = v;
    void *ws = p->ws_new ? p->ws_new(p->ctx) : NULL;
    if (p->ws_new && !ws) {
        pthread_mutex_lock(&p->lock);
        p->failed = 1;
        pthread_mutex_unlock(&p->lock);
        return NULL;
    }
    for (;;) {
        pthread_mutex_lock(&p->lock);
        size_t i = p->next < p->count ? p->next++ : p->count;
        pthread_mutex_unlock(&p->lock);
        if (i >= p->count)
            break;
        p->fn(p->ctx, ws, i);
    }
    if (p->ws_free)
        p->ws_free(ws);
    return NULL;
}

int core_parallel_for_ws(int threads, size_t count, void (*fn)(void *ctx, void *ws, size_t i),
                         void *ctx, void *(*ws_new)(void *ctx), void (*ws_free)(void *ws))
{
    pool p;
    p.next = 0;
    p.count = count;
    p.fn = fn;
    p.ctx = ctx;
    p.ws_new = ws_new;
    p.ws_free = ws_free;
    p.failed = 0;
    if (pthread_mutex_init(&p.lock, NULL) != 0)
        return -1;
    int nt = core_thread_count(threads);
    if ((size_t)nt > count)
        nt = count > 0 ? (int)count : 1;
    pthread_t tid[256];
    int started = 0;
    for (int k = 1; k < nt; k++)
        if (pthread_create(&tid[started], NULL, pool_worker, &p) == 0)
            started++; /* fewer threads only slow the loop down */
    pool_worker(&p); /* the calling thread works too */
    for (int k = 0; k < started; k++)
        pthread_join(tid[k], NULL);
    pthread_mutex_destroy(&p.lock);
    /* A worker without a workspace did no items; the others did them all unless
       every worker failed. */
    return p.next < p.count || p.failed ? -1 : 0;
}

typedef struct plain {
    void (*fn)(void *arg, size_t i);
    void *arg;
} plain;

static void plain_fn(void *ctx, void *ws, size_t i)
{
    (void)ws;
    const plain *p = ctx;
    p->fn(p->arg, i);
}

void core_parallel_for(int threads, size_t count, void (*fn)(void *arg, size_t i), void *arg)
{
    plain p = {fn, arg};
    if (core_parallel_for_ws(threads, count, plain_fn, &p, NULL, NULL) != 0)
        for (size_t i = 0; i < count; i++) /* no mutex: run the loop here */
            fn(arg, i);
}
