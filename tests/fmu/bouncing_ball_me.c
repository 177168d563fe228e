/* A model-exchange FMU (FMI 3.0) the tests build with the system's C
 * compiler, for the `fmu` block's `mode: me`: a ball under gravity g,
 * pushed by the input `a` (an extra acceleration), bouncing off the floor
 * h = 0 with restitution e.
 *
 *   states      h, v           der(h) = v, der(v) = a - g
 *   indicator   z = h          (the floor, crossed downwards)
 *   event       v := -e v      (at an impact, h = 0, in event mode)
 *   time event  at t_kick: v := v + kick (to exercise time events)
 *
 * Written for ctlgraph's tests against the FMI 3.0 standard's C API
 * (fmi3Functions.h); only the functions an importer of model exchange
 * calls do something, the others return fmi3Error. */

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

typedef int fmi3Status; /* fmi3OK 0, fmi3Warning 1, fmi3Discard 2, fmi3Error 3 */
typedef void (*LogMessage)(void *env, fmi3Status status, const char *category, const char *message);

enum { VR_TIME, VR_H, VR_DER_H, VR_V, VR_DER_V, VR_G, VR_E, VR_A, VR_KICK, VR_T_KICK, VR_Z, N_VR };

typedef struct {
    double value[N_VR];
    double time;
    bool kicked;
    void *env;
    LogMessage log;
} Ball;

static void derivatives(Ball *b) {
    b->value[VR_DER_H] = b->value[VR_V];
    b->value[VR_DER_V] = b->value[VR_A] - b->value[VR_G];
    b->value[VR_Z] = b->value[VR_H];
}

const char *fmi3GetVersion(void) { return "3.0"; }

void *fmi3InstantiateModelExchange(const char *name, const char *token, const char *resources, bool visible,
                                   bool logging, void *env, LogMessage log) {
    (void)name; (void)resources; (void)visible; (void)logging;
    if (token == NULL || strcmp(token, "{ctlgraph-test-bouncing-ball-me}") != 0) {
        if (log) log(env, 3, "logStatusError", "wrong instantiation token");
        return NULL;
    }
    Ball *b = calloc(1, sizeof(Ball));
    if (b == NULL) return NULL;
    b->value[VR_H] = 10.0;
    b->value[VR_G] = 9.81;
    b->value[VR_E] = 0.8;
    b->value[VR_KICK] = 0.0;
    b->value[VR_T_KICK] = 1e300;
    b->env = env;
    b->log = log;
    derivatives(b);
    return b;
}

void fmi3FreeInstance(void *instance) { free(instance); }

fmi3Status fmi3EnterInitializationMode(void *instance, bool tol_defined, double tol, double start, bool stop_defined,
                                       double stop) {
    (void)tol_defined; (void)tol; (void)stop_defined; (void)stop;
    ((Ball *)instance)->time = start;
    return 0;
}

fmi3Status fmi3ExitInitializationMode(void *instance) { derivatives(instance); return 0; }
fmi3Status fmi3EnterEventMode(void *instance) { (void)instance; return 0; }
fmi3Status fmi3EnterContinuousTimeMode(void *instance) { (void)instance; return 0; }
fmi3Status fmi3Terminate(void *instance) { (void)instance; return 0; }
fmi3Status fmi3Reset(void *instance) { (void)instance; return 3; }

fmi3Status fmi3GetFloat64(void *instance, const uint32_t vr[], size_t nvr, double values[], size_t n) {
    Ball *b = instance;
    if (n != nvr) return 3;
    derivatives(b);
    for (size_t i = 0; i < nvr; i++) {
        if (vr[i] >= N_VR) return 3;
        values[i] = vr[i] == VR_TIME ? b->time : b->value[vr[i]];
    }
    return 0;
}

fmi3Status fmi3SetFloat64(void *instance, const uint32_t vr[], size_t nvr, const double values[], size_t n) {
    Ball *b = instance;
    if (n != nvr) return 3;
    for (size_t i = 0; i < nvr; i++) {
        if (vr[i] == VR_TIME || vr[i] >= N_VR || vr[i] == VR_DER_H || vr[i] == VR_DER_V || vr[i] == VR_Z) {
            if (b->log) b->log(b->env, 3, "logStatusError", "that variable cannot be set");
            return 3;
        }
        b->value[vr[i]] = values[i];
    }
    return 0;
}

fmi3Status fmi3SetTime(void *instance, double t) { ((Ball *)instance)->time = t; return 0; }

fmi3Status fmi3SetContinuousStates(void *instance, const double x[], size_t n) {
    Ball *b = instance;
    if (n != 2) return 3;
    b->value[VR_H] = x[0];
    b->value[VR_V] = x[1];
    return 0;
}

fmi3Status fmi3GetContinuousStates(void *instance, double x[], size_t n) {
    Ball *b = instance;
    if (n != 2) return 3;
    x[0] = b->value[VR_H];
    x[1] = b->value[VR_V];
    return 0;
}

fmi3Status fmi3GetContinuousStateDerivatives(void *instance, double dx[], size_t n) {
    Ball *b = instance;
    if (n != 2) return 3;
    derivatives(b);
    dx[0] = b->value[VR_DER_H];
    dx[1] = b->value[VR_DER_V];
    return 0;
}

fmi3Status fmi3GetEventIndicators(void *instance, double z[], size_t n) {
    Ball *b = instance;
    if (n != 1) return 3;
    z[0] = b->value[VR_H];
    return 0;
}

fmi3Status fmi3GetNominalsOfContinuousStates(void *instance, double nominals[], size_t n) {
    (void)instance;
    for (size_t i = 0; i < n; i++) nominals[i] = 1.0;
    return 0;
}

