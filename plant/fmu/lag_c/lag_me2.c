/* The heat lag of lag_model.h as an FMI 2.0 model-exchange FMU (one state T, no events).
 * Only the functions fmpy's FMU2Model calls are implemented; build.py generates stubs returning
 * fmi2Error for the rest of the FMI 2.0 API. */
#include <stdlib.h>
#include <string.h>
#include "fmi2Functions.h"
#include "lag_model.h"

#define GUID "{8a0f8f5e-2c1d-4b7a-9e3f-c0535e5a0102}"

typedef struct {
    LagModel m;
    int initialized;
    const fmi2CallbackFunctions *cb;
    fmi2String name;
} Inst;

static fmi2Status err(Inst *c, const char *msg) {
    if (c && c->cb && c->cb->logger) c->cb->logger(c->cb->componentEnvironment, c->name, fmi2Error, "error", msg);
    return fmi2Error;
}

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid, fmi2String res,
                              const fmi2CallbackFunctions *cb, fmi2Boolean visible, fmi2Boolean logging) {
    (void)res; (void)visible; (void)logging;
    if (type != fmi2ModelExchange || !guid || strcmp(guid, GUID) != 0) return NULL;
    Inst *c = (Inst *)calloc(1, sizeof(Inst));
    if (!c) return NULL;
    lag_defaults(&c->m);
    c->cb = cb;
    c->name = name;
    return c;
}
void fmi2FreeInstance(fmi2Component c) { free(c); }
fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n, const fmi2String cat[]) {
    (void)c; (void)on; (void)n; (void)cat; return fmi2OK;
}
fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean tolDef, fmi2Real tol, fmi2Real start,
                               fmi2Boolean stopDef, fmi2Real stop) {
    (void)tolDef; (void)tol; (void)stopDef; (void)stop;
    ((Inst *)c)->m.v[VR_TIME] = start; return fmi2OK;
}
fmi2Status fmi2EnterInitializationMode(fmi2Component c) { (void)c; return fmi2OK; }
fmi2Status fmi2ExitInitializationMode(fmi2Component comp) {
    Inst *c = (Inst *)comp;
    c->m.v[VR_T] = c->m.v[VR_T_START];
    c->initialized = 1;
    return fmi2OK;
}
fmi2Status fmi2Terminate(fmi2Component c) { (void)c; return fmi2OK; }
fmi2Status fmi2Reset(fmi2Component comp) {
    Inst *c = (Inst *)comp; lag_defaults(&c->m); c->initialized = 0; return fmi2OK;
}
fmi2Status fmi2GetReal(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    Inst *c = (Inst *)comp;
    for (size_t i = 0; i < nvr; i++) {
        if (vr[i] < 1 || vr[i] >= N_VR) return err(c, "fmi2GetReal: unknown value reference");
        value[i] = vr[i] == VR_DER_T ? lag_derivative(&c->m) : c->m.v[vr[i]];
    }
    return fmi2OK;
}
fmi2Status fmi2SetReal(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    Inst *c = (Inst *)comp;
    for (size_t i = 0; i < nvr; i++) {
        if (vr[i] >= N_VR || !lag_writable(vr[i], c->initialized))
            return err(c, "fmi2SetReal: variable cannot be set now");
        c->m.v[vr[i]] = value[i];
    }
    return fmi2OK;
}
/* model exchange */
fmi2Status fmi2EnterEventMode(fmi2Component c) { (void)c; return fmi2OK; }
fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *info) {
    (void)c;
    info->newDiscreteStatesNeeded = fmi2False;
    info->terminateSimulation = fmi2False;
    info->nominalsOfContinuousStatesChanged = fmi2False;
    info->valuesOfContinuousStatesChanged = fmi2False;
    info->nextEventTimeDefined = fmi2False;
    info->nextEventTime = 0.0;
    return fmi2OK;
}
fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) { (void)c; return fmi2OK; }
fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetPrior, fmi2Boolean *enterEvent,
                                       fmi2Boolean *terminate) {
    (void)c; (void)noSetPrior; *enterEvent = fmi2False; *terminate = fmi2False; return fmi2OK;
}
fmi2Status fmi2SetTime(fmi2Component c, fmi2Real t) { ((Inst *)c)->m.v[VR_TIME] = t; return fmi2OK; }
fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx) {
    if (nx != 1) return err((Inst *)c, "fmi2SetContinuousStates: nx must be 1");
    ((Inst *)c)->m.v[VR_T] = x[0]; return fmi2OK;
}
fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx) {
    if (nx != 1) return err((Inst *)c, "fmi2GetContinuousStates: nx must be 1");
    x[0] = ((Inst *)c)->m.v[VR_T]; return fmi2OK;
}
fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real dx[], size_t nx) {
    if (nx != 1) return err((Inst *)c, "fmi2GetDerivatives: nx must be 1");
    dx[0] = lag_derivative(&((Inst *)c)->m); return fmi2OK;
}
fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real z[], size_t nz) {
    (void)c; (void)z; return nz == 0 ? fmi2OK : fmi2Error;
}
fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x[], size_t nx) {
    (void)c; if (nx != 1) return fmi2Error; x[0] = 1.0; return fmi2OK;
}
