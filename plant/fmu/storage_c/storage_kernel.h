/* Stratified storage kernel: a line-by-line port of plant/components/storage.py `step`,
 * restricted to one direct inflow and one direct outflow and no coils.
 *
 * Keep this file in step with the Python kernel: same operations in the same order, so the two
 * agree to round-off (tests/fmu/test_storage_fmu.py compares them over a day).  Temperatures are
 * in degC here, exactly as in the Python kernel; the FMI wrapper converts from/to kelvin.
 */
#ifndef COSES_STORAGE_KERNEL_H
#define COSES_STORAGE_KERNEL_H

#include <math.h>

#define ST_CP 4180.0          /* J/(kg K), plant/water.py CP */
#define ST_RHO 1000.0         /* kg/m3, plant/water.py RHO */
#define ST_K_WATER 0.6        /* W/(m K), still-water conductivity for UA_layer < 0 */
#define ST_COURANT_MAX 0.5
#define ST_N_MAX 200

typedef struct {
    double volume, height, UA_loss, T_env, UA_layer; /* m3, m, W/K, degC, W/K */
    int n_layers, limiter;
} StParams;

static double st_ua_layer(const StParams *p, int N) {
    double ua = p->UA_layer;
    if (ua < 0.0) ua = ST_K_WATER * p->volume * N / (p->height * p->height);
    return ua;
}

static double st_limiter(double r, int kind) {
    if (kind == 2) { /* MC */
        double a = 2.0 * r, b = 0.5 * (1.0 + r);
        double m = a < b ? a : b;
        if (m > 2.0) m = 2.0;
        return m > 0.0 ? m : 0.0;
    }
    if (kind == 1) { /* van Leer */
        double ar = fabs(r);
        return (r + ar) / (1.0 + ar);
    }
    if (kind == 3) { /* superbee */
        double a = 2.0 * r;
        if (a > 1.0) a = 1.0;
        double b = r < 2.0 ? r : 2.0;
        double m = a > b ? a : b;
        return m > 0.0 ? m : 0.0;
    }
    return 0.0;
}

/* Same rule as storage.n_substeps for one inflow port and one outflow port, no coils. */
static int st_n_substeps(double dt, const StParams *p, int N,
                         int in_layer, double in_m, int out_layer, double out_m) {
    double mL = ST_RHO * p->volume / N, C = ST_CP * mL, ua = st_ua_layer(p, N), g = 0.0;
    double worst = 0.0, F_above = 0.0;
    for (int k = 0; k < N; k++) {
        double net = 0.0, outk = 0.0;
        if (in_layer == k) net += in_m;
        if (out_layer == k) { net -= out_m; outk += out_m; }
        double F = k < N - 1 ? F_above + net : 0.0;
        if (F > 0.0) outk += F;
        if (F_above < 0.0) outk -= F_above;
        if (outk > worst) worst = outk;
        F_above = F;
    }
    double rate = worst / mL + (2.0 * ua + p->UA_loss / N + g) / C;
    double x = dt * rate / ST_COURANT_MAX;
    int n = (int)ceil(x);
    return n >= 1 ? n : 1;
}

static void st_remove_inversions(double *T, int N) {
    for (int k = 1; k < N; k++) {
        if (T[k] > T[k - 1]) {
            double s = T[k] + T[k - 1];
            int cnt = 2, j = k - 2;
            double mean = 0.5 * s;
            while (j >= 0 && T[j] < mean) {
                s += T[j];
                cnt += 1;
                j -= 1;
                mean = s / cnt;
            }
            for (int i = j + 1; i < k + 1; i++) T[i] = mean;
        }
    }
}

/* Advance T (top first, degC, in place) by dt.  *out_T receives the step-mean outflow
 * temperature; returns the step-mean loss Q_loss [W].  q is scratch of length N. */
static double st_step(double dt, double *T, int N, const StParams *p,
                      int in_layer, double in_m, double in_T, int out_layer, double out_m,
                      double *out_T, double *q) {
    double mL = ST_RHO * p->volume / N, C = ST_CP * mL;
    double ua = st_ua_layer(p, N), uaN = p->UA_loss / N, Tenv = p->T_env;
    int kind = p->limiter;
    int nsub = st_n_substeps(dt, p, N, in_layer, in_m, out_layer, out_m);
    double h = dt / nsub, hm = h / mL, hC = h / C;
    double Q_loss = 0.0;
    *out_T = 0.0;
    for (int s = 0; s < nsub; s++) {
        double sT = 0.0;
        for (int k = 0; k < N; k++) {
            sT += T[k];
            q[k] = -uaN * (T[k] - Tenv);
        }
        Q_loss += uaN * (sT - N * Tenv);
        q[in_layer] += in_m * ST_CP * in_T;
        double Tk = T[out_layer];
        *out_T += Tk;
        q[out_layer] -= out_m * ST_CP * Tk;

        double F = 0.0;
        for (int k = 0; k < N - 1; k++) {
            if (in_layer == k) F += in_m;
            if (out_layer == k) F -= out_m;
            double flux = ua * (T[k] - T[k + 1]);
            if (F > 0.0) {
                double TU = T[k], d = T[k + 1] - TU, Tf = TU;
                if (kind != 0 && k >= 1 && d != 0.0) {
                    double phi = st_limiter((TU - T[k - 1]) / d, kind);
                    Tf = TU + 0.5 * phi * (1.0 - F * hm) * d;
                }
                flux += F * ST_CP * Tf;
            } else if (F < 0.0) {
                double TU = T[k + 1], d = T[k] - TU, Tf = TU;
                if (kind != 0 && k + 2 < N && d != 0.0) {
                    double phi = st_limiter((TU - T[k + 2]) / d, kind);
                    Tf = TU + 0.5 * phi * (1.0 + F * hm) * d;
                }
                flux += F * ST_CP * Tf;
            }
            q[k] -= flux;
            q[k + 1] += flux;
        }
        for (int k = 0; k < N; k++) T[k] += q[k] * hC;
        st_remove_inversions(T, N);
    }
    double inv = 1.0 / nsub;
    *out_T *= inv;
    return Q_loss * inv;
}

/* storage_readings.sensor_temperatures_into: n equally spaced sensors, out[0] = lowest. */
static void st_sensors(const double *T, int N, double *out, int n) {
    for (int i = 0; i < n; i++) {
        double z = (i + 0.5) / n;
        double x = (1.0 - z) * N - 0.5;
        if (x <= 0.0) out[i] = T[0];
        else if (x >= N - 1) out[i] = T[N - 1];
        else {
            int k = (int)x;
            double w = x - k;
            out[i] = (1.0 - w) * T[k] + w * T[k + 1];
        }
    }
}

/* numpy.linspace(top, bottom, N): i * step + start, last point exactly `bottom`. */
static void st_initial(double *T, int N, double top, double bottom) {
    double step = (bottom - top) / (N - 1);
    for (int i = 0; i < N; i++) T[i] = i * step + top;
    T[N - 1] = bottom;
}

#endif
