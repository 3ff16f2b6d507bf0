/* SPDX-License-Identifier: MIT */
/* kernel.h: the Eq. 25 kernel shared by the evaluator, the tables and the estimates. */
#ifndef BTDF_MODEL_IMPL_H
#define BTDF_MODEL_IMPL_H

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "btdf.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* exp(-x) is 0 in double for x beyond about 745.1, so cutting there changes no
   result; it lets the kernel skip dividing by v_z^2, which may be 0 (MODEL.md 3.5). */
#define BTDF_EXP_CUT 746.0

/* Shadowing V(t) of Eq. 25 from tan t >= 0 and 1/tan^2 t precomputed by the caller.
   V(0) = 1 (MODEL.md 3.4); V(pi/2) = 0. */
static inline double shadow_v(double tan_t, double s, double k0)
{
    if (!(tan_t > 0.0))
        return 1.0; /* t = 0: exp(-s^2/(4 tan^2)) -> 0, so V -> exp(0) */
    if (isinf(tan_t))
        return 0.0; /* grazing: k0 tan/s -> inf, V -> 0 (and avoids inf * 0) */
    double e = exp(-s * s / (4.0 * tan_t * tan_t));
    return exp(-(k0 * tan_t / s) * e);
}

/* Incoming-side quantities that depend on ti only: hoisted out of the inner loop. */
typedef struct rho_in {
    double sin_ti, cos_ti;
    double pref; /* s^2/(4 pi) * V(ti) / cos ti, 0 when cos ti = 0 (xu-sun); without
                    V(ti) for smith, whose G2 goes to the outgoing side whole */
    btdf_model model; /* which shadowing-masking (rho_in_init: xu-sun) */
    double lam;       /* smith: Lambda(ti) */
} rho_in;

/* Outgoing-side quantities that depend on to only. */
typedef struct rho_out {
    double sin_to, cos_to; /* cos_to <= 0 */
    double pref;           /* V(to) / |cos to|, 0 when cos to = 0 */
} rho_out;

static inline void rho_in_init(rho_in *a, double sin_ti, double cos_ti, double s, double k0)
{
    a->sin_ti = sin_ti;
    a->cos_ti = cos_ti;
    a->model = BTDF_MODEL_XU_SUN;
    a->lam = 0.0;
    /* cos ti = 0 is grazing incidence, where rho -> 0 (MODEL.md 3.5): no 1/0. */
    a->pref = cos_ti > 0.0 ? s * s / (4.0 * M_PI) * shadow_v(sin_ti / cos_ti, s, k0) / cos_ti
                           : 0.0;
}

static inline void rho_out_init(rho_out *b, double sin_to, double cos_to, double s, double k0)
{
    b->sin_to = sin_to;
    b->cos_to = cos_to;
    double c = -cos_to;
    /* |cos to| = 0 is a grazing exit, where rho -> 0 (MODEL.md 3.5): no 1/0. */
    b->pref = c > 0.0 ? shadow_v(sin_to / c, s, k0) / c : 0.0;
}

/* The model's outgoing factors of the facet-space evaluators: every place where the
   models differ goes through one of the two switches below (and rho_in_init_m), so a
   model slots in by adding a case to each. The Smith forms are defined further down. */
static inline double bt_lambda_f(double sn, double cs, double s);
static inline double bt_smith_t_factor(double li, double lo);
static inline double bt_smith_r_factor(double li, double lr);

/* rho_in_init in the model m: for smith the incoming prefactor drops V(ti) and keeps
   Lambda(ti) for the outgoing side (G2 does not factor). */
static inline void rho_in_init_m(rho_in *a, double sin_ti, double cos_ti, double s, double k0,
                                 btdf_model m)
{
    switch (m) {
    case BTDF_MODEL_SMITH:
    case BTDF_MODEL_FULL: /* its single scattering; tables add the rest (table.h) */
        a->sin_ti = sin_ti;
        a->cos_ti = cos_ti;
        a->pref = cos_ti > 0.0 ? s * s / (4.0 * M_PI) / cos_ti : 0.0; /* grazing: rho = 0 */
        a->model = BTDF_MODEL_SMITH;
        a->lam = bt_lambda_f(sin_ti, cos_ti > 0.0 ? cos_ti : 0.0, s);
        return;
    default: /* xu-sun (callers have refused the rest) */
        rho_in_init(a, sin_ti, cos_ti, s, k0);
        return;
    }
}

/* The outgoing shadowing of a transmission to the direction (sin to, |cos to| > 0):
   V(to) for xu-sun, G2 = B(1 + Lambda(ti), 1 + Lambda(to)) for smith. */
static inline double rho_out_shadow(const rho_in *a, double sin_to, double abs_cos_to,
                                    double s, double k0)
{
    switch (a->model) {
    case BTDF_MODEL_SMITH:
        return bt_smith_t_factor(a->lam, bt_lambda_f(sin_to, abs_cos_to, s));
    default:
        return shadow_v(sin_to / abs_cos_to, s, k0);
    }
}

/* The same for a reflection to (sin tr, cos tr > 0): V(tr), or 1/(1 + Lambda(ti) +
   Lambda(tr)) for smith. */
static inline double rho_out_shadow_r(const rho_in *a, double sin_tr, double cos_tr,
                                      double s, double k0)
{
    switch (a->model) {
    case BTDF_MODEL_SMITH:
        return bt_smith_r_factor(a->lam, bt_lambda_f(sin_tr, cos_tr, s));
    default:
        return shadow_v(sin_tr / cos_tr, s, k0);
    }
}

/* rho_out_init with the outgoing factor of a's model. */
static inline void rho_out_init_m(rho_out *b, double sin_to, double cos_to, double s,
                                  double k0, const rho_in *a)
{
    if (a->model == BTDF_MODEL_XU_SUN) {
        rho_out_init(b, sin_to, cos_to, s, k0); /* the bits of every xu-sun output */
        return;
    }
    b->sin_to = sin_to;
    b->cos_to = cos_to;
    double c = -cos_to;
    /* |cos to| = 0 is a grazing exit, where rho -> 0 (MODEL.md 3.5): no 1/0. */
    b->pref = c > 0.0 ? rho_out_shadow(a, sin_to, c, s, k0) / c : 0.0;
}

