/* SPDX-License-Identifier: MIT */
/* core.h: the leaf layer every other folder of src/ may use: messages, the clock, worker
   threads and the random stream of the estimates. Includes nothing else of src/. */
#ifndef BTDF_CORE_H
#define BTDF_CORE_H

#include <stddef.h>
#include <stdint.h>

#include "btdf.h"

#if defined(__GNUC__)
#define CORE_PRINTF(f, a) __attribute__((format(printf, f, a)))
#else
#define CORE_PRINTF(f, a)
#endif

/* msg <- the formatted text (when msg and msglen are set); returns st. The one way the
   library fills a caller's message buffer. */
btdf_status core_say(btdf_status st, char *msg, size_t msglen, const char *fmt, ...)
    CORE_PRINTF(4, 5);

/* x as the shortest %g text that reads back as x (at most 17 digits), in buf; returns buf.
   For messages: "1000.0000001", not "1000", beside a bound it exceeds. */
const char *core_num(double x, char buf[32]);

/* Monotonic wall clock in seconds. */
double core_now(void);

/* Number of worker threads for a request (0 = all cores), at least 1. */
int core_thread_count(int requested);

/* Runs fn(arg, i) for i in [0, count) on up to `threads` threads. Which thread runs
   which i does not change any result: each i writes only its own output. */
void core_parallel_for(int threads, size_t count, void (*fn)(void *arg, size_t i), void *arg);

/* The same with a workspace per thread from ws_new (NULL: none), freed by ws_free.
   Returns 0, or -1 when some items were not run (no mutex, or no workspace could be
   made). */
int core_parallel_for_ws(int threads, size_t count, void (*fn)(void *ctx, void *ws, size_t i),
                         void *ctx, void *(*ws_new)(void *ctx), void (*ws_free)(void *ws));

/* splitmix64: a small, well-mixed generator; the estimates use one stream per test
   angle, so the points do not depend on which thread handles which angle. */
static inline uint64_t core_mix(uint64_t *x)
{
    uint64_t z = (*x += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

/* A uniform double in [0, 1) from the top 53 bits of the next value. */
static inline double core_unif(uint64_t *x)
{
    return (double)(core_mix(x) >> 11) * (1.0 / 9007199254740992.0);
}

#endif
