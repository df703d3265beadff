/* FMI 2.0 co-simulation wrapper of the CoSES stratified storage (storage_kernel.h).
 *
 * Interface (value references as in modelDescription.xml): parameters volume [m3], height [m],
 * n_layers, UA_loss [W/K], T_env [K], UA_layer [W/K], limiter, T_init_top [K], T_init_bottom [K];
 * inputs m_flow [kg/s] (> 0: in at the top, out at the bottom; < 0: the reverse), T_in_top [K],
 * T_in_bottom [K]; outputs T_top, T_bottom, T_out (step-mean outflow temperature) [K], Q_loss [W]
 * (step mean), T_sensor[1..10] [K] (1 = lowest) and T_layer[1..200] [K] (1 = top; entries
 * beyond n_layers repeat the bottom layer so that every declared output is a real temperature).
 * Kelvin is converted to the kernel's degC here and only here.
 */
#include <stdlib.h>
#include <string.h>
#include <stdio.h>
#include <stdarg.h>
#include "fmi2Functions.h"
#include "storage_kernel.h"

#define GUID "{5d1c3b6e-7f0a-4b2e-9c61-c0535e5a0001}"
#define T0 273.15
#define N_SENSORS 10

enum { VR_VOLUME = 0, VR_HEIGHT = 1, VR_N_LAYERS = 2, VR_UA_LOSS = 3, VR_T_ENV = 4, VR_UA_LAYER = 5,
       VR_LIMITER = 6, VR_T_INIT_TOP = 7, VR_T_INIT_BOTTOM = 8,
       VR_M_FLOW = 10, VR_T_IN_TOP = 11, VR_T_IN_BOTTOM = 12,
       VR_T_TOP = 20, VR_T_BOTTOM = 21, VR_Q_LOSS = 22, VR_T_OUT = 23,
       VR_SENSOR0 = 30, VR_LAYER0 = 100 };

typedef enum { S_INSTANTIATED, S_INIT, S_STEP, S_TERMINATED, S_ERROR } State;

typedef struct {
    fmi2CallbackFunctions cb;
    char *name;
    State state;
    StParams p;                       /* T_env in degC */
    double T_env_K, T_init_top_K, T_init_bottom_K;
    double m_flow, T_in_top_K, T_in_bottom_K;
    double T[ST_N_MAX], q[ST_N_MAX], sensors[N_SENSORS];
    double Q_loss, T_out;             /* degC for T_out */
    double time;
} Inst;

static void logf_(Inst *c, fmi2Status st, const char *fmt, ...) {
    char buf[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    if (c && c->cb.logger) c->cb.logger(c->cb.componentEnvironment, c->name, st, "logStatusError", "%s", buf);
}

static fmi2Status fail(Inst *c, const char *fmt, const char *what) {
    logf_(c, fmi2Error, fmt, what);
    return fmi2Error;
}

static void set_defaults(Inst *c) {
    c->p.volume = 0.8; c->p.height = 1.63; c->p.n_layers = 40; c->p.UA_loss = 20.0;
    c->T_env_K = 18.0 + T0; c->p.UA_layer = -1.0; c->p.limiter = 3;
    c->T_init_top_K = 80.0 + T0; c->T_init_bottom_K = 40.0 + T0;
    c->m_flow = 0.0; c->T_in_top_K = 60.0 + T0; c->T_in_bottom_K = 30.0 + T0;
    c->time = 0.0;
}

/* Ports for the current flow direction (same layout the native tests use). */
static void ports(const Inst *c, int *in_layer, double *in_m, double *in_T, int *out_layer, double *out_m) {
    int N = c->p.n_layers;
    if (c->m_flow >= 0.0) {
        *in_layer = 0; *in_m = c->m_flow; *in_T = c->T_in_top_K - T0; *out_layer = N - 1; *out_m = c->m_flow;
    } else {
        *in_layer = N - 1; *in_m = -c->m_flow; *in_T = c->T_in_bottom_K - T0; *out_layer = 0; *out_m = -c->m_flow;
    }
}

static void update_outputs_at_rest(Inst *c) {
    int N = c->p.n_layers, il, ol;
    double im, iT, om, s = 0.0;
    ports(c, &il, &im, &iT, &ol, &om);
    for (int k = 0; k < N; k++) s += c->T[k];
    c->Q_loss = c->p.UA_loss / N * (s - N * c->p.T_env);
    c->T_out = c->T[ol];
}

fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid, fmi2String res,
                              const fmi2CallbackFunctions *cb, fmi2Boolean visible, fmi2Boolean logging) {
    (void)res; (void)visible; (void)logging;
    if (!cb || !cb->logger) return NULL;
    if (type != fmi2CoSimulation || !guid || strcmp(guid, GUID) != 0) {
        cb->logger(cb->componentEnvironment, name, fmi2Error, "logStatusError",
                   "only co-simulation with GUID " GUID " is supported");
        return NULL;
    }
    Inst *c = (Inst *)calloc(1, sizeof(Inst));
    if (!c) return NULL;
    c->cb = *cb;
    c->name = strdup(name ? name : "storage");
    c->state = S_INSTANTIATED;
    set_defaults(c);
    return c;
}

