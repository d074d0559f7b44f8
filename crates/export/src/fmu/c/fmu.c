/* The FMI 2.0 interface of a lagrange scene, for Model Exchange and Co-Simulation in one
 * binary. The equations are the scene's generated C (through fmu_model.h); Co-Simulation
 * integrates them with DOP853 (dop853.c); the model has no events, so Model Exchange's event
 * functions only report that nothing happens.
 *
 * Value references: the states (coordinates, then rates), their derivatives, the parameters,
 * the inputs, the outputs, then KE and PE. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dop853.h"
#include "fmi2.h"
#include "fmu_model.h"

#define VR_DERIVATIVES (MODEL_STATES)
#define VR_PARAMETERS (2 * MODEL_STATES)
#define VR_INPUTS (VR_PARAMETERS + MODEL_PARAMETERS)
#define VR_OUTPUTS (VR_INPUTS + MODEL_INPUTS)
#define VR_ENERGIES (VR_OUTPUTS + MODEL_OUTPUTS)
#define VR_END (VR_ENERGIES + 2)

typedef enum { INSTANTIATED, INITIALIZING, STEPPING, TERMINATED } phase;

typedef struct {
    fmi2CallbackFunctions callbacks;
    char *name;
    fmi2Type type;
    int logging;
    phase phase;
    double time;
    double tolerance;
    double y[MODEL_STATES];
    /* Which states were set before initialization: the others follow the parameters. */
    int state_given[MODEL_STATES];
    model_parameters parameters;
    double inputs[MODEL_INPUTS + 1];
    /* Derivatives, outputs and energies at (time, y), valid while `fresh`. */
    double dy[MODEL_STATES];
    double outputs[MODEL_OUTPUTS + 1];
    double energies[2];
    int fresh;
    dop853_state integrator;
} instance;

static void report(instance *m, fmi2Status status, const char *category, const char *message) {
    if (m->callbacks.logger != NULL && (m->logging || status >= fmi2Warning)) {
        m->callbacks.logger(m->callbacks.componentEnvironment, m->name, status, category, "%s",
                            message);
    }
}

static fmi2Status fail(instance *m, const char *message) {
    report(m, fmi2Error, "logStatusError", message);
    return fmi2Error;
}

static int evaluate_rhs(void *context, double t, const double *y, double *dy) {
    instance *m = context;
    return model_rhs(t, y, &m->parameters, m->inputs, dy);
}

/* The derivatives, outputs and energies at the current point, once per change. */
static fmi2Status refresh(instance *m) {
    if (m->fresh) {
        return fmi2OK;
    }
    if (model_rhs(m->time, m->y, &m->parameters, m->inputs, m->dy) != 0) {
        return fail(m, "the equations of motion cannot be solved at this state (a singular "
                       "mass matrix or constraint Jacobian, or a value that is not finite)");
    }
#if MODEL_OUTPUTS > 0
    if (model_outputs(m->time, m->y, &m->parameters, m->inputs, m->outputs) != 0) {
        return fail(m, "the outputs cannot be evaluated at this state");
    }
#endif
    if (model_energies(m->time, m->y, &m->parameters, m->inputs, m->energies) != 0) {
        return fail(m, "the energies cannot be evaluated at this state");
    }
    m->fresh = 1;
    return fmi2OK;
}

static void changed(instance *m) {
    m->fresh = 0;
    dop853_restart(&m->integrator);
}

static void *allocate(instance *m, size_t count, size_t size) {
    return m->callbacks.allocateMemory != NULL ? m->callbacks.allocateMemory(count, size)
                                               : calloc(count, size);
}

/* The states the parameters give, in place of those not set explicitly. */
static void start_from_parameters(instance *m) {
    double y0[MODEL_STATES];
    int i;
    model_initial_state(&m->parameters, y0);
    for (i = 0; i < MODEL_STATES; i++) {
        if (!m->state_given[i]) {
            m->y[i] = y0[i];
        }
    }
}

FMI2_EXPORT const char *fmi2GetTypesPlatform(void) { return "default"; }

FMI2_EXPORT const char *fmi2GetVersion(void) { return "2.0"; }

FMI2_EXPORT fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn,
                                           size_t nCategories, const fmi2String categories[]) {
    (void)nCategories;
    (void)categories;
    ((instance *)c)->logging = loggingOn;
    return fmi2OK;
}

static void release(instance *m) {
    void (*free_memory)(void *) =
        m->callbacks.freeMemory != NULL ? m->callbacks.freeMemory : free;
    dop853_free(&m->integrator, free_memory);
    if (m->name != NULL) {
        free_memory(m->name);
    }
    free_memory(m);
}