/* Eq. 25 (MODEL.md section 2) for one channel, from hoisted incoming and outgoing
   terms and v = e_i + n e_o with e_i.v and e_o.v; rho_kernel below computes those
   from (cos phi, sin phi). The tables' kernel: it returns early where no facet
   connects the directions, so its loops are scalar; bt_rho below is the branch-free,
   vectorised form of the public entry points, accurate near n = 1 as well.
   With v = e_i + n e_o, the facet normal is h = sg v/|v| with sg = sign(v_z), and
     cos a = sg (e_i.v)/|v|,  cos b = -sg (e_o.v)/|v|,  cos tn = |v_z|/|v|,
     (n cos b - cos a)^2 = |v|^2 exactly,  so chi = n^2 cos b / |v|^2,
     1/cos^2 tn = 1 + tan^2 tn = |v|^2 / v_z^2,
     Ft = 2 n ca cb (1/(ca + n cb)^2 + 1/(n ca + cb)^2)   (1 - R without cancellation). */
static inline double rho_kernel_v(double n, double s, const rho_in *a, const rho_out *b,
                                  double vx, double vy, double vz, double ei_v, double eo_v)
{
    double rxy2 = vx * vx + vy * vy;
    double vz2 = vz * vz;
    double len2 = rxy2 + vz2;
    /* The exponent s^2 tan^2 tn / 4 written without dividing by vz2, which may be 0
       (a facet standing vertical): cut when the exponential underflows. */
    if (!(0.25 * s * s * rxy2 < BTDF_EXP_CUT * vz2))
        return 0.0;
    double sg = vz < 0.0 ? -1.0 : 1.0; /* h = sg v / |v| has h_z > 0 */
    double ca_l = sg * ei_v;  /* cos a * |v| */
    double cb_l = -sg * eo_v; /* cos b * |v| */
    if (!(ca_l > 0.0 && cb_l > 0.0))
        return 0.0; /* no facet refracts e_i into e_o (MODEL.md 2, 3.7) */
    /* len2 >= (1 - n)^2 > 0 for n != 1 (validated), and vz2 > 0 after the cut. */
    double inv_len = 1.0 / sqrt(len2);
    double ca = ca_l * inv_len, cb = cb_l * inv_len;
    double t2 = rxy2 / vz2;        /* tan^2 tn, finite after the cut */
    double sec2 = len2 / vz2;      /* 1 / cos^2 tn */
    double d1 = ca + n * cb, d2 = n * ca + cb; /* both > 0 since ca, cb > 0 */
    double ft = 2.0 * n * ca * cb * (1.0 / (d1 * d1) + 1.0 / (d2 * d2));
    double chi = n * n * cb / len2;
    double r = a->pref * b->pref * ca * ft * chi * sec2 * sec2 * exp(-0.25 * s * s * t2);
    /* Results below the smallest normal double are 0 (MODEL.md 3.6). */
    return r >= DBL_MIN ? r : 0.0;
}

static inline double rho_kernel(double n, double s, const rho_in *a, const rho_out *b,
                                double cos_phi, double sin_phi)
{
    double vx = a->sin_ti + n * b->sin_to * cos_phi;
    double vy = n * b->sin_to * sin_phi;
    double vz = a->cos_ti + n * b->cos_to;
    double ei_v = a->sin_ti * vx + a->cos_ti * vz; /* e_i . v */
    double eo_v = b->sin_to * (cos_phi * vx + sin_phi * vy) + b->cos_to * vz;
    return rho_kernel_v(n, s, a, b, vx, vy, vz, ei_v, eo_v);
}

/* Refraction of e_i = (sin ti, 0, cos ti) through the facet with normal
   h = (sin tn cos psi, sin tn sin psi, cos tn): e_o = -e_i/n + (cos a/n - cos b) h.
   1 with the two cosines and e_o when the facet refracts e_i into the lower
   hemisphere; 0 when it faces away (cos a <= 0), reflects totally (sin a >= n), or
   sends the ray back up (e_o,z >= 0). */
typedef struct facet_ray {
    double ca, cb, ox, oy, oz;
} facet_ray;

static inline int facet_refract(double n, double sti, double cti, double stn, double ctn,
                                double cpsi, double spsi, facet_ray *r)
{
    double ca = stn * cpsi * sti + ctn * cti;
    if (!(ca > 0.0))
        return 0; /* the facet faces away from e_i */
    double sb2 = (1.0 - ca * ca) / (n * n);
    if (!(sb2 < 1.0))
        return 0; /* total internal reflection on this facet */
    double cb = sqrt(1.0 - sb2);
    if (!(cb > 0.0))
        return 0; /* grazing on the facet: no transmitted direction */
    double g = ca / n - cb;
    r->ca = ca;
    r->cb = cb;
    r->ox = -sti / n + g * stn * cpsi;
    r->oy = g * stn * spsi;
    r->oz = -cti / n + g * ctn;
    return r->oz < 0.0; /* refracted back into the upper hemisphere otherwise */
}


/* ------------------------------------------------------------------------- */
/* The accurate evaluator: double precision, branch-free, the same bits in   */
/* scalar calls and in vectorised loops                                      */
/* ------------------------------------------------------------------------- */

/* Near n = 1 the half vector v = e_i + n e_o is a difference of nearly equal unit
   vectors (1e-4 of them at n = 1.0001), and the Beckmann exponent, up to 745, multiplies
   its relative error. So v is never formed as e_i + n e_o: with d = n - 1 (exact for n
   in [0.5, 2]) it is w + d e_o, where w = e_i + e_o comes from half-angle products
   of the exact differences ti + to - pi and pi - |phi|, accurate to a few ulps of |w|
   itself; e_i.v and e_o.v come from |w|^2. Every step then carries an error of a few
   ulps of |v|, so the exponent is accurate to about sqrt(745) ulps whatever n is.
   The elementary functions below are plain polynomials (Taylor series, truncated
   below 0.05 ulp on their reduced ranges), so the compiler can vectorise loops that
   call them and a loop gives the same bits as single calls. */

