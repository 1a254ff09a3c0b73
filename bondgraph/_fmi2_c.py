"""The fixed C text of an exported FMU (:mod:`bondgraph.fmu_export`): the FMI 2.0 declarations and the
co-simulation runtime, which the generated model code (sizes, start values, derivatives, signals) precedes.

The declarations are written from the FMI 2.0 specification (Modelica Association (2014), sections 2.1.2-2.1.4
and 4.2): the types, the status and callback types, and the prototypes of the functions a co-simulation FMU
exports.  The runtime keeps one instance's values in a plain struct (so that an FMU state is a copy of it),
checks the calling sequence of the specification's state machine loosely (what would corrupt the values),
and integrates the states over a communication step with the embedded Runge-Kutta pair of Dormand and Prince
(1980), 5th order with a 4th-order error estimate and step-size control, the inputs held over the step.

The error of a step is measured per state against ``rtol * max(|x| so far) + 0.01 * rtol * nominal``: relative
to the largest magnitude the state has reached, since a state's scale (a charge of microcoulombs, a momentum of
kilogram metres per second) is not known in advance, plus the absolute tolerance the FMI 2.0 specification
suggests from a variable's nominal value (section 2.2.7, ``nominal``), which keeps a state that starts at zero
on a law of infinite slope there (an orifice's square root) from asking for ever smaller steps.
"""

__all__ = ["HEADER", "HEADER_NAME", "RUNTIME"]

#: The file name of the declarations under ``sources/`` (the runtime includes it).
HEADER_NAME = "bondgraph_fmi2.h"