FMI2_EXPORT fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType,
                                          fmi2String fmuGUID, fmi2String fmuResourceLocation,
                                          const fmi2CallbackFunctions *functions,
                                          fmi2Boolean visible, fmi2Boolean loggingOn) {
    instance *m;
    int i;
    (void)fmuResourceLocation;
    (void)visible;
    if (functions == NULL) {
        return NULL;
    }
    m = functions->allocateMemory != NULL ? functions->allocateMemory(1, sizeof(instance))
                                          : calloc(1, sizeof(instance));
    if (m == NULL) {
        return NULL;
    }
    m->callbacks = *functions;
    m->logging = loggingOn;
    m->type = fmuType;
    m->name = allocate(m, strlen(instanceName != NULL ? instanceName : "") + 1, 1);
    if (m->name != NULL && instanceName != NULL) {
        strcpy(m->name, instanceName);
    }
    if (fmuGUID == NULL || strcmp(fmuGUID, MODEL_GUID) != 0) {
        report(m, fmi2Error, "logStatusError",
               "the GUID does not match this FMU's modelDescription.xml");
        release(m);
        return NULL;
    }
    if (dop853_init(&m->integrator, MODEL_STATES, MODEL_TOLERANCE, MODEL_TOLERANCE,
                    functions->allocateMemory != NULL ? functions->allocateMemory : calloc) !=
        DOP853_OK) {
        release(m);
        return NULL;
    }
    m->parameters = model_default_parameters;
    for (i = 0; i < MODEL_INPUTS; i++) {
        m->inputs[i] = model_default_input(i);
    }
    m->tolerance = MODEL_TOLERANCE;
    model_initial_state(&m->parameters, m->y);
    m->phase = INSTANTIATED;
    return m;
}

FMI2_EXPORT void fmi2FreeInstance(fmi2Component c) {
    if (c != NULL) {
        release(c);
    }
}

FMI2_EXPORT fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined,
                                           fmi2Real tolerance, fmi2Real startTime,
                                           fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    instance *m = c;
    (void)stopTimeDefined;
    (void)stopTime;
    if (toleranceDefined) {
        if (!(tolerance > 0.0)) {
            return fail(m, "the tolerance must be positive");
        }
        m->tolerance = tolerance;
    }
    m->time = startTime;
    changed(m);
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    ((instance *)c)->phase = INITIALIZING;
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    instance *m = c;
    start_from_parameters(m);
    m->integrator.rtol = m->tolerance;
    m->integrator.atol = m->tolerance;
    m->integrator.h = 0.0;
    changed(m);
    m->phase = STEPPING;
    return refresh(m);
}

FMI2_EXPORT fmi2Status fmi2Terminate(fmi2Component c) {
    ((instance *)c)->phase = TERMINATED;
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2Reset(fmi2Component c) {
    instance *m = c;
    int i;
    m->parameters = model_default_parameters;
    for (i = 0; i < MODEL_INPUTS; i++) {
        m->inputs[i] = model_default_input(i);
    }
    memset(m->state_given, 0, sizeof m->state_given);
    model_initial_state(&m->parameters, m->y);
    m->time = 0.0;
    m->tolerance = MODEL_TOLERANCE;
    m->integrator.h = 0.0;
    changed(m);
    m->phase = INSTANTIATED;
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                   fmi2Real value[]) {
    instance *m = c;
    size_t i;
    /* Derivatives and outputs are computed; before initialization they read 0. */
    for (i = 0; i < nvr && m->phase != INSTANTIATED; i++) {
        int computed = (vr[i] >= VR_DERIVATIVES && vr[i] < VR_PARAMETERS) ||
                       (vr[i] >= VR_OUTPUTS && vr[i] < VR_END);
        if (computed) {
            fmi2Status status = refresh(m);
            if (status != fmi2OK) {
                return status;
            }
            break;
        }
    }
    for (i = 0; i < nvr; i++) {
        fmi2ValueReference r = vr[i];
        if (r < VR_DERIVATIVES) {
            value[i] = m->y[r];
        } else if (r < VR_PARAMETERS) {
            value[i] = m->fresh ? m->dy[r - VR_DERIVATIVES] : 0.0;
        } else if (r < VR_INPUTS) {
            value[i] = *model_parameter(&m->parameters, r - VR_PARAMETERS);
        } else if (r < VR_OUTPUTS) {
            value[i] = m->inputs[r - VR_INPUTS];
        } else if (r < VR_ENERGIES) {
            value[i] = m->fresh ? m->outputs[r - VR_OUTPUTS] : 0.0;
        } else if (r < VR_END) {
            value[i] = m->fresh ? m->energies[r - VR_ENERGIES] : 0.0;
        } else {
            return fail(m, "fmi2GetReal: unknown value reference");
        }
    }
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                   const fmi2Real value[]) {
    instance *m = c;
    size_t i;
    for (i = 0; i < nvr; i++) {
        fmi2ValueReference r = vr[i];
        if (r < VR_DERIVATIVES) {
            m->y[r] = value[i];
            m->state_given[r] = 1;
        } else if (r >= VR_PARAMETERS && r < VR_INPUTS) {
            *model_parameter(&m->parameters, r - VR_PARAMETERS) = value[i];
        } else if (r >= VR_INPUTS && r < VR_OUTPUTS) {
            m->inputs[r - VR_INPUTS] = value[i];
        } else {
            return fail(m, "fmi2SetReal: only states, parameters and inputs can be set");
        }
    }
    changed(m);
    return fmi2OK;
}

static fmi2Status no_such_variable(fmi2Component c, size_t nvr, const char *what) {
    if (nvr == 0) {
        return fmi2OK;
    }
    return fail(c, what);
}

FMI2_EXPORT fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[],
                                      size_t nvr, fmi2Integer value[]) {
    (void)vr;
    (void)value;
    return no_such_variable(c, nvr, "the model has no Integer variables");
}