#define BT_PI_HI 0x1.921fb54442d18p+1
#define BT_PI_LO 0x1.1a62633145c07p-53
#define BT_PIO2_HI 0x1.921fb54442d18p+0
#define BT_PIO2_LO 0x1.1a62633145c07p-54
#define BT_DEG 0x1.1df46a2529d39p-6 /* pi / 180 */
#define BT_SHIFT 0x1.8p52          /* adding it rounds |x| < 2^51 to an integer */

/* The vectoriser needs the whole evaluation inlined into its loop. */
#if defined(__GNUC__)
#define BT_INLINE static inline __attribute__((always_inline))
#else
#define BT_INLINE static inline
#endif

/* Loops over many evaluations are compiled for AVX-512 and AVX2 too, chosen at run
   time. No FMA is enabled and C99 mode keeps contraction off, so every version
   rounds the same operations the same way: the same bits on every machine. */
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__linux__)
#define BT_CLONES __attribute__((target_clones("avx512f", "avx2", "default")))
#else
#define BT_CLONES
#endif

/* bits of x as an unsigned integer and back (memcpy: defined in C99, free after -O) */
BT_INLINE uint64_t bt_bits(double x)
{
    uint64_t u;
    memcpy(&u, &x, sizeof u);
    return u;
}

BT_INLINE double bt_from_bits(uint64_t u)
{
    double x;
    memcpy(&x, &u, sizeof x);
    return x;
}

/* 2^k for an integer-valued k in [-1022, 1023]. */
BT_INLINE double bt_pow2i(double k)
{
    uint64_t ki = bt_bits(k + BT_SHIFT) - bt_bits(BT_SHIFT); /* k, two's complement */
    return bt_from_bits((ki + 1023u) << 52);
}

/* f e^x for x <= 0 and |f| < 2^600, rounded once at the end, so that a result in the
   normal range keeps full precision even where e^x alone is subnormal. NaN or x below
   -1400 count as -1400, where f e^x is far below the smallest double. */
BT_INLINE double bt_exp_mul(double x, double f)
{
    x = x > -1400.0 ? x : -1400.0;
    x = x < 0.0 ? x : 0.0;
    double k = (x * 0x1.71547652b82fep+0 + BT_SHIFT) - BT_SHIFT; /* round(x / ln 2) */
    /* ln 2 in two parts; the first has 21 trailing zero bits, so k * hi is exact */
    double r = (x - k * 0x1.62e42fee00000p-1) - k * 0x1.a39ef35793c76p-33; /* |r| <= 0.347 */
    /* Taylor series to r^13 (truncation below 4e-18), in Estrin's scheme: short
       dependency chains for scalar calls, the same operations in vector lanes. */
    double r2 = r * r, r4 = r2 * r2, r8 = r4 * r4;
    double a0 = 1.0 + r, a1 = 0.5 + r * 0.16666666666666666;
    double a2 = 0.041666666666666664 + r * 0.008333333333333333;
    double a3 = 0.001388888888888889 + r * 0.0001984126984126984;
    double a4 = 2.48015873015873e-05 + r * 2.7557319223985893e-06;
    double a5 = 2.755731922398589e-07 + r * 2.505210838544172e-08;
    double a6 = 2.08767569878681e-09 + r * 1.6059043836821613e-10;
    double p = ((a0 + a1 * r2) + (a2 + a3 * r2) * r4) + ((a4 + a5 * r2) + a6 * r4) * r8;
    /* k >= -2020: two factors of at least 2^-1010 each, both normal */
    double k1 = (0.5 * k + BT_SHIFT) - BT_SHIFT;
    return f * p * bt_pow2i(k1) * bt_pow2i(k - k1);
}

/* ------------------------------------------------------------------------- */
/* Smith's shadowing-masking of the same Beckmann surface (docs/model.md 10)   */
/* ------------------------------------------------------------------------- */

/* Natural logarithm of a positive normal double, branch-free: x = 2^e m with m in
   [sqrt(1/2), sqrt(2)), log m = 2 atanh(f), f = (m - 1)/(m + 1), |f| <= 0.1716, by its
   Taylor series to f^23 (truncation below 1e-18 relative). The exponent is read as
   a double from the bits (no integer conversion, so the loops stay vectors). */
BT_INLINE double bt_log(double x)
{
    uint64_t u = bt_bits(x);
    /* the biased exponent as a double: 2^52 + field, minus 2^52 (exact) */
    double e = bt_from_bits((u >> 52) | 0x4330000000000000u) - 0x1p52 - 1023.0;
    double m = bt_from_bits((u & 0x000fffffffffffffu) | 0x3ff0000000000000u); /* [1, 2) */
    int big = m > 1.4142135623730951;
    m = big ? 0.5 * m : m; /* exact */
    e = big ? e + 1.0 : e;
    double f = (m - 1.0) / (m + 1.0); /* m - 1 exact (Sterbenz); m + 1 >= 1.7 */
    double f2 = f * f, f4 = f2 * f2, f8 = f4 * f4;
    double p = ((1.0 + f2 * (1.0 / 3)) + (0.2 + f2 * (1.0 / 7)) * f4) +
               (((1.0 / 9) + f2 * (1.0 / 11)) + ((1.0 / 13) + f2 * (1.0 / 15)) * f4) * f8 +
               (((1.0 / 17) + f2 * (1.0 / 19)) + ((1.0 / 21) + f2 * (1.0 / 23)) * f4) *
                   (f8 * f8);
    /* ln 2 in two parts: e * hi is exact for |e| < 2^21 */
    return e * 0x1.62e42fee00000p-1 + (2.0 * f * p + e * 0x1.a39ef35793c76p-33);
}

/* log(1 + z) for z >= 0 without losing z's digits when z is small: the rounding of
   w = 1 + z is put back to first order, (z - (w - 1)) / w (w >= 1: no 1/0). */