HEADER = r"""/* FMI 2.0 co-simulation declarations, written from the FMI 2.0 specification
   (Modelica Association, 2014): platform types, status and callback types, and the functions a
   co-simulation FMU exports under their standard names (no function prefix). */
#ifndef BONDGRAPH_FMI2_H
#define BONDGRAPH_FMI2_H

#include <stddef.h>

#if defined(_WIN32)
#define BG_EXPORT __declspec(dllexport)
#else
#define BG_EXPORT __attribute__((visibility("default")))
#endif

typedef void *fmi2Component;
typedef void *fmi2ComponentEnvironment;
typedef void *fmi2FMUstate;
typedef unsigned int fmi2ValueReference;
typedef double fmi2Real;
typedef int fmi2Integer;
typedef int fmi2Boolean;
typedef char fmi2Char;
typedef const fmi2Char *fmi2String;
typedef char fmi2Byte;

#define fmi2True 1
#define fmi2False 0

typedef enum { fmi2OK, fmi2Warning, fmi2Discard, fmi2Error, fmi2Fatal, fmi2Pending } fmi2Status;
typedef enum { fmi2ModelExchange, fmi2CoSimulation } fmi2Type;
typedef enum { fmi2DoStepStatus, fmi2PendingStatus, fmi2LastSuccessfulTime, fmi2Terminated } fmi2StatusKind;

typedef void (*fmi2CallbackLogger)(fmi2ComponentEnvironment, fmi2String, fmi2Status, fmi2String, fmi2String, ...);
typedef void *(*fmi2CallbackAllocateMemory)(size_t, size_t);
typedef void (*fmi2CallbackFreeMemory)(void *);
typedef void (*fmi2StepFinished)(fmi2ComponentEnvironment, fmi2Status);

typedef struct {
    const fmi2CallbackLogger logger;
    const fmi2CallbackAllocateMemory allocateMemory;
    const fmi2CallbackFreeMemory freeMemory;
    const fmi2StepFinished stepFinished;
    const fmi2ComponentEnvironment componentEnvironment;
} fmi2CallbackFunctions;

BG_EXPORT const char *fmi2GetTypesPlatform(void);
BG_EXPORT const char *fmi2GetVersion(void);
BG_EXPORT fmi2Status fmi2SetDebugLogging(fmi2Component, fmi2Boolean, size_t, const fmi2String[]);
BG_EXPORT fmi2Component fmi2Instantiate(fmi2String, fmi2Type, fmi2String, fmi2String,
                                        const fmi2CallbackFunctions *, fmi2Boolean, fmi2Boolean);
BG_EXPORT void fmi2FreeInstance(fmi2Component);
BG_EXPORT fmi2Status fmi2SetupExperiment(fmi2Component, fmi2Boolean, fmi2Real, fmi2Real, fmi2Boolean, fmi2Real);
BG_EXPORT fmi2Status fmi2EnterInitializationMode(fmi2Component);
BG_EXPORT fmi2Status fmi2ExitInitializationMode(fmi2Component);
BG_EXPORT fmi2Status fmi2Terminate(fmi2Component);
BG_EXPORT fmi2Status fmi2Reset(fmi2Component);
BG_EXPORT fmi2Status fmi2GetReal(fmi2Component, const fmi2ValueReference[], size_t, fmi2Real[]);
BG_EXPORT fmi2Status fmi2GetInteger(fmi2Component, const fmi2ValueReference[], size_t, fmi2Integer[]);
BG_EXPORT fmi2Status fmi2GetBoolean(fmi2Component, const fmi2ValueReference[], size_t, fmi2Boolean[]);
BG_EXPORT fmi2Status fmi2GetString(fmi2Component, const fmi2ValueReference[], size_t, fmi2String[]);
BG_EXPORT fmi2Status fmi2SetReal(fmi2Component, const fmi2ValueReference[], size_t, const fmi2Real[]);
BG_EXPORT fmi2Status fmi2SetInteger(fmi2Component, const fmi2ValueReference[], size_t, const fmi2Integer[]);
BG_EXPORT fmi2Status fmi2SetBoolean(fmi2Component, const fmi2ValueReference[], size_t, const fmi2Boolean[]);
BG_EXPORT fmi2Status fmi2SetString(fmi2Component, const fmi2ValueReference[], size_t, const fmi2String[]);
BG_EXPORT fmi2Status fmi2GetFMUstate(fmi2Component, fmi2FMUstate *);
BG_EXPORT fmi2Status fmi2SetFMUstate(fmi2Component, fmi2FMUstate);
BG_EXPORT fmi2Status fmi2FreeFMUstate(fmi2Component, fmi2FMUstate *);
BG_EXPORT fmi2Status fmi2SerializedFMUstateSize(fmi2Component, fmi2FMUstate, size_t *);
BG_EXPORT fmi2Status fmi2SerializeFMUstate(fmi2Component, fmi2FMUstate, fmi2Byte[], size_t);
BG_EXPORT fmi2Status fmi2DeSerializeFMUstate(fmi2Component, const fmi2Byte[], size_t, fmi2FMUstate *);
BG_EXPORT fmi2Status fmi2GetDirectionalDerivative(fmi2Component, const fmi2ValueReference[], size_t,
                                                  const fmi2ValueReference[], size_t, const fmi2Real[], fmi2Real[]);
BG_EXPORT fmi2Status fmi2SetRealInputDerivatives(fmi2Component, const fmi2ValueReference[], size_t,
                                                 const fmi2Integer[], const fmi2Real[]);
BG_EXPORT fmi2Status fmi2GetRealOutputDerivatives(fmi2Component, const fmi2ValueReference[], size_t,
                                                  const fmi2Integer[], fmi2Real[]);
BG_EXPORT fmi2Status fmi2DoStep(fmi2Component, fmi2Real, fmi2Real, fmi2Boolean);
BG_EXPORT fmi2Status fmi2CancelStep(fmi2Component);
BG_EXPORT fmi2Status fmi2GetStatus(fmi2Component, const fmi2StatusKind, fmi2Status *);
BG_EXPORT fmi2Status fmi2GetRealStatus(fmi2Component, const fmi2StatusKind, fmi2Real *);
BG_EXPORT fmi2Status fmi2GetIntegerStatus(fmi2Component, const fmi2StatusKind, fmi2Integer *);
BG_EXPORT fmi2Status fmi2GetBooleanStatus(fmi2Component, const fmi2StatusKind, fmi2Boolean *);
BG_EXPORT fmi2Status fmi2GetStringStatus(fmi2Component, const fmi2StatusKind, fmi2String *);

#endif
"""

