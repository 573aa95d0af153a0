/* The rigid pendulum psi'' = -Omega^2 sin psi integrated by DOPRI5 with the same embedded
   error (RMS over atol + rtol max(|y0|, |y1|)) and the same PI step controller as the
   kernel (kernels/impact/runge_kutta.py), for N designs over T rotor radians.

   Two loops: "scalar" (one design after another, libm sin) and "simd" (LANES designs at
   once, each lane with its own step size, accepting or rejecting on its own and retiring
   when it reaches T; the sine is glibc's vector sine, libmvec). Prints the design-steps
   taken (accepted + rejected), the CPU nanoseconds per design-step of each loop (best of
   reps) and a checksum of the final states.

   Usage: rigid_dopri5 N T reps */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#define LANES 8

static const double A21 = 1.0 / 5, A31 = 3.0 / 40, A32 = 9.0 / 40, A41 = 44.0 / 45,
    A42 = -56.0 / 15, A43 = 32.0 / 9, A51 = 19372.0 / 6561, A52 = -25360.0 / 2187,
    A53 = 64448.0 / 6561, A54 = -212.0 / 729, A61 = 9017.0 / 3168, A62 = -355.0 / 33,
    A63 = 46732.0 / 5247, A64 = 49.0 / 176, A65 = -5103.0 / 18656, B1 = 35.0 / 384,
    B3 = 500.0 / 1113, B4 = 125.0 / 192, B5 = -2187.0 / 6784, B6 = 11.0 / 84,
    E1 = 71.0 / 57600, E3 = -71.0 / 16695, E4 = 71.0 / 1920, E5 = -17253.0 / 339200,
    E6 = 22.0 / 525, E7 = -1.0 / 40;
static const double RTOL = 1e-8, ATOL = 1e-10;

static double now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);  /* CPU time: a loaded machine does not count */
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

static double clamp(double x, double lo, double hi) { return x < lo ? lo : (x > hi ? hi : x); }

/* one DOPRI5 step of psi'' = -w2 sin psi: (y0, y1) -> (z0, z1), f1 = psi'' at z, err */
#define DOPRI5_STEP(SIN)                                                                   \
    double k1a = y1, k1b = f;                                                             \
    double k2a = y1 + h * A21 * k1b, k2b = -w2 * SIN(y0 + h * A21 * k1a);                 \
    double k3a = y1 + h * (A31 * k1b + A32 * k2b),                                         \
           k3b = -w2 * SIN(y0 + h * (A31 * k1a + A32 * k2a));                              \
    double k4a = y1 + h * (A41 * k1b + A42 * k2b + A43 * k3b),                             \
           k4b = -w2 * SIN(y0 + h * (A41 * k1a + A42 * k2a + A43 * k3a));                  \
    double k5a = y1 + h * (A51 * k1b + A52 * k2b + A53 * k3b + A54 * k4b),                 \
           k5b = -w2 * SIN(y0 + h * (A51 * k1a + A52 * k2a + A53 * k3a + A54 * k4a));      \
    double k6a = y1 + h * (A61 * k1b + A62 * k2b + A63 * k3b + A64 * k4b + A65 * k5b),     \
           k6b = -w2 * SIN(y0 + h * (A61 * k1a + A62 * k2a + A63 * k3a + A64 * k4a         \
                                     + A65 * k5a));                                        \
    double z0 = y0 + h * (B1 * k1a + B3 * k3a + B4 * k4a + B5 * k5a + B6 * k6a);           \
    double z1 = y1 + h * (B1 * k1b + B3 * k3b + B4 * k4b + B5 * k5b + B6 * k6b);           \
    double k7a = z1, k7b = -w2 * SIN(z0);                                                  \
    double ea = h * (E1 * k1a + E3 * k3a + E4 * k4a + E5 * k5a + E6 * k6a + E7 * k7a);     \
    double eb = h * (E1 * k1b + E3 * k3b + E4 * k4b + E5 * k5b + E6 * k6b + E7 * k7b);     \
    double sa = ATOL + RTOL * fmax(fabs(y0), fabs(z0));                                   \
    double sb = ATOL + RTOL * fmax(fabs(y1), fabs(z1));                                    \
    double err = sqrt(0.5 * ((ea / sa) * (ea / sa) + (eb / sb) * (eb / sb)));