fmi3Status fmi3GetNumberOfContinuousStates(void *instance, size_t *n) { (void)instance; *n = 2; return 0; }
fmi3Status fmi3GetNumberOfEventIndicators(void *instance, size_t *n) { (void)instance; *n = 1; return 0; }

fmi3Status fmi3CompletedIntegratorStep(void *instance, bool no_set_prior, bool *enter_event_mode, bool *terminate) {
    (void)instance; (void)no_set_prior;
    *enter_event_mode = false;
    *terminate = false;
    return 0;
}

/* Event mode: an impact (h <= 0 moving down) reverses v; the kick, due at
 * t_kick, adds to it once. */
fmi3Status fmi3UpdateDiscreteStates(void *instance, bool *need_update, bool *terminate, bool *nominals_changed,
                                    bool *states_changed, bool *next_time_defined, double *next_time) {
    Ball *b = instance;
    *need_update = false;
    *terminate = false;
    *nominals_changed = false;
    *states_changed = false;
    if (b->value[VR_H] <= 0.0 && b->value[VR_V] < 0.0) {
        b->value[VR_H] = 0.0;
        b->value[VR_V] = -b->value[VR_E] * b->value[VR_V];
        *states_changed = true;
    }
    if (!b->kicked && b->time >= b->value[VR_T_KICK]) {
        b->value[VR_V] += b->value[VR_KICK];
        b->kicked = true;
        *states_changed = true;
    }
    *next_time_defined = !b->kicked && b->value[VR_T_KICK] < 1e299;
    *next_time = b->value[VR_T_KICK];
    return 0;
}

/* The same model through FMI 2.0's model-exchange functions (fmi2Functions.h),
 * described by bouncing_ball_me2.xml: the tests load this one binary as either. */

typedef struct {
    int newDiscreteStatesNeeded;
    int terminateSimulation;
    int nominalsOfContinuousStatesChanged;
    int valuesOfContinuousStatesChanged;
    int nextEventTimeDefined;
    double nextEventTime;
} fmi2EventInfo;

typedef struct {
    void (*logger)(void *env, const char *name, int status, const char *category, const char *message, ...);
    void *(*allocateMemory)(size_t n, size_t size);
    void (*freeMemory)(void *p);
    void *stepFinished;
    void *env;
} fmi2CallbackFunctions;

const char *fmi2GetVersion(void) { return "2.0"; }
const char *fmi2GetTypesPlatform(void) { return "default"; }

void *fmi2Instantiate(const char *name, int type, const char *guid, const char *resources,
                      const fmi2CallbackFunctions *functions, int visible, int logging) {
    (void)name; (void)resources; (void)visible; (void)logging;
    if (type != 0 || guid == NULL || strcmp(guid, "{ctlgraph-test-bouncing-ball-me}") != 0) {
        if (functions && functions->logger)
            functions->logger(functions->env, name, 3, "logStatusError", "wrong GUID or not model exchange");
        return NULL;
    }
    return fmi3InstantiateModelExchange(name, guid, resources, false, false, NULL, NULL);
}

void fmi2FreeInstance(void *c) { fmi3FreeInstance(c); }
int fmi2SetupExperiment(void *c, int tol_defined, double tol, double start, int stop_defined, double stop) {
    return fmi3EnterInitializationMode(c, tol_defined, tol, start, stop_defined, stop);
}
int fmi2EnterInitializationMode(void *c) { (void)c; return 0; }
int fmi2ExitInitializationMode(void *c) { return fmi3ExitInitializationMode(c); }
int fmi2Terminate(void *c) { (void)c; return 0; }
int fmi2EnterEventMode(void *c) { (void)c; return 0; }
int fmi2EnterContinuousTimeMode(void *c) { (void)c; return 0; }
int fmi2GetReal(void *c, const uint32_t vr[], size_t n, double v[]) { return fmi3GetFloat64(c, vr, n, v, n); }
int fmi2SetReal(void *c, const uint32_t vr[], size_t n, const double v[]) { return fmi3SetFloat64(c, vr, n, v, n); }
int fmi2SetTime(void *c, double t) { return fmi3SetTime(c, t); }
int fmi2SetContinuousStates(void *c, const double x[], size_t n) { return fmi3SetContinuousStates(c, x, n); }
int fmi2GetContinuousStates(void *c, double x[], size_t n) { return fmi3GetContinuousStates(c, x, n); }
int fmi2GetDerivatives(void *c, double dx[], size_t n) { return fmi3GetContinuousStateDerivatives(c, dx, n); }
int fmi2GetEventIndicators(void *c, double z[], size_t n) { return fmi3GetEventIndicators(c, z, n); }
int fmi2GetNominalsOfContinuousStates(void *c, double x[], size_t n) { return fmi3GetNominalsOfContinuousStates(c, x, n); }

int fmi2CompletedIntegratorStep(void *c, int no_set_prior, int *enter_event_mode, int *terminate) {
    (void)c; (void)no_set_prior;
    *enter_event_mode = 0;
    *terminate = 0;
    return 0;
}

int fmi2NewDiscreteStates(void *c, fmi2EventInfo *info) {
    bool need, terminate, nominals, states, next_defined;
    double next;
    int s = fmi3UpdateDiscreteStates(c, &need, &terminate, &nominals, &states, &next_defined, &next);
    info->newDiscreteStatesNeeded = need;
    info->terminateSimulation = terminate;
    info->nominalsOfContinuousStatesChanged = nominals;
    info->valuesOfContinuousStatesChanged = states;
    info->nextEventTimeDefined = next_defined;
    info->nextEventTime = next;
    return s;
}
