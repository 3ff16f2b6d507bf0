/* SPDX-License-Identifier: MIT */
/* fastnum.c: see fastnum.h. */
#include "fastnum.h"

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* 10^k for k in [0, 22]: exact in double. */
static const double P10[23] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                               1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
                               1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};

double fastnum_strtod(const char *s, char **end)
{
    const char *p = s;
    int neg = 0;
    if (*p == '-' || *p == '+')
        neg = *p++ == '-';
    uint64_t m = 0;
    int digits = 0, e10 = 0, any = 0;
    while (*p == '0') { /* leading zeros carry no significant digit */
        p++;
        any = 1;
    }
    while (*p >= '0' && *p <= '9') {
        if (digits == 19)
            return strtod(s, end);
        m = m * 10u + (uint64_t)(*p++ - '0');
        digits += m != 0;
        any = 1;
    }
    if (*p == '.') {
        p++;
        while (*p >= '0' && *p <= '9') {
            if (digits == 19)
                return strtod(s, end);
            m = m * 10u + (uint64_t)(*p++ - '0');
            digits += m != 0;
            e10--;
            any = 1;
        }
    }
    if (!any)
        return strtod(s, end); /* "inf", "nan", hex, or not a number: strtod decides */
    if (*p == 'e' || *p == 'E') {
        const char *q = p + 1;
        int eneg = 0, ev = 0, edig = 0;
        if (*q == '-' || *q == '+')
            eneg = *q++ == '-';
        while (*q >= '0' && *q <= '9') {
            if (ev > 10000)
                return strtod(s, end);
            ev = ev * 10 + (*q++ - '0');
            edig++;
        }
        if (edig) { /* otherwise the 'e' is not part of the number */
            e10 += eneg ? -ev : ev;
            p = q;
        }
    }
    if (*p == 'x' || *p == 'X' || (*p >= 'a' && *p <= 'z') || (*p >= 'A' && *p <= 'Z'))
        return strtod(s, end); /* hex floats, "0x", odd suffixes: strtod's rules */
    /* Exact: m < 2^53 and 10^|e10| exact, so one correctly rounded operation. */
    if (m < (UINT64_C(1) << 53) && e10 >= -22 && e10 <= 22) {
        double v = (double)m;
        v = e10 < 0 ? v / P10[-e10] : v * P10[e10];
        if (end)
            *end = (char *)p;
        return neg ? -v : v;
    }
    return strtod(s, end);
}

/* 10^k in long double for k in [-350, 330], from exact powers below 10^27 and powl. */
static long double pow10l_(int k)
{
    static long double tab[681];
    static int ready;
    if (!ready) { /* filled once; the same values on every call, so no race changes them */
        for (int j = -350; j <= 330; j++) {
            long double v = 1.0L;
            if (j >= 0 && j <= 27) {
                for (int i = 0; i < j; i++)
                    v *= 10.0L; /* exact: 10^27 < 2^91 and 5^27 < 2^64 */
            } else {
                v = powl(10.0L, (long double)j);
            }
            tab[j + 350] = v;
        }
        ready = 1;
    }
    return tab[k + 350];
}

int fastnum_g17(double x, char *buf)
{
#if LDBL_MANT_DIG == 64 && defined(__x86_64__)
    /* The fast path covers normal numbers well inside the range; zeros, subnormals,
       extremes and non-finite values go to printf. */
    double ax = fabs(x);
    if (ax == 0.0) /* the most common value of all: outside the lobe */
        return snprintf(buf, 32, "%s", signbit(x) ? "-0" : "0");
    if (!(ax >= 1e-290 && ax <= 1e290))
        return snprintf(buf, 32, "%.17g", x);
    int e2;
    frexp(ax, &e2);
    int k = (int)floor((e2 - 1) * 0.30102999566398120) - 16; /* 10^16 <= ax/10^k, +-1 */
    long double f = (long double)ax * pow10l_(-k);
    for (int step = 0; step < 2 && !(f >= 1e16L && f < 1e17L); step++) {
        k += f >= 1e17L ? 1 : -1;
        f = (long double)ax * pow10l_(-k);
    }
    /* f is off by the table's error (powl: 0.81 ulp at most over this range with
       glibc 2.36, measured against 60-digit values) and the product's rounding (0.5
       ulp); an ulp of f < 1e17 is at most 2^-7. So f is within 0.011 of the exact
       quotient, and the band below allows 3 ulps of table error. Adding 2^63 rounds f
       to an integer held in the 64-bit significand of the x87 format; where the
       fraction lies within 0.03 of one half, printf decides. */
    long double t = f + 0x1p63L, fr = t - 0x1p63L, frac = f - fr; /* |frac| <= 1/2 */
    if (fabsl(frac) > 0.47L || !(f >= 1e16L && f < 1e17L))
        return snprintf(buf, 32, "%.17g", x);
    uint64_t D;
    memcpy(&D, &t, sizeof D); /* the significand: 2^63 + round(f) */
    D -= UINT64_C(1) << 63;
    if (D >= UINT64_C(100000000000000000)) { /* rounded up to 10^17 */
        D /= 10u;
        k++;
    }
    char dig[17];
    for (int i = 16; i >= 0; i--) {
        dig[i] = (char)('0' + D % 10u);
        D /= 10u;
    }
    int nd = 17;
    while (nd > 1 && dig[nd - 1] == '0')
        nd--; /* %g drops trailing zeros */
    int X = k + 16; /* exponent of the first digit */
    char *o = buf;
    if (x < 0)
        *o++ = '-';
    if (X < -4 || X >= 17) {
        *o++ = dig[0];
        if (nd > 1) {
            *o++ = '.';
            memcpy(o, dig + 1, (size_t)nd - 1);
            o += nd - 1;
        }
        *o++ = 'e';
        *o++ = X < 0 ? '-' : '+';
        int ae = X < 0 ? -X : X;
        if (ae >= 100)
            *o++ = (char)('0' + ae / 100);
        *o++ = (char)('0' + (ae / 10) % 10);
        *o++ = (char)('0' + ae % 10);
    } else if (X >= 0) {
        for (int i = 0; i <= X; i++)
            *o++ = i < nd ? dig[i] : '0';
        if (nd > X + 1) {
            *o++ = '.';
            memcpy(o, dig + X + 1, (size_t)(nd - X - 1));
            o += nd - X - 1;
        }
    } else {
        *o++ = '0';
        *o++ = '.';
        for (int i = 0; i < -X - 1; i++)
            *o++ = '0';
        memcpy(o, dig, (size_t)nd);
        o += nd;
    }
    *o = 0;
    return (int)(o - buf);
#else
    return snprintf(buf, 32, "%.17g", x);
#endif
}