BT_INLINE double bt_log1p(double z)
{
    double w = 1.0 + z;
    return bt_log(w) + (z - (w - 1.0)) / w;
}

/* Smith's Lambda of the Beckmann distribution with alpha = 2/s (MODEL.md 2: D has
   alpha^2 = 4/s^2) for the direction of polar angle t, from sin t >= 0, cos t >= 0:
     Lambda = (erf(a) - 1)/2 + exp(-a^2)/(2 a sqrt(pi)) = exp(-a^2) P(a) / (2 a sqrt(pi)),
     a = 1/(alpha |tan t|) = s cos t / (2 sin t),  P(a) = 1 - a sqrt(pi) erfcx(a),
   written with erfcx so that the two terms' cancellation never happens in double.
   P(a) (1 + sqrt(pi) a + 2 a^2) is a degree-19 polynomial in z = (u - 0.7)/0.3,
   u = 1/(1 + a/4), on a in [0, 6] (Chebyshev interpolation of the 40-digit function,
   relative error 5.6e-17; 4e-16 evaluated in double); beyond 6 the asymptotic series
   P = (1/(2a^2))(1 - 3/(2a^2) + 15/(4a^4) - 105/(8a^6)) (relative 4e-5 at a = 6, where
   Lambda < 2e-19, so below one ulp of the 1 + Lambda it enters). */
BT_INLINE double bt_lambda(double sn, double cs, double s)
{
    /* t = 0 (sin t = 0): a = inf and Lambda = 0; the floor keeps a finite (at most
       5e305 for s <= 1e6), and exp(-a^2) underflows to exactly 0 */
    double a = 0.5 * s * cs / (sn > 1e-300 ? sn : 1e-300);
    /* t = 90 deg (cos t = 0): Lambda ~ 1/(2 a sqrt(pi)) grows without bound; the floor
       keeps it finite (below 3e149), and the caller's 1/cos t factor is 0 there */
    a = a > 1e-150 ? a : 1e-150;
    a = a < 1e100 ? a : 1e100; /* a^2 stays finite; exp(-a^2) is 0 long before */
    double ap = a < 6.0 ? a : 6.0;
    double u = 1.0 / (1.0 + 0.25 * ap);
    double z = (u - 0.7) * (1.0 / 0.3);
    double z2 = z * z, z4 = z2 * z2, z8 = z4 * z4, z16 = z8 * z8;
    double q = (((1.1867676924093455 + z * -0.023618146227367517) +
                 (-0.17886306605641428 + z * -0.10234086534320358) * z2) +
                ((0.0044565090145065149 + z * 0.047190216554424874) +
                 (0.039330353917093844 + z * 0.019367418592606416) * z2) * z4) +
               (((0.0063572500040774442 + z * 0.0013011407413532545) +
                 (9.1554866108988373e-05 + z * -3.1673794627486539e-05) * z2) +
                ((-8.91187115683128e-06 + z * 1.3020483812005169e-07) +
                 (3.8981032682771344e-07 + z * 2.3894428621003025e-08) * z2) * z4) * z8 +
               ((-1.5779711270640086e-08 + z * -1.5679996926558987e-09) +
                (5.7079271508319384e-10 + z * 6.0577447299708143e-11) * z2) * z16;
    double pp = q / (1.0 + 1.7724538509055160 * ap + 2.0 * ap * ap); /* divisor >= 1 */
    double ia2 = 1.0 / (a * a); /* a >= 1e-150: a^2 >= 1e-300, no 1/0 */
    double pt = 0.5 * ia2 * (1.0 - ia2 * (1.5 - ia2 * (3.75 - 13.125 * ia2)));
    double P = a < 6.0 ? pp : pt;
    /* P / (2 sqrt(pi) a) <= 2.9e149 < 2^600, as bt_exp_mul requires */
    return bt_exp_mul(-(a * a), P * (0.28209479177387814 / a));
}

/* Stirling's correction lnGamma(w) - ((w - 1/2) ln w - w + ln(2 pi)/2) for w >= 10,
   by its series to w^-15 (the first term left out is below 2e-18 at w = 10). */
BT_INLINE double bt_stirling_tail(double r) /* r = 1/w */
{
    double r2 = r * r, r4 = r2 * r2, r8 = r4 * r4;
    double p = ((1.0 / 12 + r2 * (-1.0 / 360)) + (1.0 / 1260 + r2 * (-1.0 / 1680)) * r4) +
               ((1.0 / 1188 + r2 * (-691.0 / 360360)) + (1.0 / 156 + r2 * (-3617.0 / 122400)) *
                                                            r4) * r8;
    return r * p;
}

/* -ln B(1 + x, 1 + y) for x, y >= 0: the exponent of the height-correlated Smith term of
   transmission, G2 = B(1 + Lambda_i, 1 + Lambda_o) = Gamma(1+x) Gamma(1+y) / Gamma(2+x+y)
   (Heitz 2014, eq. 99). Branch-free and stable for large arguments: with x the larger,
   lnGamma(2 + x + y) - lnGamma(1 + x) is formed as one difference of Stirling series,
     lnG(w + d) - lnG(w) = (w - 1/2) log1p(d/w) + d ln(w + d) - d + tail(w + d) - tail(w),
   w = 1 + x, d = 1 + y, so the two ~x ln x terms never cancel in double (x reaches
   1e16 at grazing angles). Arguments below 10 are first shifted up by 9
   (lnGamma(z) = lnGamma(z + 9) - ln(z (z+1) ... (z+8))); the three products of the shift
   stay below 1e13 and go into one logarithm. Exactly 0 at x = y = 0 (B(1, 1) = 1). */