FMI2_EXPORT fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[],
                                      size_t nvr, fmi2Boolean value[]) {
    (void)vr;
    (void)value;
    return no_such_variable(c, nvr, "the model has no Boolean variables");
}

FMI2_EXPORT fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[],
                                     size_t nvr, fmi2String value[]) {
    (void)vr;
    (void)value;
    return no_such_variable(c, nvr, "the model has no String variables");
}

FMI2_EXPORT fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[],
                                      size_t nvr, const fmi2Integer value[]) {
    (void)vr;
    (void)value;
    return no_such_variable(c, nvr, "the model has no Integer variables");
}

FMI2_EXPORT fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[],
                                      size_t nvr, const fmi2Boolean value[]) {
    (void)vr;
    (void)value;
    return no_such_variable(c, nvr, "the model has no Boolean variables");
}

FMI2_EXPORT fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[],
                                     size_t nvr, const fmi2String value[]) {
    (void)vr;
    (void)value;
    return no_such_variable(c, nvr, "the model has no String variables");
}

/* Saving and restoring the FMU's state, and directional derivatives, are not offered
 * (canGetAndSetFMUstate and providesDirectionalDerivative are false). */
FMI2_EXPORT fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *state) {
    (void)state;
    return fail(c, "fmi2GetFMUstate is not supported");
}

FMI2_EXPORT fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state) {
    (void)state;
    return fail(c, "fmi2SetFMUstate is not supported");
}

FMI2_EXPORT fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *state) {
    (void)state;
    return fail(c, "fmi2FreeFMUstate is not supported");
}

FMI2_EXPORT fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state,
                                                  size_t *size) {
    (void)state;
    (void)size;
    return fail(c, "fmi2SerializedFMUstateSize is not supported");
}

FMI2_EXPORT fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate state,
                                             fmi2Byte serialized[], size_t size) {
    (void)state;
    (void)serialized;
    (void)size;
    return fail(c, "fmi2SerializeFMUstate is not supported");
}

FMI2_EXPORT fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serialized[],
                                               size_t size, fmi2FMUstate *state) {
    (void)serialized;
    (void)size;
    (void)state;
    return fail(c, "fmi2DeSerializeFMUstate is not supported");
}

FMI2_EXPORT fmi2Status fmi2GetDirectionalDerivative(fmi2Component c,
                                                    const fmi2ValueReference unknown[],
                                                    size_t nUnknown,
                                                    const fmi2ValueReference known[],
                                                    size_t nKnown, const fmi2Real dvKnown[],
                                                    fmi2Real dvUnknown[]) {
    (void)unknown;
    (void)nUnknown;
    (void)known;
    (void)nKnown;
    (void)dvKnown;
    (void)dvUnknown;
    return fail(c, "fmi2GetDirectionalDerivative is not supported");
}

/* Model Exchange. */

