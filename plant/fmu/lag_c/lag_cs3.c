/* The heat lag of lag_model.h as an FMI 3.0 co-simulation FMU: each doStep applies the exact
 * solution with the inputs held over the step.  The state machine is strict where the adapter
 * could get it wrong: without event mode the FMU is in Step Mode right after
 * fmi3ExitInitializationMode, and fmi3EnterStepMode is then an error (FMI 3.0, 4.2.1).
 * build.py generates stubs returning fmi3Error for the rest of the FMI 3.0 API. */
#include <stdlib.h>
#include <string.h>
#include "fmi3Functions.h"
#include "lag_model.h"

#define TOKEN "{8a0f8f5e-2c1d-4b7a-9e3f-c0535e5a0103}"

typedef enum { S_INSTANTIATED, S_INIT, S_EVENT, S_STEP, S_TERMINATED } State;

typedef struct {
    LagModel m;
    State state;
    int event_mode_used;
    fmi3InstanceEnvironment env;
    fmi3LogMessageCallback log;
    fmi3String name;
} Inst;

static fmi3Status err(Inst *c, const char *msg) {
    if (c && c->log) c->log(c->env, fmi3Error, "error", msg);
    return fmi3Error;
}

const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Instance fmi3InstantiateCoSimulation(fmi3String name, fmi3String token, fmi3String res,
        fmi3Boolean visible, fmi3Boolean logging, fmi3Boolean eventModeUsed, fmi3Boolean earlyReturnAllowed,
        const fmi3ValueReference required[], size_t nRequired, fmi3InstanceEnvironment env,
        fmi3LogMessageCallback log, fmi3IntermediateUpdateCallback update) {
    (void)res; (void)visible; (void)logging; (void)earlyReturnAllowed; (void)required; (void)nRequired;
    (void)update;
    if (!token || strcmp(token, TOKEN) != 0) {
        if (log) log(env, fmi3Error, "error", "instantiation token mismatch");
        return NULL;
    }
    Inst *c = (Inst *)calloc(1, sizeof(Inst));
    if (!c) return NULL;
    lag_defaults(&c->m);
    c->state = S_INSTANTIATED;
    c->event_mode_used = eventModeUsed;
    c->env = env;
    c->log = log;
    c->name = name;
    return c;
}
void fmi3FreeInstance(fmi3Instance c) { free(c); }
fmi3Status fmi3SetDebugLogging(fmi3Instance c, fmi3Boolean on, size_t n, const fmi3String cat[]) {
    (void)c; (void)on; (void)n; (void)cat; return fmi3OK;
}
fmi3Status fmi3EnterInitializationMode(fmi3Instance comp, fmi3Boolean tolDef, fmi3Float64 tol,
                                       fmi3Float64 start, fmi3Boolean stopDef, fmi3Float64 stop) {
    Inst *c = (Inst *)comp;
    (void)tolDef; (void)tol; (void)stopDef; (void)stop;
    if (c->state != S_INSTANTIATED) return err(c, "fmi3EnterInitializationMode: not in Instantiated state");
    c->m.v[VR_TIME] = start;
    c->state = S_INIT;
    return fmi3OK;
}
fmi3Status fmi3ExitInitializationMode(fmi3Instance comp) {
    Inst *c = (Inst *)comp;
    if (c->state != S_INIT) return err(c, "fmi3ExitInitializationMode: not in Initialization Mode");
    c->m.v[VR_T] = c->m.v[VR_T_START];
    c->state = c->event_mode_used ? S_EVENT : S_STEP;
    return fmi3OK;
}
fmi3Status fmi3EnterEventMode(fmi3Instance comp) {
    Inst *c = (Inst *)comp;
    if (!c->event_mode_used || c->state != S_STEP) return err(c, "fmi3EnterEventMode: not allowed");
    c->state = S_EVENT; return fmi3OK;
}
fmi3Status fmi3EnterStepMode(fmi3Instance comp) {
    Inst *c = (Inst *)comp;
    if (c->state != S_EVENT) return err(c, "fmi3EnterStepMode: only allowed in Event Mode");
    c->state = S_STEP; return fmi3OK;
}
fmi3Status fmi3Terminate(fmi3Instance comp) { ((Inst *)comp)->state = S_TERMINATED; return fmi3OK; }
fmi3Status fmi3Reset(fmi3Instance comp) {
    Inst *c = (Inst *)comp; lag_defaults(&c->m); c->state = S_INSTANTIATED; return fmi3OK;
}
fmi3Status fmi3GetFloat64(fmi3Instance comp, const fmi3ValueReference vr[], size_t nvr,
                          fmi3Float64 values[], size_t nValues) {
    Inst *c = (Inst *)comp;
    if (nValues != nvr) return err(c, "fmi3GetFloat64: scalar variables only");
    for (size_t i = 0; i < nvr; i++) {
        if (vr[i] >= N_VR) return err(c, "fmi3GetFloat64: unknown value reference");
        values[i] = vr[i] == VR_DER_T ? lag_derivative(&c->m) : c->m.v[vr[i]];
    }
    return fmi3OK;
}
fmi3Status fmi3SetFloat64(fmi3Instance comp, const fmi3ValueReference vr[], size_t nvr,
                          const fmi3Float64 values[], size_t nValues) {
    Inst *c = (Inst *)comp;
    if (nValues != nvr) return err(c, "fmi3SetFloat64: scalar variables only");
    for (size_t i = 0; i < nvr; i++) {
        if (vr[i] >= N_VR || !lag_writable(vr[i], c->state != S_INSTANTIATED && c->state != S_INIT))
            return err(c, "fmi3SetFloat64: variable cannot be set now");
        c->m.v[vr[i]] = values[i];
    }
    return fmi3OK;
}
fmi3Status fmi3DoStep(fmi3Instance comp, fmi3Float64 t, fmi3Float64 h, fmi3Boolean noSetPrior,
                      fmi3Boolean *eventNeeded, fmi3Boolean *terminate, fmi3Boolean *earlyReturn,
                      fmi3Float64 *lastTime) {
    Inst *c = (Inst *)comp;
    (void)noSetPrior;
    if (c->state != S_STEP) return err(c, "fmi3DoStep: not in Step Mode");
    if (h < 0.0) return err(c, "fmi3DoStep: negative step size");
    if (fabs(t - c->m.v[VR_TIME]) > 1e-9 * (1.0 + fabs(t)))
        return err(c, "fmi3DoStep: currentCommunicationPoint differs from the FMU's time");
    lag_exact_step(&c->m, h);
    c->m.v[VR_TIME] = t + h;
    *eventNeeded = fmi3False; *terminate = fmi3False; *earlyReturn = fmi3False;
    *lastTime = t + h;
    return fmi3OK;
}