RUNTIME = r"""
/* ------------------------------------------------------------------------------------------------------
   The co-simulation runtime (the same text in every FMU this toolkit writes).
   Value references: parameters [0, NP), inputs [NP, NP + NU), states [.., + NX), signals [.., + NY).
   ------------------------------------------------------------------------------------------------------ */

#define BG_N (BG_NP + BG_NU + BG_NX + BG_NY)
/* the most internal steps in one communication step, and the smallest step relative to the time */
#define BG_MAX_STEPS 10000000L
#define BG_MIN_STEP 1e-14

typedef enum { BG_INSTANTIATED, BG_INITIALIZING, BG_STEPPING, BG_TERMINATED, BG_FAILED } bg_phase;

/* Everything a step changes: an FMU state is a copy of it (no pointers inside). */
typedef struct {
    double p[BG_SIZE(BG_NP)], u[BG_SIZE(BG_NU)], x[BG_SIZE(BG_NX)];
    double scale[BG_SIZE(BG_NX)];   /* the largest |x| each state has reached: its error's yardstick */
    double time, stop_time, h, rtol;
    int stop_defined;
    bg_phase phase;
} bg_values;

typedef struct {
    bg_values v;
    fmi2CallbackLogger logger;
    fmi2CallbackAllocateMemory allocate;
    fmi2CallbackFreeMemory release;
    fmi2ComponentEnvironment environment;
    char name[128];
} bg_instance;

/* the logger takes a printf format: the message is formatted here and its percent signs replaced */
static void bg_log(const bg_instance *c, fmi2Status status, const char *category, const char *message) {
    char text[512];
    size_t i;
    if (c == NULL || c->logger == NULL) return;
    strncpy(text, message, sizeof text - 1);
    text[sizeof text - 1] = '\0';
    for (i = 0; text[i] != '\0'; i++) {
        if (text[i] == '%') text[i] = '?';
    }
    c->logger(c->environment, c->name, status, category, text);
}

static fmi2Status bg_fail(bg_instance *c, const char *message) {
    bg_log(c, fmi2Error, "logError", message);
    return fmi2Error;
}

static void bg_start_values(bg_values *v) {
    int i;
    memset(v, 0, sizeof *v);
    for (i = 0; i < BG_NP; i++) v->p[i] = bg_parameter_start[i];
    for (i = 0; i < BG_NU; i++) v->u[i] = bg_input_start[i];
    for (i = 0; i < BG_NX; i++) v->x[i] = bg_state_start[i];
    v->rtol = BG_DEFAULT_TOLERANCE;
    v->phase = BG_INSTANTIATED;
}

static void bg_reset_scale(bg_values *v) {
    int i;
    for (i = 0; i < BG_NX; i++) v->scale[i] = fabs(v->x[i]);
}

const char *fmi2GetTypesPlatform(void) { return "default"; }

const char *fmi2GetVersion(void) { return "2.0"; }

fmi2Status fmi2SetDebugLogging(fmi2Component component, fmi2Boolean on, size_t n, const fmi2String categories[]) {
    (void)on; (void)n; (void)categories;   /* errors are always logged; there is nothing else to log */
    return component == NULL ? fmi2Error : fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation, const fmi2CallbackFunctions *functions,
                              fmi2Boolean visible, fmi2Boolean loggingOn) {
    bg_instance probe, *c;
    (void)fmuResourceLocation; (void)visible; (void)loggingOn;
    memset(&probe, 0, sizeof probe);
    if (functions != NULL) {
        probe.logger = functions->logger;
        probe.allocate = functions->allocateMemory;
        probe.release = functions->freeMemory;
        probe.environment = functions->componentEnvironment;
    }
    strncpy(probe.name, instanceName != NULL ? instanceName : "", sizeof probe.name - 1);
    if (fmuType != fmi2CoSimulation) {
        bg_log(&probe, fmi2Error, "logError", "this FMU implements co-simulation only, not model exchange");
        return NULL;
    }
    if (fmuGUID == NULL || strcmp(fmuGUID, BG_GUID) != 0) {
        bg_log(&probe, fmi2Error, "logError", "the GUID does not match this FMU's modelDescription.xml");
        return NULL;
    }
    c = probe.allocate != NULL ? (bg_instance *)probe.allocate(1, sizeof *c) : (bg_instance *)calloc(1, sizeof *c);
    if (c == NULL) {
        bg_log(&probe, fmi2Error, "logError", "out of memory");
        return NULL;
    }
    *c = probe;
    bg_start_values(&c->v);
    return c;
}

void fmi2FreeInstance(fmi2Component component) {
    bg_instance *c = (bg_instance *)component;
    if (c == NULL) return;
    if (c->release != NULL) c->release(c); else free(c);
}

fmi2Status fmi2SetupExperiment(fmi2Component component, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    bg_instance *c = (bg_instance *)component;
    if (c == NULL) return fmi2Error;
    if (c->v.phase != BG_INSTANTIATED) return bg_fail(c, "fmi2SetupExperiment: called after initialization");
    if (toleranceDefined && !(tolerance > 0.0 && tolerance < 1.0))
        return bg_fail(c, "fmi2SetupExperiment: the tolerance must be in (0, 1)");
    if (toleranceDefined) c->v.rtol = tolerance;
    c->v.time = startTime;
    c->v.stop_defined = stopTimeDefined ? 1 : 0;
    c->v.stop_time = stopTime;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component component) {
    bg_instance *c = (bg_instance *)component;
    if (c == NULL) return fmi2Error;
    if (c->v.phase != BG_INSTANTIATED) return bg_fail(c, "fmi2EnterInitializationMode: not instantiated");
    c->v.phase = BG_INITIALIZING;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component component) {
    bg_instance *c = (bg_instance *)component;
    if (c == NULL) return fmi2Error;
    if (c->v.phase != BG_INITIALIZING) return bg_fail(c, "fmi2ExitInitializationMode: not initializing");
    bg_reset_scale(&c->v);
    c->v.h = 0.0;
    c->v.phase = BG_STEPPING;
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component component) {
    bg_instance *c = (bg_instance *)component;
    if (c == NULL) return fmi2Error;
    c->v.phase = BG_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component component) {
    bg_instance *c = (bg_instance *)component;
    if (c == NULL) return fmi2Error;
    bg_start_values(&c->v);
    return fmi2OK;
}

static int bg_finite(const double *values, int n) {
    int i;
    for (i = 0; i < n; i++) {
        if (!isfinite(values[i])) return 0;
    }
    return 1;
}

fmi2Status fmi2GetReal(fmi2Component component, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    bg_instance *c = (bg_instance *)component;
    double y[BG_SIZE(BG_NY)];
    int have_signals = 0;
    size_t i;
    char message[160];
    if (c == NULL) return fmi2Error;
    if (nvr > 0 && (vr == NULL || value == NULL)) return bg_fail(c, "fmi2GetReal: null array");
    for (i = 0; i < nvr; i++) {
        unsigned int r = vr[i];
        if (r < BG_NP) {
            value[i] = c->v.p[r];
        } else if (r < BG_NP + BG_NU) {
            value[i] = c->v.u[r - BG_NP];
        } else if (r < BG_NP + BG_NU + BG_NX) {
            value[i] = c->v.x[r - BG_NP - BG_NU];
        } else if (r < BG_N) {
            if (!have_signals) {   /* the signals of the present states and inputs, computed once per call */
                bg_signals(c->v.time, c->v.x, c->v.u, c->v.p, y);
                have_signals = 1;
            }
            value[i] = y[r - BG_NP - BG_NU - BG_NX];
        } else {
            snprintf(message, sizeof message, "fmi2GetReal: no Real variable has value reference %u", r);
            return bg_fail(c, message);
        }
    }
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component component, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    bg_instance *c = (bg_instance *)component;
    size_t i;
    char message[200];
    if (c == NULL) return fmi2Error;
    if (nvr > 0 && (vr == NULL || value == NULL)) return bg_fail(c, "fmi2SetReal: null array");
    for (i = 0; i < nvr; i++) {
        unsigned int r = vr[i];
        const char *name = r < BG_N ? bg_variable_names[r] : "";
        if (r >= BG_N) {
            snprintf(message, sizeof message, "fmi2SetReal: no Real variable has value reference %u", r);
            return bg_fail(c, message);
        }
        if (!isfinite(value[i])) {
            snprintf(message, sizeof message, "fmi2SetReal: %.80s must be a finite number", name);
            return bg_fail(c, message);
        }
        if (c->v.phase == BG_TERMINATED || c->v.phase == BG_FAILED) {
            snprintf(message, sizeof message, "fmi2SetReal: %.80s set after the simulation ended", name);
            return bg_fail(c, message);
        }
        if (r < BG_NP) {
            c->v.p[r] = value[i];   /* tunable: read afresh by every evaluation of the derivatives */
        } else if (r < BG_NP + BG_NU) {
            c->v.u[r - BG_NP] = value[i];
        } else if (r < BG_NP + BG_NU + BG_NX) {
            if (c->v.phase == BG_STEPPING) {
                snprintf(message, sizeof message, "fmi2SetReal: the state %.80s is set only before "
                         "fmi2ExitInitializationMode", name);
                return bg_fail(c, message);
            }
            c->v.x[r - BG_NP - BG_NU] = value[i];
        } else {
            snprintf(message, sizeof message, "fmi2SetReal: %.80s is an output the model computes", name);
            return bg_fail(c, message);
        }
    }
    return fmi2OK;
}

static fmi2Status bg_no_variables(fmi2Component component, size_t nvr, const char *function) {
    char message[120];
    if (component == NULL) return fmi2Error;
    if (nvr == 0) return fmi2OK;
    snprintf(message, sizeof message, "%s: this FMU has Real variables only", function);
    return bg_fail((bg_instance *)component, message);
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[]) {
    (void)vr; (void)value;
    return bg_no_variables(c, nvr, "fmi2GetInteger");
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean value[]) {
    (void)vr; (void)value;
    return bg_no_variables(c, nvr, "fmi2GetBoolean");
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2String value[]) {
    (void)vr; (void)value;
    return bg_no_variables(c, nvr, "fmi2GetString");
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer value[]) {
    (void)vr; (void)value;
    return bg_no_variables(c, nvr, "fmi2SetInteger");
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Boolean value[]) {
    (void)vr; (void)value;
    return bg_no_variables(c, nvr, "fmi2SetBoolean");
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[]) {
    (void)vr; (void)value;
    return bg_no_variables(c, nvr, "fmi2SetString");
}

fmi2Status fmi2GetFMUstate(fmi2Component component, fmi2FMUstate *state) {
    bg_instance *c = (bg_instance *)component;
    bg_values *copy;
    if (c == NULL || state == NULL) return fmi2Error;
    copy = (bg_values *)(*state);
    if (copy == NULL) {
        copy = c->allocate != NULL ? (bg_values *)c->allocate(1, sizeof *copy) : (bg_values *)calloc(1, sizeof *copy);
        if (copy == NULL) return bg_fail(c, "fmi2GetFMUstate: out of memory");
    }
    *copy = c->v;
    *state = copy;
    return fmi2OK;
}

fmi2Status fmi2SetFMUstate(fmi2Component component, fmi2FMUstate state) {
    bg_instance *c = (bg_instance *)component;
    if (c == NULL || state == NULL) return fmi2Error;
    c->v = *(const bg_values *)state;
    return fmi2OK;
}

fmi2Status fmi2FreeFMUstate(fmi2Component component, fmi2FMUstate *state) {
    bg_instance *c = (bg_instance *)component;
    if (c == NULL || state == NULL) return fmi2Error;
    if (*state != NULL) {
        if (c->release != NULL) c->release(*state); else free(*state);
    }
    *state = NULL;
    return fmi2OK;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component component, fmi2FMUstate state, size_t *size) {
    (void)state;
    if (component == NULL || size == NULL) return fmi2Error;
    *size = sizeof(bg_values);
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component component, fmi2FMUstate state, fmi2Byte bytes[], size_t size) {
    bg_instance *c = (bg_instance *)component;
    if (c == NULL || state == NULL || bytes == NULL) return fmi2Error;
    if (size != sizeof(bg_values)) return bg_fail(c, "fmi2SerializeFMUstate: wrong size");
    memcpy(bytes, state, sizeof(bg_values));
    return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component component, const fmi2Byte bytes[], size_t size,
                                   fmi2FMUstate *state) {
    bg_instance *c = (bg_instance *)component;
    bg_values *copy;
    if (c == NULL || state == NULL || bytes == NULL) return fmi2Error;
    if (size != sizeof(bg_values)) return bg_fail(c, "fmi2DeSerializeFMUstate: the bytes are not a state of this FMU");
    copy = (bg_values *)(*state);
    if (copy == NULL) {
        copy = c->allocate != NULL ? (bg_values *)c->allocate(1, sizeof *copy) : (bg_values *)calloc(1, sizeof *copy);
        if (copy == NULL) return bg_fail(c, "fmi2DeSerializeFMUstate: out of memory");
    }
    memcpy(copy, bytes, sizeof *copy);
    *state = copy;
    return fmi2OK;
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference u[], size_t nu,
                                        const fmi2ValueReference z[], size_t nz, const fmi2Real du[], fmi2Real dz[]) {
    (void)u; (void)nu; (void)z; (void)nz; (void)du; (void)dz;
    return c == NULL ? fmi2Error : bg_fail((bg_instance *)c, "fmi2GetDirectionalDerivative: not provided");
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[]) {
    (void)vr; (void)nvr; (void)order; (void)value;
    return c == NULL ? fmi2Error : bg_fail((bg_instance *)c, "fmi2SetRealInputDerivatives: inputs are held "
                                                             "constant over a step (canInterpolateInputs false)");
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[]) {
    (void)vr; (void)nvr; (void)order; (void)value;
    return c == NULL ? fmi2Error : bg_fail((bg_instance *)c, "fmi2GetRealOutputDerivatives: not provided");
}

/* The Dormand-Prince 5(4) pair: nodes, stages, 5th-order weights (the 7th stage's row) and the
   difference of the 5th- and 4th-order weights (the error estimate). */
static const double bg_c[7] = {0.0, 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0, 1.0};
static const double bg_a[7][6] = {
    {0.0, 0.0, 0.0, 0.0, 0.0, 0.0},
    {1.0 / 5.0, 0.0, 0.0, 0.0, 0.0, 0.0},
    {3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0},
    {44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0},
    {19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0, 0.0, 0.0},
    {9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0, -5103.0 / 18656.0, 0.0},
    {35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0},
};
static const double bg_e[7] = {71.0 / 57600.0, 0.0, -71.0 / 16695.0, 71.0 / 1920.0, -17253.0 / 339200.0,
                               22.0 / 525.0, -1.0 / 40.0};

static fmi2Status bg_derivatives_checked(bg_instance *c, double t, const double *x, double *dx) {
    int i;
    char message[200];
    bg_derivatives(t, x, c->v.u, c->v.p, dx);
    for (i = 0; i < BG_NX; i++) {
        if (!isfinite(dx[i])) {
            snprintf(message, sizeof message, "fmi2DoStep: the derivative of %.80s is NaN or infinite at t = %g; "
                     "check the parameters and inputs", bg_variable_names[BG_NP + BG_NU + i], t);
            return bg_fail(c, message);
        }
    }
    return fmi2OK;
}

/* Integrate the states from the present time to t_end, the inputs and parameters held. */
static fmi2Status bg_integrate(bg_instance *c, double t_end) {
    double k[7][BG_SIZE(BG_NX)], stage[BG_SIZE(BG_NX)], next[BG_SIZE(BG_NX)];
    double t = c->v.time, h = c->v.h;
    long steps = 0;
    int i, j, s;
    char message[200];
    if (BG_NX == 0 || !(t_end > t)) {
        c->v.time = t_end > t ? t_end : t;
        return fmi2OK;
    }
    if (!(h > 0.0) || h > t_end - t) h = t_end - t;   /* the first try: the whole step; the control shrinks it */
    if (bg_derivatives_checked(c, t, c->v.x, k[0]) != fmi2OK) return fmi2Error;
    while (t < t_end) {
        double error = 0.0, factor, h_try = h;
        int last = 0;
        if (++steps > BG_MAX_STEPS) {
            snprintf(message, sizeof message, "fmi2DoStep: more than %ld internal steps to reach t = %g "
                     "(a stiff model?)", BG_MAX_STEPS, t_end);
            return bg_fail(c, message);
        }
        if (t + h >= t_end || t_end - (t + h) < BG_MIN_STEP * fabs(t_end)) {
            h = t_end - t;
            last = 1;
        }
        for (s = 1; s < 7; s++) {
            for (i = 0; i < BG_NX; i++) {
                double sum = 0.0;
                for (j = 0; j < s; j++) sum += bg_a[s][j] * k[j][i];
                stage[i] = c->v.x[i] + h * sum;
            }
            if (bg_derivatives_checked(c, t + bg_c[s] * h, stage, k[s]) != fmi2OK) return fmi2Error;
        }
        /* the 7th stage was evaluated at the 5th-order solution itself */
        for (i = 0; i < BG_NX; i++) {
            double estimate = 0.0, yardstick;
            next[i] = stage[i];
            for (j = 0; j < 7; j++) estimate += bg_e[j] * k[j][i];
            estimate = fabs(h * estimate);
            yardstick = c->v.rtol * (fmax(c->v.scale[i], fmax(fabs(c->v.x[i]), fabs(next[i])))
                                     + 0.01 * bg_state_nominal[i]);
            if (estimate > 0.0) error = fmax(error, yardstick > 0.0 ? estimate / yardstick : INFINITY);
        }
        factor = error > 0.0 ? 0.9 * pow(error, -0.2) : 5.0;
        if (error <= 1.0) {
            t = last ? t_end : t + h;
            for (i = 0; i < BG_NX; i++) {
                c->v.x[i] = next[i];
                c->v.scale[i] = fmax(c->v.scale[i], fabs(next[i]));
                k[0][i] = k[6][i];   /* first same as last */
            }
            /* a step shortened to land on t_end says nothing about the next one's size */
            h = last && h < h_try ? h_try : h * fmin(5.0, fmax(0.2, factor));
        } else {
            h *= fmax(0.2, fmin(0.9, factor));
            if (h < BG_MIN_STEP * fmax(1.0, fabs(t))) {
                snprintf(message, sizeof message, "fmi2DoStep: the internal step fell below %g s at t = %g",
                         BG_MIN_STEP * fmax(1.0, fabs(t)), t);
                return bg_fail(c, message);
            }
        }
    }
    c->v.time = t_end;
    c->v.h = h;
    return fmi2OK;
}

fmi2Status fmi2DoStep(fmi2Component component, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    bg_instance *c = (bg_instance *)component;
    double t = currentCommunicationPoint, t_end = currentCommunicationPoint + communicationStepSize;
    char message[200];
    (void)noSetFMUStatePriorToCurrentPoint;
    if (c == NULL) return fmi2Error;
    if (c->v.phase != BG_STEPPING) return bg_fail(c, "fmi2DoStep: called outside the stepping phase");
    if (!(communicationStepSize >= 0.0) || !isfinite(t_end))
        return bg_fail(c, "fmi2DoStep: the communication step size must be a finite number >= 0");
    if (fabs(t - c->v.time) > 1e-9 * fmax(1.0, fabs(t))) {
        snprintf(message, sizeof message, "fmi2DoStep: the communication point %.17g is not the FMU's time %.17g",
                 t, c->v.time);
        return bg_fail(c, message);
    }
    if (c->v.stop_defined && t_end > c->v.stop_time + 1e-9 * fmax(1.0, fabs(c->v.stop_time))) {
        snprintf(message, sizeof message, "fmi2DoStep: t = %.17g is after the stop time %.17g", t_end,
                 c->v.stop_time);
        return bg_fail(c, message);
    }
    if (!bg_finite(c->v.x, BG_NX)) return bg_fail(c, "fmi2DoStep: a state is NaN or infinite");
    c->v.time = t;   /* the importer's clock, not a sum of step sizes */
    if (bg_integrate(c, t_end) != fmi2OK) {
        c->v.phase = BG_FAILED;
        return fmi2Error;
    }
    return fmi2OK;
}

fmi2Status fmi2CancelStep(fmi2Component c) {
    return c == NULL ? fmi2Error : bg_fail((bg_instance *)c, "fmi2CancelStep: fmi2DoStep never runs asynchronously");
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Status *value) {
    (void)kind; (void)value;
    return c == NULL ? fmi2Error : fmi2Discard;   /* fmi2DoStep never returns fmi2Pending */
}

fmi2Status fmi2GetRealStatus(fmi2Component component, const fmi2StatusKind kind, fmi2Real *value) {
    bg_instance *c = (bg_instance *)component;
    if (c == NULL || value == NULL) return fmi2Error;
    if (kind != fmi2LastSuccessfulTime) return fmi2Discard;
    *value = c->v.time;
    return fmi2OK;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Integer *value) {
    (void)kind; (void)value;
    return c == NULL ? fmi2Error : fmi2Discard;
}

fmi2Status fmi2GetBooleanStatus(fmi2Component component, const fmi2StatusKind kind, fmi2Boolean *value) {
    bg_instance *c = (bg_instance *)component;
    if (c == NULL || value == NULL) return fmi2Error;
    if (kind != fmi2Terminated) return fmi2Discard;
    *value = fmi2False;   /* the model never asks to stop */
    return fmi2OK;
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind kind, fmi2String *value) {
    (void)kind; (void)value;
    return c == NULL ? fmi2Error : fmi2Discard;
}
"""
