/* First-order heat lag (a lumped tank losing heat to its surroundings), shared by the FMI 2.0
 * model-exchange and FMI 3.0 co-simulation test FMUs of plant/fmu/build.py:
 *
 *     C dT/dt = 1000 P - UA (T - T_env)        T, T_env in K, P in kW, UA in W/K, C in J/K
 *
 * With P and T_env held constant over a step h the exact solution is
 *     T(t + h) = T_inf + (T(t) - T_inf) exp(-h UA / C),   T_inf = T_env + 1000 P / UA.
 * Value references (both FMUs): 0 time (FMI 3 only), 1 T, 2 der(T), 3 P, 4 T_env, 5 UA, 6 C, 7 T_start.
 */
#ifndef LAG_MODEL_H
#define LAG_MODEL_H
#include <math.h>

#define VR_TIME 0
#define VR_T 1
#define VR_DER_T 2
#define VR_P 3
#define VR_T_ENV 4
#define VR_UA 5
#define VR_C 6
#define VR_T_START 7
#define N_VR 8

typedef struct {
    double v[N_VR];  /* indexed by value reference; v[VR_TIME] = time */
} LagModel;

static void lag_defaults(LagModel *m) {
    for (int i = 0; i < N_VR; i++) m->v[i] = 0.0;
    m->v[VR_UA] = 20.0;
    m->v[VR_C] = 3.35e6;          /* 800 l of water */
    m->v[VR_T_START] = 343.15;    /* 70 degC */
    m->v[VR_T_ENV] = 291.15;      /* 18 degC */
    m->v[VR_T] = m->v[VR_T_START];
}

static double lag_derivative(const LagModel *m) {
    return (1000.0 * m->v[VR_P] - m->v[VR_UA] * (m->v[VR_T] - m->v[VR_T_ENV])) / m->v[VR_C];
}

static void lag_exact_step(LagModel *m, double h) {
    double T_inf = m->v[VR_T_ENV] + 1000.0 * m->v[VR_P] / m->v[VR_UA];
    m->v[VR_T] = T_inf + (m->v[VR_T] - T_inf) * exp(-h * m->v[VR_UA] / m->v[VR_C]);
}

static int lag_writable(unsigned vr, int initialized) {
    /* inputs always; parameters only before initialization ends; T and der(T) never */
    if (vr == VR_P || vr == VR_T_ENV) return 1;
    if (vr == VR_UA || vr == VR_C || vr == VR_T_START) return !initialized;
    return 0;
}
#endif
