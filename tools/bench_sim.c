/* SPDX-License-Identifier: MIT */
/* bench_sim.c: the Monte Carlo surface: rays per second and first hits (btdf-bench sim,
   simhit). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "btdf.h"
#include "btdf_sim.h"
#include "bench.h"
#include "sim/rng.h"
#include "sim/surface.h"
#include "sim/trace.h"
#if BENCH_EMBREE
#include <embree3/rtcore.h>
#endif

/* The Monte Carlo surface (btdf_sim.h): rays per second on one thread at n = 1.5,
   ti = 30, for the min/max hierarchy and the plain cell DDA on the same rays (both
   find the same hits, so T agrees to the bit), with the hits per ray and the time a
   standard error of 1e-3 on T would take. 2e6 rays: 32 realisations of 62,500 rays,
   so making the surfaces is a small share. CPU seconds of this process, the median of
   REPS runs: the machine may be shared, and one thread's CPU time is what a thread
   costs. */
static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

void bench_sim(FILE *f, int reps)
{
    fprintf(f, "method,s,rays,realisations,cpu_seconds_median,rays_per_s_thread,mean_hits,T,"
               "T_se,seconds_to_T_se_1e-3,tile_mib\n");
    const double ss[] = {0.5, 1, 3, 6, 30};
    double ti = 30.0 * M_PI / 180.0;
    for (int k = 0; k < 5; k++)
        for (int accel = 1; accel >= 0; accel--) {
            btdf_sim_opts o;
            btdf_sim_opts_default(&o);
            o.smoothness = ss[k];
            o.theta_i = &ti;
            o.n_theta = 1;
            o.rays = 2000000;
            o.threads = 1;
            o.accel = accel;
            double cpu[9];
            btdf_sim_result *keep = NULL;
            for (int r = 0; r < reps; r++) {
                btdf_sim_result *res = NULL;
                clock_t c0 = clock();
                if (btdf_sim_run(&o, &res, NULL, 0) != BTDF_OK) {
                    btdf_sim_result_free(keep);
                    return;
                }
                cpu[r] = (double)(clock() - c0) / CLOCKS_PER_SEC;
                btdf_sim_result_free(keep); /* every run gives the same numbers */
                keep = res;
            }
            qsort(cpu, (size_t)reps, sizeof cpu[0], cmp_double);
            double med = reps % 2 ? cpu[reps / 2] : 0.5 * (cpu[reps / 2 - 1] + cpu[reps / 2]);
            const btdf_sim_tally *t = &keep->tally[0];
            double rate = (double)o.rays / (med > 0 ? med : 1e-9); /* clock() may read 0 */
            double need = (double)o.rays * (t->T.se / 1e-3) * (t->T.se / 1e-3);
            fprintf(f, "%s,%g,%llu,%llu,%.3f,%.4g,%.4f,%.5f,%.2g,%.3g,%.2f\n",
                    accel ? "hierarchy" : "plain-dda", ss[k], (unsigned long long)o.rays,
                    (unsigned long long)t->batches, med, rate, t->mean_hits.mean, t->T.mean,
                    t->T.se, need / rate, (double)keep->surface.tile_bytes / 1048576.0);
            fflush(f);
            btdf_sim_result_free(keep);
        }
}

/* First hits on one surface: the traversal alone, the plain DDA and the min/max
   hierarchy of src/sim/trace.c against Embree (when the benchmark was built with it),
   on the same rays: from the top of the slab at a uniform point of the tile, ti = 30,
   uniform azimuth, to the bottom of the slab. Embree gets the same triangles (two per
   cell, the same diagonal) in the same units (grid cells across, sigma up) as a mesh of
   the periodic tile with a margin the rays cannot cross, in 32-bit floats (its only
   vertex format), so its hit parameters differ from the double ones in the last
   float digits: the rows give the largest relative difference of t and the rays where
   one finds a hit and the other not. CPU seconds of the query loop, the median of REPS;
   the BVH build is timed apart. */