static long scalar(int n, const double *w2s, const double *vs, double T, double *out) {
    long steps = 0;
    for (int i = 0; i < n; i++) {
        double w2 = w2s[i], y0 = 0.0, y1 = vs[i], f = 0.0, t = 0.0, h = 0.01, prev = 1.0;
        int rejected = 0;
        while (t < T) {
            if (t + h > T) h = T - t;
            DOPRI5_STEP(sin)
            steps++;
            if (err <= 1.0) {
                t += h; y0 = z0; y1 = z1; f = k7b;
                double factor = rejected ? fmin(1.0, fmax(0.2, 0.9 * pow(fmax(err, 1e-10), -0.2)))
                    : clamp(0.9 * pow(fmax(err, 1e-10), -0.17) * pow(fmax(prev, 1e-4), 0.04), 0.2, 5.0);
                h *= factor; prev = err; rejected = 0;
            } else {
                h *= fmin(1.0, fmax(0.2, 0.9 * pow(fmax(err, 1e-10), -0.2)));
                rejected = 1;
            }
        }
        out[i] = y0 + y1;
    }
    return steps;
}

static long simd(int n, const double *w2s, const double *vs, double T, double *out) {
    long steps = 0;
    for (int base = 0; base < n; base += LANES) {
        double W2[LANES], Y0[LANES], Y1[LANES], F[LANES], TT[LANES], H[LANES], P[LANES];
        int R[LANES];
        for (int j = 0; j < LANES; j++) {
            int i = base + j < n ? base + j : n - 1;
            W2[j] = w2s[i]; Y0[j] = 0.0; Y1[j] = vs[i]; F[j] = 0.0; TT[j] = 0.0;
            H[j] = 0.01; P[j] = 1.0; R[j] = 0;
        }
        int running = LANES;
        while (running) {
            running = 0;
#pragma omp simd reduction(+ : running, steps)
            for (int j = 0; j < LANES; j++) {
                double w2 = W2[j], y0 = Y0[j], y1 = Y1[j], f = F[j], t = TT[j];
                int live = t < T;
                double h = fmin(H[j], T - t);
                DOPRI5_STEP(sin)
                int accept = live && err <= 1.0;
                double e = fmax(err, 1e-10);
                double shrink = fmin(1.0, fmax(0.2, 0.9 * exp(-0.2 * log(e))));
                double grow = clamp(0.9 * exp(-0.17 * log(e) + 0.04 * log(fmax(P[j], 1e-4))),
                                    0.2, 5.0);
                double factor = accept ? (R[j] ? shrink : grow) : shrink;
                TT[j] = accept ? t + h : t;
                Y0[j] = accept ? z0 : y0;
                Y1[j] = accept ? z1 : y1;
                F[j] = accept ? k7b : f;
                P[j] = accept ? err : P[j];
                R[j] = live ? !accept : R[j];
                H[j] = live ? h * factor : H[j];
                steps += live;
                running += live && (accept ? t + h < T : 1);
            }
        }
        for (int j = 0; j < LANES && base + j < n; j++) out[base + j] = Y0[j] + Y1[j];
    }
    return steps;
}

int main(int argc, char **argv) {
    int n = argc > 1 ? atoi(argv[1]) : 4096;
    double T = argc > 2 ? atof(argv[2]) : 20.0;
    int reps = argc > 3 ? atoi(argv[3]) : 5;
    double *w2 = malloc(n * sizeof(double)), *v = malloc(n * sizeof(double));
    double *out = malloc(n * sizeof(double));
    for (int i = 0; i < n; i++) {  /* the benchmark's designs, as in bench_step.py */
        double x = (i + 0.5) / n;
        w2[i] = 1.0 + 2.0 * x;
        v[i] = (0.3 + 0.6 * fmod(x * 7.0, 1.0)) * 2.0 * sqrt(w2[i]);
    }
    const char *names[2] = {"c_scalar", "c_simd"};
    long (*loops[2])(int, const double *, const double *, double, double *) = {scalar, simd};
    for (int m = 0; m < 2; m++) {
        double best = 1e300;
        long steps = 0;
        for (int r = 0; r < reps; r++) {
            double t0 = now();
            steps = loops[m](n, w2, v, T, out);
            double dt = now() - t0;
            if (dt < best) best = dt;
        }
        double sum = 0.0;
        for (int i = 0; i < n; i++) sum += out[i];
        printf("%s %ld %.6f %.12e\n", names[m], steps, 1e9 * best / steps, sum);
    }
    return 0;
}