BT_INLINE double bt_smith_t_exponent(double li, double lo)
{
    double x = li > lo ? li : lo, y = li > lo ? lo : li;
    int mx = x < 9.0, my = y < 9.0;
    double px = 1.0, pxy = 1.0, py = 1.0;
    for (int k = 0; k < 9; k++) {
        px *= mx ? 1.0 + x + k : 1.0;
        pxy *= mx ? 2.0 + x + y + k : 1.0;
        py *= my ? 1.0 + y + k : 1.0;
    }
    double w = 1.0 + x + (mx ? 9.0 : 0.0), d = 1.0 + y;
    double wy = 1.0 + y + (my ? 9.0 : 0.0);
    double rw = 1.0 / w, rwd = 1.0 / (w + d), rwy = 1.0 / wy; /* all >= 10: no 1/0 */
    double dxy = (w - 0.5) * bt_log1p(d * rw) + d * bt_log(w + d) - d +
                 (bt_stirling_tail(rwd) - bt_stirling_tail(rw));
    double gy = (wy - 0.5) * bt_log(wy) - wy + 0.91893853320467274 + bt_stirling_tail(rwy);
    double sh = dxy - gy + bt_log(px * py / pxy); /* pxy >= 1 */
    sh = sh > 0.0 ? sh : 0.0; /* -ln B >= 0 for x, y >= 0: a rounding below it is 0 */
    return x > 0.0 ? sh : 0.0; /* no shadowing at all: B(1, 1) = 1 exactly */
}

/* ln(1 + Lambda_i + Lambda_r): the exponent of the height-correlated Smith term of
   reflection, G2 = 1/(1 + Lambda_i + Lambda_r) (Walter et al. 2007, Heitz 2014). */
BT_INLINE double bt_smith_r_exponent(double li, double lr)
{
    return bt_log1p(li + lr);
}

/* The forms the facet-space evaluators above declared: Lambda, and the two G2. */
static inline double bt_lambda_f(double sn, double cs, double s) { return bt_lambda(sn, cs, s); }
static inline double bt_smith_t_factor(double li, double lo)
{
    return bt_exp_mul(-bt_smith_t_exponent(li, lo), 1.0);
}
static inline double bt_smith_r_factor(double li, double lr)
{
    return bt_exp_mul(-bt_smith_r_exponent(li, lr), 1.0);
}

/* sin and cos of y in [-pi/4, pi/4]; swapped when swap is set (the caller reduced
   its angle x to y = pi/2 - x). */
BT_INLINE void bt_sincos_red(double y, int swap, double *s, double *c)
{
    double y2 = y * y;
    /* Taylor series to y^17 and y^16 (truncation below 0.05 ulp for |y| <= pi/4),
       Estrin's scheme in y^2 */
    double y4 = y2 * y2, y8 = y4 * y4;
    double ps = ((-0.16666666666666666 + y2 * 0.008333333333333333) +
                 (-0.0001984126984126984 + y2 * 2.7557319223985893e-06) * y4) +
                ((-2.505210838544172e-08 + y2 * 1.6059043836821613e-10) +
                 (-7.647163731819816e-13 + y2 * 2.8114572543455206e-15) * y4) * y8;
    double pc = ((-0.5 + y2 * 0.041666666666666664) +
                 (-0.001388888888888889 + y2 * 2.48015873015873e-05) * y4) +
                ((-2.755731922398589e-07 + y2 * 2.08767569878681e-09) +
                 (-1.1470745597729725e-11 + y2 * 4.779477332387385e-14) * y4) * y8;
    double sy = y + y * y2 * ps;
    double cy = 1.0 + y2 * pc;
    *s = swap ? cy : sy;
    *c = swap ? sy : cy;
}

/* sin and cos of x in radians, x in [-pi/4, pi/2 + 1e-15]: relative accuracy near
   0 and near pi/2 alike (pi/2 - x is formed exactly). */
BT_INLINE void bt_sincos_rad(double x, double *s, double *c)
{
    int swap = x > 0.78539816339744828;
    double y = swap ? (BT_PIO2_HI - x) + BT_PIO2_LO : x;
    bt_sincos_red(y, swap, s, c);
}

/* The same with x in degrees, x in [-45, 90]: exact at 0 and 90. */
BT_INLINE void bt_sincos_deg(double x, double *s, double *c)
{
    int swap = x > 45.0;
    double y = (swap ? 90.0 - x : x) * BT_DEG;
    bt_sincos_red(y, swap, s, c);
}

/* The exponent of the shadowing, V(t) = e^-a with a = (k0 tan t / s) e^{-s^2/(4 tan^2 t)},
   from sin t >= 0 and cos t. Kept as an exponent so that V(ti) V(to) and the Beckmann
   factor share one exponential. cos t <= 0 (grazing) gives a finite a; the caller's
   1/cos t factor is 0 there (MODEL.md 3.5). */
BT_INLINE double bt_shadow_exponent(double sn, double cs, double s, double k0)
{
    double c = cs > 0.0 ? cs : 1.0; /* no 1/0 on the discarded branch */
    double t = sn / c;
    double t2 = t * t;
    /* t = 0 is V = 1 (MODEL.md 3.4): the floor keeps s^2/(4 t^2) finite, and
       e^-(huge) = 0 */
    double q = 0.25 * s * s / (t2 > 1e-300 ? t2 : 1e-300);
    return (k0 * t / s) * bt_exp_mul(-q, 1.0);
}

/* 1/cos t, 0 for cos t <= 0. */
BT_INLINE double bt_inv_cos(double cs)
{
    return cs > 0.0 ? 1.0 / (cs > 0.0 ? cs : 1.0) : 0.0;
}

/* The (ti, to) part of rho: sines and cosines, w = e_i + e_o without its azimuth
   term, and the shadowing prefactors. Channel-independent. */
typedef struct bt_io {
    double sti, cti;   /* sin ti, cos ti >= 0 */
    double sto;        /* sin to >= 0 */
    double cto;        /* |cos to| >= 0 */
    double wx0;        /* sin ti - sin to */
    double wz;         /* cos ti - |cos to| */
    double pref;       /* s^2/(4 pi) / (cos ti |cos to|), 0 at grazing (bt_io_pref) */
    double sh;         /* shadowing exponent: V(ti) V(to) = e^-sh */
} bt_io;

/* From sin/cos of ti and of b = pi - to, and sin/cos of p and sin m with
   p = (ti + b)/2, m = (ti - b)/2 = (ti + to - pi)/2 accurate to its own ulps. */