void fmi2FreeInstance(fmi2Component comp) {
    Inst *c = (Inst *)comp;
    if (!c) return;
    free(c->name);
    free(c);
}

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }
fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n, const fmi2String cat[]) {
    (void)c; (void)on; (void)n; (void)cat; return fmi2OK;
}

fmi2Status fmi2SetupExperiment(fmi2Component comp, fmi2Boolean tolDef, fmi2Real tol, fmi2Real start,
                               fmi2Boolean stopDef, fmi2Real stop) {
    (void)tolDef; (void)tol; (void)stopDef; (void)stop;
    ((Inst *)comp)->time = start;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component comp) {
    ((Inst *)comp)->state = S_INIT;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component comp) {
    Inst *c = (Inst *)comp;
    StParams *p = &c->p;
    /* parameters are checked once here, with the ranges of storage.Params */
    if (p->n_layers < 3 || p->n_layers > ST_N_MAX) return fail(c, "%s: must be 3..200", "n_layers");
    if (!(p->volume >= 0.01 && p->volume <= 100.0)) return fail(c, "%s: must be 0.01..100 m3", "volume");
    if (!(p->height >= 0.1 && p->height <= 20.0)) return fail(c, "%s: must be 0.1..20 m", "height");
    if (!(p->UA_loss >= 0.0)) return fail(c, "%s: must be >= 0", "UA_loss");
    if (p->limiter < 0 || p->limiter > 3) return fail(c, "%s: must be 0..3", "limiter");
    p->T_env = c->T_env_K - T0;
    st_initial(c->T, p->n_layers, c->T_init_top_K - T0, c->T_init_bottom_K - T0);
    update_outputs_at_rest(c);
    c->state = S_STEP;
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component comp) { ((Inst *)comp)->state = S_TERMINATED; return fmi2OK; }

fmi2Status fmi2Reset(fmi2Component comp) {
    Inst *c = (Inst *)comp;
    set_defaults(c);
    c->state = S_INSTANTIATED;
    return fmi2OK;
}

static double *real_ref(Inst *c, fmi2ValueReference vr) {
    switch (vr) {
    case VR_VOLUME: return &c->p.volume;
    case VR_HEIGHT: return &c->p.height;
    case VR_UA_LOSS: return &c->p.UA_loss;
    case VR_T_ENV: return &c->T_env_K;
    case VR_UA_LAYER: return &c->p.UA_layer;
    case VR_T_INIT_TOP: return &c->T_init_top_K;
    case VR_T_INIT_BOTTOM: return &c->T_init_bottom_K;
    case VR_M_FLOW: return &c->m_flow;
    case VR_T_IN_TOP: return &c->T_in_top_K;
    case VR_T_IN_BOTTOM: return &c->T_in_bottom_K;
    default: return NULL;
    }
}

fmi2Status fmi2GetReal(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    Inst *c = (Inst *)comp;
    int N = c->p.n_layers;
    for (size_t i = 0; i < nvr; i++) {
        fmi2ValueReference r = vr[i];
        double *ref = real_ref(c, r);
        if (ref) { value[i] = *ref; continue; }
        if (c->state != S_STEP && c->state != S_TERMINATED) {
            value[i] = 0.0; /* outputs are calculated when initialization ends */
            continue;
        }
        if (r == VR_T_TOP) value[i] = c->T[0] + T0;
        else if (r == VR_T_BOTTOM) value[i] = c->T[N - 1] + T0;
        else if (r == VR_Q_LOSS) value[i] = c->Q_loss;
        else if (r == VR_T_OUT) value[i] = c->T_out + T0;
        else if (r >= VR_SENSOR0 && r < VR_SENSOR0 + N_SENSORS) {
            st_sensors(c->T, N, c->sensors, N_SENSORS);
            value[i] = c->sensors[r - VR_SENSOR0] + T0;
        } else if (r >= VR_LAYER0 && r < VR_LAYER0 + ST_N_MAX) {
            int k = (int)(r - VR_LAYER0);
            value[i] = c->T[k < N ? k : N - 1] + T0;
        } else {
            logf_(c, fmi2Error, "fmi2GetReal: unknown value reference %u", (unsigned)r);
            return fmi2Error;
        }
    }
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    Inst *c = (Inst *)comp;
    for (size_t i = 0; i < nvr; i++) {
        double *ref = real_ref(c, vr[i]);
        if (!ref) { logf_(c, fmi2Error, "fmi2SetReal: value reference %u is not settable", (unsigned)vr[i]); return fmi2Error; }
        if (vr[i] < VR_M_FLOW && c->state == S_STEP) {
            logf_(c, fmi2Error, "fmi2SetReal: parameter %u is fixed after initialization", (unsigned)vr[i]);
            return fmi2Error;
        }
        *ref = value[i];
    }
    return fmi2OK;
}