FMI2_EXPORT fmi2Status fmi2EnterEventMode(fmi2Component c) {
    (void)c;
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *info) {
    (void)c;
    info->newDiscreteStatesNeeded = fmi2False;
    info->terminateSimulation = fmi2False;
    info->nominalsOfContinuousStatesChanged = fmi2False;
    info->valuesOfContinuousStatesChanged = fmi2False;
    info->nextEventTimeDefined = fmi2False;
    info->nextEventTime = 0.0;
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) {
    (void)c;
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2CompletedIntegratorStep(fmi2Component c,
                                                   fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                                   fmi2Boolean *enterEventMode,
                                                   fmi2Boolean *terminateSimulation) {
    (void)c;
    (void)noSetFMUStatePriorToCurrentPoint;
    *enterEventMode = fmi2False;
    *terminateSimulation = fmi2False;
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time) {
    instance *m = c;
    m->time = time;
    m->fresh = 0;
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx) {
    instance *m = c;
    if (nx != MODEL_STATES) {
        return fail(m, "fmi2SetContinuousStates: wrong number of states");
    }
    memcpy(m->y, x, nx * sizeof(double));
    m->fresh = 0;
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real derivatives[], size_t nx) {
    instance *m = c;
    fmi2Status status;
    if (nx != MODEL_STATES) {
        return fail(m, "fmi2GetDerivatives: wrong number of states");
    }
    status = refresh(m);
    if (status != fmi2OK) {
        return status;
    }
    memcpy(derivatives, m->dy, nx * sizeof(double));
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real eventIndicators[],
                                              size_t ni) {
    (void)eventIndicators;
    return ni == 0 ? fmi2OK : fail(c, "the model has no event indicators");
}

FMI2_EXPORT fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx) {
    instance *m = c;
    if (nx != MODEL_STATES) {
        return fail(m, "fmi2GetContinuousStates: wrong number of states");
    }
    memcpy(x, m->y, nx * sizeof(double));
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[],
                                                         size_t nx) {
    size_t i;
    (void)c;
    for (i = 0; i < nx; i++) {
        x_nominal[i] = 1.0;
    }
    return fmi2OK;
}

/* Co-Simulation. */

FMI2_EXPORT fmi2Status fmi2SetRealInputDerivatives(fmi2Component c,
                                                   const fmi2ValueReference vr[], size_t nvr,
                                                   const fmi2Integer order[],
                                                   const fmi2Real value[]) {
    (void)vr;
    (void)order;
    (void)value;
    return nvr == 0 ? fmi2OK
                    : fail(c, "input derivatives are not supported (canInterpolateInputs is "
                              "false: inputs are held over a step)");
}

FMI2_EXPORT fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c,
                                                    const fmi2ValueReference vr[], size_t nvr,
                                                    const fmi2Integer order[],
                                                    fmi2Real value[]) {
    (void)vr;
    (void)order;
    (void)value;
    return nvr == 0 ? fmi2OK : fail(c, "output derivatives are not supported");
}

FMI2_EXPORT fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                                  fmi2Real communicationStepSize,
                                  fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    instance *m = c;
    double end = currentCommunicationPoint + communicationStepSize;
    char message[160];
    int status;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (fabs(currentCommunicationPoint - m->time) > 1e-9 * (1.0 + fabs(m->time))) {
        return fail(m, "fmi2DoStep: the communication point is not the FMU's time");
    }
    if (communicationStepSize < 0.0) {
        return fail(m, "fmi2DoStep: the step size is negative");
    }
    m->fresh = 0;
    status = dop853_integrate(&m->integrator, evaluate_rhs, m, &m->time, m->y, end);
    if (status != DOP853_OK) {
        snprintf(message, sizeof message, "fmi2DoStep: the integration stopped at t = %.17g: %s",
                 m->time,
                 status == DOP853_STEP_TOO_SMALL
                     ? "the step fell below what floating point resolves"
                     : "the equations of motion cannot be solved there");
        return fail(m, message);
    }
    m->time = end;
    return refresh(m);
}

FMI2_EXPORT fmi2Status fmi2CancelStep(fmi2Component c) {
    return fail(c, "fmi2CancelStep: steps are never asynchronous");
}

FMI2_EXPORT fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s,
                                     fmi2Status *value) {
    (void)s;
    (void)value;
    return fail(c, "fmi2GetStatus: steps are never asynchronous");
}

FMI2_EXPORT fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s,
                                         fmi2Real *value) {
    instance *m = c;
    if (s == fmi2LastSuccessfulTime) {
        *value = m->time;
        return fmi2OK;
    }
    return fail(m, "fmi2GetRealStatus: only fmi2LastSuccessfulTime is reported");
}

FMI2_EXPORT fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s,
                                            fmi2Integer *value) {
    (void)s;
    (void)value;
    return fail(c, "fmi2GetIntegerStatus: no integer status is reported");
}

FMI2_EXPORT fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s,
                                            fmi2Boolean *value) {
    if (s == fmi2Terminated) {
        *value = fmi2False;
        return fmi2OK;
    }
    return fail(c, "fmi2GetBooleanStatus: only fmi2Terminated is reported");
}

FMI2_EXPORT fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s,
                                           fmi2String *value) {
    (void)s;
    (void)value;
    return fail(c, "fmi2GetStringStatus: no string status is reported");
}