BT_INLINE void bt_io_set(bt_io *io, double sti, double cti, double sto, double cto,
                         double sp, double cp, double sm)
{
    io->sti = sti;
    io->cti = cti;
    io->sto = sto;
    io->cto = cto;
    io->wx0 = 2.0 * cp * sm; /* sin ti - sin b */
    io->wz = -2.0 * sp * sm; /* cos ti - cos b */
    io->pref = 0.0;
    io->sh = 0.0;
}

/* The shadowing prefactor, apart: a caller may skip it where no facet connects. */
BT_INLINE void bt_io_pref(bt_io *io, double s, double k0)
{
    io->pref = s * s / (4.0 * M_PI) * bt_inv_cos(io->cti) * bt_inv_cos(io->cto);
    io->sh = bt_shadow_exponent(io->sti, io->cti, s, k0) +
             bt_shadow_exponent(io->sto, io->cto, s, k0);
}

/* The same prefactor with the Smith term of the same surface (BTDF_MODEL_SMITH):
   V(ti) V(to) = e^-sh becomes G2 = B(1 + Lambda(ti), 1 + Lambda(to)) = e^-sh, Lambda of
   the lower direction from |tan to| (sto, cto >= 0), so that swapping the two sides
   swaps the two Lambdas and the symmetric B keeps the reciprocity of MODEL.md 4. */
BT_INLINE void bt_io_pref_smith(bt_io *io, double s)
{
    io->pref = s * s / (4.0 * M_PI) * bt_inv_cos(io->cti) * bt_inv_cos(io->cto);
    io->sh = bt_smith_t_exponent(bt_lambda(io->sti, io->cti, s), bt_lambda(io->sto, io->cto, s));
}

/* sin and cos of four reduced arguments at once (the lanes of one vector where the
   target has them): lane by lane the operations of bt_sincos_red. */
BT_INLINE void bt_sincos_red4(const double y[4], const int swap[4], double sn[4],
                              double cs[4])
{
    for (int k = 0; k < 4; k++)
        bt_sincos_red(y[k], swap[k], &sn[k], &cs[k]);
}

/* From the sines and cosines of ti, b = pi - to, p and m (lanes 0 to 3). */
BT_INLINE void bt_io_from4(bt_io *io, const double sn[4], const double cs[4])
{
    double cti = cs[0], sto = sn[1], cto = cs[1];
    bt_io_set(io, sn[0], cti > 0.0 ? cti : 0.0, sto > 0.0 ? sto : 0.0,
              cto > 0.0 ? cto : 0.0, sn[2], cs[2], sn[3]);
}

/* Radians: ti in [0, pi/2], to in [pi/2, pi] (a few ulps beyond are clamped). */
BT_INLINE void bt_io_geom_rad(bt_io *io, double ti, double to)
{
    double b = (BT_PI_HI - to) + BT_PI_LO; /* exact difference: to >= pi/2 */
    b = b > 0.0 ? b : 0.0;
    /* ti + to - pi to a few ulps of itself: the sum's rounding error is kept (Knuth's
       two-sum) and pi is subtracted in two parts; the first step is exact because
       ti + to lies in [pi/2, 3 pi/2] (Sterbenz). |m| <= pi/4. */
    double sum = ti + to, bb = sum - ti, lo = (ti - (sum - bb)) + (to - bb);
    double m = 0.5 * (((sum - BT_PI_HI) + lo) - BT_PI_LO);
    double x[4] = {ti, b, ti - m, m}, y[4], sn[4], cs[4];
    int sw[4];
    for (int k = 0; k < 4; k++) { /* as bt_sincos_rad */
        sw[k] = x[k] > 0.78539816339744828;
        y[k] = sw[k] ? (BT_PIO2_HI - x[k]) + BT_PIO2_LO : x[k];
    }
    bt_sincos_red4(y, sw, sn, cs);
    bt_io_from4(io, sn, cs);
}

BT_INLINE void bt_io_rad(bt_io *io, double ti, double to, double s, double k0)
{
    bt_io_geom_rad(io, ti, to);
    bt_io_pref(io, s, k0);
}

/* Degrees: ti in [0, 90], to in [90, 180]; exact at multiples of 90. */
BT_INLINE void bt_io_geom_deg(bt_io *io, double ti, double to)
{
    double sum = ti + to, bb = sum - ti, lo = (ti - (sum - bb)) + (to - bb);
    double md = 0.5 * ((sum - 180.0) + lo); /* (ti + to - 180) / 2, Sterbenz as above */
    double x[3] = {ti, 180.0 - to, ti - md}, y[4], sn[4], cs[4]; /* 180 - to: exact */
    int sw[4];
    for (int k = 0; k < 3; k++) { /* as bt_sincos_deg */
        sw[k] = x[k] > 45.0;
        y[k] = (sw[k] ? 90.0 - x[k] : x[k]) * BT_DEG;
    }
    sw[3] = 0;
    y[3] = md * BT_DEG;
    bt_sincos_red4(y, sw, sn, cs);
    bt_io_from4(io, sn, cs);
}

/* The azimuth part: h2 = sin^2(c/2) and sphi = sin c = |sin phi|, where c = pi - |phi|
   (folded to [0, pi]) is the angle from the forward plane: 1 + cos phi = 2 h2. */
typedef struct bt_az {
    double h2, sphi;
} bt_az;

BT_INLINE void bt_az_half(bt_az *az, double sh, double ch)
{
    az->h2 = sh * sh;
    az->sphi = 2.0 * sh * ch;
}

/* Folds any finite phi (radians) to c = |pi - (|phi| mod 2 pi)| in [0, pi], exactly
   where it matters (near the forward plane). */
BT_INLINE double bt_fold_rad(double phi)
{
    double x = fabs(phi);
    if (x > 2.0 * BT_PI_HI)
        x = fmod(x, 2.0 * BT_PI_HI); /* beyond one turn: modulo the double nearest 2 pi */
    double c = (x - BT_PI_HI) - BT_PI_LO;
    return fabs(c);
}

