/* SPDX-License-Identifier: MIT */
/* elemfn.h: the branch-free elementary functions of the accurate evaluator (model/rho.h):
   e^x, log, sin and cos, Smith's Lambda and the shadowing exponent. */
#ifndef BTDF_MODEL_ELEMFN_H
#define BTDF_MODEL_ELEMFN_H

#include <math.h>
#include <stdint.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* exp(-x) is 0 in double for x beyond about 745.1, so cutting there changes no
   result; it lets the kernel skip dividing by v_z^2, which may be 0 (MODEL.md 3.5). */
#define BTDF_EXP_CUT 746.0

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
    int series = a < 6.0;
    double dd = 1.0 + 1.7724538509055160 * ap + 2.0 * ap * ap; /* >= 1 */
    /* one division for both forms: rr = 1/(a dd) below 6, 1/a^3 above; a in
       [1e-150, 1e100] keeps a dd >= 1e-150 and a^3 <= 1e300, so no 1/0 and no inf */
    double rr = 1.0 / (series ? a * dd : a * a * a);
    double ia2 = a * rr; /* 1/a^2 where the asymptotic form uses it (a >= 6) */
    double pa = series ? q * rr /* P / a */
                       : 0.5 * rr * (1.0 - ia2 * (1.5 - ia2 * (3.75 - 13.125 * ia2)));
    /* P / (2 sqrt(pi) a) <= 2.9e149 < 2^600, as bt_exp_mul requires */
    return bt_exp_mul(-(a * a), 0.28209479177387814 * pa);
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

/* c[0] + c[1] t + ... + c[16] t^16 in Estrin's scheme (short dependency chains). */
BT_INLINE double bt_poly16(const double c[17], double t)
{
    double t2 = t * t, t4 = t2 * t2, t8 = t4 * t4;
    double r0 = (c[0] + c[1] * t) + (c[2] + c[3] * t) * t2;
    double r1 = (c[4] + c[5] * t) + (c[6] + c[7] * t) * t2;
    double r2 = (c[8] + c[9] * t) + (c[10] + c[11] * t) * t2;
    double r3 = (c[12] + c[13] * t) + (c[14] + c[15] * t) * t2;
    return ((r0 + r1 * t4) + (r2 + r3 * t4) * t8) + c[16] * (t8 * t8);
}

/* The two series of bt_smith_t_exponent_small, as monomials in t on [-1, 1]:
   (lnGamma(1 + z) + gamma z) / z^2 for z in [0, 1/2], t = 4z - 1, and
   (lnGamma(2 + z) - (1 - gamma) z) / z^2 for z in [0, 1], t = 2z - 1: Chebyshev
   interpolants of degree 16 of the 50-digit functions (analytic on the intervals, the
   nearest singularity at z = -1 and -2: a convergence ratio of 9.9 per degree),
   relative error 6e-17 with the coefficients rounded to double. */
static const double BT_LGAMMA1_Q[17] = {0.7365132768571209, -0.07397802761317189,
    0.010107355622778322, -0.001559181029757405, 0.0002561731273294925,
    -4.3710620452788424e-05, 7.646592774714669e-06, -1.3614713641646265e-06,
    2.4562192159869764e-07, -4.476874896037351e-08, 8.227500659030772e-09,
    -1.52291050182321e-09, 2.8341508370250317e-10, -5.241841462912307e-11,
    9.843683082010727e-12, -2.1900695231749067e-12, 4.146114768698709e-13};
static const double BT_LGAMMA2_Q[17] = {0.29316281169474234, -0.02558101229593262,
    0.0031780909472403193, -0.00045884056869221237, 7.19427819900362e-05,
    -1.1874161437430832e-05, 2.0285598639184464e-06, -3.5511919485849294e-07,
    6.329599641886561e-08, -1.1437370518771048e-08, 2.088972105657327e-09,
    -3.8496151478735105e-10, 7.14157407660682e-11, -1.317938987138669e-11,
    2.4709445286441827e-12, -5.489799466456034e-13, 1.0385044577889636e-13};

/* -ln B(1 + x, 1 + y) for 0 <= y <= x <= 1/2 (both Lambdas at most 1/2: s = 3 up to
   78.4 degrees, s = 1 up to 58.3): with lnGamma(1 + z) = -gamma z + z^2 q1(z) and
   lnGamma(2 + z) = (1 - gamma) z + z^2 q2(z) the linear terms sum to x + y, so
     -ln B = (x + y) + (x + y)^2 q2(x + y) - x^2 q1(x) - y^2 q1(y),
   no division and no logarithm. With q2 <= 0.33, q1 <= 0.83 and x, y <= 1/2 the square
   terms are at most 0.33 (x + y) and 0.42 (x + y), so no cancellation: against 40-digit
   lnGamma on 20,000 pairs (uniform, log-uniform down to 1e-18, near x = 1/2) absolute
   error 2.6e-16 and relative 3.6e-16, where the Stirling form gives 8.5e-15. 0 at 0. */
BT_INLINE double bt_smith_t_exponent_small(double x, double y)
{
    double z = x + y;
    double q2 = bt_poly16(BT_LGAMMA2_Q, 2.0 * z - 1.0);
    double qx = bt_poly16(BT_LGAMMA1_Q, 4.0 * x - 1.0);
    double qy = bt_poly16(BT_LGAMMA1_Q, 4.0 * y - 1.0);
    return z + ((z * z) * q2 - ((x * x) * qx + (y * y) * qy));
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
BT_INLINE double bt_smith_t_exponent_stirling(double li, double lo)
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

/* -ln B(1 + x, 1 + y) for x, y >= 0: the series where both are at most 1/2 (most
   directions; no logarithm or division there), the shifted Stirling form elsewhere. */
BT_INLINE double bt_smith_t_exponent(double li, double lo)
{
    double x = li > lo ? li : lo, y = li > lo ? lo : li;
    return x <= 0.5 ? bt_smith_t_exponent_small(x, y) : bt_smith_t_exponent_stirling(x, y);
}

/* ln(1 + Lambda_i + Lambda_r): the exponent of the height-correlated Smith term of
   reflection, G2 = 1/(1 + Lambda_i + Lambda_r) (Walter et al. 2007, Heitz 2014). */
BT_INLINE double bt_smith_r_exponent(double li, double lr)
{
    return bt_log1p(li + lr);
}

/* The forms the facet-space evaluators of model/kernel.h call: Lambda, and the two G2. */
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

#endif
