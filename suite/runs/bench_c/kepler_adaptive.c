/* Reference C loop for the adaptive part of `gnibench bench`: an embedded explicit Runge-Kutta
 * pair with Hairer's step-size controller (DOPRI5 / DOP853, HNW I §II.4) on kepler-2d, state
 * (p1, p2, q1, q2), field (-q/|q|^3, p).
 *
 * A straight port of methods/kernels/adaptive.py (integrate_adaptive, initial_step) and of the
 * step_err that methods/embedded_rk.py generates: the same floating-point operations in the same
 * order (zero coefficients skipped, sums left to right; build with -ffp-contract=off), so the
 * accepted/rejected step counts and the final state agree with the numba kernel (bit for bit in
 * practice).
 *
 * The pair is compiled in: suite/bench.py (pair_header) writes a header from the same Pair record
 * the kernel is generated from -- the controller constants S, IORD, EXPO, BETA, SAFE, FAC1, FAC2
 * and step_err(y, h, k0, rtol, atol, y1, knew), the attempted step unrolled with constant
 * coefficients as a hand-written DOPRI5 would be -- as DIR/pair.h, and builds with
 *   gcc -O3 -march=native -ffp-contract=off -fno-math-errno -I DIR kepler_adaptive.c -lm
 * (-march=native: numba compiles for the host CPU too, and -ffp-contract=off still forbids FMA;
 * -fno-math-errno: sqrt/pow without the errno branch, as numba; results are unchanged).
 * FSAL pairs only (the last stage is f(y1)); with LAZY_LAST (DOP853, whose estimate does not
 * use f(y1)) f(y1) is evaluated only once the step is accepted.
 *
 * usage: kepler_adaptive T_END RTOL ATOL P1 P2 Q1 Q2 REPEATS
 * prints "us_min us_median" (microseconds per attempted step, accepted + rejected, over the
 * repeats), then "nacc nrej nfev", then the final state, one value a line.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define N 4

static void field(const double *y, double *k) {
    double r2 = y[2] * y[2] + y[3] * y[3];
    double t0 = 1.0 / (r2 * sqrt(r2));
    k[0] = -t0 * y[2];
    k[1] = -t0 * y[3];
    k[2] = y[0];
    k[3] = y[1];
}

#include "pair.h"   /* S, LAZY_LAST, IORD, EXPO, BETA, SAFE, FAC1, FAC2, step_err: see the header comment */

static double initial_step(const double *y, const double *fy, double hmax, double rtol,
                           double atol) {
    double dnf = 0.0, dny = 0.0, y1[N], f1[N];
    for (int i = 0; i < N; i++) {
        double sk = atol + rtol * fabs(y[i]);
        dnf += (fy[i] / sk) * (fy[i] / sk);
        dny += (y[i] / sk) * (y[i] / sk);
    }
    double h = (dnf <= 1.0e-10 || dny <= 1.0e-10) ? 1.0e-6 : sqrt(dny / dnf) * 0.01;
    h = fmin(h, hmax);
    for (int i = 0; i < N; i++) y1[i] = y[i] + h * fy[i];
    field(y1, f1);
    double der2 = 0.0;
    for (int i = 0; i < N; i++) {
        double sk = atol + rtol * fabs(y[i]);
        der2 += ((f1[i] - fy[i]) / sk) * ((f1[i] - fy[i]) / sk);
    }
    der2 = sqrt(der2) / h;
    double der12 = fmax(fabs(der2), sqrt(dnf));
    double h1 = der12 <= 1.0e-15 ? fmax(1.0e-6, fabs(h) * 1.0e-3) : pow(0.01 / der12, 1.0 / IORD);
    return fmin(fmin(100.0 * fabs(h), h1), hmax);
}

/* the driver of methods/kernels/adaptive.py (h0 = 0: HINIT; hmax = t_end; no sampling) */
static int integrate(double *y, double t_end, double rtol, double atol, long *nacc_o,
                     long *nrej_o, double *nfev_o) {
    double k0[N], k1[N], y1[N], hmax = t_end;
    field(y, k0);
    double nfev = 2.0, h = initial_step(y, k0, hmax, rtol, atol), t = 0.0, facold = 1.0e-4;
    long nacc = 0, nrej = 0;
    int reject = 0, last = 0, status = 0;
    for (;;) {
        if (0.1 * fabs(h) <= fabs(t) * 2.220446049250313e-16 || !(h > 0.0)) { status = 4; break; }
        if (t + 1.01 * h - t_end > 0.0) { h = t_end - t; last = 1; }
        double err = step_err(y, h, k0, rtol, atol, y1, k1);
        nfev += S - 1 - LAZY_LAST;
        double fac11 = pow(err, EXPO);
        double fac = fac11 / pow(facold, BETA);
        fac = fmax(1.0 / FAC2, fmin(1.0 / FAC1, fac / SAFE));
        double hnew = h / fac;
        if (err <= 1.0) {
            facold = fmax(err, 1.0e-4);
            nacc++;
            t = last ? t_end : t + h;
            memcpy(y, y1, sizeof y1);
            if (LAZY_LAST) { field(y, k0); nfev += 1.0; }    /* f(y1) once accepted */
            else memcpy(k0, k1, sizeof k0);                 /* FSAL */
            if (fabs(hnew) > hmax) hnew = hmax;
            if (reject) hnew = fmin(fabs(hnew), fabs(h));
            reject = 0;
            if (last) break;
            h = hnew;
        } else {
            hnew = h / fmin(1.0 / FAC1, fac11 / SAFE);
            reject = 1;
            if (nacc >= 1) nrej++;
            last = 0;
            h = hnew;
        }
    }
    *nacc_o = nacc; *nrej_o = nrej; *nfev_o = nfev;
    return status;
}

static double now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec * 1e9 + ts.tv_nsec;
}

static int cmp(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

int main(int argc, char **argv) {
    if (argc != 9) {
        fprintf(stderr, "usage: kepler_adaptive T_END RTOL ATOL P1 P2 Q1 Q2 REPEATS\n");
        return 2;
    }
    double t_end = strtod(argv[1], NULL), rtol = strtod(argv[2], NULL),
           atol = strtod(argv[3], NULL), y0[N], y[N];
    for (int i = 0; i < N; i++) y0[i] = strtod(argv[4 + i], NULL);
    int reps = atoi(argv[8]);
    if (reps < 1 || reps > 100 || !(t_end > 0.0)) return 2;
    double t[100], nfev = 0.0;
    long nacc = 0, nrej = 0;
    for (int r = 0; r < reps; r++) {
        memcpy(y, y0, sizeof y);
        double t0 = now();
        int status = integrate(y, t_end, rtol, atol, &nacc, &nrej, &nfev);
        t[r] = (now() - t0) / 1e3 / (double)(nacc + nrej);
        if (status) { fprintf(stderr, "step size underflow\n"); return 1; }
    }
    qsort(t, reps, sizeof t[0], cmp);
    printf("%.6f %.6f\n%ld %ld %.0f\n", t[0], t[reps / 2], nacc, nrej, nfev);
    for (int i = 0; i < N; i++) printf("%.17g\n", y[i]);
    return 0;
}