BT_INLINE double bt_fold_deg(double phi)
{
    double x = fabs(phi);
    if (x >= 360.0)
        x = fmod(x, 360.0); /* exact */
    return fabs(x - 180.0);
}

BT_INLINE void bt_az_rad(bt_az *az, double c)
{
    double sh, ch;
    bt_sincos_rad(0.5 * c, &sh, &ch);
    bt_az_half(az, sh, ch);
}

BT_INLINE void bt_az_deg(bt_az *az, double cdeg)
{
    double sh, ch;
    bt_sincos_deg(0.5 * cdeg, &sh, &ch);
    bt_az_half(az, sh, ch);
}

/* Eq. 25 for index n = 1 + d from the parts above; branch-free (MODEL.md section 2,
   the algebra in the comment of rho_kernel_v). 0 where no facet connects the two
   directions, and below the smallest normal double. */
/* The geometry of v = w + d e_o shared by bt_rho and bt_rho_one. */
#define BT_RHO_GEOMETRY                                                                 \
    double cph = 2.0 * h2 - 1.0;                                                        \
    double wx = io->wx0 + io->sto * (2.0 * h2); /* sin ti + sin to cos phi */         \
    double wy = io->sto * sphi;                                                         \
    double wz = io->wz;                                                                 \
    double w2 = wx * wx + wy * wy + wz * wz; /* |e_i + e_o|^2 = 2 + 2 e_i.e_o */       \
    double vx = wx + d * io->sto * cph;                                                 \
    double vy = n * wy;                                                                 \
    double vz = wz - d * io->cto;                                                       \
    double ei_v = n * (0.5 * w2) - d; /* 1 + n e_i.e_o */                              \
    double eo_v = d + 0.5 * w2;       /* e_i.e_o + n */                                \
    double rxy2 = vx * vx + vy * vy, vz2 = vz * vz, len2 = rxy2 + vz2;                  \
    double sg = vz < 0.0 ? -1.0 : 1.0;                                                  \
    double ca_l = sg * ei_v, cb_l = -sg * eo_v;                                         \
    double e = 0.25 * s * s * rxy2;                                                     \
    /* cut where exp underflows (this also keeps v_z = 0 out, MODEL.md 3.5), and where \
       no facet refracts e_i into e_o (MODEL.md 2, 3.7); & rather than &&: no branch */ \
    int ok = (ca_l > 0.0) & (cb_l > 0.0) & (e < BTDF_EXP_CUT * vz2)

/* The value from BT_RHO_GEOMETRY's quantities and the prefactor pref. */
#define BT_RHO_VALUE(pref)                                                              \
    /* On the discarded branch every divisor is replaced by 1: no 1/0, no NaN. */      \
    vz2 = ok ? vz2 : 1.0;                                                               \
    len2 = ok ? len2 : 1.0;                                                             \
    ca_l = ok ? ca_l : 1.0;                                                             \
    cb_l = ok ? cb_l : 1.0;                                                             \
    double inv_len = 1.0 / sqrt(len2); /* len2 >= d^2 > 0 */                            \
    double inv_vz2 = 1.0 / vz2;                                                         \
    double ca = ca_l * inv_len, cb = cb_l * inv_len;                                    \
    double sec2 = len2 * inv_vz2;                                                       \
    double d1 = ca + n * cb, d2 = n * ca + cb; /* > 0 */                                \
    double q1 = d1 * d1, q2 = d2 * d2;                                                  \
    double ft = 2.0 * n * ca * cb * ((q1 + q2) / (q1 * q2));                            \
    double chi = n * n * cb * (inv_len * inv_len);                                      \
    double r = bt_exp_mul(-(e * inv_vz2 + io->sh), (pref) * ca * ft * chi * (sec2 * sec2)); \
    r = (ok & (r >= DBL_MIN)) ? r : 0.0

/* Eq. 25 for index n = 1 + d from the parts above; branch-free (MODEL.md section 2,
   the algebra in the comment of rho_kernel_v). 0 where no facet connects the two
   directions, and below the smallest normal double. */
BT_INLINE double bt_rho(double n, double d, double s, const bt_io *io, double h2,
                        double sphi)
{
    BT_RHO_GEOMETRY;
    BT_RHO_VALUE(io->pref);
    return r;
}

/* The same for one evaluation: the shadowing prefactor (four exponentials) is only
   formed where some facet connects the directions; the same operations, the same
   bits. */
BT_INLINE double bt_rho_one(double n, double d, double s, double k0, bt_io *io, double h2,
                            double sphi)
{
    BT_RHO_GEOMETRY;
    if (!ok)
        return 0.0;
    bt_io_pref(io, s, k0);
    BT_RHO_VALUE(io->pref);
    return r;
}

/* bt_rho_one with the Smith term (bt_io_pref_smith): the same operations otherwise. */
BT_INLINE double bt_rho_one_smith(double n, double d, double s, bt_io *io, double h2,
                                  double sphi)
{
    BT_RHO_GEOMETRY;
    if (!ok)
        return 0.0;
    bt_io_pref_smith(io, s);
    BT_RHO_VALUE(io->pref);
    return r;
}

/* The reflection of the same facets (MODEL.md section 8): the (ti, tr) part, with
   u = e_i + e_r, tr in [0, pi/2]. */
typedef struct bt_ir {
    double str;  /* sin tr */
    double ux0;  /* sin ti - sin tr = 2 cos p sin m, p = (ti + tr)/2, m = (ti - tr)/2 */
    double uz;   /* cos ti + cos tr = 2 cos p cos m */
    double pref; /* s^2/(16 pi) / (cos ti cos tr), 0 at grazing */
    double sh;   /* shadowing exponent: V(ti) V(tr) = e^-sh */
} bt_ir;

BT_INLINE void bt_ir_set(bt_ir *ir, double sti, double cti, double str, double ctr,
                         double cp, double sm, double cm, double s, double k0)
{
    ir->str = str;
    ir->ux0 = 2.0 * cp * sm;
    ir->uz = 2.0 * cp * cm;
    ir->pref = s * s / (16.0 * M_PI) * bt_inv_cos(cti) * bt_inv_cos(ctr);
    ir->sh = bt_shadow_exponent(sti, cti, s, k0) + bt_shadow_exponent(str, ctr, s, k0);
}