fmi2Status fmi2GetInteger(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[]) {
    Inst *c = (Inst *)comp;
    for (size_t i = 0; i < nvr; i++) {
        if (vr[i] == VR_N_LAYERS) value[i] = c->p.n_layers;
        else if (vr[i] == VR_LIMITER) value[i] = c->p.limiter;
        else return fmi2Error;
    }
    return fmi2OK;
}

fmi2Status fmi2SetInteger(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer value[]) {
    Inst *c = (Inst *)comp;
    if (c->state == S_STEP) { logf_(c, fmi2Error, "fmi2SetInteger: parameters are fixed after initialization"); return fmi2Error; }
    for (size_t i = 0; i < nvr; i++) {
        if (vr[i] == VR_N_LAYERS) c->p.n_layers = value[i];
        else if (vr[i] == VR_LIMITER) c->p.limiter = value[i];
        else return fmi2Error;
    }
    return fmi2OK;
}

fmi2Status fmi2DoStep(fmi2Component comp, fmi2Real t, fmi2Real h, fmi2Boolean noSetPrior) {
    Inst *c = (Inst *)comp;
    (void)noSetPrior;
    if (c->state != S_STEP) { logf_(c, fmi2Error, "fmi2DoStep: not initialized"); return fmi2Error; }
    if (!(h > 0.0)) { logf_(c, fmi2Error, "fmi2DoStep: step size %g must be > 0", h); return fmi2Error; }
    int il, ol;
    double im, iT, om;
    ports(c, &il, &im, &iT, &ol, &om);
    c->Q_loss = st_step(h, c->T, c->p.n_layers, &c->p, il, im, iT, ol, om, &c->T_out, c->q);
    c->time = t + h;
    return fmi2OK;
}

/* ---- not supported: booleans, strings, FMU state, derivatives, model exchange ---- */
#define UNSUPPORTED(sig) fmi2Status sig { return fmi2Error; }
UNSUPPORTED(fmi2GetBoolean(fmi2Component c, const fmi2ValueReference v[], size_t n, fmi2Boolean x[]))
UNSUPPORTED(fmi2SetBoolean(fmi2Component c, const fmi2ValueReference v[], size_t n, const fmi2Boolean x[]))
UNSUPPORTED(fmi2GetString(fmi2Component c, const fmi2ValueReference v[], size_t n, fmi2String x[]))
UNSUPPORTED(fmi2SetString(fmi2Component c, const fmi2ValueReference v[], size_t n, const fmi2String x[]))
UNSUPPORTED(fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *s))
UNSUPPORTED(fmi2SetFMUstate(fmi2Component c, fmi2FMUstate s))
UNSUPPORTED(fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *s))
UNSUPPORTED(fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate s, size_t *n))
UNSUPPORTED(fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate s, fmi2Byte b[], size_t n))
UNSUPPORTED(fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte b[], size_t n, fmi2FMUstate *s))
UNSUPPORTED(fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference u[], size_t nu,
            const fmi2ValueReference k[], size_t nk, const fmi2Real dv[], fmi2Real df[]))
UNSUPPORTED(fmi2EnterEventMode(fmi2Component c))
UNSUPPORTED(fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *e))
UNSUPPORTED(fmi2EnterContinuousTimeMode(fmi2Component c))
UNSUPPORTED(fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean n, fmi2Boolean *e, fmi2Boolean *t))
UNSUPPORTED(fmi2SetTime(fmi2Component c, fmi2Real t))
UNSUPPORTED(fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t n))
UNSUPPORTED(fmi2GetDerivatives(fmi2Component c, fmi2Real d[], size_t n))
UNSUPPORTED(fmi2GetEventIndicators(fmi2Component c, fmi2Real e[], size_t n))
UNSUPPORTED(fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t n))
UNSUPPORTED(fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x[], size_t n))
UNSUPPORTED(fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference v[], size_t n,
            const fmi2Integer o[], const fmi2Real x[]))
UNSUPPORTED(fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference v[], size_t n,
            const fmi2Integer o[], fmi2Real x[]))
UNSUPPORTED(fmi2CancelStep(fmi2Component c))
UNSUPPORTED(fmi2GetStatus(fmi2Component c, const fmi2StatusKind k, fmi2Status *s))
UNSUPPORTED(fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind k, fmi2Real *x))
UNSUPPORTED(fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind k, fmi2Integer *x))
UNSUPPORTED(fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind k, fmi2Boolean *x))
UNSUPPORTED(fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind k, fmi2String *x))
