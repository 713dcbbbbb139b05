/* Reference C loops for `gnibench bench`: kepler-2d, state (p1, p2, q1, q2), H = |p|^2/2 - 1/|q|.
 *
 * Each method performs the floating-point operations of the generated numba kernel in the same
 * order (build with -ffp-contract=off), so the final states agree with it to round-off:
 *   rk4      classical RK4, 4 evaluations of the field per step (methods/explicit_rk.py);
 *   sv       Stormer-Verlet [HLW] (1.17) as symplectic Euler(h/2) then its adjoint(h/2), two
 *            force evaluations per step, no FSAL (methods/partitioned.py);
 *   sv-fsal  the same map, reusing the last force of a step as the first of the next (for
 *            information: one force evaluation per step).
 *
 * usage: kepler METHOD NSTEPS H P1 P2 Q1 Q2 REPEATS
 * prints "ns_min ns_median" (ns/step over REPEATS runs), then the final state, one value a line.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* the force part of the field: F(q) = -q / |q|^3, written as problems/codegen.py writes it */
#define FORCE(q1, q2, f1, f2)                          \
    do {                                               \
        double r2_ = (q1) * (q1) + (q2) * (q2);        \
        double t0_ = 1.0 / (r2_ * sqrt(r2_));          \
        f1 = -t0_ * (q1);                              \
        f2 = -t0_ * (q2);                              \
    } while (0)

static void rk4(double y[4], double h, long n) {
    const double w0 = 0.16666666666666666, w1 = 0.3333333333333333;
    double p1 = y[0], p2 = y[1], q1 = y[2], q2 = y[3];
    for (long i = 0; i < n; i++) {
        double a1, a2, b1, b2, c1, c2, d1, d2;         /* k_j = (force, velocity) */
        FORCE(q1, q2, a1, a2);                         /* k0 = (a, p) */
        double P1 = p1 + h * (0.5 * a1), P2 = p2 + h * (0.5 * a2);
        double Q1 = q1 + h * (0.5 * p1), Q2 = q2 + h * (0.5 * p2);
        FORCE(Q1, Q2, b1, b2);                         /* k1 = (b, P) */
        double R1 = p1 + h * (0.5 * b1), R2 = p2 + h * (0.5 * b2);
        double S1 = q1 + h * (0.5 * P1), S2 = q2 + h * (0.5 * P2);
        FORCE(S1, S2, c1, c2);                         /* k2 = (c, R) */
        double T1 = p1 + h * (1.0 * c1), T2 = p2 + h * (1.0 * c2);
        double U1 = q1 + h * (1.0 * R1), U2 = q2 + h * (1.0 * R2);
        FORCE(U1, U2, d1, d2);                         /* k3 = (d, T) */
        double np1 = p1 + h * (w0 * a1 + w1 * b1 + w1 * c1 + w0 * d1);
        double np2 = p2 + h * (w0 * a2 + w1 * b2 + w1 * c2 + w0 * d2);
        double nq1 = q1 + h * (w0 * p1 + w1 * P1 + w1 * R1 + w0 * T1);
        double nq2 = q2 + h * (w0 * p2 + w1 * P2 + w1 * R2 + w0 * T2);
        p1 = np1; p2 = np2; q1 = nq1; q2 = nq2;
    }
    y[0] = p1; y[1] = p2; y[2] = q1; y[3] = q2;
}

static void sv(double y[4], double h, long n) {
    const double hh = 0.5 * h;
    double p1 = y[0], p2 = y[1], q1 = y[2], q2 = y[3], f1, f2;
    for (long i = 0; i < n; i++) {
        FORCE(q1, q2, f1, f2);                         /* symplectic Euler, h/2 */
        p1 = p1 + hh * f1; p2 = p2 + hh * f2;
        q1 = q1 + hh * p1; q2 = q2 + hh * p2;
        q1 = q1 + hh * p1; q2 = q2 + hh * p2;          /* adjoint, h/2 */
        FORCE(q1, q2, f1, f2);
        p1 = p1 + hh * f1; p2 = p2 + hh * f2;
    }
    y[0] = p1; y[1] = p2; y[2] = q1; y[3] = q2;
}

static void sv_fsal(double y[4], double h, long n) {
    const double hh = 0.5 * h;
    double p1 = y[0], p2 = y[1], q1 = y[2], q2 = y[3], f1, f2;
    FORCE(q1, q2, f1, f2);
    for (long i = 0; i < n; i++) {
        p1 = p1 + hh * f1; p2 = p2 + hh * f2;
        q1 = q1 + hh * p1; q2 = q2 + hh * p2;
        q1 = q1 + hh * p1; q2 = q2 + hh * p2;
        FORCE(q1, q2, f1, f2);
        p1 = p1 + hh * f1; p2 = p2 + hh * f2;
    }
    y[0] = p1; y[1] = p2; y[2] = q1; y[3] = q2;
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
        fprintf(stderr, "usage: kepler rk4|sv|sv-fsal NSTEPS H P1 P2 Q1 Q2 REPEATS\n");
        return 2;
    }
    void (*run)(double *, double, long) = !strcmp(argv[1], "rk4") ? rk4
                                        : !strcmp(argv[1], "sv") ? sv
                                        : !strcmp(argv[1], "sv-fsal") ? sv_fsal : NULL;
    if (!run) {
        fprintf(stderr, "kepler: unknown method %s\n", argv[1]);
        return 2;
    }
    long n = atol(argv[2]);
    double h = atof(argv[3]), y0[4], y[4];
    int reps = atoi(argv[8]);
    if (n < 1 || reps < 1 || reps > 100) return 2;
    for (int i = 0; i < 4; i++) y0[i] = strtod(argv[4 + i], NULL);
    double t[100];
    for (int r = 0; r < reps; r++) {
        memcpy(y, y0, sizeof y);
        double t0 = now();
        run(y, h, n);
        t[r] = (now() - t0) / n;
    }
    qsort(t, reps, sizeof t[0], cmp);
    printf("%.4f %.4f\n", t[0], t[reps / 2]);
    for (int i = 0; i < 4; i++) printf("%.17g\n", y[i]);
    return 0;
}