#define HIT_RAYS 1000000
void bench_simhit(FILE *f, int reps)
{
    fprintf(f, "method,s,rays,cpu_seconds_median,hits_per_s_thread,hit_fraction,"
               "max_rel_dt_vs_dda,disagreements,build_seconds\n");
    const double ss[] = {0.5, 1, 3, 6, 30};
    const double ti = 30.0 * M_PI / 180.0;
    for (int k = 0; k < 5; k++) {
        int n = 256;
        double tau = ss[k], dx = tau / 16.0;
        sim_gen *g = sim_gen_new(n, dx, tau);
        sim_scratch *w = g ? sim_scratch_new(g) : NULL;
        sim_surface surf;
        if (!w || sim_gen_surface(g, w, sim_stream(1, 1, 0), &surf, NULL) != 0) {
            fprintf(stderr, "btdf-bench: out of memory\n");
            sim_scratch_free(w);
            sim_gen_free(g);
            return;
        }
        double *ray = malloc((size_t)HIT_RAYS * 7 * sizeof *ray); /* o, d, tmax */
        double *tref = malloc((size_t)HIT_RAYS * sizeof *tref);
        if (!ray || !tref) {
            free(ray);
            free(tref);
            sim_surface_free(&surf);
            sim_scratch_free(w);
            sim_gen_free(g);
            return;
        }
        uint64_t rng = sim_stream(1, 2, (uint64_t)k);
        for (int r = 0; r < HIT_RAYS; r++) {
            double p = 2.0 * M_PI * sim_uniform(&rng), *q = ray + (size_t)r * 7;
            q[0] = sim_uniform(&rng) * n;
            q[1] = sim_uniform(&rng) * n;
            q[2] = surf.hmax;
            q[3] = -sin(ti) * cos(p) / dx;
            q[4] = -sin(ti) * sin(p) / dx;
            q[5] = -cos(ti);
            q[6] = (surf.hmin - surf.hmax) / q[5]; /* to the slab's bottom; q[5] < 0 */
        }
        for (int accel = 0; accel <= 1; accel++) {
            double cpu[9];
            long hits = 0;
            for (int rep = 0; rep < reps; rep++) {
                clock_t c0 = clock();
                hits = 0;
                for (int r = 0; r < HIT_RAYS; r++) {
                    const double *q = ray + (size_t)r * 7;
                    double t, nrm[3];
                    int h = sim_first_hit(&surf, q, q + 3, 1, q[6], accel, &t, nrm);
                    hits += h;
                    if (accel == 0)
                        tref[r] = h ? t : -1.0;
                }
                cpu[rep] = (double)(clock() - c0) / CLOCKS_PER_SEC;
            }
            qsort(cpu, (size_t)reps, sizeof cpu[0], cmp_double);
            double med = cpu[reps / 2];
            fprintf(f, "%s,%g,%d,%.3f,%.4g,%.4f,0,0,0\n", accel ? "hierarchy" : "plain-dda",
                    ss[k], HIT_RAYS, med, HIT_RAYS / (med > 0 ? med : 1e-9),
                    (double)hits / HIT_RAYS);
            fflush(f);
        }
#if BENCH_EMBREE
        {
            /* the margin: a ray crosses at most (hmax - hmin) tan(ti) / dx cells */
            int m = (int)ceil((surf.hmax - surf.hmin) * tan(ti) / dx) + 2, side = n + 2 * m;
            clock_t b0 = clock();
            RTCDevice dev = rtcNewDevice("threads=1");
            RTCScene sc = rtcNewScene(dev);
            RTCGeometry geo = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
            float *v = rtcSetNewGeometryBuffer(geo, RTC_BUFFER_TYPE_VERTEX, 0,
                                               RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                               (size_t)(side + 1) * (size_t)(side + 1));
            unsigned *ix = rtcSetNewGeometryBuffer(geo, RTC_BUFFER_TYPE_INDEX, 0,
                                                   RTC_FORMAT_UINT3, 3 * sizeof(unsigned),
                                                   2 * (size_t)side * (size_t)side);
            for (int j = 0; j <= side; j++)
                for (int i = 0; i <= side; i++) {
                    size_t q = (size_t)j * (size_t)(side + 1) + (size_t)i;
                    int ii = ((i - m) % n + n) % n, jj = ((j - m) % n + n) % n;
                    v[3 * q] = (float)(i - m);
                    v[3 * q + 1] = (float)(j - m);
                    v[3 * q + 2] = (float)surf.h[(size_t)jj * (size_t)n + (size_t)ii];
                }
            for (int j = 0; j < side; j++)
                for (int i = 0; i < side; i++) {
                    unsigned a = (unsigned)(j * (side + 1) + i), b = a + 1;
                    unsigned c = a + (unsigned)(side + 1), d = c + 1;
                    unsigned *t = ix + 6 * ((size_t)j * (size_t)side + (size_t)i);
                    t[0] = a; t[1] = b; t[2] = d; /* (0,0) (1,0) (1,1) */
                    t[3] = a; t[4] = d; t[5] = c; /* (0,0) (1,1) (0,1) */
                }
            rtcCommitGeometry(geo);
            rtcAttachGeometry(sc, geo);
            rtcReleaseGeometry(geo);
            rtcSetSceneBuildQuality(sc, RTC_BUILD_QUALITY_HIGH);
            rtcCommitScene(sc);
            double build = (double)(clock() - b0) / CLOCKS_PER_SEC;
            double cpu[9], maxrel = 0.0;
            long hits = 0, dis = 0;
            for (int rep = 0; rep < reps; rep++) {
                struct RTCIntersectContext ctx;
                rtcInitIntersectContext(&ctx);
                clock_t c0 = clock();
                hits = dis = 0;
                maxrel = 0.0;
                for (int r = 0; r < HIT_RAYS; r++) {
                    const double *q = ray + (size_t)r * 7;
                    struct RTCRayHit rh;
                    rh.ray.org_x = (float)q[0];
                    rh.ray.org_y = (float)q[1];
                    rh.ray.org_z = (float)q[2];
                    rh.ray.dir_x = (float)q[3];
                    rh.ray.dir_y = (float)q[4];
                    rh.ray.dir_z = (float)q[5];
                    rh.ray.tnear = 0.0f;
                    rh.ray.tfar = (float)q[6];
                    rh.ray.mask = ~0u;
                    rh.ray.flags = 0;
                    rh.ray.time = 0.0f;
                    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
                    rtcIntersect1(sc, &ctx, &rh);
                    int h = rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
                    hits += h;
                    if (h != (tref[r] >= 0.0))
                        dis++;
                    else if (h) {
                        double rel = fabs((double)rh.ray.tfar - tref[r]) / tref[r];
                        maxrel = rel > maxrel ? rel : maxrel;
                    }
                }
                cpu[rep] = (double)(clock() - c0) / CLOCKS_PER_SEC;
            }
            qsort(cpu, (size_t)reps, sizeof cpu[0], cmp_double);
            double med = cpu[reps / 2];
            fprintf(f, "embree,%g,%d,%.3f,%.4g,%.4f,%.2g,%ld,%.3f\n", ss[k], HIT_RAYS, med,
                    HIT_RAYS / (med > 0 ? med : 1e-9), (double)hits / HIT_RAYS, maxrel, dis,
                    build);
            fflush(f);
            rtcReleaseScene(sc);
            rtcReleaseDevice(dev);
        }
#endif
        free(ray);
        free(tref);
        sim_surface_free(&surf);
        sim_scratch_free(w);
        sim_gen_free(g);
    }
}