/* The Smith term of reflection in place of V(ti) V(tr) (BTDF_MODEL_SMITH):
   e^-sh = 1/(1 + Lambda(ti) + Lambda(tr)); sti, cti, str, ctr >= 0. */
BT_INLINE void bt_ir_smith(bt_ir *ir, double sti, double cti, double str, double ctr,
                           double s)
{
    ir->sh = bt_smith_r_exponent(bt_lambda(sti, cti, s), bt_lambda(str, ctr, s));
}

/* smith: 1 for the Smith term (k0 is then unused). */
BT_INLINE void bt_ir_rad_m(bt_ir *ir, double ti, double tr, double s, double k0, int smith)
{
    double sti, cti, str, ctr, sp, cp, sm, cm;
    bt_sincos_rad(ti, &sti, &cti);
    bt_sincos_rad(tr, &str, &ctr);
    bt_sincos_rad(0.5 * (ti + tr), &sp, &cp);
    bt_sincos_red(0.5 * (ti - tr), 0, &sm, &cm);
    cti = cti > 0.0 ? cti : 0.0;
    ctr = ctr > 0.0 ? ctr : 0.0;
    bt_ir_set(ir, sti, cti, str, ctr, cp, sm, cm, s, k0);
    if (smith)
        bt_ir_smith(ir, sti, cti, str, ctr, s);
}

BT_INLINE void bt_ir_rad(bt_ir *ir, double ti, double tr, double s, double k0)
{
    bt_ir_rad_m(ir, ti, tr, s, k0, 0);
}

BT_INLINE void bt_ir_deg_m(bt_ir *ir, double ti, double tr, double s, double k0, int smith)
{
    double sti, cti, str, ctr, sp, cp, sm, cm;
    bt_sincos_deg(ti, &sti, &cti);
    bt_sincos_deg(tr, &str, &ctr);
    bt_sincos_deg(0.5 * (ti + tr), &sp, &cp);
    bt_sincos_red(0.5 * (ti - tr) * BT_DEG, 0, &sm, &cm);
    bt_ir_set(ir, sti, cti, str, ctr, cp, sm, cm, s, k0);
    if (smith)
        bt_ir_smith(ir, sti, cti, str, ctr, s);
}

BT_INLINE void bt_ir_deg(bt_ir *ir, double ti, double tr, double s, double k0)
{
    bt_ir_deg_m(ir, ti, tr, s, k0, 0);
}

/* Fresnel reflectance of a facet at incidence cosine ca > 0 for n = 1 + d, without
   the cancellation of 1 - Ft: with dd = n^2 - 1 = d (2 + d) and n^2 cos^2 b = dd + ca^2,
     ca - n cb = -dd / (ca + n cb),
     n ca - cb = dd ((n^2 + 1) ca^2 - 1) / (n^2 (n ca + cb)),
   so Rs and Rp keep their relative accuracy when n is near 1. 1 past the critical
   angle (total internal reflection, n < 1). */
BT_INLINE double bt_fresnel_r(double n, double d, double ca)
{
    double dd = d * (2.0 + d);
    double g2 = dd + ca * ca; /* n^2 cos^2 b */
    int tir = !(g2 > 0.0);
    double ncb = sqrt(tir ? 0.0 : g2);
    double s1 = ca + ncb;           /* > 0 for ca > 0 */
    double p1 = n * ca + ncb / n;   /* > 0 */
    double rs = dd / (s1 * s1);
    double rp = dd * ((n * n + 1.0) * ca * ca - 1.0) / (n * n * p1 * p1);
    return tir ? 1.0 : 0.5 * (rs * rs + rp * rp);
}

/* rho_r of MODEL.md section 8; branch-free like bt_rho. h = u/|u|, cos a = |u|/2,
   tan^2 tn = (ux^2 + uy^2)/uz^2, 1/cos^2 tn = |u|^2/uz^2. */
BT_INLINE double bt_rho_r(double n, double d, double s, const bt_ir *ir, double h2,
                              double sphi)
{
    double ux = ir->ux0 + ir->str * (2.0 * h2); /* sin ti + sin tr cos phi */
    double uy = ir->str * sphi;
    double uz = ir->uz;
    double rxy2 = ux * ux + uy * uy, uz2 = uz * uz, u2 = rxy2 + uz2;
    double e = 0.25 * s * s * rxy2;
    /* uz = 0 only when both directions graze (where pref is 0 anyway); the cut also
       drops the underflowing tail */
    int ok = (uz > 0.0) & (e < BTDF_EXP_CUT * uz2);
    uz2 = ok ? uz2 : 1.0;
    u2 = ok ? u2 : 1.0;
    double ca = 0.5 * sqrt(u2);
    double fr = bt_fresnel_r(n, d, ca);
    double sec2 = u2 / uz2;
    double r = bt_exp_mul(-(e / uz2 + ir->sh), ir->pref * fr * (sec2 * sec2));
    return (ok & (r >= DBL_MIN)) ? r : 0.0;
}

/* sin and cos of an angle in degrees, exact at multiples of 90 degrees, for tools
   and tests that speak degrees: reduces to [-45, 45] before converting. */
void btdf_sincos_deg(double deg, double *s, double *c);

/* min over channels of T(ti) from a coarse quadrature (within 2.8e-3 absolute, worst
   near the critical angle for n < 1: btdf_transmittance_coarse). */
double btdf_transmittance_coarse(const btdf_params *p, double ti);

/* T(ti) (refl = 0) or R(ti) (refl = 1) per channel, with the given panels of the
   facet-slope and azimuth quadratures (16 x 12 is btdf_transmittance's converged rule);
   ti in [0, pi/2] and p checked by the caller. */
void bt_albedo_panels(const btdf_params *p, int refl, double ti, int u_panels,
                      int psi_panels, double *out);

/* min over channels of R(ti) from the same coarse quadrature. */
double btdf_reflectance_coarse(const btdf_params *p, double ti);

#endif
